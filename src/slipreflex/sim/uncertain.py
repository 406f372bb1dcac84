"""The uncertain constants of the simulated plant, as data.

Every constant of the plant whose value is not known from a datasheet or the
paper appears ONCE here, with its unit, nominal value, plausible range,
distribution, source (or the reason for the estimate) and the parameter
fields it sets. The nominal values are the defaults of
:mod:`slipreflex.sim.params` and :mod:`slipreflex.sim.objects`; a test checks
that they agree, so the table cannot drift from the model.

* :data:`UNCERTAIN` is the table (name -> :class:`UncertainConstant`).
* :func:`plant_from_values` builds a :class:`Plant` (every parameter object a
  :class:`~slipreflex.sim.Rig` takes, plus the paper's bottles) from a dict
  of values; constants not given keep their nominal value.
* :func:`load_ranges` reads a TOML file that narrows, widens or fixes any of
  them and returns the modified table.
* :meth:`UncertainConstant.value_at` maps a number in [0, 1] (a row of a
  Sobol or Latin-hypercube design) onto the constant's distribution.

How a constant maps onto the plant (``targets``): ``"hand.latency_s"`` sets a
field of a parameter object (``hand``, ``slip_sensor``, ``imu``,
``tactile``, ``flow``, ``physics``, ``water``); ``"bottle.wall_stiffness_n_m"`` sets a
field of every paper bottle; ``"bottle[TR,DK].mu_s"`` only of those;
``"bottle.mu_k/mu_s"`` sets ``mu_k`` to the value times the bottle's
(new) ``mu_s``; ``"calibration.first_slip_ml"`` is the open-loop target of
:meth:`Plant.calibrated` (the pads' ``mu_s`` is calibrated, not drawn).

Examples
--------
>>> from slipreflex.sim.uncertain import UNCERTAIN, plant_from_values
>>> UNCERTAIN["hand_latency"].unit
's'
>>> plant = plant_from_values({"hand_latency": 0.02})
>>> plant.hand.latency_s
0.02
>>> rig = plant.rig("TR", seed=1)
>>> rig.hand.latency
0.02
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any

from ..core.errors import ParameterError
from ..files.paths import read_toml
from ..methods.baselines.calibration import REST_K
from ..methods.baselines.swt import SWT_PERSIST, SWT_PERSISTENCE
from .calibration import CALIBRATION_SEEDS, calibrate_bottle
from .objects import BOTTLES, Bottle, Surface
from .params import FlowParams, HandParams, ImuParams, PhysicsParams, SlipSensorParams, TactileParams, WaterParams
from .rig import Rig

__all__ = ["UncertainConstant", "UNCERTAIN", "Plant", "plant_from_values", "load_ranges", "nominal_values",
           "DISTRIBUTIONS", "markdown_table", "WIDEN_LIMIT", "plausible_limits"]

#: Distributions a constant may have: uniform on [low, high], or log-uniform (for
#: constants known to within a factor, such as stiffnesses and speeds).
DISTRIBUTIONS: tuple[str, ...] = ("uniform", "loguniform")

_SECTIONS = ("hand", "slip_sensor", "imu", "tactile", "flow", "physics", "water")


@dataclass(frozen=True, slots=True)
class UncertainConstant:
    """One uncertain plant constant.

    Parameters
    ----------
    name : str
        Identifier (used in TOML range files and as a results column).
    unit : str
        Unit of ``nominal``, ``low`` and ``high`` ("1" for a ratio).
    nominal, low, high : float
        The value the default plant uses and the plausible range
        (``low <= nominal <= high``; ``low == high`` fixes it).
    distribution : {"uniform", "loguniform"}
        How a design spreads draws over the range.
    source : str
        The published source, or "estimate: " and the reason.
    targets : tuple of str
        The plant fields it sets (see the module notes).

    Examples
    --------
    >>> c = UncertainConstant("k", "N/m", 100.0, 50.0, 200.0, "loguniform", "estimate: test", ("hand.x",))
    >>> round(c.value_at(0.5), 9)
    100.0
    """

    name: str
    unit: str
    nominal: float
    low: float
    high: float
    distribution: str
    source: str
    targets: tuple[str, ...] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        for f in ("nominal", "low", "high"):
            v = getattr(self, f)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ParameterError(f"{self.name}.{f} must be a finite number, got {v!r}")
        if not self.low <= self.nominal <= self.high:
            raise ParameterError(f"{self.name}: need low <= nominal <= high, got {self.low!r} <= "
                                 f"{self.nominal!r} <= {self.high!r}")
        if self.distribution not in DISTRIBUTIONS:
            raise ParameterError(f"{self.name}.distribution must be one of {', '.join(DISTRIBUTIONS)}, "
                                 f"got {self.distribution!r}")
        if self.distribution == "loguniform" and self.low <= 0:
            raise ParameterError(f"{self.name}: a log-uniform range needs low > 0, got {self.low!r}")

    @property
    def fixed(self) -> bool:
        """True when the range is a single value.

        Examples
        --------
        >>> UNCERTAIN["hand_latency"].fixed
        False
        """
        return self.low == self.high

    def value_at(self, u: float) -> float:
        """The value at quantile ``u`` in [0, 1] of the distribution.

        Examples
        --------
        >>> c = UNCERTAIN["hand_latency"]
        >>> c.value_at(0.0) == c.low and c.value_at(1.0) == c.high
        True
        """
        if not 0.0 <= u <= 1.0:
            raise ParameterError(f"{self.name}: quantile must be in [0, 1], got {u!r}")
        if self.fixed:
            return float(self.low)
        if self.distribution == "loguniform":
            return float(math.exp(math.log(self.low) + u * (math.log(self.high) - math.log(self.low))))
        return float(self.low + u * (self.high - self.low))


def _c(name: str, unit: str, nominal: float, low: float, high: float, dist: str, source: str,
       *targets: str) -> UncertainConstant:
    return UncertainConstant(name, unit, nominal, low, high, dist, source, tuple(targets))


_B = BOTTLES


def _surface(bottle: str) -> Surface:
    """A paper bottle's surface (a bottle resolves its surface's name when it is made)."""
    s = BOTTLES[bottle].surface
    assert isinstance(s, Surface), s
    return s
_H = HandParams()
_T = TactileParams()
_S = SlipSensorParams()
_W = WaterParams()

#: The table: every uncertain plant constant, by name. Nominal values are read from the
#: parameter defaults (one definition); ranges and sources are documented in docs/simulator.md.
UNCERTAIN: Mapping[str, UncertainConstant] = MappingProxyType({c.name: c for c in (
    _c("first_slip_ml", "ml", 200.0, 170.0, 230.0, "uniform",
       "paper Fig. 15 and III-B: the first pour slip 'at about 200 ml' (read as +-30 ml); the pads' mu_s "
       "is calibrated to it (Plant.calibrated)", "calibration.first_slip_ml"),
    _c("pad_mu_k_ratio", "1", round(_B["TR"].mu_k / _B["TR"].mu_s, 6), 0.6, 1.0, "uniform",
       "estimate: kinetic friction of rubber on polymers 0-40 % below static; the smooth PET bottles (TR, DK: "
       "one polymer, one finish)", "bottle[TR,DK].mu_k/mu_s"),
    _c("pad_mu_k_ratio_TX", "1", round(_B["TX"].mu_k / _B["TX"].mu_s, 6), 0.6, 1.0, "uniform",
       "estimate: kinetic friction of rubber on polymers 0-40 % below static; TX's vinyl tape, drawn apart "
       "from the smooth bottles", "bottle[TX].mu_k/mu_s"),
    _c("stribeck_velocity", "m/s", _B["TR"].stribeck_velocity_m_s, 1e-4, 1e-2, "loguniform",
       "estimate: soft polymer contacts lose their static friction over 0.1-10 mm/s",
       "bottle.stribeck_velocity_m_s"),
    _c("cuff_mu_s", "1", _B["TR"].cuff_mu_s, 0.2, 0.45, "uniform",
       "estimate: polymer on polymer (PLA cuff on PET), tables give 0.2-0.4", "bottle.cuff_mu_s"),
    _c("cuff_mu_k_ratio", "1", round(_B["TR"].cuff_mu_k / _B["TR"].cuff_mu_s, 6), 0.6, 1.0, "uniform",
       "estimate: glassy polymers lose 0-40 % from static to kinetic", "bottle.cuff_mu_k/cuff_mu_s"),
    _c("rate_a", "1", _B["TR"].rate_a, 0.01, 0.12, "loguniform",
       "rubber friction rises with log sliding speed (Grosch 1963; PDMS: Vorvolakos & Chaudhury 2003); "
       "slope per e-fold relative to mu_k, estimate", "bottle.rate_a"),
    _c("cuff_rate_a", "1", _B["TR"].cuff_rate_a, 0.005, 0.05, "loguniform",
       "direct effect of glassy polymer multicontacts, A ~ 0.01 at mu ~ 0.5 (Baumberger & Caroli 2006)",
       "bottle.cuff_rate_a"),
    _c("rate_v0", "m/s", _B["TR"].rate_v0_m_s, 1e-7, 1e-5, "loguniform",
       "estimate: reference speed of the log-rate term, 0.1-10 um/s (rate-state laws, Baumberger & Caroli 2006)",
       "bottle.rate_v0_m_s"),
    _c("slip_distance", "m", _B["TR"].slip_distance_m, 10e-6, 300e-6, "loguniform",
       "estimate: slip-weakening distance of a soft pad, of the order of its micro-contacts",
       "bottle.slip_distance_m"),
    _c("cuff_slip_distance", "m", _B["TR"].cuff_slip_distance_m, 0.3e-6, 5e-6, "loguniform",
       "memory length D_0 ~ 0.5-1 um of glassy polymer multicontacts (Baumberger & Caroli 2006)",
       "bottle.cuff_slip_distance_m"),
    _c("heal_time", "s", _B["TR"].heal_s, 0.1, 10.0, "loguniform",
       "estimate: a stuck contact regains its static friction by ageing (Dieterich 1972: log growth with "
       "hold time)", "bottle.heal_s"),
    _c("wall_stiffness", "N/m", _B["TR"].wall_stiffness_n_m, 300.0, 1500.0, "loguniform",
       "estimate: a thin 500 ml PET bottle dents 0.7-3 mm under a 1 N fingertip push",
       "bottle.wall_stiffness_n_m"),
    _c("shoulder_slope", "1", _B["TR"].shoulder_slope, 0.0, 1.0, "uniform",
       "absent (0: the contacts are lost at once at grip_travel) to 1; a 500 ml bottle's shoulder narrows from the "
       "32.5 mm body to a ~13 mm neck over 20-60 mm (0.3-1), estimate", "bottle.shoulder_slope"),
    _c("drop_eccentricity", "m", _B["TR"].drop_eccentricity_m, 0.0, 0.02, "uniform",
       "absent (0: the dropped mass lands on the tilt axis and does not rock the bottle) to 2 cm; a mass released "
       "over the opening falls inside a 28 mm finish's ~21.7 mm bore (within 11 mm of the axis) onto a petaloid "
       "base whose dome moves it outward, and the axis' direction to its landing point is random (estimate)",
       "bottle.drop_eccentricity_m"),
    _c("grasp_height", "m", _B["TR"].grasp_height_m, 0.05, 0.10, "uniform",
       "estimate: the fingertips hold the 16 cm body 3 cm below a shoulder that starts ~6 cm below the top (7 cm), "
       "2 cm either way; the tilt's axis (no 'absent' value: the bottle always has a height)",
       "bottle.grasp_height_m"),
    _c("wall_softening", "1", _B["TR"].wall_softening, 0.0, 0.67, "uniform",
       "absent (0: the linear law) to 0.67; beyond its linear range the section ovalizes into three lobes with the "
       "ring's bending stiffness E t^3 b / (12 x 0.0159 R^3): 200-1000 N/m for 0.2-0.3 mm PET (E 2-4 GPa) over a "
       "band one diameter wide, estimate", "bottle.wall_softening"),
    _c("wall_linear_range", "m", _B["TR"].wall_linear_range_m, 1.5e-3, 6e-3, "uniform",
       "estimate: a point-loaded thin shell leaves its linear law at deflections of several wall thicknesses "
       "(6-24 x 0.25 mm)", "bottle.wall_linear_range_m"),
    _c("wall_collapse", "m", _B["TR"].wall_collapse_m, 0.013, 0.03, "uniform",
       "estimate: the three lobes fold against each other at 0.4-0.9 of the radius; no 'absent' value (without "
       "it the fingertips would pass the axis)", "bottle.wall_collapse_m"),
    _c("stall_force", "N", _H.stall_force_n, 20.0, 34.0, "uniform",
       "i-Limb whole-hand grip 100-136 N (Belter et al. 2013), the thumb against four fingers: 25-34 N per digit; "
       "20 N for a worn or low-battery hand (estimate)", "hand.stall_force_n"),
    _c("motor_droop", "1", _H.motor_droop, 0.0, 1.0, "uniform",
       "absent (0: full speed up to the stall) to 1: a brushed DC motor's speed falls linearly from no load to "
       "stall at constant voltage", "hand.motor_droop"),
    _c("motor_vibration", "N", _H.motor_vibration_n, 0.0, 0.06, "uniform",
       "absent (0) to 0.06 N at full speed: rotor unbalance m_r G omega of a ~3 g rotor at balance grade G6.3 "
       "(ISO 1940, small electric motors; 0.015 N) up to G2.5-G16 and gear-mesh forces, estimate",
       "hand.motor_vibration_n"),
    _c("motor_vibration_hz", "Hz", _H.motor_vibration_hz, 60.0, 250.0, "loguniform",
       "estimate: a digit closing half a turn in 0.8 s through a 1:100-1:400 worm gear turns its motor at "
       "60-250 rev/s at full speed", "hand.motor_vibration_hz"),
    _c("hand_latency", "s", _H.latency_s, 0.005, 0.030, "uniform",
       "estimate: 15-byte packet at 115200 baud (1.3 ms) plus control unit and digit controller",
       "hand.latency_s"),
    _c("finger_speed", "units/s", _H.speed_units_s, 415.0, 625.0, "uniform",
       "i-Limb digits close fully (0..500) in about 0.8 s (manufacturer; Belter et al. 2013 review); "
       "up to 1.2 s reported",
       "hand.speed_units_s"),
    _c("servo_gain", "1/s", _H.servo_gain, 20.0, 80.0, "loguniform",
       "estimate: geared DC digit under position control settles small steps in 0.05-0.2 s",
       "hand.servo_gain"),
    _c("travel_per_unit", "m", _H.travel_per_unit_m, 0.12e-3, 0.3e-3, "uniform",
       "estimate: the distal pad of a 9 cm digit sweeps 6-15 cm over 0..500", "hand.travel_per_unit_m"),
    _c("pad_normal_stiffness", "N/m", _H.pad_normal_stiffness_n_m, 1500.0, 6000.0, "loguniform",
       "estimate: 2-3 mm silicone pad, Shore 20-40 A", "hand.pad_normal_stiffness_n_m"),
    _c("cuff_shear_stiffness", "N/m", _H.cuff_shear_stiffness_n_m, 4000.0, 30000.0, "loguniform",
       "estimate: bending of the middle digit along the bottle axis", "hand.cuff_shear_stiffness_n_m"),
    _c("spot_travel_per_unit", "m", _H.spot_travel_per_unit_m, 0.0, 40e-6, "uniform",
       "absent (0, nominal: a cuff turning about a point of the wall, pivoting on its stuck contact or rolling "
       "without slip, moves the spot under its perpendicular sight line at second order only; rigid-body "
       "kinematics) to 40 um: a cuff sliding over the wall as the distal segment turns 0.0063 rad per unit of the "
       "tip's advance (estimate from the finger's geometry)",
       "hand.spot_travel_per_unit_m"),
    _c("gap_dent_fraction", "1", _S.gap_dent_fraction, 0.0, 0.15, "uniform",
       "absent (0: the spot on the cuff's contact) to 0.15; the dent is mostly the ring's three-lobe ovalization "
       "plus a ~5 % local indentation decaying over sqrt(R t) ~ 2.85 mm; nominal 0.0085: a flat cuff face on the "
       "cylinder touches on the window's rim ~3 mm above and below the spot, which is 0.176 of the local part "
       "less dented; 0.03-0.07 for a spot 3 mm beside a one-sided contact, twice that 6 mm off, estimate",
       "slip_sensor.gap_dent_fraction"),
    _c("pad_shear_stiffness", "N/m", _H.pad_shear_stiffness_n_m, 1000.0, 4000.0, "loguniform",
       "estimate: G A / h with G 0.1-0.4 MPa, 20 mm^2, 2 mm", "hand.pad_shear_stiffness_n_m"),
    _c("tactile_noise", "N", _T.noise_n, 2e-3, 10e-3, "loguniform",
       "estimate: piezoresistive 4 x 4 array with a 12-bit reading", "tactile.noise_n"),
    _c("tactile_bandwidth", "Hz", _T.bandwidth_hz, 50.0, 500.0, "loguniform",
       "estimate: elastomer-covered resistive arrays respond in 0.3-3 ms", "tactile.bandwidth_hz"),
    _c("tactile_hysteresis", "N", _T.hysteresis_n, 0.0, 0.015, "uniform",
       "Interlink FSR datasheet: about 10 % between loading and unloading (of ~0.1-0.3 N per taxel)",
       "tactile.hysteresis_n"),
    _c("tactile_drift", "1", _T.drift_per_decade, 0.0, 0.05, "uniform",
       "Interlink FSR datasheet: drift < 5 % per log10(time)", "tactile.drift_per_decade"),
    _c("tactile_gain_sd", "1", _T.gain_sd, 0.0, 0.15, "uniform",
       "Interlink FSR datasheet: +-6 % part-to-part within a batch; more between batches",
       "tactile.gain_sd"),
    _c("slip_events", "1", _T.slip_events, 0.0, 1.0, "uniform",
       "absent (0) to 1 (each event a full stick-slip cycle): stick-slip and detachment of soft silicone on smooth "
       "polymer (Howe & Cutkosky 1989; Holweg et al. 1996); an event renews part of the contact, estimate 0.3",
       "tactile.slip_events"),
    _c("slip_vibration_hz", "Hz", _T.slip_vibration_hz, 50.0, 400.0, "loguniform",
       "slip vibrations of elastomer fingertips at tens to hundreds of Hz (Howe & Cutkosky 1989; Fernandez et al. "
       "2014; Heyneman & Cutkosky 2016); the value is an estimate", "tactile.slip_vibration_hz"),
    _c("slip_vibration_zeta", "1", _T.slip_vibration_zeta, 0.05, 0.3, "uniform",
       "estimate: silicone loss factor 0.1-0.6", "tactile.slip_vibration_zeta"),
    _c("incipient_slip", "1", _T.incipient_slip, 0.0, 1.0, "uniform",
       "absent (0: the linear shift) to 1: the Cattaneo-Mindlin partial-slip law (Johnson 1985, ch. 7), the "
       "slipping annulus spreading from the contact's edge", "tactile.incipient_slip"),
    _c("slip_sensor_noise", "V", _S.noise_v, 0.5e-3, 3e-3, "uniform",
       "paper: noise below the 2-LSB threshold; the value is an estimate", "slip_sensor.noise_v"),
    _c("splash_rms", "1", _W.splash_rms, 0.05, 0.5, "uniform",
       "estimate: plunge-pool floor pressures under a plunging water jet fluctuate by 5-30 % of its dynamic "
       "pressure (Ervine, Falvey & Withers 1997); relative to the jet's momentum flux", "water.splash_rms"),
    _c("splash_corner", "Hz", _W.splash_corner_hz, 10.0, 200.0, "loguniform",
       "estimate: a 4 mm jet at 1.4 m/s carries disturbances of ~Rayleigh's wavelength (~80 Hz); the plunging "
       "cavity's air pockets break up more slowly", "water.splash_corner_hz"),
    _c("jet_offset", "m", _W.jet_offset_m, 0.0, 0.01, "uniform",
       "estimate: a hand-held tube pours through the ~22 mm neck of a 28 mm PCO finish",
       "water.jet_offset_m"),
    _c("slosh_damping_factor", "1", _W.slosh_damping_factor, 0.7, 3.0, "loguniform",
       "smooth-wall slosh damping of Stephens et al. 1962 (NASA TN D-1367), times 0.7-3: its scatter and the "
       "contact-line dissipation of small containers (estimate)", "water.slosh_damping_factor"),
    *(c for b in ("TR", "DK", "TX") for c in (
        _c(f"reflectance_{b}", "1", _surface(b).reflectance, round(0.7 * _surface(b).reflectance, 6),
           round(min(0.95, 1.3 * _surface(b).reflectance), 6), "uniform",
           "estimate: the paper gives no level for its bottles, only that less reflective surfaces fluctuate "
           "less than textured ones (II-C-2); ±30 % of the nominal reflectance", f"bottle[{b}].surface.reflectance"),
        _c(f"texture_{b}", "1", _surface(b).texture, round(0.5 * _surface(b).texture, 6),
           round(2.0 * _surface(b).texture, 6), "loguniform",
           "estimate: the bottles' texture is known only qualitatively (II-C-2); half to twice the nominal rms",
           f"bottle[{b}].surface.texture"))),
    _c("swt_persist", "samples", float(SWT_PERSIST), float(min(SWT_PERSISTENCE.values())),
       float(max(SWT_PERSISTENCE.values())), "uniform",
       "a reading, not physics: the paper's 'movement would continue for at least another 21 ms' as samples "
       "the SWT-SD crossing must persist (rounded to a whole sample), between the two named readings of "
       "baselines.swt: 0 'within-window' (the nominal, the project's reading) and 8 'after-crossing'",
       "method.swt_persist"),
    _c("rest_k", "1", REST_K, 3.0, 6.0, "uniform",
       "a reading, not physics: the rest-noise multiple of NMSD's and SWT-SD's thresholds (baselines."
       "calibration); 3-6 standard deviations span the common choices", "method.rest_k"),
    _c("response_cutoff", "ms", 1000.0, 500.0, 2000.0, "loguniform",
       "a reading, not physics: a command rise later than this after a slip's onset is no response (a censored "
       "trial); the paper gives none, its slowest reported totals are under 0.8 s", "judge.cutoff_ms"),
    _c("time_tolerance", "ms", round(1e3 / 333.3333333333333, 6), 0.0, round(2e3 / 333.3333333333333, 6),
       "uniform", "a reading, not physics: claim 8's tolerance on 85 ms, none to two DAQ samples",
       "judge.time_tol_ms"),
    _c("near_volume", "ml", 50.0, 25.0, 100.0, "uniform",
       "a reading, not physics: claim 6's 'about 200 ml' and 'about 400 ml', an eighth to a half of the 200 ml "
       "between them", "judge.near_ml"),
)})


def nominal_values(table: Mapping[str, UncertainConstant] | None = None) -> dict[str, float]:
    """The nominal value of every constant of ``table`` (default :data:`UNCERTAIN`).

    Examples
    --------
    >>> nominal_values()["hand_latency"]
    0.01
    """
    return {k: float(c.nominal) for k, c in (table or UNCERTAIN).items()}


def markdown_table(table: Mapping[str, UncertainConstant] | None = None) -> str:
    """The table as Markdown (docs/simulator.md quotes it; a test keeps the two equal).

    Examples
    --------
    >>> markdown_table().splitlines()[0].startswith("| constant |")
    True
    """
    lines = ["| constant | unit | nominal | low | high | distribution | sets | source |",
             "|---|---|---|---|---|---|---|---|"]
    for c in (table or UNCERTAIN).values():
        lines.append(f"| `{c.name}` | {c.unit} | {c.nominal:g} | {c.low:g} | {c.high:g} | {c.distribution} | "
                     f"{', '.join(f'`{t}`' for t in c.targets)} | {c.source} |")
    return "\n".join(lines)


@dataclass(frozen=True)
class Plant:
    """Every parameter object of the simulated rig, and the bottles it holds.

    Attributes
    ----------
    hand, slip_sensor, imu, tactile, flow, physics, water : parameter dataclasses
    bottles : mapping of str to Bottle
        The paper's bottles with this plant's friction and wall.
    values : mapping of str to float
        The uncertain constants this plant was built from.

    Examples
    --------
    >>> Plant().bottles["TX"].name
    'TX'
    """

    hand: HandParams = field(default_factory=HandParams)
    slip_sensor: SlipSensorParams = field(default_factory=SlipSensorParams)
    imu: ImuParams = field(default_factory=ImuParams)
    tactile: TactileParams = field(default_factory=TactileParams)
    flow: FlowParams = field(default_factory=FlowParams)
    physics: PhysicsParams = field(default_factory=PhysicsParams)
    water: WaterParams = field(default_factory=WaterParams)
    bottles: Mapping[str, Bottle] = field(default_factory=lambda: dict(BOTTLES))
    values: Mapping[str, float] = field(default_factory=nominal_values)
    first_slip_ml: float = 200.0
    readings: Mapping[str, float] = field(default_factory=dict)

    def method_options(self) -> dict[str, Any]:
        """The method readings this plant carries, as :class:`~slipreflex.reproduce.experiments.ReproduceConfig` fields.

        Examples
        --------
        >>> plant_from_values({"swt_persist": 2.4}).method_options()["swt_persist"]
        2
        >>> Plant().method_options()
        {}
        """
        out: dict[str, Any] = {}
        if "swt_persist" in self.readings:
            out["swt_persist"] = int(round(self.readings["swt_persist"]))
        if "rest_k" in self.readings:
            out["rest_k"] = float(self.readings["rest_k"])
        return out

    def __reduce__(self):
        """Pickle with plain dicts (a read-only mappingproxy does not pickle): worker processes get plants.

        Examples
        --------
        >>> import pickle
        >>> p = plant_from_values({"hand_latency": 0.02})
        >>> q = pickle.loads(pickle.dumps(p))
        >>> q == p, type(q.bottles).__name__
        (True, 'mappingproxy')
        """
        state = {f.name: getattr(self, f.name) for f in fields(self)}
        state.update(bottles=dict(self.bottles), values=dict(self.values), readings=dict(self.readings))
        return (_unpickle_plant, (state,))

    def calibrated(self, seeds: tuple[int, ...] | None = None) -> Plant:
        """This plant with every bottle's pad friction calibrated to :attr:`first_slip_ml`.

        See :func:`slipreflex.sim.calibration.calibrate_bottle` (open loop only).

        Examples
        --------
        >>> p = plant_from_values({"first_slip_ml": 180.0}).calibrated(seeds=(0,))
        >>> p.bottles["TR"].mu_s < Plant().bottles["TR"].mu_s
        True
        """
        kw = self.rig_kwargs()
        bottles = {n: calibrate_bottle(b, self.first_slip_ml, rig_kwargs=kw,
                                       seeds=seeds or CALIBRATION_SEEDS).bottle for n, b in self.bottles.items()}
        return replace(self, bottles=MappingProxyType(bottles))

    def rig_kwargs(self) -> dict[str, Any]:
        """Keyword arguments for :class:`~slipreflex.sim.Rig` (all but the bottle and seed).

        Examples
        --------
        >>> sorted(Plant().rig_kwargs())
        ['flow', 'hand', 'imu', 'physics', 'slip_sensor', 'tactile', 'water']
        """
        return {s: getattr(self, s) for s in _SECTIONS}

    def rig(self, bottle: str | Bottle, seed: Any = 0, **kwargs: Any):
        """A :class:`~slipreflex.sim.Rig` of this plant holding ``bottle`` (a name of :attr:`bottles`).

        Examples
        --------
        >>> Plant().rig("DK", seed=3).bottle.name
        'DK'
        """

        if isinstance(bottle, str):
            if bottle not in self.bottles:
                raise ParameterError(f"bottle: unknown bottle {bottle!r} (known: {', '.join(self.bottles)})")
            bottle = self.bottles[bottle]
        return Rig(bottle, seed, **self.rig_kwargs(), **kwargs)


def _unpickle_plant(state: dict[str, Any]) -> Plant:
    """A pickled :class:`Plant` with its mappings read-only again."""
    return Plant(**{**state, "bottles": MappingProxyType(state["bottles"]),
                    "values": MappingProxyType(state["values"]),
                    "readings": MappingProxyType(state.get("readings", {}))})


def _parse_target(target: str) -> tuple[str, tuple[str, ...] | None, str, str | None]:
    """``"bottle[TR,DK].mu_k/mu_s"`` -> ("bottle", ("TR", "DK"), "mu_k", "mu_s")."""
    head, _, fld = target.partition(".")
    sel = None
    if "[" in head:
        head, _, rest = head.partition("[")
        sel = tuple(s.strip() for s in rest.rstrip("]").split(","))
    fld, _, ratio_of = fld.partition("/")
    return head, sel, fld, (ratio_of or None)


def plant_from_values(values: Mapping[str, float] | None = None, *,
                      table: Mapping[str, UncertainConstant] | None = None) -> Plant:
    """Build a :class:`Plant` from values of uncertain constants.

    Parameters
    ----------
    values : mapping of str to float, optional
        Values by constant name; constants not given keep their nominal value.
    table : mapping, optional
        The table to read names and nominal values from (default :data:`UNCERTAIN`).

    Returns
    -------
    Plant
        ``plant_from_values({})`` is the built-in plant: the paper's bottles as
        :data:`~slipreflex.sim.BOTTLES` holds them, bit for bit (a ratio
        constant at a bottle's own ratio keeps that bottle's field).

    Raises
    ------
    ParameterError
        On an unknown name or a value the parameter objects reject (the
        message names the constant).

    Examples
    --------
    >>> p = plant_from_values({"cuff_mu_s": 0.4, "cuff_mu_k_ratio": 0.5, "first_slip_ml": 190.0})
    >>> p.bottles["TR"].cuff_mu_s, p.bottles["TR"].cuff_mu_k, p.first_slip_ml
    (0.4, 0.2, 190.0)
    """
    table = UNCERTAIN if table is None else table
    values = dict(values or {})
    unknown = sorted(set(values) - set(table))
    if unknown:
        raise ParameterError(f"unknown uncertain constant {unknown[0]!r} (known: {', '.join(table)})")
    full = {k: float(values.get(k, c.nominal)) for k, c in table.items()}
    sections: dict[str, dict[str, float]] = {s: {} for s in (*_SECTIONS, "calibration")}
    readings: dict[str, float] = {}
    bottle_set: dict[str, dict[str, float]] = {b: {} for b in BOTTLES}
    ratios: list[tuple[str, str, float, str]] = []
    for name, val in full.items():
        for target in table[name].targets:
            head, sel, fld, ratio_of = _parse_target(target)
            if head == "bottle":
                for b in sel or tuple(BOTTLES):
                    if ratio_of:
                        ratios.append((b, fld, val, ratio_of))
                    else:
                        bottle_set[b][fld] = val
            elif head in sections:
                sections[head][fld] = val
            elif head in ("method", "judge"):      # readings of the paper, not physics: carried beside it
                readings[fld] = val
            else:
                raise ParameterError(f"{name}: unknown target {target!r}")
    for b, fld, val, ratio_of in ratios:
        own = getattr(BOTTLES[b], fld) / getattr(BOTTLES[b], ratio_of)
        base = bottle_set[b][ratio_of] if ratio_of in bottle_set[b] else getattr(BOTTLES[b], ratio_of)
        if base == getattr(BOTTLES[b], ratio_of) and round(own, 6) == val:
            continue    # the bottle's own ratio on its own base: keep its own field, bit for bit
        bottle_set[b][fld] = val * base
    defaults = {"hand": HandParams, "slip_sensor": SlipSensorParams, "imu": ImuParams,
                "tactile": TactileParams, "flow": FlowParams, "physics": PhysicsParams, "water": WaterParams}
    built: dict[str, Any] = dict(sections.pop("calibration"))
    for s, kw in sections.items():
        try:
            built[s] = defaults[s](**kw)
        except (ParameterError, TypeError) as err:
            raise ParameterError(f"uncertain constants -> {s}: {err}") from None
    bottles = {}
    for b, kw in bottle_set.items():
        surface = {k.partition(".")[2]: kw.pop(k) for k in [k for k in kw if k.startswith("surface.")]}
        try:
            more: dict[str, Any] = {"surface": replace(_surface(b), **surface)} if surface else {}
            bottles[b] = replace(BOTTLES[b], **kw, **more)
        except (ParameterError, TypeError) as err:
            raise ParameterError(f"uncertain constants -> bottle {b}: {err}") from None
    return Plant(bottles=MappingProxyType(bottles), values=MappingProxyType(full),
                 readings=MappingProxyType(readings), **built)


_RANGE_KEYS = ("low", "high", "nominal", "fixed", "distribution")


def load_ranges(path: str | Path, table: Mapping[str, UncertainConstant] | None = None
                ) -> Mapping[str, UncertainConstant]:
    """Read a TOML file that narrows, widens or fixes constants; return the modified table.

    The file has one table per constant to change::

        [hand_latency]          # narrow
        low = 0.008
        high = 0.015

        [wall_stiffness]        # widen, and change the distribution
        low = 200.0
        high = 3000.0
        distribution = "loguniform"

        [pad_mu_k_ratio]        # fix
        fixed = 0.8

    Keys: ``low``, ``high``, ``nominal``, ``distribution``, or ``fixed`` alone.
    A nominal value outside a new range is moved to the range's nearest end.

    Raises
    ------
    ParameterError
        Naming the file and the constant or key, on an unknown constant or key,
        a bad value, ``low > high`` or a missing file.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "r.toml"
    >>> _ = p.write_text("[hand_latency]\\nfixed = 0.02\\n")
    >>> t = load_ranges(p)
    >>> t["hand_latency"].fixed, t["hand_latency"].nominal
    (True, 0.02)
    """
    table = UNCERTAIN if table is None else table

    path = Path(path)
    doc = read_toml(path, "")
    out = dict(table)
    for name, spec in doc.items():
        if name not in table:
            raise ParameterError(f"{path}: [{name}]: unknown constant (known: {', '.join(table)})")
        if not isinstance(spec, dict):
            raise ParameterError(f"{path}: {name} must be a table")
        bad = sorted(set(spec) - set(_RANGE_KEYS))
        if bad:
            raise ParameterError(f"{path}: {name}.{bad[0]}: unknown key (use {', '.join(_RANGE_KEYS)})")
        c = table[name]
        if "fixed" in spec:
            if set(spec) - {"fixed"}:
                raise ParameterError(f"{path}: {name}: 'fixed' cannot be combined with other keys")
            v = spec["fixed"]
            kw: dict[str, Any] = {"low": v, "high": v, "nominal": v}
        else:
            kw = {k: spec[k] for k in ("low", "high", "distribution") if k in spec}
            lo, hi = kw.get("low", c.low), kw.get("high", c.high)
            nom = spec.get("nominal", c.nominal)
            if isinstance(lo, (int, float)) and isinstance(hi, (int, float)) and isinstance(nom, (int, float)):
                if lo > hi:
                    raise ParameterError(f"{path}: {name}: low {lo!r} > high {hi!r}")
                nom = min(max(nom, lo), hi)
            kw["nominal"] = nom
        lo_lim, hi_lim = plausible_limits(c)
        for key in ("low", "high", "nominal"):
            v = kw.get(key)
            if isinstance(v, (int, float)) and not isinstance(v, bool) and not (lo_lim <= v <= hi_lim):
                which = "fixed" if "fixed" in spec else key
                raise ParameterError(f"{path}: {name}.{which} = {v!r} {c.unit} is outside the plausible "
                                     f"{lo_lim:g}..{hi_lim:g} {c.unit} (the table's range widened "
                                     f"{WIDEN_LIMIT:g}-fold; docs/simulator.md)")
        try:
            out[name] = replace(c, **kw)
        except ParameterError as err:
            raise ParameterError(f"{path}: {err}") from None
    return MappingProxyType(out)


#: How far a ranges file may widen a constant beyond the table's plausible range: a factor on
#: each side (a value 10 times outside what the sources allow is a typo, not a plant).
WIDEN_LIMIT: float = 10.0


def plausible_limits(c: UncertainConstant) -> tuple[float, float]:
    """The values a ranges file may give ``c``: its range widened :data:`WIDEN_LIMIT`-fold each way.

    Examples
    --------
    >>> plausible_limits(UNCERTAIN["hand_latency"])
    (0.0005, 0.3)
    """
    lo = c.low / WIDEN_LIMIT if c.low > 0 else (0.0 if c.low == 0 else c.low - (WIDEN_LIMIT - 1) * (c.high - c.low))
    hi = c.high * WIDEN_LIMIT if c.high > 0 else c.high + (WIDEN_LIMIT - 1) * (c.high - c.low)
    return float(lo), float(hi)
