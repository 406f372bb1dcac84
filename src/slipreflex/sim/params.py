"""Model constants of the simulated rig, each with where it came from.

Hardware facts shared with the rest of the package (sampling rate, ADC,
finger range, tactile shape, 0.8 N contact force, flow-sensor pulses per
litre, gravity) live in :mod:`slipreflex.core.hardware` and are imported, not
repeated. This module holds what only the simulator needs, grouped into
frozen dataclasses that validate themselves; a :class:`~slipreflex.sim.Rig`
takes one of each, so any of them can be changed per rig without editing
the package.

Sources are marked in each field's description:

* **datasheet**: the part's datasheet (OPR5005, MPU6050, YF-S201);
* **paper**: the paper or the docs/method.md;
* **estimate**: a physical estimate, with the reason given.

Examples
--------
>>> from slipreflex.sim.params import HandParams
>>> HandParams().speed_units_s
625.0
>>> HandParams(latency_s=-1)
Traceback (most recent call last):
...
slipreflex.core.errors.ParameterError: HandParams.latency_s must be a finite number >= 0, got -1
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core import hardware as hw
from ..core.errors import ParameterError
from ..core.validation import positive, set_field

__all__ = ["HandParams", "SlipSensorParams", "ImuParams", "TactileParams", "FlowParams", "PhysicsParams", "WaterParams",
           "WATER_KINEMATIC_VISCOSITY", "SLOSH_ROOT"]


#: Kinematic viscosity of water at 20 C (m^2/s): 1.004e-6 (CRC Handbook of Chemistry and Physics).
WATER_KINEMATIC_VISCOSITY: float = 1.004e-6
#: First zero of J1' (Abramowitz & Stegun, table 9.5): the first antisymmetric slosh mode of an
#: upright cylinder of radius R has the wave number 1.8412 / R (Ibrahim 2005, Liquid Sloshing Dynamics, ch. 2).
SLOSH_ROOT: float = 1.8411837813406593


def _validate(obj: object, zero_ok: tuple[str, ...] = ()) -> None:
    """Every field a finite number > 0 (>= 0 for ``zero_ok``), stored as a float (the one validator)."""
    cls = type(obj).__name__
    for name in obj.__dataclass_fields__:  # type: ignore[attr-defined]
        set_field(obj, name, positive(f"{cls}.{name}", getattr(obj, name), zero_ok=name in zero_ok))


@dataclass(frozen=True, slots=True)
class HandParams:
    """The i-Limb fingers of the tripod grasp and their fingertip pads.

    Parameters
    ----------
    speed_units_s : float
        Servo speed limit (position units/s): an i-Limb digit closes fully
        (0 -> 500) in about 0.8 s (manufacturer; Belter et al. 2013, J
        Rehabil Res Dev 50(5)), so 625 units/s
        (:data:`slipreflex.core.hardware.FINGER_SPEED_UNITS_S`).
    latency_s : float
        Command latency (s): a 15-byte packet at 115200 baud takes 1.3 ms,
        the prosthesis control unit and the digit controller add a few ms;
        estimate 10 ms.
    servo_gain : float
        Proportional gain of the digit position loop (1/s) below the speed
        limit: estimate 40/s, a 25 ms time constant, so a small step settles
        in ~0.1 s like a geared DC motor under position control.
    travel_per_unit_m : float
        Fingertip travel toward the bottle axis per position unit (m).
        Estimate: the distal pad of a 9 cm digit sweeps ~10 cm radially over
        0..500, so 0.2 mm per unit.
    aperture_radius_m : float
        Radius (m) of the circle through the three fingertips at position 0.
        Estimate: the open i-Limb takes objects up to ~12 cm wide, so 6 cm.
    pad_normal_stiffness_n_m : float
        Normal stiffness (N/m) of a silicone fingertip pad at about 1 N: a
        2-3 mm pad compresses ~0.3 mm per newton (estimate from silicone of
        Shore 20-40 A), 3000 N/m.
    finger_stiffness_n_m : float
        Structural stiffness (N/m) of a digit (worm-geared, non back-drivable):
        estimate 20000 N/m. In series with the pad and the bottle wall.
    pad_shear_stiffness_n_m : float
        Tangential stiffness (N/m) of one pad: G A / h with G ~ 0.2 MPa,
        contact area ~20 mm^2 and 2 mm thickness gives 2000 N/m (estimate).
    pad_shear_damping_n_s_m : float
        Tangential damping (N s/m) of one pad: estimate 1.0, a loss factor of
        about 0.2 at the grasp's ~60 Hz stick resonance.
    cuff_normal_stiffness_n_m : float
        Normal stiffness (N/m) of the middle finger's rigid 3D-printed cuff,
        which touches the bottle instead of a pad: estimate 20000 N/m (a
        1-2 mm PLA shell); in series with the finger and the bottle wall.
    cuff_shear_stiffness_n_m, cuff_shear_damping_n_s_m : float
        Tangential stiffness (N/m) and damping (N s/m) of the cuff contact:
        the digit's own bending along the bottle axis, estimate 10000 N/m
        and 1 N s/m.
    spot_travel_per_unit_m : float
        How far (m) the slip sensor's spot moves over the bottle surface per
        position unit the middle fingertip advances into the wall (its
        cuff's compression and the wall's dent: in contact the digit turns
        only as far as the wall yields; the distal segment turns ~180
        degrees over 0..500, 0.0063 rad per unit). The sensor looks at the
        wall perpendicularly through the cuff's 3 mm gap (paper II-B, II-D).
        While the cuff does not slide on the wall, the cuff's turn is a
        rotation about a point of the wall's surface: about the stuck contact
        if it pivots, about the instantaneous contact if its face rolls
        (rolling without slip puts the instantaneous centre of rotation at
        the contact point). A rotation ``omega`` about a point of the
        surface moves the cuff's points on that surface normal to it, and the
        sight line's turn shifts its foot by its height above the surface
        (zero), so the spot's speed along the surface is zero to first order
        in the turn, whatever the face's shape or the spot's offset ``e``
        from the contact (the bottle's curvature adds ``e^2 / (2 R)`` per
        radian, under 1 um per unit for ``e`` = 3 mm). Only sliding of the
        cuff over the wall moves the spot at first order: 0 here (the cuff's
        contact is stuck while the grip holds), up to ~40 um per unit in the
        study if the cuff slides as the tip sweeps. Estimate from rigid-body
        kinematics; an earlier 19 um took the rolling contact point's advance
        (3 mm face radius x 0.0063) for the spot's.
    stall_force_n : float
        Normal force (N) at which a digit's motor stalls and stops advancing:
        the i-Limb's whole-hand grip is 100-136 N (Belter et al. 2013, J
        Rehabil Res Dev 50(5)), the thumb against four fingers, so 25-34 N
        per finger digit; 25 N.
    motor_droop : float
        The digit's DC motor slows as it loads (its torque-speed line): the
        closing speed limit is ``speed (1 - motor_droop N / stall_force_n)``,
        so a closing digit approaches its stall force exponentially instead
        of at full speed. 1 is the DC motor's straight line (a brushed DC
        motor's speed falls linearly from no-load to stall at constant
        voltage); 0 keeps full speed up to the stall.
    motor_vibration_n, motor_vibration_hz : float
        The digit motor's vibration at full speed, a force on the digit's
        contact (N amplitude) at the motor's rotation frequency (Hz); both
        scale with the digit's speed (rotor unbalance: ``F = m_r G omega``
        for a balance grade ``G``). Estimate: a ~3 g rotor balanced to ISO
        1940 grade G6.3 (6.3 mm/s, small electric motors) at ~7500 rpm (a
        digit closing half a turn in 0.8 s through a ~1:200 worm gear)
        gives 0.003 x 0.0063 x 785 = 0.015 N at 125 Hz; 0 switches it off.
        Seen by the tactile arrays (the normal force of that digit's pad)
        and, through the grasp's sideways stiffness, by the IMU.
    grasp_speed_units_s : float
        Closing speed (units/s) of the grasp routine's approach: a slow
        "close" (about 30 % PWM) so the 0.8 N stop does not overshoot much;
        estimate 150 units/s.
    grasp_poll_fs : float
        Rate (Hz) at which the grasp routine reads the index and thumb
        tactile sensors while closing: estimate 100 Hz.
    settle_s : float
        Hold time (s) after the fingers stop and again after the bottle's
        support is removed: 0.5 s.

    Examples
    --------
    >>> round(HandParams().travel_per_unit_m * 500, 3)
    0.1
    """

    speed_units_s: float = hw.FINGER_SPEED_UNITS_S
    latency_s: float = 0.010
    servo_gain: float = 40.0
    travel_per_unit_m: float = 0.2e-3
    aperture_radius_m: float = 0.060
    pad_normal_stiffness_n_m: float = 3000.0
    finger_stiffness_n_m: float = 20000.0
    pad_shear_stiffness_n_m: float = 2000.0
    pad_shear_damping_n_s_m: float = 1.0
    cuff_normal_stiffness_n_m: float = 20000.0
    cuff_shear_stiffness_n_m: float = 10000.0
    cuff_shear_damping_n_s_m: float = 1.0
    spot_travel_per_unit_m: float = 0.0
    stall_force_n: float = 25.0
    motor_droop: float = 1.0
    motor_vibration_n: float = 0.015
    motor_vibration_hz: float = 125.0
    grasp_speed_units_s: float = 150.0
    grasp_poll_fs: float = 100.0
    settle_s: float = 0.5

    def __post_init__(self) -> None:
        _validate(self, zero_ok=("latency_s", "settle_s", "spot_travel_per_unit_m", "motor_droop",
                                   "motor_vibration_n"))
        if self.motor_droop > 1.0:
            raise ParameterError(f"HandParams.motor_droop must be in [0, 1], got {self.motor_droop!r}")


@dataclass(frozen=True, slots=True)
class SlipSensorParams:
    """The OPR5005 reflective sensor and its driver, read by a 10-bit ADC.

    The phototransistor (4.7 kohm collector resistor to the 5 V supply)
    pulls the output down in proportion to the reflected light, so
    ``V_lin = supply * (1 - reflectance)``; near the rail it saturates at
    ``v_sat`` with a soft knee of width ``knee_v``::

        V = v_sat + knee_v * log(1 + exp((V_lin - v_sat) / knee_v))

    Parameters
    ----------
    supply_v : float
        Driver supply (V): the DAQ's 5 V rail (paper: ADC reference 5 V).
    v_sat : float
        Collector-emitter saturation (V). Datasheet: V_CE(sat) <= 0.4 V;
        0.2 V typical at these currents.
    knee_v : float
        Width of the soft saturation knee (V): estimate 0.15 V, so that the
        white surface (~0.4 V) still fluctuates as in the paper's Fig. 6B.
    noise_v : float
        Electrical noise (V rms) at the ADC input: the paper set its
        threshold at 2 LSB after measuring the noise, so the noise is below
        one LSB; estimate 1.5 mV.
    gap_m : float
        Sensor-to-surface gap set by the cuff (m). Paper: 3 mm. When the
        finger is further away (before contact) the reflected light falls as
        ``1 / (1 + (extra / gap)^2)``.
    spot_sigma_m : float
        Standard deviation (m) of the sensor's spot on the surface: blurs
        edges such as the white/black boundary. Estimate 0.8 mm for the
        OPR5005's emitter/detector overlap at 3 mm.
    gap_dent_fraction : float
        Fraction of the wall's dent under the cuff by which the gap under
        the sensor's spot opens. The sensor sits inside the cuff, centred
        behind its window (paper Fig. 2B). The cuff's face is flat and the
        bottle a cylinder, so the face touches the wall along the bottle's
        generatrix through the face's centre: on the window's rim above and
        below the spot, ``e`` ~ 3 mm each way along the axis (half the
        OPR5005's 5 mm package plus the rim). The dent is mostly the ring's
        three-lobe ovalization (the wall's 600 N/m), which does not change
        over 3 mm along the axis; the rest is the shell's local indentation
        under each rim point (Reissner's ``4 E t^2 / (R sqrt(3 (1 - nu^2)))``
        ~ 12.6 kN/m for 0.25 mm PET, ~5 % of the dent), decaying as
        ``exp(-(d / sqrt(R t))^2)`` with ``sqrt(R t)`` ~ 2.85 mm. Each rim
        point carries half the load; under a rim point the local dent is
        ``(1 + exp(-(2 e / sqrt(R t))^2)) / 2`` = 0.506 of one point load's,
        at the spot ``exp(-(e / sqrt(R t))^2)`` = 0.330: the gap opens by
        0.05 x 0.176 = 0.0085 of the dent (estimate from the shell's two
        length scales; an earlier 0.05 put the spot beside a one-sided
        contact, which a flat face on a cylinder does not make).
        0 when the spot sits on the contact.

    Examples
    --------
    >>> SlipSensorParams().gap_m
    0.003
    """

    supply_v: float = 5.0
    v_sat: float = 0.2
    knee_v: float = 0.15
    noise_v: float = 1.5e-3
    gap_m: float = hw.SLIP_SENSOR_GAP_M
    spot_sigma_m: float = 0.8e-3
    gap_dent_fraction: float = 0.0085

    def __post_init__(self) -> None:
        _validate(self, zero_ok=("noise_v", "gap_dent_fraction"))
        if self.gap_dent_fraction > 1.0:
            raise ParameterError(f"SlipSensorParams.gap_dent_fraction must be in [0, 1], "
                                 f"got {self.gap_dent_fraction!r}")


@dataclass(frozen=True, slots=True)
class ImuParams:
    """The MPU6050 accelerometer taped to the bottle.

    Parameters
    ----------
    fs : float
        Output data rate (Hz). Datasheet: 1 kHz with the DLPF on; the DAQ
        attaches the latest reading to each 333.33 Hz sample.
    range_g : float
        Full scale (g). Datasheet: +-2 g setting (16384 LSB/g).
    lsb_per_g : float
        Sensitivity (LSB/g) at +-2 g. Datasheet: 16384.
    noise_g : float
        Noise (g rms): datasheet 400 ug/sqrt(Hz) over the 44 Hz DLPF
        (noise bandwidth ~1.57 x 44 Hz) gives ~3.4 mg; 4 mg.
    dlpf_hz : float
        Digital low-pass bandwidth (Hz). Datasheet: DLPF_CFG = 3, 44 Hz.
    tilt_x_deg, tilt_z_deg : float
        Mounting tilt (deg) of the sensor on the bottle: gravity leaks into
        x and z. Estimate: 3 and 2 degrees (taped by hand).

    Examples
    --------
    >>> ImuParams().lsb_per_g
    16384.0
    """

    fs: float = 1000.0
    range_g: float = hw.IMU_RANGE_G
    lsb_per_g: float = float(hw.IMU_LSB_PER_G)
    noise_g: float = 4e-3
    dlpf_hz: float = 44.0
    tilt_x_deg: float = 3.0
    tilt_z_deg: float = 2.0

    def __post_init__(self) -> None:
        _validate(self, zero_ok=("noise_g", "tilt_x_deg", "tilt_z_deg"))


@dataclass(frozen=True, slots=True)
class TactileParams:
    """The 4 x 4 tactile arrays on the index finger and thumb.

    Parameters
    ----------
    noise_n : float
        Noise per taxel (N rms). Estimate: 5 mN for a piezoresistive array
        with a 12-bit reading (about 2 mN per count).
    resolution_n : float
        Quantization step per taxel (N): estimate 2 mN.
    patch_sigma_taxels : float
        Width of the contact pressure patch (taxel pitches, Gaussian sigma):
        a fingertip on a 6.5 cm cylinder covers 2-3 of 4 taxels; 0.9.
    shear_shift_taxels : float
        Shift of the pressure centre along the slip direction per unit of
        tangential/normal force ratio (taxel pitches): a 2-3 mm pad sheared
        at ratio 0.6 moves the centre ~1 mm, ~0.4 pitch; 0.7.
    bandwidth_hz : float
        -3 dB bandwidth (Hz) of a taxel's response to force (first order): the
        pad's viscoelastic relaxation and the piezoresistive layer. Estimate
        100 Hz (range 50-500 Hz for elastomer-covered resistive arrays).
    hysteresis_n : float
        Half-width (N per taxel) of the play between loading and unloading:
        the Interlink FSR datasheet gives about +10 % (R_F+ - R_F-)/R_F+;
        at the ~0.1-0.3 N per taxel of this grasp, estimate 5 mN.
    drift_per_decade : float
        Creep of the reading under a held load, relative, per decade of time
        since the rig started: the Interlink FSR datasheet gives < 5 % per
        log10(time); estimate 2 %.
    gain_sd : float
        Part-to-part spread of an array's sensitivity (relative sd): each
        array (thumb, index) draws its gain from the rig's seed. The
        Interlink FSR datasheet gives +-6 % part-to-part repeatability
        within a batch; 0.06.

    slip_events : float
        Size of a pad's micro-slip events, as a fraction of the contact's
        static-to-kinetic drop ``(mu_s - mu_k) N``: while a pad slides, events
        come as a Poisson process of rate ``w / D_c`` (one renewal of the
        micro-contacts per slip-weakening distance slid) and each releases
        this much of the drop as sensed shear, ringing in the pad
        (stick-slip and detachment of soft silicone on smooth polymer,
        Howe & Cutkosky 1989; Holweg et al. 1996). Estimate 0.3: an event
        renews part of the contact, not all of it (1 would be a full
        stick-slip cycle); 0 switches the events off.
    slip_vibration_hz, slip_vibration_zeta : float
        Resonance (Hz) and damping ratio of the pad's shear ringing after an
        event: slip vibrations of elastomer fingertips lie at tens to
        hundreds of Hz (Howe & Cutkosky 1989; Fernandez et al. 2014,
        Sensors 14:709; Heyneman & Cutkosky 2016); estimate 150 Hz and 0.1
        (a silicone loss factor of about 0.2).
    incipient_slip : float
        Share (0-1) of the Cattaneo-Mindlin law in the pressure centre's
        shift: as the load ratio ``q = |F_t| / (mu N)`` grows the slipping
        annulus spreads from the contact's edge and the pad's surface
        displacement grows as ``(3/2) mu N [1 - (1 - q)^(2/3)] / k_t``
        (Johnson 1985, ch. 7), the linear shift at small ``q``, steepening
        toward slip. 1 (the law); 0 keeps the linear shift.

    The arrays see the contact's own forces (normal force, and the shear
    that shifts the pressure centre), the micro-slip events' ringing and
    the incipient slip's redistribution. The events are redistributions of
    traction within the pad's contact: the friction the bottle feels
    follows the friction law, so the IMU does not see them.

    Examples
    --------
    >>> TactileParams().noise_n
    0.005
    """

    noise_n: float = 5e-3
    resolution_n: float = 2e-3
    patch_sigma_taxels: float = 0.9
    shear_shift_taxels: float = 0.7
    bandwidth_hz: float = 100.0
    hysteresis_n: float = 5e-3
    drift_per_decade: float = 0.02
    gain_sd: float = 0.06
    slip_events: float = 0.3
    slip_vibration_hz: float = 150.0
    slip_vibration_zeta: float = 0.1
    incipient_slip: float = 1.0

    def __post_init__(self) -> None:
        _validate(self, zero_ok=("noise_n", "resolution_n", "shear_shift_taxels", "hysteresis_n",
                                 "drift_per_decade", "gain_sd", "slip_events", "incipient_slip"))
        for f in ("slip_events", "slip_vibration_zeta", "incipient_slip"):
            if getattr(self, f) > 1.0:
                raise ParameterError(f"TactileParams.{f} must be in [0, 1], got {getattr(self, f)!r}")


@dataclass(frozen=True, slots=True)
class FlowParams:
    """The YF-S201 hall-effect flow sensor.

    Parameters
    ----------
    k_factor_sd : float
        Relative standard deviation of this unit's pulses per litre around
        the nominal 450 (``slipreflex.core.hardware.FLOW_PULSES_PER_LITRE``).
        Datasheet accuracy is +-10 % over the range; a given unit at a fixed
        flow is repeatable, so each seed draws one factor with sd 3 %.

    Examples
    --------
    >>> FlowParams().k_factor_sd
    0.03
    """

    k_factor_sd: float = 0.03

    def __post_init__(self) -> None:
        _validate(self, zero_ok=("k_factor_sd",))


@dataclass(frozen=True, slots=True)
class PhysicsParams:
    """Integration settings.

    Parameters
    ----------
    dt : float
        Physics time step (s). 1e-4 s resolves the stiffest mode (the landing
        mass on the bottle's bottom, ~700 rad/s, and the grasp's stick
        resonance) with omega*dt < 0.1; ``tests/sim/test_sim_physics.py`` shows
        that halving it does not change the results.
    track_length_m : float
        Length (m) of the surface texture generated for a bottle (covers the
        grip travel with margin).

    Examples
    --------
    >>> PhysicsParams().dt
    0.0001
    """

    dt: float = 1e-4
    track_length_m: float = 0.12

    def __post_init__(self) -> None:
        _validate(self)
        if self.dt > 1e-3:
            raise ParameterError(f"PhysicsParams.dt must be <= 0.001, got {self.dt!r}")


@dataclass(frozen=True, slots=True)
class WaterParams:
    """What the poured water does to the bottle besides its weight: the jet's splash and the slosh.

    The jet's mean momentum flux ``rho Q v`` (``Pour``) is a steady push; a jet
    plunging into water does not push steadily. Its impact force fluctuates
    (``splash_rms``, ``splash_corner_hz``), along the bottle's axis. Landing
    ``jet_offset_m`` off the axis, the jet also drives the first antisymmetric
    slosh mode of the water column (wave number ``1.8412 / R``, frequency
    ``sqrt(g k tanh(k h)) / 2 pi`` at fill height ``h``), whose sideways
    reaction shakes the bottle in the fingers and reaches the accelerometer's
    x axis. The slosh is the equivalent spring-mass of the mode (slosh mass
    ``m1 = m_water 2 tanh(k h) / ((1.8412^2 - 1) k h)``; Abramson 1966, NASA
    SP-106; Dodge 2000, SwRI), lightly damped (Stephens et al. 1962, NASA TN
    D-1367: ``zeta = 0.79 sqrt(nu / (g^0.5 R^1.5)) [1 + 0.318 / sinh(1.84 h / R)
    (1 + (1 - h / R) / cosh(1.84 h / R))]``, about 0.6 % in this bottle), its
    stiffness scaled by the effective gravity ``g - a`` (the bottle's own axial
    acceleration, parametric) and its base moved by the bottle's sideways
    motion. See docs/simulator.md for the derivation of the jet's modal force.

    Parameters
    ----------
    splash_rms : float
        RMS of the impact force's fluctuation relative to the mean momentum
        flux ``rho Q v``. Estimate 0.2: plunge-pool floor pressures under a
        plunging water jet fluctuate with an rms of 5-30 % of the jet's
        dynamic pressure (Ervine, Falvey & Withers 1997, J. Hydraul. Res.
        35(2)); range 0.05-0.5.
    splash_corner_hz : float
        Corner (Hz) of the fluctuation's one-pole (Lorentzian) spectrum.
        Estimate 30 Hz: a 4 mm jet at 1.4 m/s carries surface disturbances of
        about Rayleigh's wavelength (4.5 d), 18 mm, i.e. ~80 Hz, and the
        plunging cavity's air pockets break up more slowly; range 10-200 Hz.
    jet_offset_m : float
        Distance (m) from the bottle's axis at which the jet lands. Estimate
        5 mm: a hand-held tube pours through a ~22 mm neck (28 mm PCO
        finish); range 0-10 mm. Zero leaves the slosh unexcited by the jet.
    slosh_damping_factor : float
        Multiplier on the smooth-wall damping of Stephens et al. (1962):
        estimate 1; range 0.7-3 (the formula's scatter, and the extra
        contact-line dissipation of small containers).

    Examples
    --------
    >>> WaterParams().splash_rms
    0.2
    >>> WaterParams(jet_offset_m=0.05)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: WaterParams.jet_offset_m must be <= 0.02 m (inside a bottle's neck), got 0.05
    """

    splash_rms: float = 0.2
    splash_corner_hz: float = 30.0
    jet_offset_m: float = 5e-3
    slosh_damping_factor: float = 1.0

    def __post_init__(self) -> None:
        _validate(self, zero_ok=("splash_rms", "jet_offset_m"))
        if self.jet_offset_m > 0.02:
            raise ParameterError(f"WaterParams.jet_offset_m must be <= 0.02 m (inside a bottle's neck), "
                                 f"got {self.jet_offset_m!r}")
        if self.splash_corner_hz > 400.0:
            raise ParameterError(f"WaterParams.splash_corner_hz must be <= 400 Hz (the splash noise is drawn "
                                 f"every 1 ms), got {self.splash_corner_hz!r}")
