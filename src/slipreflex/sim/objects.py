"""Objects, surfaces and perturbations of the simulated rig, as data.

Everything the experiments vary is a frozen, validated dataclass: a
:class:`Surface` (what the slip sensor and the tactile array see), a
:class:`Bottle` (mass, size, friction against the fingertip pads, surface),
a :class:`Drop` (a mass dropped into the bottle) and a :class:`Pour` (water
poured at a constant rate). Built-ins reproduce the paper's set-up
(:data:`BOTTLES`, :data:`SURFACES`, :data:`PAPER_DROP`, :data:`PAPER_POUR`);
a user adds new ones from Python or from a TOML file (:func:`load_objects`)
without editing the package. Invalid values raise
:class:`~slipreflex.core.errors.ParameterError` naming the field.

Units are SI and spelled out in the field names (``mass_kg``, ``height_m``),
except the pour, which uses the units the paper uses (L/min, ml).

Where the numbers come from (see ``docs/simulator.md`` for the long form):

* bottle mass 40 g and height 16 cm: the paper (section II-D);
* diameter 6.5 cm: the paper's "2 cm" cannot hold 500 ml in 16 cm
  (pi * 1 cm^2 * 16 cm = 50 ml); a 500 ml, 16 cm bottle is 6.3-6.5 cm wide
  (V = pi d^2 h / 4 -> d = 6.3 cm for the full volume), so 6.5 cm;
* friction, silicone fingertip pad on plastic: published static coefficients
  of silicone rubber on smooth polymers are about 0.5-1.0 and the kinetic
  ones 20-30 % lower (e.g. engineering tables for rubber on plastics; soft
  silicone fingertip studies report 0.6-1.0). Smooth PET (TR, DK): mu_s 0.6,
  mu_k 0.45; vinyl tape (TX) grips a soft pad a little better: mu_s 0.7,
  mu_k 0.5. These are estimates from that range, not fitted to any result;
* wall stiffness 600 N/m: a thin-walled 500 ml PET water bottle dents about
  1.5-2 mm under a 1 N finger push (estimate from squeezing such bottles);
* grip travel 3 cm: the fingertips hold the straight body about 3 cm below
  the shoulder; once the bottle has slid that far the contacts reach the
  taper and are lost (this defines "fallen out", see :mod:`.rig`);
* surfaces: reflectances calibrated to the paper's scan levels (white
  0.3-0.5 V, black 3.32-3.35 V); bottle reflectances and textures are
  estimates from the paper's qualitative statement that less reflective
  surfaces fluctuate less than textured ones (section II-C-2).

Examples
--------
>>> from slipreflex.sim import BOTTLES, Bottle, Drop
>>> BOTTLES["TR"].mass_kg
0.04
>>> Bottle("heavy", mass_kg=0.1, surface="DK").surface.name
'DK'
>>> Drop(mass_kg=-1)
Traceback (most recent call last):
...
slipreflex.core.errors.ParameterError: Drop.mass_kg must be a finite number > 0 and <= 5, got -1
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import MISSING, dataclass, field, fields
from pathlib import Path
from types import MappingProxyType
from typing import Any

from ..core.errors import ParameterError
from ..core.validation import number
from ..files.paths import read_toml

__all__ = [
    "Surface", "Bottle", "Drop", "Pour", "Objects", "SURFACES", "BOTTLES",
    "PAPER_DROP", "PAPER_POUR", "WATER_DENSITY", "PAPER_PAD_MU_S", "PAPER_PAD_MU_S_TX", "FRICTION_LAWS",
    "load_objects", "resolve_surface",
]

#: Density of water (kg/m^3) used for poured volume -> mass.
WATER_DENSITY: float = 1000.0
#: The pads' static friction on the paper's smooth bottles (TR, DK): calibrated so that the open-loop
#: first pour slip as the paper's instruments observe it (accelerometer-onset recipe, flow sensor; 0.8 N
#: grasp, no reflex, rig seeds 0-2) comes at the paper's 200 ml, by
#: :func:`slipreflex.sim.calibration.calibrate_bottle` (0.843267 for DK, searched from the earlier 0.973 on
#: the plant with the bounded grip and the shoulder), rounded to 4 decimals.
PAPER_PAD_MU_S: float = 0.8433
#: The same for the tape-covered TX, whose kinetic friction ratio differs (0.848723), rounded to 4 decimals.
PAPER_PAD_MU_S_TX: float = 0.8487
#: Fields a bottle from a TOML file must give (mass, size, friction, surface).
BOTTLE_REQUIRED: tuple[str, ...] = ("mass_kg", "diameter_m", "mu_s", "mu_k", "surface")
#: Friction laws a contact can have (see :class:`Bottle`).
FRICTION_LAWS: tuple[str, ...] = ("rate-state", "coulomb")


def _check(cls: str, name: str, value: Any, *, lo: float | None = None, hi: float | None = None,
           lo_open: bool = False, hi_open: bool = False) -> None:
    """A finite number within the bounds (:func:`slipreflex.core.validation.number`, the one validator)."""
    number(f"{cls}.{name}", value, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open)


@dataclass(frozen=True, slots=True)
class Surface:
    """What the slip sensor and the tactile pad see of a surface.

    Parameters
    ----------
    name : str
        Identifier (used by bottles and TOML files).
    reflectance : float
        Effective infrared reflectance in [0, 1] at the sensor's 3 mm gap, as
        the fraction of the supply voltage the phototransistor pulls down
        before saturating: mean output ``V ~= 5 V * (1 - reflectance)`` above
        the saturation knee (see :func:`slipreflex.sim.sensors.opr5005_volts`).
    texture : float
        Relative rms fluctuation of the reflectance along the surface
        (texture, anisotropy); 0 is a perfectly uniform surface.
    texture_exponent : float
        Slope ``beta`` of the texture's amplitude spectrum, ``|A(k)| ~ k**-beta``
        between ``texture_min_wavelength_m`` and ``texture_max_wavelength_m``.
    texture_min_wavelength_m, texture_max_wavelength_m : float
        Band of the texture spectrum (m). A broad band makes both slow slips
        (fine features pass the 10 Hz filter) and fast ones (coarse features)
        visible.

    Examples
    --------
    >>> s = Surface("foil", reflectance=0.8, texture=0.01)
    >>> round(s.reflectance, 2)
    0.8
    """

    name: str
    reflectance: float
    texture: float = 0.01
    texture_exponent: float = 1.0
    texture_min_wavelength_m: float = 40e-6
    texture_max_wavelength_m: float = 20e-3

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ParameterError(f"Surface.name must be a non-empty string, got {self.name!r}")
        _check("Surface", "reflectance", self.reflectance, lo=0.0, hi=1.0)
        _check("Surface", "texture", self.texture, lo=0.0, hi=0.5)
        _check("Surface", "texture_exponent", self.texture_exponent, lo=-1.0, hi=3.0)
        _check("Surface", "texture_min_wavelength_m", self.texture_min_wavelength_m, lo=2e-6, hi=0.05)
        _check("Surface", "texture_max_wavelength_m", self.texture_max_wavelength_m, lo=0.0, lo_open=True,
               hi=0.05)
        if self.texture_max_wavelength_m <= self.texture_min_wavelength_m:
            raise ParameterError("Surface.texture_max_wavelength_m must be > texture_min_wavelength_m, "
                                 f"got {self.texture_max_wavelength_m!r} <= {self.texture_min_wavelength_m!r}")


#: Built-in surfaces. "white" and "black" are the test surface of the
#: characterization scan (calibrated to the paper's Fig. 6-9 levels, see
#: docs/simulator.md); "stand" is the 3D-printed stand around it (grey PLA,
#: an estimate); "TR", "DK", "TX" are the bottles' surfaces (estimates).
SURFACES: Mapping[str, Surface] = MappingProxyType({
    # Calibrated to the paper's scan (Fig. 6-9; see docs/simulator.md) on ensemble statistics, texture
    # blurred by the sensor's spot: over 200 texture seeds the median filtered level range is 0.3-0.5 V
    # on white and 3.32-3.35 V on black (python -m scripts.research.scan_calibration; sim.scan.calibrate_surface).
    "white": Surface("white", reflectance=0.9332, texture=0.0384, texture_exponent=2.5,
                     texture_max_wavelength_m=8e-3),
    "black": Surface("black", reflectance=0.3325, texture=0.0062, texture_exponent=2.5,
                     texture_max_wavelength_m=8e-3),
    # Grey PLA stand around the test surface (estimate; only seen at the scan's ends).
    "stand": Surface("stand", reflectance=0.60, texture=0.010, texture_exponent=2.5,
                     texture_max_wavelength_m=8e-3),
    # Bottles (estimates): a broad texture band (40 um .. 40 mm, flat slope per octave,
    # exponent 1.5) so that slow slips (fine features pass the 10 Hz filter) and fast
    # ones (coarse features) both move the signal.
    # Transparent PET: little light comes back (V ~3.5 V), smooth, weak texture.
    "TR": Surface("TR", reflectance=0.30, texture=0.012, texture_exponent=1.5,
                  texture_max_wavelength_m=0.04),
    # Dark PET: the least reflective (V ~3.9 V), smooth, the weakest texture.
    "DK": Surface("DK", reflectance=0.22, texture=0.010, texture_exponent=1.5,
                  texture_max_wavelength_m=0.04),
    # Blue vinyl tape over the bottle: matte (V ~2.2 V), rough, strong texture.
    "TX": Surface("TX", reflectance=0.55, texture=0.025, texture_exponent=1.5,
                  texture_max_wavelength_m=0.04),
})


def resolve_surface(surface: Surface | str, extra: Mapping[str, Surface] | None = None,
                    where: str = "surface") -> Surface:
    """Return a :class:`Surface` given one or its name.

    Parameters
    ----------
    surface : Surface or str
        A surface, or the name of a built-in (or of one in ``extra``).
    extra : mapping of str to Surface, optional
        User surfaces looked up before the built-ins.
    where : str
        Field name used in the error message.

    Returns
    -------
    Surface

    Raises
    ------
    ParameterError
        If the name is unknown.

    Examples
    --------
    >>> resolve_surface("white").reflectance
    0.9332
    """
    if isinstance(surface, Surface):
        return surface
    if isinstance(surface, str):
        if extra and surface in extra:
            return extra[surface]
        if surface in SURFACES:
            return SURFACES[surface]
        known = sorted(set(SURFACES) | set(extra or {}))
        raise ParameterError(f"{where}: unknown surface {surface!r} (known: {', '.join(known)})")
    raise ParameterError(f"{where} must be a Surface or a surface name, got {surface!r}")


@dataclass(frozen=True, slots=True)
class Bottle:
    """A bottle held in the tripod grasp.

    Parameters
    ----------
    name : str
        Identifier ("TR", "DK", "TX" for the built-ins).
    mass_kg : float
        Empty mass (kg). Paper: 40 g.
    height_m : float
        Height (m); the dropped mass falls this far plus the drop height to
        reach the bottom. Paper: 16 cm.
    diameter_m : float
        Diameter (m) where the fingers hold it; sets where the fingertips
        touch it. 6.5 cm (see module notes).
    mu_s, mu_k : float
        Static and kinetic friction coefficients of the thumb's and index
        finger's silicone pads on this bottle (``mu_k <= mu_s``).
    surface : Surface or str
        The surface under the slip sensor and the tactile pad (a name is
        resolved against :data:`SURFACES`).
    stribeck_velocity_m_s : float
        Coulomb law only: sliding speed (m/s) over which friction falls from
        ``mu_s`` to ``mu_k`` (``mu_k + (mu_s - mu_k) exp(-(w/vs)^2)``).
        1 mm/s, typical for soft polymer contacts.
    friction_law, cuff_friction_law : {"rate-state", "coulomb"}
        The law of the pads' contacts and of the middle finger's cuff
        contact: ``"rate-state"`` (slip weakening over ``slip_distance_m``,
        healing over ``heal_s`` and a log-rate term,
        ``mu = mu_k (1 + a ln(1 + w / v0)) + (mu_s - mu_k) phi``) or
        ``"coulomb"`` (Coulomb with a Stribeck curve).
    rate_a, cuff_rate_a : float
        Log-rate coefficient ``a`` relative to ``mu_k`` (friction rises by
        ``a mu_k`` per e-fold of sliding speed) of the pads (silicone rubber:
        friction rises with log sliding speed, Grosch 1963, Vorvolakos &
        Chaudhury 2003; estimate 0.04) and of the cuff (glassy polymer on
        polymer: direct effect A ~ 0.01 at mu ~ 0.5, Baumberger & Caroli
        2006, so 0.02).
    rate_v0_m_s : float
        Reference speed ``v0`` of the log-rate term (m/s): 1 um/s.
    slip_distance_m, cuff_slip_distance_m : float
        Slip-weakening distance ``D_c`` (m) over which static friction falls
        to kinetic: 50 um for a soft pad (of the order of its micro-contacts;
        estimate), 1 um for the rigid cuff (multicontact glassy polymers,
        D_c ~ 0.5-1 um, Baumberger & Caroli 2006).
    heal_s : float
        Healing time (s) in which a stuck contact regains its static friction
        (contact ageing, Dieterich 1972; estimate 1 s).
    cuff_mu_s, cuff_mu_k : float
        Static and kinetic friction of the middle finger's rigid 3D-printed
        cuff (PLA) on this bottle: 0.3 / 0.25 (polymer-on-polymer tables give
        0.2-0.4).
    wall_stiffness_n_m : float
        Lateral stiffness (N/m) of the bottle wall under one fingertip, in
        series with the pad and the finger.
    grip_travel_m : float
        How far (m) the bottle can slide down before the fingertips reach the
        shoulder and lose contact ("fallen out").
    shoulder_slope : float
        Radius the bottle loses per metre it slides down once the fingertips
        have passed ``grip_travel_m`` and are on its shoulder (the shape the
        grasp sees): the normal force falls as the gap opens, the three
        normal forces lean along the axis and push the bottle out with ``3 N
        sin(alpha)``, and the contacts are lost when the shoulder has taken up
        the fingertips' whole travel. Estimate for the paper's 500 ml bottles:
        the shoulder narrows from the 32.5 mm body to a ~13 mm neck over
        ~40 mm, 0.49. 0: no taper, the contacts are lost at once at
        ``grip_travel_m`` (the earlier model).
    wall_linear_range_m : float
        Dent (m) of the wall under one fingertip up to which it follows the
        linear law ``wall_stiffness_n_m``: estimate 3 mm (about ten wall
        thicknesses of a 0.25 mm PET wall, where a point-loaded thin shell's
        response stops being linear; 1.8 N per contact at 600 N/m).
    wall_softening : float
        Beyond the linear range the section ovalizes into three lobes and the
        wall's stiffness falls to ``(1 - wall_softening) wall_stiffness_n_m``:
        the ring's three-lobe bending stiffness, ``W / delta = E t^3 b / (12
        x 0.0159 R^3)`` (a ring under three equal radial loads: the Fourier
        series of the inextensible ring, ``delta = (3 / pi) sum over m = 3, 6,
        ... of W R^3 / (E I (m^2 - 1)^2)``), is 420 N/m for a 0.25 mm PET
        wall (E 2.7 GPa) over a band one diameter wide (b = 65 mm, R = 32.5
        mm), so 1 - 420 / 600 = 0.3 (estimate); 0 keeps the linear law.
    wall_collapse_m : float
        Dent (m) at which the lobes fold against each other and back the
        wall: beyond it the wall is rigid and only pad and finger yield.
        Estimate: the inextensible section folds into three lobes that meet
        near the axis; 0.8 of the radius (26 mm) leaves the wall's and the
        pads' thickness and the folds' bend radius.
    grasp_height_m : float
        Height (m) of the grasp's plane above the bottom: the axis the
        bottle tilts about in the grasp. Estimate for the paper's 16 cm
        bottles: the fingertips hold the body ``grip_travel_m`` (3 cm) below
        the shoulder, which starts about 6 cm below the top (a ~2 cm
        finish and a ~4 cm shoulder, see ``shoulder_slope``): 7 cm.
    drop_eccentricity_m : float
        Horizontal distance (m) from the tilt axis at which a dropped mass
        lands on the bottom: its impact rocks the bottle. Estimate: 1 cm. A
        mass released over the opening falls inside the neck (a 28 mm
        finish has a ~21.7 mm bore: within 11 mm of the axis) and lands on a
        petaloid base whose dome moves it outward; the axis' direction to
        the landing point is random, so the lever is up to that distance.
        0: the impact on the axis, no tilt (the earlier model).

    Examples
    --------
    >>> b = Bottle("B", mass_kg=0.05, surface="TX")
    >>> b.mu_s >= b.mu_k
    True
    """

    name: str
    mass_kg: float = 0.040
    height_m: float = 0.16
    diameter_m: float = 0.065
    mu_s: float = PAPER_PAD_MU_S
    mu_k: float = 0.75 * PAPER_PAD_MU_S
    surface: Surface | str = "TR"
    stribeck_velocity_m_s: float = 1e-3
    wall_stiffness_n_m: float = 600.0
    grip_travel_m: float = 0.03
    shoulder_slope: float = 0.49
    wall_linear_range_m: float = 3e-3
    wall_softening: float = 0.3
    wall_collapse_m: float = 0.026
    grasp_height_m: float = 0.07
    drop_eccentricity_m: float = 0.01
    friction_law: str = "rate-state"
    rate_a: float = 0.04
    rate_v0_m_s: float = 1e-6
    slip_distance_m: float = 50e-6
    heal_s: float = 1.0
    cuff_mu_s: float = 0.3
    cuff_mu_k: float = 0.25
    cuff_friction_law: str = "rate-state"
    cuff_rate_a: float = 0.02
    cuff_slip_distance_m: float = 1e-6

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ParameterError(f"Bottle.name must be a non-empty string, got {self.name!r}")
        # upper bounds: what a prosthetic tripod grip can hold at all (i-Limb digits lift a few kg)
        _check("Bottle", "mass_kg", self.mass_kg, lo=0.0, lo_open=True, hi=5.0)
        _check("Bottle", "height_m", self.height_m, lo=0.0, lo_open=True, hi=1.0)
        _check("Bottle", "diameter_m", self.diameter_m, lo=0.005, hi=0.11)
        _check("Bottle", "mu_s", self.mu_s, lo=0.0, lo_open=True, hi=5.0)
        _check("Bottle", "mu_k", self.mu_k, lo=0.0, lo_open=True, hi=5.0)
        if self.mu_k > self.mu_s:
            raise ParameterError(f"Bottle.mu_k must be <= mu_s, got mu_k={self.mu_k!r} > mu_s={self.mu_s!r}")
        _check("Bottle", "stribeck_velocity_m_s", self.stribeck_velocity_m_s, lo=0.0, lo_open=True, hi=1.0)
        # 1e5 N/m: a glass wall under a fingertip; stiffer walls change nothing (the pad yields first)
        _check("Bottle", "wall_stiffness_n_m", self.wall_stiffness_n_m, lo=0.0, lo_open=True, hi=1e5)
        _check("Bottle", "grip_travel_m", self.grip_travel_m, lo=0.0, lo_open=True, hi=0.09)
        _check("Bottle", "shoulder_slope", self.shoulder_slope, lo=0.0, hi=10.0)
        _check("Bottle", "wall_linear_range_m", self.wall_linear_range_m, lo=0.0, lo_open=True, hi=0.05)
        _check("Bottle", "wall_softening", self.wall_softening, lo=0.0, hi=0.99)
        _check("Bottle", "wall_collapse_m", self.wall_collapse_m, lo=0.0, lo_open=True, hi=0.06)
        if self.wall_collapse_m < self.wall_linear_range_m:
            raise ParameterError(f"Bottle.wall_collapse_m must be >= wall_linear_range_m, got "
                                 f"{self.wall_collapse_m!r} < {self.wall_linear_range_m!r}")
        _check("Bottle", "grasp_height_m", self.grasp_height_m, lo=0.0, lo_open=True, hi=self.height_m)
        _check("Bottle", "drop_eccentricity_m", self.drop_eccentricity_m, lo=0.0, hi=self.diameter_m / 2.0)
        for f in ("friction_law", "cuff_friction_law"):
            if getattr(self, f) not in FRICTION_LAWS:
                raise ParameterError(f"Bottle.{f} must be one of {', '.join(FRICTION_LAWS)}, got {getattr(self, f)!r}")
        _check("Bottle", "rate_a", self.rate_a, lo=0.0, hi=1.0)
        _check("Bottle", "cuff_rate_a", self.cuff_rate_a, lo=0.0, hi=1.0)
        _check("Bottle", "rate_v0_m_s", self.rate_v0_m_s, lo=0.0, lo_open=True, hi=1.0)
        _check("Bottle", "slip_distance_m", self.slip_distance_m, lo=0.0, lo_open=True, hi=0.01)
        _check("Bottle", "cuff_slip_distance_m", self.cuff_slip_distance_m, lo=0.0, lo_open=True, hi=0.01)
        _check("Bottle", "heal_s", self.heal_s, lo=0.0, lo_open=True, hi=1e4)
        _check("Bottle", "cuff_mu_s", self.cuff_mu_s, lo=0.0, lo_open=True, hi=5.0)
        _check("Bottle", "cuff_mu_k", self.cuff_mu_k, lo=0.0, lo_open=True, hi=5.0)
        if self.cuff_mu_k > self.cuff_mu_s:
            raise ParameterError(f"Bottle.cuff_mu_k must be <= cuff_mu_s, got cuff_mu_k={self.cuff_mu_k!r} > "
                                 f"cuff_mu_s={self.cuff_mu_s!r}")
        object.__setattr__(self, "surface", resolve_surface(self.surface, where="Bottle.surface"))


#: The paper's three bottles (section II-D): same body, different surfaces.
#: The pads' mu_s is :data:`PAPER_PAD_MU_S` (:data:`PAPER_PAD_MU_S_TX` on tape); mu_k keeps its estimated
#: ratio to mu_s (0.75 on smooth PET, 0.714 on tape). ``tests/sim/test_sim_friction.py`` recomputes the calibration.
BOTTLES: Mapping[str, Bottle] = MappingProxyType({
    "TR": Bottle("TR", surface="TR", mu_s=PAPER_PAD_MU_S, mu_k=0.75 * PAPER_PAD_MU_S),
    "DK": Bottle("DK", surface="DK", mu_s=PAPER_PAD_MU_S, mu_k=0.75 * PAPER_PAD_MU_S),
    "TX": Bottle("TX", surface="TX", mu_s=PAPER_PAD_MU_S_TX, mu_k=0.714 * PAPER_PAD_MU_S_TX),
})


@dataclass(frozen=True, slots=True)
class Drop:
    """A mass dropped into the bottle: a second body that falls and lands.

    The mass is released at rest ``height_m`` above the bottle's opening and
    falls through it onto the bottom (bottle height + drop height). Landing
    is a compliant contact with the bottom (``contact_stiffness_n_m``) and a
    damper set from ``restitution``; the contact force acts on the bottle.

    Parameters
    ----------
    mass_kg : float
        Paper: 10 g.
    height_m : float
        Height above the opening at release (m). Paper: 2 cm.
    contact_stiffness_n_m : float
        Stiffness of the flexible PET bottom under the landing mass (N/m);
        5000 N/m (the petaloid bottom of a thin bottle flexes ~2 mm per 10 N,
        estimate).
    restitution : float
        Coefficient of restitution of the landing, in [0, 1). 0.3 (estimate for
        a small plastic/metal mass on a thin plastic bottom).

    Examples
    --------
    >>> Drop().mass_kg, Drop().height_m
    (0.01, 0.02)
    """

    mass_kg: float = 0.010
    height_m: float = 0.02
    contact_stiffness_n_m: float = 5000.0
    restitution: float = 0.3

    def __post_init__(self) -> None:
        _check("Drop", "mass_kg", self.mass_kg, lo=0.0, lo_open=True, hi=5.0)
        _check("Drop", "height_m", self.height_m, lo=0.0, hi=2.0)
        _check("Drop", "contact_stiffness_n_m", self.contact_stiffness_n_m, lo=10.0, hi=1e6)
        _check("Drop", "restitution", self.restitution, lo=0.0, hi=1.0, hi_open=True)


@dataclass(frozen=True, slots=True)
class Pour:
    """Water poured into the bottle at a constant rate.

    The flow sensor sits in the tube and counts from the start; the water
    reaches the bottle ``fall_height_m`` below the spout after its fall time
    ``sqrt(2 h / g)`` and pushes on it with the jet's momentum flux
    ``rho * Q * sqrt(2 g h)`` while it flows.

    Parameters
    ----------
    rate_l_min : float
        Flow rate (L/min). Paper: 1 L/min.
    volume_ml : float
        Volume poured (ml). Paper: 500 ml.
    fall_height_m : float
        Height of the spout above the water's landing point (m); 0.1 m
        (estimate: a tube held just above a 16 cm bottle).

    Examples
    --------
    >>> p = Pour()
    >>> round(p.duration_s, 1)
    30.0
    """

    rate_l_min: float = 1.0
    volume_ml: float = 500.0
    fall_height_m: float = 0.10

    def __post_init__(self) -> None:
        _check("Pour", "rate_l_min", self.rate_l_min, lo=0.0, lo_open=True, hi=30.0)
        _check("Pour", "volume_ml", self.volume_ml, lo=0.0, lo_open=True, hi=5000.0)
        _check("Pour", "fall_height_m", self.fall_height_m, lo=0.0, hi=2.0)

    @property
    def duration_s(self) -> float:
        """Time the pump runs (s).

        Examples
        --------
        >>> Pour(rate_l_min=2.0, volume_ml=100).duration_s
        3.0
        """
        return self.volume_ml / 1000.0 / self.rate_l_min * 60.0


#: The paper's sudden-load experiment: 10 g from 2 cm above the opening.
PAPER_DROP: Drop = Drop()
#: The paper's gradual-load experiment: 500 ml at 1 L/min.
PAPER_POUR: Pour = Pour()


@dataclass(frozen=True)
class Objects:
    """What a TOML file defines, by kind and name (see :func:`load_objects`).

    Examples
    --------
    >>> Objects().bottles
    {}
    """

    surfaces: dict[str, Surface] = field(default_factory=dict)
    bottles: dict[str, Bottle] = field(default_factory=dict)
    drops: dict[str, Drop] = field(default_factory=dict)
    pours: dict[str, Pour] = field(default_factory=dict)


def _build(cls: type, table: Any, where: str, extra_surfaces: Mapping[str, Surface] | None = None,
           name: str | None = None) -> Any:
    if not isinstance(table, dict):
        raise ParameterError(f"{where}: must be a table, got {type(table).__name__}")
    known = {f.name for f in fields(cls)}
    kwargs = dict(table)
    if name is not None:
        kwargs.setdefault("name", name)
    unknown = sorted(set(kwargs) - known)
    if unknown:
        raise ParameterError(f"{where}.{unknown[0]}: unknown field (known: {', '.join(sorted(known))})")
    required = [f.name for f in fields(cls) if f.default is MISSING and f.default_factory is MISSING]
    for req in required:
        if req not in kwargs:
            raise ParameterError(f"{where}.{req}: missing field")
    if cls is Bottle:
        # a user's bottle must say what it weighs, how wide it is, how it grips and what it looks like
        for req in BOTTLE_REQUIRED:
            if req not in kwargs:
                raise ParameterError(f"{where}.{req}: missing field (a bottle needs {', '.join(BOTTLE_REQUIRED)})")
    if cls is Bottle and "surface" in kwargs:
        kwargs["surface"] = resolve_surface(kwargs["surface"], extra_surfaces, where=f"{where}.surface")
    try:
        obj = cls(**kwargs)
    except ParameterError as err:
        msg = str(err)
        # "Bottle.mass_kg must be ..." -> "<file>: bottles.X.mass_kg must be ..."
        head = f"{cls.__name__}."
        raise ParameterError(f"{where}.{msg[len(head):]}" if msg.startswith(head) else f"{where}: {msg}") from None
    return obj


def load_objects(path: str | Path) -> Objects:
    """Read surfaces, bottles, drops and pours from a TOML file.

    The file has up to four tables of named entries; every field of the
    matching dataclass may be given, the others keep their defaults::

        [surfaces.foil]
        reflectance = 0.8
        texture = 0.02

        [bottles.BIG]
        mass_kg = 0.06
        diameter_m = 0.07
        mu_s = 0.5
        mu_k = 0.4
        surface = "foil"      # a surface from this file or a built-in

        [drops.heavy]
        mass_kg = 0.02
        height_m = 0.05

        [pours.slow]
        rate_l_min = 0.5
        volume_ml = 300

    Parameters
    ----------
    path : str or Path
        The TOML file.

    Returns
    -------
    Objects

    Raises
    ------
    ParameterError
        On a missing or unknown field, an out-of-range value, an unknown
        surface or an unknown table; the message names the file and field.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "o.toml"
    >>> _ = p.write_text('[bottles.B]\\nmass_kg = 0.05\\ndiameter_m = 0.06\\nmu_s = 1.0\\nmu_k = 0.8\\n'
    ...                  'surface = "DK"\\n')
    >>> load_objects(p).bottles["B"].surface.name
    'DK'
    """

    path = Path(path)
    doc = read_toml(path, "")
    unknown = sorted(set(doc) - {"surfaces", "bottles", "drops", "pours"})
    if unknown:
        raise ParameterError(f"{path}: unknown table [{unknown[0]}] (use surfaces, bottles, drops, pours)")
    for kind in ("surfaces", "bottles", "drops", "pours"):
        if kind in doc and not isinstance(doc[kind], dict):
            raise ParameterError(f"{path}: {kind} must be a table of named entries ([{kind}.NAME]), "
                                 f"got {type(doc[kind]).__name__} {doc[kind]!r:.40}")
    out = Objects()
    for name, table in (doc.get("surfaces") or {}).items():
        out.surfaces[name] = _build(Surface, table, f"{path}: surfaces.{name}", name=name)
    for name, table in (doc.get("bottles") or {}).items():
        out.bottles[name] = _build(Bottle, table, f"{path}: bottles.{name}", out.surfaces, name=name)
    for name, table in (doc.get("drops") or {}).items():
        out.drops[name] = _build(Drop, table, f"{path}: drops.{name}")
    for name, table in (doc.get("pours") or {}).items():
        out.pours[name] = _build(Pour, table, f"{path}: pours.{name}")
    return out
