"""The physics terms of the simulated plant, as one table.

A physics term is a piece of the plant's physics that the verdicts hinge on and
that can be switched off: it has an "absent" value (the value at which the plant
behaves as if the term were not modelled). The table names each term once, with
the uncertain constant that carries it; the parameter it sets, its source and its
plausible range are read from :data:`slipreflex.sim.uncertain.UNCERTAIN` (one
definition), never copied.

* :data:`PHYSICS_TERMS` is the table (name -> :class:`PhysicsTerm`).
* :data:`SWITCHES` names what the physics scripts and the ablation switch off
  together: the groups of :data:`GROUPS` (``grip``, the bounded grip; ``roll``,
  the fingertip's roll and the gap's opening) and each term alone;
  :data:`VERDICT_SWITCHES` the ones the physics tables run.
* :func:`absent_values` gives the uncertain-constant values that switch terms
  off, ready for :func:`~slipreflex.sim.uncertain.plant_from_values`.
* :func:`markdown_table` is the table as docs/simulator.md quotes it (a test
  keeps the two equal).

Adding a term: its parameter in :mod:`slipreflex.sim.params` (or
:mod:`slipreflex.sim.objects` for a bottle's), its fill in ``Rig._params``, its
slot and use in :mod:`slipreflex.sim.kernel`, its row with range and source in
:data:`~slipreflex.sim.uncertain.UNCERTAIN`, and its row here.

Examples
--------
>>> from slipreflex.sim.terms import PHYSICS_TERMS, absent_values
>>> PHYSICS_TERMS["tilt"].parameters
('bottle.drop_eccentricity_m',)
>>> absent_values("grip")
{'wall_softening': 0.0, 'motor_droop': 0.0}
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from ..core.errors import ParameterError
from .uncertain import UNCERTAIN, UncertainConstant

__all__ = ["PhysicsTerm", "PHYSICS_TERMS", "GROUPS", "SWITCHES", "VERDICT_SWITCHES", "absent_values", "markdown_table"]


@dataclass(frozen=True, slots=True)
class PhysicsTerm:
    """One physics term: what it is, the uncertain constant that carries it and its "absent" value.

    Parameters
    ----------
    name : str
        Short identifier (a switch name of the physics scripts and the ablation).
    title : str
        What the term is, in a few words.
    constant : str
        The name of the constant in :data:`~slipreflex.sim.uncertain.UNCERTAIN` that sets it.
    absent : float
        The constant's value that switches the term off (inside its plausible range).

    Examples
    --------
    >>> t = PHYSICS_TERMS["events"]
    >>> t.constant, t.absent, t.low <= t.absent <= t.high
    ('slip_events', 0.0, True)
    """

    name: str
    title: str
    constant: str
    absent: float

    def __post_init__(self) -> None:
        if self.constant not in UNCERTAIN:
            raise ParameterError(f"physics term {self.name!r}: unknown uncertain constant {self.constant!r}")
        c = UNCERTAIN[self.constant]
        if not c.low <= self.absent <= c.high:
            raise ParameterError(f"physics term {self.name!r}: absent value {self.absent!r} is outside "
                                 f"{self.constant}'s plausible range {c.low:g}..{c.high:g} {c.unit}")

    @property
    def uncertain(self) -> UncertainConstant:
        """The constant's row of the uncertain table.

        Examples
        --------
        >>> PHYSICS_TERMS["motor"].uncertain.unit
        'N'
        """
        return UNCERTAIN[self.constant]

    @property
    def parameters(self) -> tuple[str, ...]:
        """The parameter fields it sets (``"hand.motor_droop"``: a field of :class:`~slipreflex.sim.HandParams`).

        Examples
        --------
        >>> PHYSICS_TERMS["droop"].parameters
        ('hand.motor_droop',)
        """
        return self.uncertain.targets

    @property
    def source(self) -> str:
        """The published source of its range, or the reason for the estimate.

        Examples
        --------
        >>> PHYSICS_TERMS["incipient"].source.startswith("absent")
        True
        """
        return self.uncertain.source

    @property
    def low(self) -> float:
        """The lower end of its plausible range.

        Examples
        --------
        >>> PHYSICS_TERMS["wall"].low
        0.0
        """
        return self.uncertain.low

    @property
    def high(self) -> float:
        """The upper end of its plausible range.

        Examples
        --------
        >>> PHYSICS_TERMS["wall"].high
        0.67
        """
        return self.uncertain.high


def _t(name: str, title: str, constant: str, absent: float) -> PhysicsTerm:
    return PhysicsTerm(name, title, constant, absent)


#: The table: every physics term, by name, in the order the documents list them.
PHYSICS_TERMS: Mapping[str, PhysicsTerm] = MappingProxyType({t.name: t for t in (
    _t("wall", "wall softening: the bottle's wall beyond its linear range", "wall_softening", 0.0),
    _t("droop", "motor droop: the motor's torque-speed line", "motor_droop", 0.0),
    _t("spot", "spot travel: the fingertip's roll moving the sensed spot", "spot_travel_per_unit", 0.0),
    _t("gap", "gap dent: the gap's opening by the wall's dent", "gap_dent_fraction", 0.0),
    _t("events", "micro-slip events of the pads", "slip_events", 0.0),
    _t("incipient", "incipient slip: the Cattaneo-Mindlin redistribution", "incipient_slip", 0.0),
    _t("motor", "motor vibration of the digits", "motor_vibration", 0.0),
    _t("shoulder", "shoulder slope: the bottle's taper above the grasp", "shoulder_slope", 0.0),
    _t("tilt", "tilt: a drop landing off the axis rocks the bottle", "drop_eccentricity", 0.0),
)})

#: Terms switched off together, by group name: the bounded grip, and the fingertip's roll with the gap's opening.
GROUPS: Mapping[str, tuple[str, ...]] = MappingProxyType({"grip": ("wall", "droop"), "roll": ("spot", "gap")})

#: What the physics scripts and the ablation can switch off, by name: each group, then each term alone.
SWITCHES: Mapping[str, tuple[str, ...]] = MappingProxyType({**GROUPS, **{n: (n,) for n in PHYSICS_TERMS}})

#: The switches the verdicts hinge on, in the order the physics tables print them: each group,
#: then each term that is in none (a term in a group is a half of it).
VERDICT_SWITCHES: tuple[str, ...] = (*GROUPS, *(n for n in PHYSICS_TERMS
                                               if not any(n in g for g in GROUPS.values())))


def absent_values(*switches: str) -> dict[str, float]:
    """The uncertain-constant values that switch off every term of ``switches`` (every term if none given).

    Raises
    ------
    ParameterError
        On an unknown switch, naming the known ones.

    Examples
    --------
    >>> absent_values("tilt")
    {'drop_eccentricity': 0.0}
    >>> len(absent_values()) == len(PHYSICS_TERMS)
    True
    """
    names: list[str] = []
    for s in switches or tuple(PHYSICS_TERMS):
        if s not in SWITCHES:
            raise ParameterError(f"unknown physics term {s!r} (known: {', '.join(SWITCHES)})")
        names += [n for n in SWITCHES[s] if n not in names]
    return {PHYSICS_TERMS[n].constant: PHYSICS_TERMS[n].absent for n in names}


def markdown_table() -> str:
    """The table as Markdown (docs/simulator.md quotes it; a test keeps the two equal).

    Examples
    --------
    >>> markdown_table().splitlines()[0].startswith("| term |")
    True
    """
    lines = ["| term | what | constant | sets | absent | plausible range | source |",
             "|---|---|---|---|---|---|---|"]
    for t in PHYSICS_TERMS.values():
        c = t.uncertain
        lines.append(f"| `{t.name}` | {t.title} | `{t.constant}` | {', '.join(f'`{p}`' for p in t.parameters)} | "
                     f"{t.absent:g} | {c.low:g}..{c.high:g} {c.unit} | {t.source} |")
    return "\n".join(lines)
