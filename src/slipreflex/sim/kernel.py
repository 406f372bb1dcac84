"""The numba kernel: grasp physics, finger servos and the DAQ-side sensors.

Internal module: :class:`slipreflex.sim.Rig` is the public face. The state,
parameters and outputs are flat float64 arrays indexed by the constants
below, so the jitted functions compile once (``cache=True``) and a call has
few arguments.

Model (one physics step of ``dt``, semi-implicit Euler):

* **Fingers** (thumb, index, middle): first-order position servo
  ``dq/dt = clip(K (target - q), -speed, speed)``; closing, the speed limit
  falls along the DC motor's torque-speed line, ``speed (1 - droop N_c /
  stall)``, and a finger does not advance while its contact force exceeds
  the stall force (non-back-drivable: it holds its position under load).
* **Normal force**: the three fingertips sit 120 degrees apart around the
  bottle, which is free to shift sideways; three radial forces at 120 degrees
  balance only when equal, so every contact carries the same normal force
  ``N_c = k_n * travel * max(0, mean(q) - q_contact)`` with ``k_n`` three
  over the sum of the contacts' compliances (each: pad or cuff, finger and
  bottle wall in series), up to the wall's linear range; beyond it the wall
  ovalizes (softer) and then, folded flat, is rigid
  (:func:`slipreflex.sim.contacts.grip_curve`, :func:`_grip_force`).
* **Friction, per contact** (thumb and index through their silicone pads,
  the middle finger through the rigid cuff of the slip sensor), each with
  its own law and constants. A contact's tangential compliance ``k_t``
  (damping ``c_t``) ties the bottle to an anchor ``s`` on its surface; the
  bottle slips grossly only when all three slide. Two laws:

  - *rate-state* (default): slip weakening over a distance ``D_c``, healing
    over ``t_heal`` and a logarithmic rate term,
    ``mu = mu_k + (mu_s - mu_k) phi + a ln(1 + w / v0)`` (``PC_A`` holds
    ``a`` in absolute units); see
    :func:`_rs_contact` (implicit return mapping, :func:`rs_slide_speed`);
  - *Coulomb-Stribeck*: ``mu(w) = mu_k + (mu_s - mu_k) exp(-(w / v_s)^2)``,
    explicit, with the massless pad relaxing exactly toward ``F / k_t``.

  No creep while stuck: ``s`` does not move at all.
* **Loads**: gravity on bottle + water (+ landed masses, through their
  contact springs); a dropped mass is a second body with a compliant,
  damped contact on the bottom; a pour adds water at a constant rate after
  the jet's fall time and pushes with the jet's momentum flux, plus its
  splash (a one-pole noise on a fixed 1 ms grid, stream ``keys[5]``).
* **Slosh** (sideways, ``WaterParams``): the first antisymmetric mode of the
  water as a spring-mass (:func:`slosh_mode`) on the bottle, which the grasp
  holds sideways; driven by the jet landing off the axis and by the bottle's
  own motion (its axial acceleration scales the mode's gravity). The
  accelerometer's x axis reads the bottle's sideways acceleration.
* **Tilt** (the second degree of freedom): the bottle turns by ``th`` about
  the horizontal axis through the grasp's centre and the middle finger's
  cuff; each contact's friction law sees its own slide ``x + lever th``, so
  the contacts' tangential forces carry the weight and the tilt together,
  each bounded by its friction (the friction couple); gravity acts on the
  centre of mass below the axis, and the tilted section's ellipse presses
  the off-axis fingertips in (second order). A dropped mass lands on the
  bottom ``P_DROP_E`` off the axis and rocks the bottle
  (:func:`tilt_inertia`). Nothing else tilts it: a bottle that is never
  pushed off the axis runs the one-degree-of-freedom arithmetic.
* **Fallen out**: once the bottle has moved ``grip_travel`` below the
  fingertips the contacts reach the shoulder (each contact at its own
  height when tilted) and are lost; the bottle then falls freely.
* **Sensors** sampled inside the loop on their own clocks: the OPR5005 slip
  sensor (track interpolation at the surface position under the sensor,
  which moves with the bottle and with the middle fingertip's own rolling as
  it advances into the wall, ``P_SPOT_K`` metres per position unit of the
  tip's advance (the cuff's compression and the wall's dent), the gap
  opening by ``P_DENT_FRAC`` of the dent, transfer curve, electrical noise, 10-bit ADC) and flow pulses at the DAQ's
  333.33 Hz; the MPU6050 at its own ODR through its DLPF. Tactile snapshots
  (normal and tangential force, slip distance) at each requested tactile
  rate; frames are built by :func:`tactile_frames`.

Noise is counter-based (splitmix64 of a per-channel key and the sample
index), so a trace does not depend on how the run is cut into calls.

Speed: the per-step helpers (:func:`_rs_contact`, :func:`_coulomb_contact`,
:func:`_coulomb_post`) take and return scalars and the step writes its output
rows element by element. An inlined helper that takes an array, or a row view
``daq_out[nd]``, costs numba an atomic incref/decref pair per call that its
reference-count pruning does not remove: with them a held grasp took about
160 ns per step, without them about 50 ns (``benchmarks/bench_sim.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core._numba_cache import CACHE
from ..core._slots import Layout

__all__: list[str] = []

# Every vector's slots are named once, in a Layout (slipreflex.core._slots); the constants below are
# bound from it for the kernels, and tests/house/test_slots.py checks each against its layout's name.

# ---- state vector S -------------------------------------------------------
# Bottle-level: S_S mean slid distance of the contacts, S_W smallest sliding speed,
# S_STUCK 1 unless every contact slides (gross slip), S_FT total friction force.
# Per contact (thumb, index, middle): a CONTACT block of SC_SIZE from S_C0 + i * SC_SIZE
# (SC_Z: ln(1 + w / v0), the solver's variable).
# The water (WaterParams), from S_L0: bottle's sideways position and velocity, the slosh mass's, the
# bottle's sideways acceleration and its DLPF, the splash noise at the two ends of the current 1 ms
# interval, the slosh mode's k tanh(k h), mass m1, damping coefficient and jet participation, the
# axial load and the water's sideways force on the bottle (truth).
# The pads' slip vibration (thumb, index): the sensed shear's resonator, displacement VY (N) and its rate
# VV (N/s). The digits' motor vibration (thumb, index, middle): each motor's phase MPH (rad, set by the rig
# from the seed) and its force FM on the contact (N). The bottle's tilt in the grasp: TH (rad, about the
# horizontal axis through the grasp's centre and the middle finger's contact; positive turns the thumb's
# side down) and its rate OM (rad/s).
CONTACT = Layout("a contact's block of the rig's state S", "S=0 W=0 STUCK=1 DIR=1 PHI=1 FT=0 Z=0", prefix="SC_")
SC_S, SC_W, SC_STUCK, SC_DIR, SC_PHI, SC_FT, SC_Z = CONTACT.slots
SC_SIZE = CONTACT.size
STATE = Layout("the rig's state S", f"""
    X=0 V=0 S=0 W=0 STUCK=1 DIR=1 Q0:3=0 TGT0:3=0 SPD0:3
    NC=0 FT=0 AF=0 SUPPORTED=1 FALLEN=0 TFALL=nan AX=0 AY=0 AZ=0 AFRESH=0 MASS A=0
    C0:{3 * SC_SIZE}
    YB=0 VB=0 Y1=0 V1=0 ALAT=0 AFL=0 SPL0 SPL1 KTH=0 M1=0 C1=0 BETA=0 LOAD=0 FWAT=0
    VY0=0 VV0=0 VY1=0 VV1=0 MPH0:3 FM0:3=0 TH=0 OM=0""", prefix="S_")
(S_X, S_V, S_S, S_W, S_STUCK, S_DIR, S_Q0, S_TGT0, S_SPD0,
 S_NC, S_FT, S_AF, S_SUPPORTED, S_FALLEN, S_TFALL, S_AX, S_AY, S_AZ, S_AFRESH, S_MASS, S_A,
 S_C0,
 S_YB, S_VB, S_Y1, S_V1, S_ALAT, S_AFL, S_SPL0, S_SPL1, S_KTH, S_M1, S_C1, S_BETA, S_LOAD, S_FWAT,
 S_VY0, S_VV0, S_VY1, S_VV1, S_MPH0, S_FM0, S_TH, S_OM) = STATE.slots
S_L0 = S_YB
S_SIZE = STATE.size

# ---- counters C (int64) ---------------------------------------------------
# C_NFAIL: implicit friction solves that did not converge; C_NITER: most iterations one took.
# C_SPL: index j of the 1 ms splash-noise interval [j, j + 1) ms the values S_SPL0, S_SPL1 belong to.
# C_MS0, C_MS1: micro-slip events of the thumb's and the index finger's pad so far. C_STEPS: steps taken (a
# coarse step of the adaptive stepping counts once; with fixed steps it equals C_N). C_RECHECK: the step from
# which the adaptive stepping looks again whether the rig is calm (kept here: a call's end changes nothing).
# C_DAQ_AT1 .. C_SEEN_END: the adaptive stepping's next DAQ row (plus one; 0: none yet), the step at whose end
# it is taken, the IMU reading it carries and that reading's step, functions of the row alone, kept from call
# to call (a closed loop calls once per row). C_CAP: the adaptive stepping's longest coarse step for the fill
# the slosh mode last followed (:func:`mass_cap`; 0 before any water: the empty bottle's ``P_COARSE``).
COUNTERS = Layout("the rig's counters C", "N DAQ ACC NFAIL NITER SPL MS0 MS1 STEPS RECHECK DAQ_AT1 DAQ_END SEEN_J "
                  "SEEN_END CAP", prefix="C_")
(C_N, C_DAQ, C_ACC, C_NFAIL, C_NITER, C_SPL, C_MS0, C_MS1, C_STEPS, C_RECHECK, C_DAQ_AT1, C_DAQ_END, C_SEEN_J,
 C_SEEN_END, C_CAP) = COUNTERS.slots
C_SIZE = COUNTERS.size

# ---- parameters P ---------------------------------------------------------
# Per contact friction: a FRICTION block of PC_SIZE from P_C0 + i * PC_SIZE. The water, from P_L0:
# splash rms (relative), noise grid (s), its one-pole factor and innovation, bottle radius, the
# slosh's deep-fill damping ratio (slosh_zeta0), jet's mode participation J1(k r_j) / J1(1.8412),
# water density, sideways stiffness and damping of the bottle in the grasp, 1 / noise grid.
# The bounded grip (contacts.grip_curve, HandParams.motor_droop): the normal force's three pieces past
# contact (travel and force where they meet, the slopes of the second and third) and the motor's droop
# toward stall. The middle fingertip under the slip sensor: the wall's dent law (1 / k_w,
# 1 / ((1 - softening) k_w), linear range, collapse), the cuff's normal compliance, and the fraction of
# the dent that opens the sensor's gap. The pads' slip signature (TactileParams): micro-slip events' size
# (fraction of the static-to-kinetic drop) and rate (per metre slid, 1 / D_c), the sensed shear's
# resonator (omega^2, 2 zeta omega, omega), and the share of the Cattaneo-Mindlin law in the pressure
# centre's shift. The digits' motor vibration (HandParams): force amplitude and angular frequency at full
# speed, 1 / full speed. The bottle's shoulder (Bottle.shoulder_slope): radius lost per metre the bottle
# slides past grip_travel (0: the contacts are lost at once there), and the sine of its half-angle.
# The tilt (Bottle.grasp_height_m, Bottle.drop_eccentricity_m): each contact's lever about the tilt axis
# (m; its point moves down by LEVER th), the axis' height above the bottom, the empty bottle's moment of
# inertia about the axis and its mass times the depth of its centre of mass below the axis, and the
# horizontal distance from the axis at which a dropped mass lands on the bottom, and the mean over the contacts
# of lever^2 / R (the tilted body's elliptic section presses the fingertips by that times 1 / cos(th) - 1).
FRICTION = Layout("a contact's friction block of the rig's parameters P", """
    LAW MUS MUK VS A V0 DC HEAL KT CT DECAY HEAL_DECAY""", prefix="PC_")
(PC_LAW, PC_MUS, PC_MUK, PC_VS, PC_A, PC_V0, PC_DC, PC_HEAL, PC_KT, PC_CT, PC_DECAY,
 PC_HEAL_DECAY) = FRICTION.slots
PC_SIZE = FRICTION.size
#: The IMU's DLPF over a step of ``m`` fine steps, ``1 - (1 - ACC_ALPHA)^m``, and each contact's healing over it,
#: ``exp(-m dt / t_heal)``, are tabled in P for ``m`` up to this (``ACC_ALPHA_H[m]``, ``HEAL_DECAY_H[c * (ALPHA_STEPS
#: + 1) + m]`` for contact ``c``; longer steps compute them): the adaptive stepping would otherwise take an
#: ``expm1`` and an ``exp`` per step. ``ACC_LQ`` is ``log1p(-ACC_ALPHA)`` (:func:`fill_step_tables` fills them).
ALPHA_STEPS = 32
PARAMS = Layout("the rig's parameters P", f"""
    DT G MB KN LAM QC KSERVO STALL GRIP
    DAQ_T ACC_T ACC_ALPHA ACC_NOISE ACC_LSB ACC_RANGE TILT_X TILT_Z TILT_Y
    VCC VSAT KNEE VNOISE GAP ADC_LSB ADC_MAX TRACK_DX TRACK_OFF
    FLOW_K FLOW_PHASE SPOT_K PADS_SAME
    C0:{3 * PC_SIZE}
    SPL_RMS SPL_DT SPL_RHO SPL_SIG SLOSH_R ZETA0 PHIJ RHO_W KLAT CLAT SPL_INV
    WALL_PEN1 WALL_PEN2 WALL_N1 WALL_N2 WALL_K2 WALL_K3 DROOP
    WALL_KW_INV WALL_KW2_INV WALL_DLIN WALL_DCOL CUFF_INV DENT_FRAC
    MS_ETA MS_PER_M MS_W2 MS_2ZW MS_W INCIPIENT
    MV_F MV_W MV_INV_SPEED
    TAPER TAPER_SIN
    LEVER0:3 ZG IB MBD DROP_E TILT_PEN
    COARSE=1 COARSE_MAX=1 KT_SUM TILT_K
    ACC_LQ ACC_ALPHA_H:{ALPHA_STEPS + 1} HEAL_DECAY_H:{3 * (ALPHA_STEPS + 1)}""", prefix="P_")
(P_DT, P_G, P_MB, P_KN, P_LAM, P_QC, P_KSERVO, P_STALL, P_GRIP,
 P_DAQ_T, P_ACC_T, P_ACC_ALPHA, P_ACC_NOISE, P_ACC_LSB, P_ACC_RANGE, P_TILT_X, P_TILT_Z, P_TILT_Y,
 P_VCC, P_VSAT, P_KNEE, P_VNOISE, P_GAP, P_ADC_LSB, P_ADC_MAX, P_TRACK_DX, P_TRACK_OFF,
 P_FLOW_K, P_FLOW_PHASE, P_SPOT_K, P_PADS_SAME,
 P_C0,
 P_SPL_RMS, P_SPL_DT, P_SPL_RHO, P_SPL_SIG, P_SLOSH_R, P_ZETA0, P_PHIJ, P_RHO_W, P_KLAT,
 P_CLAT, P_SPL_INV,
 P_WALL_PEN1, P_WALL_PEN2, P_WALL_N1, P_WALL_N2, P_WALL_K2, P_WALL_K3, P_DROOP,
 P_WALL_KW_INV, P_WALL_KW2_INV, P_WALL_DLIN, P_WALL_DCOL, P_CUFF_INV, P_DENT_FRAC,
 P_MS_ETA, P_MS_PER_M, P_MS_W2, P_MS_2ZW, P_MS_W, P_INCIPIENT,
 P_MV_F, P_MV_W, P_MV_INV_SPEED,
 P_TAPER, P_TAPER_SIN,
 P_LEVER0, P_ZG, P_IB, P_MBD, P_DROP_E, P_TILT_PEN,
 P_COARSE, P_COARSE_MAX, P_KT_SUM, P_TILT_K, P_ACC_LQ, P_ACC_ALPHA_H, P_HEAL_DECAY_H) = PARAMS.slots
P_L0 = P_SPL_RMS
P_SIZE = PARAMS.size
#: Friction laws (PC_LAW): Coulomb with a Stribeck curve; slip weakening + healing + log rate.
LAW_COULOMB, LAW_RATE_STATE = 0.0, 1.0
_NEWTON_MAX = 60
_COS30 = 0.8660254037844386
#: First zero of J1' (``params.SLOSH_ROOT``): the first antisymmetric slosh mode's k R.
_XI = 1.8411837813406593

# ---- drops D (one row per drop) -------------------------------------------
DROP = Layout("a drop's row of D", "REL M H0 KC CC ACT=0 Z=0 VZ=0 LANDED=0", prefix="D_")
D_REL, D_M, D_H0, D_KC, D_CC, D_ACT, D_Z, D_VZ, D_LANDED = DROP.slots
D_SIZE = DROP.size

# ---- timed loads W (one row per pour or shake) -----------------------------
# A row acts from START + DELAY for DUR: a pour's water (RATE_KG_S, JET_N; TOTAL_KG, RATE_L_S for the
# rig) and the grip's own acceleration along the axis, ACC sin(ACC_W t) (m/s^2, down positive; t from the
# row's start), which the held bottle feels as the force -m ACC in the grip's frame and the IMU reads
POUR = Layout("a timed load's row of W", "START RATE_KG_S TOTAL_KG DELAY JET_N RATE_L_S DUR ACC=0 ACC_W=0",
              prefix="W_")
W_START, W_RATE_KG_S, W_TOTAL_KG, W_DELAY, W_JET_N, W_RATE_L_S, W_DUR, W_ACC, W_ACC_W = POUR.slots
W_SIZE = POUR.size

# ---- DAQ output rows --------------------------------------------------------
DAQ_ROW = Layout("a DAQ output row", """
    T VOLTS AX AY AZ AFRESH PULSES X V S STUCK NC MASS Q0 Q1 Q2 FALLEN A ALAT LOAD FWAT""", prefix="O_")
(O_T, O_VOLTS, O_AX, O_AY, O_AZ, O_AFRESH, O_PULSES, O_X, O_V, O_S, O_STUCK, O_NC, O_MASS,
 O_Q0, O_Q1, O_Q2, O_FALLEN, O_A, O_ALAT, O_LOAD, O_FWAT) = DAQ_ROW.slots
O_SIZE = DAQ_ROW.size

# ---- tactile snapshot rows --------------------------------------------------
TACTILE_ROW = Layout("a tactile snapshot row", "ID IDX T NC FT S FALLEN W MS", prefix="T_")
T_ID, T_IDX, T_T, T_NC, T_FT, T_S, T_FALLEN, T_W, T_MS = TACTILE_ROW.slots
T_SIZE = TACTILE_ROW.size  # T_FT, T_S, T_W, T_MS (its micro-slip events so far): the sampler's own contact

# ---- events -----------------------------------------------------------------
E_ONSET, E_STICK, E_FALLEN, E_LANDED = 1.0, 2.0, 3.0, 4.0

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_TWO53 = 1.0 / 9007199254740992.0


@njit(cache=CACHE, inline="always")
def _mix(z):
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@njit(cache=CACHE, inline="always")
def _uniform(key, i):
    h = _mix(key + np.uint64(i) * _GOLDEN)
    return (float(h >> _S11) + 0.5) * _TWO53


@njit(cache=CACHE)
def normal(key, i):
    """Standard normal number ``i`` of the stream ``key`` (counter-based, Box-Muller)."""
    u1 = _uniform(key, 2 * i)
    u2 = _uniform(key, 2 * i + 1)
    return np.sqrt(-2.0 * np.log(u1)) * np.cos(2.0 * np.pi * u2)


@njit(cache=CACHE)
def normal_pair(key, i):
    """Standard normal numbers ``2 i`` and ``2 i + 1`` of the stream ``key``: both of one Box-Muller pair
    (the uniforms ``2 i``, ``2 i + 1``; ``normal(key, i)`` is the first of them)."""
    u1 = _uniform(key, 2 * i)
    u2 = _uniform(key, 2 * i + 1)
    r = np.sqrt(-2.0 * np.log(u1))
    return r * np.cos(2.0 * np.pi * u2), r * np.sin(2.0 * np.pi * u2)


@njit(cache=CACHE)
def uniform(key, i):
    """Uniform number ``i`` in (0, 1) of the stream ``key`` (counter-based)."""
    return _uniform(key, i)


@njit(cache=CACHE)
def derive_key(key, i):
    """A new stream key from ``key`` and a small integer (wrap-around arithmetic)."""
    return _mix(key ^ (np.uint64(i) * _GOLDEN))


def fill_step_tables(P: np.ndarray) -> np.ndarray:
    """Fill ``P_ACC_LQ``, ``P_ACC_ALPHA_H`` and ``P_HEAL_DECAY_H`` from ``P[P_DT]``, ``P[P_ACC_ALPHA]`` (the IMU's
    DLPF per fine step) and each contact's ``PC_HEAL``; return ``P``.

    The same arithmetic and libm functions :func:`step_until` would use, so a tabled value is the computed
    one, bit for bit.

    Examples
    --------
    >>> P = np.zeros(P_SIZE); P[P_DT] = 1e-4; P[P_ACC_ALPHA] = 0.5
    >>> for c in range(3): P[P_C0 + c * PC_SIZE + PC_HEAL] = 0.1
    >>> float(fill_step_tables(P)[P_ACC_ALPHA_H + 2])    # 1 - (1 - 0.5)^2
    0.75
    """
    dt = float(P[P_DT])
    lq = math.log1p(-float(P[P_ACC_ALPHA]))
    P[P_ACC_LQ] = lq
    for m in range(ALPHA_STEPS + 1):
        P[P_ACC_ALPHA_H + m] = -math.expm1(m * lq)
    for c in range(3):
        heal = float(P[P_C0 + c * PC_SIZE + PC_HEAL])
        for m in range(ALPHA_STEPS + 1):
            P[P_HEAL_DECAY_H + c * (ALPHA_STEPS + 1) + m] = math.exp(-(m * dt) / heal)
    return P


@njit(cache=CACHE, inline="always")
def _track_at(pos, off, dx, nt):
    """Index ``i`` and fraction ``fr`` of surface position ``pos`` on a track of ``nt`` samples (clamped)."""
    fi = (pos + off) / dx
    i = int(np.floor(fi))
    if i < 0:
        i = 0
        fi = 0.0
    elif i > nt - 2:
        i = nt - 2
        fi = float(nt - 1)
    return i, fi - i


@njit(cache=CACHE, inline="always")
def _sensor_volts(rho, extra, gap, vcc, vsat, knee, vnoise, key, k, lsb, code_max):
    """OPR5005 output (ADC volts) for reflectance ``rho`` with the finger ``extra`` metres further than
    the gap (before contact), electrical noise number ``k`` of stream ``key``, 10-bit ADC."""
    if extra > 0.0:
        r = extra / gap
        rho = rho / (1.0 + r * r)
    vlin = vcc * (1.0 - rho)
    z = (vlin - vsat) / knee
    if z > 0.0:
        v = vsat + knee * (z + np.log1p(np.exp(-z)))
    else:
        v = vsat + knee * np.log1p(np.exp(z))
    v += vnoise * normal(key, k)
    code = np.floor(v / lsb)
    if code < 0.0:
        code = 0.0
    elif code > code_max:
        code = code_max
    return code * lsb


@njit(cache=CACHE, inline="always")
def _quant_g(val, lsb, full_range):
    c = np.floor(val / lsb + 0.5)
    hi = np.floor(full_range / lsb + 0.5) - 1.0
    lo = -np.floor(full_range / lsb + 0.5)
    if c > hi:
        c = hi
    elif c < lo:
        c = lo
    return c * lsb


@njit(cache=CACHE, inline="always")
def _grip_force(pen, kn, pen1, pen2, n1, n2, k2, k3):
    """Normal force per contact at mean travel ``pen`` past contact: three straight pieces
    (:class:`slipreflex.sim.contacts.GripCurve`)."""
    if pen <= 0.0:
        return 0.0
    if pen <= pen1:
        return kn * pen
    if pen <= pen2:
        return n1 + k2 * (pen - pen1)
    return n2 + k3 * (pen - pen2)


@njit(cache=CACHE, inline="always")
def _wall_dent(nc, n1, n2, kw_inv, kw2_inv, dlin, dcol):
    """The wall's dent (m) under one fingertip pressing with ``nc`` (the inverse of its three pieces)."""
    if nc <= n1:
        return nc * kw_inv
    if nc <= n2:
        return dlin + (nc - n1) * kw2_inv
    return dcol


@njit(cache=CACHE, inline="always")
def _sensed_shear(ft, nc, phi, P, i, inc):
    """The shear (N) whose ratio to ``nc`` shifts the array's pressure centre: with ``inc`` = 1 the
    Cattaneo-Mindlin law of a contact whose slipping annulus grows from the edge as the load ratio
    ``q = |F_t| / (mu N)`` grows, ``(3 / 2) mu N [1 - (1 - q)^(2/3)]`` (``F_t`` at small ``q``, steepening
    to infinite slope at ``q = 1``), with ``inc`` = 0 the linear ``F_t``."""
    if inc <= 0.0 or nc <= 0.0:
        return ft
    bp = P_C0 + i * PC_SIZE
    mu = P[bp + PC_MUK] + (P[bp + PC_MUS] - P[bp + PC_MUK]) * phi
    q = abs(ft) / (mu * nc)
    if q > 1.0:
        q = 1.0
    m = 1.5 * mu * nc * (1.0 - (1.0 - q) ** (2.0 / 3.0))
    return (1.0 - inc) * ft + inc * (m if ft >= 0.0 else -m)


@njit(cache=CACHE, inline="always")
def _shoulder(x, th, l0, l1, l2, grip):
    """The contacts past ``grip`` with the bottle slid ``x`` and tilted ``th``: the mean distance they have
    gone onto the shoulder (each contact at ``x + lever th``) and the furthest contact's position."""
    x0 = x + l0 * th
    x1 = x + l1 * th
    x2 = x + l2 * th
    past = (max(x0 - grip, 0.0) + max(x1 - grip, 0.0) + max(x2 - grip, 0.0)) / 3.0
    return past, max(x0, max(x1, x2))


@njit(cache=CACHE, inline="always")
def tilt_inertia(mw, P):
    """The bottle's moment of inertia (kg m^2) about the tilt axis with ``mw`` kg of water, and its mass times
    the depth of its centre of mass below the axis (kg m): the empty bottle's (``P_IB``, ``P_MBD``) and the
    water as a rigid cylinder of its fill height ``h``, ``mw (R^2 / 4 + h^2 / 12 + (z_g - h / 2)^2)``. A
    dropped mass is a body of its own: it acts only through its contact force on the bottom."""
    r = P[P_SLOSH_R]
    zg = P[P_ZG]
    h = mw / (P[P_RHO_W] * np.pi * r * r)
    dw = zg - 0.5 * h
    return P[P_IB] + mw * (0.25 * r * r + h * h / 12.0 + dw * dw), P[P_MBD] + mw * dw


@njit(cache=CACHE, inline="always")
def mass_cap(mw, m1, P, coarse):
    """Fine steps a coarse step may span with ``mw`` kg of water in the bottle (``m1`` of it sloshing):
    ``omega h <= 1`` for the stiffest mode of the bottle as it is now (along the axis on the contacts'
    shear stiffness ``P_KT_SUM``, sideways on ``P_KLAT`` without the slosh mass, in tilt on ``P_TILT_K``
    about :func:`tilt_inertia`), at least the empty bottle's ``coarse`` and at most ``P_COARSE_MAX``.
    Water only lowers these frequencies, so a bound from an earlier, smaller fill errs on the short side."""
    m = P[P_MB] + mw
    ml = m - m1 if m1 > 0.0 else m
    inertia, _ = tilt_inertia(mw, P)
    om2 = max(P[P_KT_SUM] / m, max(P[P_KLAT] / ml, P[P_TILT_K] / inertia))
    k = np.int64(1.0 / (np.sqrt(om2) * P[P_DT]))
    return min(np.int64(P[P_COARSE_MAX]), max(coarse, k))


@njit(cache=CACHE, inline="always")
def _rs_solve(R, K, N, mu_st, a, v0, z_guess, w_guess=-1.0):
    """Scalar core of :func:`rs_slide_speed`: returns ``(w, z, iterations, converged)``.

    With ``w_guess >= 0`` (the sliding speed that goes with ``z_guess``, i.e. the previous
    step's), the start is one Newton step from ``z_guess`` taken with ``exp(z_guess) = 1 +
    w_guess / v0``, which costs no exponential: under a load that changes from step to step
    (the pour's splash) the solve then usually converges in one more step.
    """
    rp = R - N * mu_st
    na = N * a
    if na <= 0.0:
        return rp / K, np.log1p(rp / K / v0), 0, True
    kv = K * v0
    if z_guess > 0.0 and w_guess >= 0.0:
        e = 1.0 + w_guess / v0
        z = z_guess + (rp - kv * (e - 1.0) - na * z_guess) / (kv * e + na)
        if z <= 0.0:
            z = min(rp / na, np.log1p(rp / kv))
    elif z_guess > 0.0:
        z = z_guess
    else:
        z = min(rp / na, np.log1p(rp / kv))
    it = 0
    converged = False
    ez = 1.0
    dz = 0.0
    while it < _NEWTON_MAX:
        ez = np.exp(z)
        h = rp - kv * (ez - 1.0) - na * z
        dz = h / (-kv * ez - na)
        z -= dz
        it += 1
        # quadratic convergence: after a step of 1e-7 the error is of order 1e-14
        if abs(dz) <= 1e-7 * (1.0 + abs(z)):
            converged = True
            break
    if z < 0.0:
        return 0.0, 0.0, it, converged
    if converged and z > 0.5:
        # exp(z) = exp(z + dz) exp(-dz), the first factor from the last iteration (|dz| <= 1e-7 (1 + z): the
        # series' error is below 1e-21 (1 + z)^3; no cancellation, exp(z) > 1.6): one exponential saved
        return v0 * (ez * (1.0 - dz + 0.5 * dz * dz) - 1.0), z, it, converged
    return v0 * np.expm1(z), z, it, converged


@njit(cache=CACHE, inline="always")
def rs_slide_speed(R, K, N, mu_st, a, v0, C, z_guess=0.0):
    """Sliding speed ``w >= 0`` of a rate-state contact: ``R - K w = N (mu_st + a ln(1 + w / v0))``.

    ``R`` is the trial (stuck) force magnitude, ``R > N mu_st``; ``K = k_t dt + c_t``.
    Newton's method in ``z = ln(1 + w / v0)``, where the residual is concave and
    decreasing, so Newton converges from any start (from the right of the root
    monotonically; from the left its first step lands on the right). It starts
    from ``z_guess`` (the previous step's ``z``) when positive, else from an
    upper bound of the root. Returns ``(w, z)``. ``C[C_NITER]`` keeps the most
    iterations one solve took and ``C[C_NFAIL]`` counts solves that did not
    converge.
    """
    w, z, it, converged = _rs_solve(R, K, N, mu_st, a, v0, z_guess)
    if it > C[C_NITER]:
        C[C_NITER] = it
    if not converged:
        C[C_NFAIL] += 1
    return w, z


@njit(cache=CACHE, inline="always")
def _rs_contact(kt, ct, s, mus, muk, phi, z_prev, w_prev, a, v0, dc, heal_s, heal_decay, x, v, nc, dt, dt_fine):
    """One step of a rate-state contact (implicit, return mapping); scalars in and out.

    The contact sticks while the trial force ``k_t (x - s + v dt) + c_t v``
    stays within the static threshold ``N (mu_k + (mu_s - mu_k) phi)``;
    beyond it the sliding speed solves the force balance of pad and interface
    with the friction ``N (mu_k + (mu_s - mu_k) phi + a ln(1 + w / v0))``. The
    state ``phi`` (1 = fully healed) decays over the slip distance ``D_c`` and
    heals over ``t_heal``: ``dphi/dt = -phi w / D_c + (1 - phi) / t_heal``,
    integrated exactly over the step. While the contact keeps sliding the solve
    starts from a Newton step off the previous step's ``z_prev`` and ``w_prev``
    (see :func:`_rs_solve`), so one more Newton step usually converges. Returns
    ``(F, s, w, z, d, phi, it, ok)``:
    the force on the bottle (up when positive), the new anchor, sliding speed,
    solver variable (0 when stuck), direction (0 when stuck), state, and the
    solver's iterations and convergence.

    ``dt_fine`` is the fine step: the trial force's predictor ``v dt_fine`` (which damps the stuck pad like
    ``k_t dt_fine`` more) stays the fine step's in a coarse step of ``dt``, so a ringing grasp decays as
    with fixed steps.
    """
    mu_st = muk + (mus - muk) * phi
    A = kt * (x - s + v * dt_fine) + ct * v
    R = abs(A)
    w = 0.0
    z = 0.0
    d = 0.0
    it = 0
    ok = True
    if R <= mu_st * nc:
        F = A
    else:
        d = 1.0 if A > 0.0 else -1.0
        K = kt * dt + ct
        w, z, it, ok = _rs_solve(R, K, nc, mu_st, a, v0, z_prev, w_prev)
        F = d * (R - K * w)
        s = s + d * w * dt
    if w > 0.0:
        heal = 1.0 / heal_s
        rate = w / dc + heal
        phi_ss = heal / rate
        phi = phi_ss + (phi - phi_ss) * np.exp(-rate * dt)
    elif phi < 1.0:
        # stuck: heal toward 1 (the same update with w = 0, its factor precomputed)
        phi = 1.0 - (1.0 - phi) * heal_decay
    return F, s, w, z, d, phi, it, ok


@njit(cache=CACHE, inline="always")
def _coulomb_contact(kt, ct, s, mus, muk, vs, stuck, d, w, x, v, nc):
    """Coulomb-Stribeck contact before the bottle moves (explicit); returns ``(F, stuck, d, w)``.

    ``mu(w) = mu_k + (mu_s - mu_k) exp(-(w / v_s)^2)``; finished by
    :func:`_coulomb_post` after the bottle has moved.
    """
    fp = kt * (x - s) + ct * v
    if stuck > 0.0 and abs(fp) > mus * nc:
        stuck = 0.0
        d = 1.0 if fp > 0.0 else -1.0
        w = 0.0
    if stuck > 0.0:
        return fp, stuck, d, w
    wr = w / vs
    return d * (muk + (mus - muk) * np.exp(-wr * wr)) * nc, stuck, d, w


@njit(cache=CACHE, inline="always")
def _coulomb_post(F, kt, decay, s, d, x_old, x_new, dt):
    """Coulomb-Stribeck contact after the bottle moved: the massless pad relaxes toward
    ``F / k_t`` exactly, the anchor follows, and the contact sticks when it stops.
    Returns ``(s, stuck, w)``."""
    ueq = F / kt
    u = ueq + (x_old - s - ueq) * decay
    sn = x_new - u
    wn = (sn - s) / dt
    if wn * d <= 0.0:
        return s, 1.0, 0.0
    return sn, 0.0, abs(wn)


@njit(cache=CACHE, inline="always")
def slosh_mode(mw, radius, rho, zeta0, phi_jet):
    """First antisymmetric slosh mode of ``mw`` kg of water in an upright cylinder of ``radius``.

    Returns ``(k tanh(k h), m1, zeta, beta)``: ``omega^2 = g k tanh(k h)`` with
    ``k = 1.8412 / R`` and fill height ``h``; the slosh mass of the
    equivalent spring-mass ``m1 = mw 2 tanh(k h) / ((xi^2 - 1) k h)``
    (Abramson 1966; Dodge 2000); the damping ratio of Stephens et al. (1962),
    ``zeta0 [1 + 0.318 / sinh(k h) (1 + (1 - h / R) / cosh(k h))]`` with the
    deep-fill ratio ``zeta0 = 0.79 sqrt(nu / (g^0.5 R^1.5))`` times the damping
    factor (:func:`slosh_zeta0`), at most 1; and ``beta``, the modal force on
    the slosh mass per newton of vertical force on the surface ``phi_jet =
    J1(k r_j) / J1(xi)`` of the way out: the mode's elevation at the wall ``q``
    and the slosh mass's displacement ``y1`` share the mode's potential energy,
    ``y1 = q (xi^2 - 1) / (2 xi tanh(k h))``, so ``beta = phi_jet 2 xi tanh(k h)
    / (xi^2 - 1)``. (``k h = xi h / R``: one exponential gives all three
    hyperbolic functions.)
    """
    h = mw / (rho * np.pi * radius * radius)
    kh = _XI * h / radius
    if kh <= 1e-9:
        return 0.0, mw * 2.0 / (_XI * _XI - 1.0), 1.0, 0.0
    e = np.exp(min(kh, 300.0))
    sh = 0.5 * (e - 1.0 / e)
    ch = 0.5 * (e + 1.0 / e)
    th = sh / ch
    m1 = mw * 2.0 * th / ((_XI * _XI - 1.0) * kh)
    zeta = zeta0 * (1.0 + 0.318 / sh * (1.0 + (1.0 - h / radius) / ch))
    if zeta > 1.0:
        zeta = 1.0
    return _XI / radius * th, m1, zeta, phi_jet * 2.0 * _XI * th / (_XI * _XI - 1.0)


def slosh_zeta0(radius, nu, g, damp_factor=1.0):
    """Deep-fill damping ratio of the first slosh mode, Stephens et al. (1962): ``0.79 sqrt(nu / (g^0.5 R^1.5))``.

    Examples
    --------
    >>> round(slosh_zeta0(0.0325, 1.004e-6, 9.81), 4)
    0.0058
    """
    return 0.79 * (nu / (g ** 0.5 * radius ** 1.5)) ** 0.5 * damp_factor


#: The adaptive stepping (``P_COARSE`` > 1, :func:`step_until`): a contact counts as calm while it sticks with
#: its force under this share of its static threshold (the cuff: ``_CALM_RATIO_CUFF``; its yield alone is no
#: gross slip, and the fast slide that follows it takes fine steps) (the splash's peaks are ~3 % of it; a pour's load
#: takes ~0.2 s to rise by 5 %), or, the cuff only, once its state has weakened under ``_CALM_PHI`` (its
#: friction within that share of the static-to-kinetic drop of kinetic) while it sticks or creeps slower than
#: ``_CALM_SLIP`` of its slip-weakening distance per coarse step ...
_CALM_RATIO = 0.9
_CALM_RATIO_CUFF = 0.99
_CALM_SLIP = 0.5
_CALM_PHI = 0.25
#: ... and the bottle while it moves slower than ``_CALM_V`` (m/s; the stick resonance's ringing at 2.5 um,
#: a held pour's splash ~6e-5 m/s) and turns slower than ``_CALM_OM`` (rad/s), a dropped mass resting
#: on the bottom when its speed and its spring's deviation from rest are under ``_CALM_V`` as well.
_CALM_V = 1e-3
_CALM_OM = 1e-3
#: A finger counts as still within this many position units of its target (2 um of travel; its servo then
#: turns it at most 0.4 units/s, 1e-3 of full speed: its motor's shake, 1e-5 N at 0.1 Hz, is left out).
_CALM_Q = 1e-2
#: ... and its motor's shake under this force (N; 1e-5 N within _CALM_Q of the target).
_CALM_FM = 1e-4
#: Fine steps after a calm check that failed before the next one (the check costs a few ns).
_CALM_RECHECK = 8


@njit(cache=CACHE, inline="always")
def _fire_end(T, dt):
    """The step count ``k`` at whose end a sample due at ``T`` is taken: the least ``k`` with
    ``T <= k dt + 1e-12`` (the sensors' rule in :func:`step_until`)."""
    k = np.int64(np.ceil((T - 1e-12) / dt))
    while T <= (k - 1) * dt + 1e-12:
        k -= 1
    while T > k * dt + 1e-12:
        k += 1
    return k


@njit(cache=CACHE, inline="always")
def _tactile_end(j, r, dt):
    """The step count at whose end tactile sample ``j`` of a sampler at ``r`` Hz is taken: the least ``k``
    with ``j <= (k dt + 1e-12) r``."""
    k = np.int64(np.ceil((j / r - 1e-12) / dt))
    while j <= ((k - 1) * dt + 1e-12) * r:
        k -= 1
    while j > (k * dt + 1e-12) * r:
        k += 1
    return k


@njit(cache=CACHE, inline="always")
def _load_switch(n, t_switch, dt):
    """The first step ``k > n`` whose start lies past ``t_switch`` (a pour's water arrives at ``k dt >
    t_switch``), or a step count far away when that step is not after ``n``."""
    k = np.int64(np.floor(t_switch / dt))
    while k > 0 and (k - 1) * dt > t_switch:
        k -= 1
    while k * dt <= t_switch:
        k += 1
    return k if k > n else np.int64(1) << 62


@njit(cache=CACHE, inline="always")
def _load_stop(n, ta, dur, dt):
    """The first step ``k > n`` with ``k dt - ta >= dur`` (a pour's water stops), or a step count far away."""
    k = np.int64(np.floor((ta + dur) / dt))
    while k > 0 and (k - 1) * dt - ta >= dur:
        k -= 1
    while k * dt - ta < dur:
        k += 1
    return k if k > n else np.int64(1) << 62


@njit(cache=CACHE)
def step_until(S, C, P, keys, D, W, track, tac_rates, tac_next, tac_contact, n_end, daq_out, tac_out, ev_out,
               counts):
    """Advance the physics to step ``n_end``; write DAQ rows, tactile snapshots and events.

    ``counts`` receives the number of rows written to each output. Stops
    early (without error) if an output buffer would overflow; the caller
    sizes them so that this does not happen.
    """
    dt = P[P_DT]
    g = P[P_G]
    nd = 0
    ntac = 0
    nev = 0
    n = C[C_N]
    cap_daq = daq_out.shape[0]
    cap_tac = tac_out.shape[0]
    cap_ev = ev_out.shape[0]
    nsamp = tac_rates.shape[0]
    key0 = keys[0]
    key1 = keys[1]
    key5 = keys[5]
    key6 = keys[6]
    ms_eta, ms_per_m, ms_w2, ms_2zw, ms_w = P[P_MS_ETA], P[P_MS_PER_M], P[P_MS_W2], P[P_MS_2ZW], P[P_MS_W]
    inc = P[P_INCIPIENT]
    ringing = True   # a pad's resonator may hold a value from the last call: look once
    mv_f, mv_w, mv_inv_dt = P[P_MV_F], P[P_MV_W], P[P_MV_INV_SPEED] / P[P_DT]
    taper, taper_sin, grip = P[P_TAPER], P[P_TAPER_SIN], P[P_GRIP]
    lev0, lev1, lev2, zg, drop_e = P[P_LEVER0], P[P_LEVER0 + 1], P[P_LEVER0 + 2], P[P_ZG], P[P_DROP_E]
    # loop invariants and the states every step reads, kept in locals (numba cannot tell that the
    # output arrays do not alias S and P, so it would reload them from memory every step)
    kservo = P[P_KSERVO]
    stall = P[P_STALL]
    qc = P[P_QC]
    lam = P[P_LAM]
    kn = P[P_KN]
    pen1, pen2, n1w, n2w = P[P_WALL_PEN1], P[P_WALL_PEN2], P[P_WALL_N1], P[P_WALL_N2]
    k2w, k3w = P[P_WALL_K2], P[P_WALL_K3]
    droop = P[P_DROOP] / stall
    mb = P[P_MB]
    acc_alpha = P[P_ACC_ALPHA]
    klat = P[P_KLAT]
    clat = P[P_CLAT]
    x = S[S_X]
    v = S[S_V]
    a_prev = S[S_A]
    yb = S[S_YB]
    vb = S[S_VB]
    y1 = S[S_Y1]
    v1 = S[S_V1]
    th = S[S_TH]
    om = S[S_OM]
    coarse = np.int64(P[P_COARSE])
    # the coarse step's bound for the bottle as the slosh mode last saw it filled: longer as it fills
    cap_m = coarse if C[C_CAP] < coarse else C[C_CAP]
    acc_lq = P[P_ACC_LQ]
    alpha_coarse = P[P_ACC_ALPHA_H + coarse] if coarse <= ALPHA_STEPS else -np.expm1(coarse * acc_lq)
    # the step at whose end the next DAQ row is taken (for the counter's value daq_at; recomputed when it
    # moves), and the last IMU reading before it (seen_j) and its step
    daq_at = C[C_DAQ_AT1] - 1
    daq_end = C[C_DAQ_END]
    seen_j = C[C_SEEN_J] if daq_at >= 0 else np.int64(-1)
    seen_end = C[C_SEEN_END]
    acc_t = P[P_ACC_T]
    daq_t = P[P_DAQ_T]
    n_switch = n   # the next step where a load switches (a drop's release, a pour's start or stop): look first
    while n < n_end:
        if nev + 3 + D.shape[0] > cap_ev or nd + 2 > cap_daq:
            break
        # the step: one fine step, or (adaptive, while nothing needs the fine step) ``ms`` of them at once,
        # ending where the next sample is due; ``h`` its length, loads taken at its middle ``tl``
        ms = 1
        if coarse > 1 and n >= C[C_RECHECK]:
            # calm: nothing in the rig needs the fine step (the conditions are written out here, not in a
            # helper: an inlined helper taking arrays costs an atomic reference count per array and call)
            # a fallen bottle falls freely (no contact, nothing rings on it, its fingers touch nothing)
            gone = S[S_FALLEN] > 0.0
            calm = gone or (abs(v) <= _CALM_V and abs(om) <= _CALM_OM)
            if calm and not gone:
                calm = S[S_VY0] == 0.0 and S[S_VV0] == 0.0 and S[S_VY1] == 0.0 and S[S_VV1] == 0.0
            if calm and not gone:
                calm = x + abs(th) * max(abs(lev0), abs(lev1)) < grip
            for i in range(3 if calm and not gone else 0):
                if abs(S[S_TGT0 + i] - S[S_Q0 + i]) > _CALM_Q or abs(S[S_FM0 + i]) > _CALM_FM:
                    calm = False
            if calm and not gone and S[S_SUPPORTED] == 0.0:
                ncc = S[S_NC]
                for i in range(3):
                    bs = S_C0 + i * SC_SIZE
                    bp = P_C0 + i * PC_SIZE
                    rs = P[bp + PC_LAW] == LAW_RATE_STATE
                    if i == 2 and rs and S[bs + SC_PHI] < _CALM_PHI:
                        # the cuff weakened, creeping or stuck for a moment between creeps: a yield releases
                        # at most _CALM_PHI of its static-to-kinetic drop
                        if S[bs + SC_STUCK] == 0.0 and S[bs + SC_W] * cap_m * dt > _CALM_SLIP * P[bp + PC_DC]:
                            calm = False
                    elif S[bs + SC_STUCK] > 0.0:
                        lim = (P[bp + PC_MUK] + (P[bp + PC_MUS] - P[bp + PC_MUK]) * S[bs + SC_PHI] if rs
                               else P[bp + PC_MUS])
                        if abs(S[bs + SC_FT]) > (_CALM_RATIO if i < 2 else _CALM_RATIO_CUFF) * lim * ncc:
                            calm = False
                    else:
                        calm = False
            cap = cap_m
            for d in range(D.shape[0] if calm else 0):
                if D[d, D_ACT] > 0.0:
                    # a mass resting on the bottom rings on its contact spring: omega h <= 1
                    cap = min(cap, max(1, np.int64(1.0 / (np.sqrt(D[d, D_KC] / D[d, D_M]) * dt))))
                    # a dropped mass in flight, or bouncing on the bottom (its speed or its spring's sag from
                    # rest over _CALM_V)
                    sag = D[d, D_Z] - x - D[d, D_M] * g / D[d, D_KC]
                    if (D[d, D_LANDED] == 0.0 or abs(D[d, D_VZ] - v) > _CALM_V
                            or abs(sag) * np.sqrt(D[d, D_KC] / D[d, D_M]) > _CALM_V):
                        calm = False
            for p in range(W.shape[0] if calm else 0):
                # a shaking grip: ten coarse steps a radian of its shake at most
                if W[p, W_ACC] != 0.0 and n * dt - W[p, W_START] - W[p, W_DELAY] < W[p, W_DUR]:
                    cap = min(cap, max(1, np.int64(0.1 / (W[p, W_ACC_W] * dt))))
            if calm:
                # the coarse step ends where the next IMU, DAQ or tactile sample is taken (each from the state
                # at its instant, as with fixed steps), before a drop's release and where a pour's water
                # starts or stops
                if n >= n_switch:
                    n_switch = np.int64(1) << 62
                    for d in range(D.shape[0]):
                        if D[d, D_ACT] == 0.0:
                            k = _fire_end(D[d, D_REL] + 1e-12, dt) - 1   # the first k with (k + 1) dt > rel
                            while (k + 1) * dt <= D[d, D_REL]:
                                k += 1
                            while k > 0 and k * dt > D[d, D_REL]:
                                k -= 1
                            if k >= n:
                                n_switch = min(n_switch, k)
                    for p in range(W.shape[0]):
                        ta = W[p, W_START] + W[p, W_DELAY]
                        n_switch = min(n_switch, _load_switch(n, ta, dt), _load_stop(n, ta, W[p, W_DUR], dt))
                if C[C_DAQ] != daq_at:
                    daq_at = C[C_DAQ]
                    daq_end = _fire_end(daq_at * daq_t, dt)
                    # the IMU reading the row will carry: the last taken by the row's step (the readings
                    # before it are drawn by no one, and end no step)
                    seen_j = np.int64(np.floor((daq_end * dt + 1e-12) / acc_t)) + 1
                    while seen_j >= 0 and _fire_end(seen_j * acc_t, dt) > daq_end:
                        seen_j -= 1
                    seen_end = _fire_end(seen_j * acc_t, dt)
                ms = min(cap, n_end - n, n_switch - n, daq_end - n)
                if seen_j >= C[C_ACC]:
                    ms = min(ms, seen_end - n)
                for si in range(nsamp):
                    ms = min(ms, _tactile_end(tac_next[si], tac_rates[si], dt) - n)
                if ms < 1:
                    ms = 1
            else:
                C[C_RECHECK] = n + _CALM_RECHECK
        t0 = n * dt
        if ms == 1:
            h = dt
            t1 = (n + 1) * dt
            tl = t0
            alpha_h = acc_alpha
        else:
            h = ms * dt
            t1 = (n + ms) * dt
            tl = t0 + 0.5 * (ms - 1) * dt
            alpha_h = (alpha_coarse if ms == coarse else P[P_ACC_ALPHA_H + ms] if ms <= ALPHA_STEPS
                       else -np.expm1(ms * acc_lq))
        # ---- fingers (in a coarse step of a held bottle within _CALM_Q of their targets: their motors quiet)
        nc_prev = S[S_NC]
        moving = False
        quiet = ms > 1 and S[S_FALLEN] == 0.0
        for i in range(3):
            q = S[S_Q0 + i]
            tg = S[S_TGT0 + i]
            e = tg - q
            r = kservo * e
            sp = S[S_SPD0 + i]
            if r > 0.0:
                # closing against the load: the DC motor's torque-speed line
                spc = sp * (1.0 - droop * nc_prev)
                if r > spc:
                    r = spc if spc > 0.0 else 0.0
            elif r < -sp:
                r = -sp
            if r > 0.0 and nc_prev >= stall:
                r = 0.0
            qn = q + r * h
            if (tg - qn) * e < 0.0:
                qn = tg
            S[S_Q0 + i] = qn
            if quiet:
                S[S_FM0 + i] = 0.0
            # the digit's motor shakes its contact while it turns: rotor unbalance, force and frequency
            # proportional to the speed
            if mv_f > 0.0 and not quiet:
                if qn != q:
                    mvr = abs(qn - q) * (mv_inv_dt if ms == 1 else mv_inv_dt * dt / h)
                    ph = S[S_MPH0 + i] + mv_w * mvr * h
                    if ph > 6.283185307179586:
                        ph -= 6.283185307179586
                    S[S_MPH0 + i] = ph
                    S[S_FM0 + i] = mv_f * mvr * np.sin(ph)
                    moving = True
                elif S[S_FM0 + i] != 0.0:
                    S[S_FM0 + i] = 0.0
        qbar = (S[S_Q0] + S[S_Q0 + 1] + S[S_Q0 + 2]) / 3.0
        pen = (qbar - qc) * lam
        pen_full = pen
        # past grip_travel the fingertips are on the shoulder, whose radius shrinks as the bottle slides; tilted,
        # each contact is at its own height, and the three equal normal forces (the bottle shifts sideways
        # until they balance) follow the mean of their gaps
        tilted = th != 0.0 or om != 0.0
        xmax = x
        if tilted:
            shl, xmax = _shoulder(x, th, lev0, lev1, lev2, grip)
        else:
            shl = x - grip if x > grip else 0.0
        if taper > 0.0 and shl > 0.0:
            pen -= taper * shl
        if tilted:
            # the tilted body's section in the grasp's plane is an ellipse, R / cos(th) across the axis: it
            # presses the fingertips off the axis further in (second order in the tilt)
            pen += P[P_TILT_PEN] * (1.0 / np.cos(th) - 1.0)
        fallen = S[S_FALLEN] > 0.0
        nc = _grip_force(pen, kn, pen1, pen2, n1w, n2w, k2w, k3w) if not fallen else 0.0
        S[S_NC] = nc
        # ---- loads
        mw = 0.0
        fjet = 0.0
        gacc = 0.0
        for p in range(W.shape[0]):
            ta = W[p, W_START] + W[p, W_DELAY]
            if tl > ta:
                mw += W[p, W_RATE_KG_S] * min(tl - ta, W[p, W_DUR])
                if tl - ta < W[p, W_DUR]:
                    fjet += W[p, W_JET_N]
                    if W[p, W_ACC] != 0.0:
                        gacc += W[p, W_ACC] * np.sin(W[p, W_ACC_W] * (tl - ta))
        # the weight in the grip's frame: gravity less the grip's acceleration (down positive)
        geff = g - gacc if gacc != 0.0 else g
        # ---- the jet's splash: a one-pole (Ornstein-Uhlenbeck) noise drawn on a fixed 1 ms grid and
        # interpolated, so it does not depend on dt; the grid (and the slosh mode's coefficients, which
        # change with the fill) advances only while a jet flows, catching up on its first use
        fspl = 0.0
        if fjet > 0.0:
            gdt = P[P_SPL_DT]
            advanced = False
            tenth = False
            while (C[C_SPL] + 1) * gdt <= tl:
                j = C[C_SPL] + 1
                S[S_SPL0] = S[S_SPL1]
                S[S_SPL1] = P[P_SPL_RHO] * S[S_SPL1] + P[P_SPL_SIG] * normal(key5, j + 1)
                C[C_SPL] = j
                advanced = True
                tenth = tenth or j % 10 == 0
            fr = tl * P[P_SPL_INV] - C[C_SPL]
            fspl = P[P_SPL_RMS] * fjet * (S[S_SPL0] + fr * (S[S_SPL1] - S[S_SPL0]))
            # the mode follows the fill every 10 ms (0.17 ml at 1 L/min: its mass changes by < 0.1 %; a coarse
            # step that passes a tenth grid point updates it too)
            if (advanced and (C[C_SPL] % 10 == 0 or (ms > 1 and tenth))) or S[S_M1] == 0.0:
                kth, m1, zeta, beta = slosh_mode(mw, P[P_SLOSH_R], P[P_RHO_W], P[P_ZETA0], P[P_PHIJ])
                S[S_KTH] = kth
                S[S_M1] = m1
                S[S_C1] = 2.0 * zeta * m1 * np.sqrt(kth * g)
                S[S_BETA] = beta
                if coarse > 1:
                    cap_m = mass_cap(mw, m1, P, coarse)
                    C[C_CAP] = cap_m
        x_old = x
        fdrop = 0.0
        mdrop = 0.0
        mland = 0.0
        for d in range(D.shape[0]):
            if t1 <= D[d, D_REL]:
                continue
            if D[d, D_ACT] == 0.0:
                D[d, D_ACT] = 1.0
                D[d, D_Z] = x - D[d, D_H0]
                D[d, D_VZ] = 0.0
            # the mass lands on the bottom off the tilt axis, where the bottom moves with the tilt
            xbot = x + drop_e * th if tilted else x
            pd = D[d, D_Z] - xbot
            f = 0.0
            if pd > 0.0:
                f = D[d, D_KC] * pd + D[d, D_CC] * (D[d, D_VZ] - (v + drop_e * om if tilted else v))
                if f < 0.0:
                    f = 0.0
                if D[d, D_LANDED] == 0.0:
                    D[d, D_LANDED] = 1.0
                    ev_out[nev, 0] = t1
                    ev_out[nev, 1] = E_LANDED
                    ev_out[nev, 2] = x
                    nev += 1
            if D[d, D_LANDED] > 0.0:
                mland += D[d, D_M]
            D[d, D_VZ] += (geff - f / D[d, D_M]) * h
            D[d, D_Z] += D[d, D_VZ] * h
            fdrop += f
            if f != 0.0 and drop_e != 0.0:
                # its force on the bottom, at the eccentricity; the bottom point z_g below the axis moves
                # sideways with the tilt, shortening the lever
                mdrop += f * (drop_e - zg * th)
        m = mb + mw
        mrec = mw
        if ms > 1:
            # the truth's mass as the fixed steps record it: at the start of the step that ends at t1
            mrec = 0.0
            tr = t1 - dt
            for p in range(W.shape[0]):
                ta = W[p, W_START] + W[p, W_DELAY]
                if tr > ta:
                    mrec += W[p, W_RATE_KG_S] * min(tr - ta, W[p, W_DUR])
            S[S_MASS] = mb + mrec + mland
        else:
            S[S_MASS] = m + mland
        wload = m * geff + fjet + fspl + fdrop
        # on the shoulder the three normal forces lean along the axis and push the bottle out of the grasp
        if taper > 0.0 and shl > 0.0 and not fallen:
            wload += 3.0 * nc * taper_sin
        # recorded with the mass recorded (the splash and the drops' forces: the step's)
        S[S_LOAD] = wload if ms == 1 else wload + (mrec - mw) * g
        # ---- the slosh (sideways): slosh mass m1 on the spring m1 k tanh(k h) (g - a) and damper c1,
        # tied to the bottle, which the grasp holds sideways; the jet's force drives the mode (equal and
        # opposite on the bottle: a vertical jet gives the pair no sideways momentum)
        # the digits' motor forces, radial at 0, 120 and 240 degrees from the accelerometer's x axis
        flat = S[S_FM0] - 0.5 * (S[S_FM0 + 1] + S[S_FM0 + 2]) if (moving and nc > 0.0) else 0.0
        if S[S_M1] > 0.0 and not fallen:
            m1 = S[S_M1]
            du = v1 - vb
            fs = m1 * S[S_KTH] * (g - a_prev) * (y1 - yb) + S[S_C1] * du
            fq = S[S_BETA] * (fjet + fspl)
            S[S_FWAT] = fs - fq
            ab = (fs - fq + flat - klat * yb - clat * vb) / (m + mland - m1)
            v1 += (fq - fs) / m1 * h
            y1 += v1 * h
            vb += ab * h
            yb += vb * h
            S[S_V1] = v1
            S[S_Y1] = y1
            S[S_VB] = vb
            S[S_YB] = yb
            S[S_ALAT] = ab
        elif (flat != 0.0 or vb != 0.0 or yb != 0.0) and not fallen:
            # no water: the bottle alone on the grasp's sideways stiffness
            ab = (flat - klat * yb - clat * vb) / (m + mland)
            vb += ab * h
            yb += vb * h
            if abs(yb) < 1e-15 and abs(vb) < 1e-12:
                yb = 0.0
                vb = 0.0
            S[S_VB] = vb
            S[S_YB] = yb
            S[S_ALAT] = ab
            S[S_FWAT] = 0.0
        else:
            S[S_ALAT] = 0.0
            S[S_FWAT] = 0.0
        # ---- bottle
        a = 0.0
        if S[S_SUPPORTED] > 0.0:
            S[S_FT] = 0.0
        elif fallen:
            a = wload / m
            v += a * h
            x += v * h
            S[S_FT] = 0.0
        else:
            # thumb and index pads with the same constants see the same x, v and N, so they
            # evolve identically: compute the thumb's and copy it (P_PADS_SAME)
            # the tilt: each contact's point moves down by its lever times the tilt (the tilt moves only
            # when tilted or pushed: a bottle that never tilts runs the same arithmetic as without it)
            tilt_now = tilted or mdrop != 0.0
            same = P[P_PADS_SAME] > 0.0 and not tilt_now
            ftot = 0.0
            mom = 0.0
            for i in range(3):
                bs = S_C0 + i * SC_SIZE
                if i == 1 and same:
                    ftot += S[S_C0 + SC_FT]
                    continue
                bp = P_C0 + i * PC_SIZE
                xi = x
                vi = v
                if tilt_now:
                    lv = P[P_LEVER0 + i]
                    xi = x + lv * th
                    vi = v + lv * om
                if P[bp + PC_LAW] == LAW_RATE_STATE:
                    hdec = P[bp + PC_HEAL_DECAY]
                    if ms > 1 and S[bs + SC_PHI] < 1.0:
                        hdec = (P[P_HEAL_DECAY_H + i * (ALPHA_STEPS + 1) + ms] if ms <= ALPHA_STEPS
                                else np.exp(-h / P[bp + PC_HEAL]))
                    F, s_new, w, z, d, phi, it, ok = _rs_contact(
                        P[bp + PC_KT], P[bp + PC_CT], S[bs + SC_S], P[bp + PC_MUS], P[bp + PC_MUK], S[bs + SC_PHI],
                        S[bs + SC_Z], S[bs + SC_W], P[bp + PC_A], P[bp + PC_V0], P[bp + PC_DC], P[bp + PC_HEAL],
                        hdec, xi, vi, nc, h, dt)
                    S[bs + SC_S] = s_new
                    S[bs + SC_Z] = z
                    if d != 0.0:
                        S[bs + SC_DIR] = d
                    S[bs + SC_STUCK] = 1.0 if d == 0.0 else 0.0
                    S[bs + SC_PHI] = phi
                    S[bs + SC_W] = w
                    if it > C[C_NITER]:
                        C[C_NITER] = it
                    if not ok:
                        C[C_NFAIL] += 1
                else:
                    F, stk, d, w = _coulomb_contact(P[bp + PC_KT], P[bp + PC_CT], S[bs + SC_S], P[bp + PC_MUS],
                                                    P[bp + PC_MUK], P[bp + PC_VS], S[bs + SC_STUCK],
                                                    S[bs + SC_DIR], S[bs + SC_W], xi, vi, nc)
                    S[bs + SC_STUCK] = stk
                    S[bs + SC_DIR] = d
                    S[bs + SC_W] = w
                S[bs + SC_FT] = F
                ftot += F
                if tilt_now:
                    mom -= F * P[P_LEVER0 + i]
            a = (wload - ftot) / m
            v += a * h
            x += v * h
            th_old = th
            if tilt_now:
                # the contacts' tangential forces at their levers (each bounded by its friction: together
                # the friction couple), the drop's eccentric force and gravity on the centre of mass below
                # the axis (restoring) turn the bottle about the axis
                inertia, mgd = tilt_inertia(mw, P)
                om += (mom + mdrop - g * mgd * th) / inertia * h
                th += om * h
            sliding = True
            s_mean = 0.0
            w_min = np.inf
            for i in range(3):
                if i == 1 and same:
                    for j in range(SC_SIZE):
                        S[S_C0 + SC_SIZE + j] = S[S_C0 + j]
                bs = S_C0 + i * SC_SIZE
                bp = P_C0 + i * PC_SIZE
                if not (i == 1 and same) and P[bp + PC_LAW] != LAW_RATE_STATE and S[bs + SC_STUCK] == 0.0:
                    lv = P[P_LEVER0 + i] if tilt_now else 0.0
                    s_new, stk, w = _coulomb_post(S[bs + SC_FT], P[bp + PC_KT], P[bp + PC_DECAY], S[bs + SC_S],
                                                  S[bs + SC_DIR], x_old + lv * th_old, x + lv * th, dt)
                    S[bs + SC_S] = s_new
                    S[bs + SC_STUCK] = stk
                    S[bs + SC_W] = w
                if S[bs + SC_STUCK] > 0.0:
                    sliding = False
                s_mean += S[bs + SC_S] / 3.0
                if S[bs + SC_W] < w_min:
                    w_min = S[bs + SC_W]
            if sliding and S[S_STUCK] > 0.0:
                ev_out[nev, 0] = t0
                ev_out[nev, 1] = E_ONSET
                ev_out[nev, 2] = x_old
                nev += 1
            elif not sliding and S[S_STUCK] == 0.0:
                ev_out[nev, 0] = t1
                ev_out[nev, 1] = E_STICK
                ev_out[nev, 2] = x
                nev += 1
            # the pads' micro-slip events: a Poisson process of rate w / D_c while a pad slides, each releasing
            # ms_eta of the static-to-kinetic drop (mu_s - mu_k) N of sensed shear into the pad's resonator
            if ms_eta > 0.0 and (ringing or S[S_C0 + SC_STUCK] == 0.0 or S[S_C0 + SC_SIZE + SC_STUCK] == 0.0):
                ringing = False
                for i in range(2):
                    bs = S_C0 + i * SC_SIZE
                    bp = P_C0 + i * PC_SIZE
                    iy = S_VY0 + 2 * i
                    vy = S[iy]
                    vv = S[iy + 1]
                    if S[bs + SC_STUCK] == 0.0 and S[bs + SC_W] > 0.0:
                        if _uniform(key6, 2 * n + i) < S[bs + SC_W] * dt * ms_per_m:
                            vv -= S[bs + SC_DIR] * ms_eta * (P[bp + PC_MUS] - P[bp + PC_MUK]) * nc * ms_w
                            C[C_MS0 + i] += 1
                    if vv != 0.0 or vy != 0.0:
                        vv -= (ms_w2 * vy + ms_2zw * vv) * dt
                        vy += vv * dt
                        if abs(vy) < 1e-12 and abs(vv) < 1e-9:
                            vy = 0.0
                            vv = 0.0
                        S[iy] = vy
                        S[iy + 1] = vv
                        if vy != 0.0:
                            ringing = True
            S[S_STUCK] = 0.0 if sliding else 1.0
            S[S_S] = s_mean
            S[S_W] = w_min if sliding else 0.0
            S[S_FT] = ftot
            # the contacts are lost where the shoulder has taken up the fingertips' travel (a contact past
            # grip_travel without a shoulder); tilted, by the contacts' own positions
            if tilt_now:
                shl, xmax = _shoulder(x, th, lev0, lev1, lev2, grip)
                lost = taper * shl > pen_full if taper > 0.0 else xmax > grip
            else:
                lost = (x > grip + pen_full / taper) if taper > 0.0 else (x > grip)
            if lost:
                S[S_FALLEN] = 1.0
                S[S_TFALL] = t1
                S[S_STUCK] = 0.0
                for i in range(3):
                    S[S_C0 + i * SC_SIZE + SC_STUCK] = 0.0
                    S[S_C0 + i * SC_SIZE + SC_FT] = 0.0
                ev_out[nev, 0] = t1
                ev_out[nev, 1] = E_FALLEN
                ev_out[nev, 2] = x
                nev += 1
        S[S_X] = x
        S[S_V] = v
        S[S_A] = a
        S[S_TH] = th
        S[S_OM] = om
        a_prev = a
        # the IMU's DLPF states; flushed to zero below 1e-200 m/s^2 (they decay toward an exact zero at rest
        # and would otherwise sit in the subnormal range, where every step's arithmetic is slow)
        # (the IMU reads the bottle's acceleration in the world: the grip's added)
        af = S[S_AF] + ((a + gacc if gacc != 0.0 else a) - S[S_AF]) * alpha_h
        S[S_AF] = af if abs(af) > 1e-200 else 0.0
        # the accelerometer's x axis (radial at the thumb, 30 degrees off the normal of the tilt axis) also
        # reads gravity tilted with the bottle
        afl = S[S_AFL] + (S[S_ALAT] + (_COS30 * g * th if th != 0.0 and not fallen else 0.0) - S[S_AFL]) * alpha_h
        S[S_AFL] = afl if abs(afl) > 1e-200 else 0.0
        # ---- accelerometer ticks (own ODR)
        while C[C_ACC] * acc_t <= t1 + 1e-12:
            j = C[C_ACC]
            # a DAQ row carries the latest reading: with adaptive steps only the readings a row will carry are
            # drawn (the last before each row; the others would be overwritten unseen: the same rows)
            seen = True
            if coarse > 1:
                if C[C_DAQ] != daq_at:
                    daq_at = C[C_DAQ]
                    daq_end = _fire_end(daq_at * daq_t, dt)
                    seen_j = np.int64(np.floor((daq_end * dt + 1e-12) / acc_t)) + 1
                    while seen_j >= 0 and _fire_end(seen_j * acc_t, dt) > daq_end:
                        seen_j -= 1
                    seen_end = _fire_end(seen_j * acc_t, dt)
                # the reading the next row carries is the last taken by the row's step
                seen = j == seen_j
            if not seen:
                S[S_AFRESH] = 1.0
                C[C_ACC] = j + 1
                continue
            spec = 1.0 - S[S_AF] / g
            lsb = P[P_ACC_LSB]
            rng = P[P_ACC_RANGE]
            # the slosh shakes the bottle sideways along the accelerometer's x axis (the jet's offset)
            S[S_AX] = _quant_g(P[P_TILT_X] * spec + S[S_AFL] / g + P[P_ACC_NOISE] * normal(key1, 3 * j), lsb, rng)
            S[S_AY] = _quant_g(P[P_TILT_Y] * spec + P[P_ACC_NOISE] * normal(key1, 3 * j + 1), lsb, rng)
            S[S_AZ] = _quant_g(P[P_TILT_Z] * spec + P[P_ACC_NOISE] * normal(key1, 3 * j + 2), lsb, rng)
            S[S_AFRESH] = 1.0
            C[C_ACC] = j + 1
        # ---- DAQ ticks (slip sensor, flow, latest accel)
        while C[C_DAQ] * P[P_DAQ_T] <= t1 + 1e-12 and nd < cap_daq:
            k = C[C_DAQ]
            tk = k * P[P_DAQ_T]
            frac = (tk - t0) / h
            if frac < 0.0:
                frac = 0.0
            xk = x_old + frac * (x - x_old)
            # in contact the middle fingertip turns as far as it advances into the wall (the cuff's
            # compression and the wall's dent under N), rolling the spot over the surface, and the dent
            # opens the sensor's gap where the spot sits beside the cuff's contact
            spot = xk
            extra = (P[P_QC] - S[S_Q0 + 2]) * P[P_LAM]
            if nc > 0.0:
                dent = _wall_dent(nc, n1w, n2w, P[P_WALL_KW_INV], P[P_WALL_KW2_INV], P[P_WALL_DLIN],
                                  P[P_WALL_DCOL])
                spot += P[P_SPOT_K] * (nc * P[P_CUFF_INV] + dent) / lam
                extra = P[P_DENT_FRAC] * dent
            daq_out[nd, O_T] = tk
            if S[S_FALLEN] > 0.0:
                rho = 0.0
                extra = 0.0
            else:
                ti, fr = _track_at(spot, P[P_TRACK_OFF], P[P_TRACK_DX], track.shape[0])
                rho = track[ti] + fr * (track[ti + 1] - track[ti])
            daq_out[nd, O_VOLTS] = _sensor_volts(rho, extra, P[P_GAP], P[P_VCC], P[P_VSAT], P[P_KNEE],
                                                 P[P_VNOISE], key0, k, P[P_ADC_LSB], P[P_ADC_MAX])
            daq_out[nd, O_AX] = S[S_AX]
            daq_out[nd, O_AY] = S[S_AY]
            daq_out[nd, O_AZ] = S[S_AZ]
            daq_out[nd, O_AFRESH] = S[S_AFRESH]
            S[S_AFRESH] = 0.0
            # litres through the flow sensor at tk (the pumps start at W_START; written out, not in a helper:
            # an inlined helper taking W would cost a reference count per row)
            litres = 0.0
            for p in range(W.shape[0]):
                if tk > W[p, W_START]:
                    litres += W[p, W_RATE_L_S] * min(tk - W[p, W_START], W[p, W_DUR])
            daq_out[nd, O_PULSES] = np.floor(P[P_FLOW_K] * litres + P[P_FLOW_PHASE]) if litres > 0.0 else 0.0
            daq_out[nd, O_X] = xk
            daq_out[nd, O_V] = v
            daq_out[nd, O_S] = S[S_S]
            daq_out[nd, O_STUCK] = S[S_STUCK]
            daq_out[nd, O_NC] = nc
            daq_out[nd, O_MASS] = S[S_MASS]
            daq_out[nd, O_Q0] = S[S_Q0]
            daq_out[nd, O_Q1] = S[S_Q0 + 1]
            daq_out[nd, O_Q2] = S[S_Q0 + 2]
            daq_out[nd, O_FALLEN] = S[S_FALLEN]
            daq_out[nd, O_A] = a
            daq_out[nd, O_ALAT] = S[S_ALAT]
            daq_out[nd, O_LOAD] = S[S_LOAD]
            daq_out[nd, O_FWAT] = S[S_FWAT]
            nd += 1
            C[C_DAQ] = k + 1
        # ---- tactile snapshots
        for si in range(nsamp):
            while tac_next[si] <= (t1 + 1e-12) * tac_rates[si] and ntac < cap_tac:
                tac_out[ntac, T_ID] = si
                tac_out[ntac, T_IDX] = tac_next[si]
                tac_out[ntac, T_T] = tac_next[si] / tac_rates[si]
                bc = S_C0 + tac_contact[si] * SC_SIZE
                tac_out[ntac, T_NC] = nc + S[S_FM0 + tac_contact[si]] if nc > 0.0 else nc
                fsen = _sensed_shear(S[bc + SC_FT], nc, S[bc + SC_PHI], P, tac_contact[si], inc) + (
                    S[S_VY0 + 2 * tac_contact[si]] if tac_contact[si] < 2 else 0.0)
                # the pad's surface carries at most the Cattaneo-Mindlin shear of full slip, 1.5 mu_s N (the
                # ringing of earlier events cannot outlast the normal force that carried it)
                fmax = 1.5 * P[P_C0 + tac_contact[si] * PC_SIZE + PC_MUS] * nc
                tac_out[ntac, T_FT] = min(max(fsen, -fmax), fmax)
                tac_out[ntac, T_S] = S[bc + SC_S]
                tac_out[ntac, T_FALLEN] = S[S_FALLEN]
                tac_out[ntac, T_W] = S[bc + SC_W] if S[bc + SC_STUCK] == 0.0 else 0.0
                tac_out[ntac, T_MS] = C[C_MS0 + tac_contact[si]] if tac_contact[si] < 2 else 0.0
                ntac += 1
                tac_next[si] += 1
        n += ms
        C[C_STEPS] += 1
    C[C_N] = n
    C[C_DAQ_AT1] = daq_at + 1
    C[C_DAQ_END] = daq_end
    C[C_SEEN_J] = seen_j
    C[C_SEEN_END] = seen_end
    counts[0] = nd
    counts[1] = ntac
    counts[2] = nev


@njit(cache=CACHE)
def tactile_frames(snap, key, gain0, patch_sigma, shear_shift, noise, resolution, alpha, hyst, drift, state,
                   out):
    """Build ``(4, 4)`` frames (N per taxel) from tactile snapshots of one contact.

    ``snap`` rows are (id, index, t, N_c, F_t, s, fallen, w). The pressure
    patch is a Gaussian of ``patch_sigma`` taxels carrying ``N_c``, centred
    on the array and shifted along the bottle axis by ``shear_shift * F_t /
    N_c`` (the pad's shear). Each taxel then goes through the sensor (the
    array's sensitivity ``gain0``): a
    first-order low-pass (``alpha`` per frame), a play of half-width
    ``hyst`` (hysteresis), a creep gain ``1 + drift log10(1 + t)``, noise
    (stream ``key``, eight Box-Muller pairs per frame index), quantization and
    clipping at 0.
    ``state`` (2, 4, 4) holds the low-pass and play outputs between calls
    (NaN: start from the first frame).
    """
    inv2s2 = 1.0 / (2.0 * patch_sigma * patch_sigma)
    ex = np.empty(4)   # the patch is separable: its profile across the axis does not move
    ey = np.empty(4)
    sx = 0.0
    for a in range(4):
        ex[a] = np.exp(-(a - 1.5) * (a - 1.5) * inv2s2)
        sx += ex[a]
    inv_res = 1.0 / resolution if resolution > 0.0 else 0.0
    for r in range(snap.shape[0]):
        nc = snap[r, T_NC]
        idx = np.int64(snap[r, T_IDX])
        if nc > 0.0 and snap[r, T_FALLEN] == 0.0:
            tot = nc
            cy = 1.5 + shear_shift * snap[r, T_FT] / nc
        else:
            tot = 0.0
            cy = 1.5
        sy = 0.0
        for b in range(4):
            ey[b] = np.exp(-(b - cy) * (b - cy) * inv2s2)
            sy += ey[b]
        scale = tot / (sx * sy) if sy > 0.0 else 0.0   # a patch shifted far off the array (all terms underflow)
        gain = gain0 * (1.0 + drift * np.log10(1.0 + snap[r, T_T]))
        for b in range(4):
            for a2 in range(2):
                # one Box-Muller pair (stream key, pair idx * 8 + b * 2 + a2) serves two taxels
                n0, n1 = normal_pair(key, idx * 8 + b * 2 + a2)
                for k in range(2):
                    a = 2 * a2 + k
                    f = scale * ex[a] * ey[b]
                    if np.isnan(state[0, b, a]):
                        state[0, b, a] = f
                        state[1, b, a] = f
                    lp = state[0, b, a] + alpha * (f - state[0, b, a])
                    hy = state[1, b, a]
                    if hy < lp - hyst:
                        hy = lp - hyst
                    elif hy > lp + hyst:
                        hy = lp + hyst
                    state[0, b, a] = lp
                    state[1, b, a] = hy
                    y = hy * gain + noise * (n0 if k == 0 else n1)
                    if resolution > 0.0:
                        y = np.floor(y * inv_res + 0.5) * resolution
                    if y < 0.0:
                        y = 0.0
                    out[r, b, a] = y


@njit(cache=CACHE)
def volts_along(P, track, keys, positions, out):
    """Slip-sensor volts at surface positions (sample k uses noise number k); for the scan."""
    for k in range(positions.shape[0]):
        ti, fr = _track_at(positions[k], P[P_TRACK_OFF], P[P_TRACK_DX], track.shape[0])
        rho = track[ti] + fr * (track[ti + 1] - track[ti])
        out[k] = _sensor_volts(rho, P[P_QC] * P[P_LAM], P[P_GAP], P[P_VCC], P[P_VSAT], P[P_KNEE],
                               P[P_VNOISE], keys[0], k, P[P_ADC_LSB], P[P_ADC_MAX])
