"""The rig's kernel parameter vector, filled from its bottle, hand, sensors and physics.

:func:`rig_params` is what :class:`slipreflex.sim.Rig` runs once when it is made;
:func:`fill_slip_sensor_params` is the part the scan (:mod:`slipreflex.sim.scan`) also uses.

Examples
--------
>>> from slipreflex.sim import Rig
>>> bool(rig_params(Rig("DK"), 450.0, 0.5)[K.P_MB] == Rig("DK").bottle.mass_kg)
True
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from scipy.special import j1

from ..core import hardware as hw
from . import kernel as K
from .contacts import fill_contact_params
from .objects import WATER_DENSITY
from .params import SLOSH_ROOT, WATER_KINEMATIC_VISCOSITY, SlipSensorParams
from .sensors import Track
from .stepping import COARSE_STEP_S

if TYPE_CHECKING:
    from .rig import Rig

__all__ = ["rig_params", "water_params", "fill_slip_sensor_params"]

_SPLASH_GRID_S = 1e-3  # the splash noise is drawn every 1 ms (independent of dt) and interpolated


def fill_slip_sensor_params(P: np.ndarray, sensor: SlipSensorParams, track: Track) -> np.ndarray:
    """Write the slip sensor's constants and its track into a kernel parameter vector.

    The one place that maps :class:`SlipSensorParams` and a :class:`Track` onto the
    kernel's slots; the rig and the scan both use it.

    Examples
    --------
    >>> from slipreflex.sim.sensors import Track
    >>> import numpy as np
    >>> P = fill_slip_sensor_params(np.zeros(K.P_SIZE), SlipSensorParams(),
    ...                             Track(np.zeros(4), 5e-6, 0.0))
    >>> float(P[K.P_VCC])
    5.0
    """
    P[K.P_VCC] = sensor.supply_v
    P[K.P_VSAT] = sensor.v_sat
    P[K.P_KNEE] = sensor.knee_v
    P[K.P_VNOISE] = sensor.noise_v
    P[K.P_GAP] = sensor.gap_m
    P[K.P_DENT_FRAC] = sensor.gap_dent_fraction
    P[K.P_ADC_LSB] = hw.ADC_LSB
    P[K.P_ADC_MAX] = (1 << hw.ADC_BITS) - 1
    P[K.P_TRACK_DX] = track.dx
    P[K.P_TRACK_OFF] = track.origin
    return P


def rig_params(rig: Rig, flow_k: float, flow_phase: float) -> np.ndarray:
    """The kernel parameter vector of ``rig``: its bottle, hand, sensors and physics, checked complete.

    ``flow_k`` and ``flow_phase`` are the flow sensor's drawn K factor and pulse phase.

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> P = rig_params(Rig("TR"), 450.0, 0.0)
    >>> float(P[K.P_FLOW_K])
    450.0
    """
    b, h, s, imu, ph = rig.bottle, rig.hand_params, rig.slip_sensor, rig.imu, rig.physics
    P = K.PARAMS.new()   # NaN until filled: checked complete below
    P[K.P_DT] = ph.dt
    P[K.P_COARSE] = 1
    P[K.P_G] = hw.GRAVITY
    P[K.P_MB] = b.mass_kg
    fill_contact_params(P, h, b, ph.dt)
    P[K.P_SPOT_K] = h.spot_travel_per_unit_m
    P[K.P_LAM] = h.travel_per_unit_m
    P[K.P_QC] = (h.aperture_radius_m - b.diameter_m / 2.0) / h.travel_per_unit_m
    P[K.P_KSERVO] = h.servo_gain
    P[K.P_STALL] = h.stall_force_n
    P[K.P_DROOP] = h.motor_droop
    tp = rig.tactile_params
    w = 2.0 * math.pi * tp.slip_vibration_hz
    P[K.P_MS_ETA] = tp.slip_events
    P[K.P_MS_PER_M] = 1.0 / b.slip_distance_m
    P[K.P_MS_W2] = w * w
    P[K.P_MS_2ZW] = 2.0 * tp.slip_vibration_zeta * w
    P[K.P_MS_W] = w
    P[K.P_INCIPIENT] = tp.incipient_slip
    P[K.P_MV_F] = h.motor_vibration_n
    P[K.P_MV_W] = 2.0 * math.pi * h.motor_vibration_hz
    P[K.P_MV_INV_SPEED] = 1.0 / h.speed_units_s
    P[K.P_TAPER] = b.shoulder_slope
    P[K.P_TAPER_SIN] = b.shoulder_slope / math.sqrt(1.0 + b.shoulder_slope ** 2)
    P[K.P_GRIP] = b.grip_travel_m
    # the tilt about the horizontal axis through the grasp's centre and the middle finger's contact (the
    # stiff cuff on the axis: the softest of the tripod's tilts); thumb and index 120 degrees either side
    r, zg, hb = b.diameter_m / 2.0, b.grasp_height_m, b.height_m
    P[K.P_LEVER0:K.P_LEVER0 + 3] = (r * math.sqrt(3.0) / 2.0, -r * math.sqrt(3.0) / 2.0, 0.0)
    P[K.P_ZG] = zg
    # the empty bottle as a thin-walled cylinder: about its centre m (R^2 / 2 + H^2 / 12), moved to the axis
    P[K.P_IB] = b.mass_kg * (r * r / 2.0 + hb * hb / 12.0 + (zg - hb / 2.0) ** 2)
    P[K.P_MBD] = b.mass_kg * (zg - hb / 2.0)
    P[K.P_DROP_E] = b.drop_eccentricity_m
    P[K.P_TILT_PEN] = float(sum(P[K.P_LEVER0 + i] ** 2 for i in range(3))) / (3.0 * r)
    P[K.P_DAQ_T] = hw.DAQ_PERIOD_S
    P[K.P_ACC_T] = 1.0 / imu.fs
    P[K.P_ACC_ALPHA] = 1.0 - math.exp(-2.0 * math.pi * imu.dlpf_hz * ph.dt)
    P[K.P_ACC_NOISE] = imu.noise_g
    P[K.P_ACC_LSB] = 1.0 / imu.lsb_per_g
    P[K.P_ACC_RANGE] = imu.range_g
    tx, tz = math.radians(imu.tilt_x_deg), math.radians(imu.tilt_z_deg)
    P[K.P_TILT_X] = math.sin(tx)
    P[K.P_TILT_Z] = math.cos(tx) * math.sin(tz)
    P[K.P_TILT_Y] = math.cos(tx) * math.cos(tz)
    fill_slip_sensor_params(P, s, rig.track)
    P[K.P_FLOW_K] = flow_k
    P[K.P_FLOW_PHASE] = flow_phase
    water_params(rig, P)
    kts = [P[K.P_C0 + i * K.PC_SIZE + K.PC_KT] for i in range(3)]
    P[K.P_KT_SUM] = sum(kts)
    P[K.P_TILT_K] = sum(k * P[K.P_LEVER0 + i] ** 2 for i, k in enumerate(kts))
    if rig.stepping == "adaptive":
        P[K.P_COARSE] = rig.coarse_steps(P)
        # a filling bottle's modes slow down and its steps may grow (kernel.mass_cap), with rate-and-state
        # contacts only: their stuck pads' predictor keeps the fine step's damping in a long step, the
        # Coulomb contact's explicit update has none (with steps past the empty bottle's bound a stuck
        # Coulomb pad slipped under a pour's splash where the fixed steps' did not)
        rate_state = all(P[K.P_C0 + i * K.PC_SIZE + K.PC_LAW] == K.LAW_RATE_STATE for i in range(3))
        P[K.P_COARSE_MAX] = max(P[K.P_COARSE], int(COARSE_STEP_S / ph.dt + 1e-9)) if rate_state else P[K.P_COARSE]
    K.fill_step_tables(P)
    return K.PARAMS.check(P)


def water_params(rig: Rig, P: np.ndarray) -> None:
    """Write the water's splash and slosh constants (:class:`WaterParams`) and the grasp's sideways stiffness.

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> P = K.PARAMS.new(); rig = Rig("TR"); P[:] = rig.kernel_arrays().P
    >>> water_params(rig, P); float(P[K.P_SPL_DT])
    0.001
    """

    w, r = rig.water, rig.bottle.diameter_m / 2.0
    P[K.P_SPL_RMS] = w.splash_rms
    P[K.P_SPL_DT] = _SPLASH_GRID_S
    P[K.P_SPL_INV] = 1.0 / _SPLASH_GRID_S
    rho = math.exp(-2.0 * math.pi * w.splash_corner_hz * _SPLASH_GRID_S)
    P[K.P_SPL_RHO] = rho
    P[K.P_SPL_SIG] = math.sqrt(1.0 - rho * rho)
    P[K.P_SLOSH_R] = r
    P[K.P_ZETA0] = K.slosh_zeta0(r, WATER_KINEMATIC_VISCOSITY, hw.GRAVITY, w.slosh_damping_factor)
    P[K.P_PHIJ] = float(j1(SLOSH_ROOT * w.jet_offset_m / r) / j1(SLOSH_ROOT))
    P[K.P_RHO_W] = WATER_DENSITY
    # sideways, three contacts 120 degrees apart: their normal stiffness (k_n, mean cos^2 = 1/2) and
    # their shear stiffness along the circumference (mean sin^2 = 1/2)
    kt = sum(P[K.P_C0 + i * K.PC_SIZE + K.PC_KT] for i in range(3))
    ct = sum(P[K.P_C0 + i * K.PC_SIZE + K.PC_CT] for i in range(3))
    P[K.P_KLAT] = 1.5 * P[K.P_KN] + 0.5 * kt
    P[K.P_CLAT] = 0.5 * ct
