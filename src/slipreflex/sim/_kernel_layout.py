"""The physics kernel's vectors: every slot of the state, counters, parameters, loads and output rows, named once.

Internal module (:mod:`slipreflex.sim.kernel` re-exports every name). Each flat
float64 (or int64) vector the kernels take is a :class:`~slipreflex.core._slots.Layout`;
the constants (``S_X``, ``P_KN``, ...) are bound from it, and numba compiles them
into every kernel that reads them (each kernel module declares this file in its
cache stamp, :func:`slipreflex.core._numba_cache.stamped_cache`).
"""

from __future__ import annotations

import math

import numpy as np

from ..core import _slots
from ..core._numba_cache import stamped_cache
from ..core._slots import Layout

# no kernel here, but every kernel compiles in these constants, which Layout numbers: a kernel that declares
# this file is stamped with _slots.py too
stamped_cache(__file__, _slots.__file__)

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
# the slosh mode last followed (:func:`~slipreflex.sim.kernel.mass_cap`; 0 before any water: ``P_COARSE``).
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
