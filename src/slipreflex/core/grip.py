"""Grip only ever added: a reflex's commands become closing time, never a position.

A reflex (the paper's MPI, NMSD's closing rule) outputs a command in finger
position units that never decreases. Sending it as a position target trusts
the reflex's frame: a ``p0`` that is not where the fingers really are opens
the hand (a command below them) or makes it jump shut (a command far above).
The rule here sends only what the command *rises* by, as closing time: a rise
of ``g`` units closes the fingers at the hand's documented closing speed
(:data:`~slipreflex.core.hardware.FINGER_SPEED_UNITS_S`, full PWM) for
``g / speed`` seconds, then STOP. A rise that comes while the fingers are
still closing extends the closing by its own time (NMSD's rule, each detection
adding its closing time). Nothing else reaches the fingers: no OPEN and no
position, so a reflex cannot open the hand, whatever its start says.

:class:`Grip` holds the arithmetic, once, for every finger group; the
real-rig loop (:func:`slipreflex.rig.runtime.run_loop`) and the simulator's closed
loop (:func:`slipreflex.sim.run_closed_loop`, Python and compiled) apply it,
so simulation and rig agree. A reflex's declared ``finger_offsets`` (the
authors' rig code closes the middle finger 20 units further) become one extra
rise of that finger's group at the first command, as the position rule gave it.

Examples
--------
>>> from slipreflex.core.hardware import TRIPOD, Finger
>>> g = Grip(147.0, TRIPOD)
>>> g.rise(157.0)                      # 10 units more grip for the one group
[10.0]
>>> g.rise(150.0), g.rise(157.0)       # a command that does not rise adds nothing
([0.0], [0.0])
>>> span(0.1, -math.inf, 10.0)         # close from 0.1 s for 16 ms
(0.1, 0.116)
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

from .errors import ParameterError
from .hardware import FINGER_MAX, FINGER_MIN, FINGER_SPEED_UNITS_S, Finger

__all__ = ["Grip", "span", "finger_groups", "FINGER_SPEED_UNITS_S", "TRAVEL"]

#: One whole finger travel (units): the most grip a run adds to a finger, whatever the reflex says.
TRAVEL: float = float(FINGER_MAX - FINGER_MIN)


def finger_groups(fingers: Iterable[Finger], offsets: Mapping[Finger, float] | None = None
                  ) -> list[tuple[tuple[Finger, ...], float]]:
    """Fingers that close together: ``(fingers, offset)`` pairs, in the order of ``fingers``.

    Fingers with the same declared offset (0 when none) share a group: they get the same
    closing time at the same moments.

    Examples
    --------
    >>> from slipreflex.core.hardware import TRIPOD
    >>> finger_groups(TRIPOD, {Finger.MIDDLE: 20.0})
    [((<Finger.THUMB: 0>, <Finger.INDEX: 1>), 0.0), ((<Finger.MIDDLE: 2>,), 20.0)]
    """
    offs = {Finger(f): float(v) for f, v in (offsets or {}).items()}
    groups: dict[float, list[Finger]] = {}
    for f in fingers:
        groups.setdefault(offs.get(Finger(f), 0.0), []).append(Finger(f))
    return [(tuple(fs), off) for off, fs in groups.items()]


def span(t: float, until: float, grip: float, speed: float = FINGER_SPEED_UNITS_S) -> tuple[float, float]:
    """When closing for ``grip`` units starts and stops, given a closing that runs ``until``.

    ``start = max(t, until)`` (a closing in progress is extended, not restarted),
    ``stop = start + grip / speed``. The simulator's compiled loop repeats these two
    operations in the same order, so both loops give the same bits.

    Parameters
    ----------
    t : float
        Time of the command (s).
    until : float
        When the closing in progress ends (``-inf``: none).
    grip : float
        Units of grip to add (>= 0).
    speed : float
        Closing speed (units/s).

    Returns
    -------
    tuple of float
        ``(start, stop)`` in seconds.

    Examples
    --------
    >>> span(1.0, 1.05, 6.25)          # still closing until 1.05 s: 10 ms more
    (1.05, 1.06)
    """
    start = t if t > until else until
    return start, start + grip / speed


class Grip:
    """The rises of a reflex's command, per finger group: the grip the hand is to add.

    Parameters
    ----------
    start : float
        The reflex's command when the loop starts (its bookkeeping of where the
        fingers are; ``SlipReflex``: its ``p0``). Only rises above it add grip.
    fingers : iterable of Finger
        The fingers that grasp.
    offsets : mapping of Finger to float, optional
        A reflex's declared ``finger_offsets``: that finger's group closes
        ``offset`` units further at the first command (the position rule's
        ``command + offset``).
    ceiling : float, optional
        The highest level any group is taken to (the real-rig loop gives ``start`` plus
        one whole finger travel, :data:`TRAVEL`: whatever a reflex commands, 1e9, a
        start of -1e6, an offset of 1e7, no finger gets more than that much grip in a
        run). None: no ceiling (the simulator's loops, whose compiled twin has none).

    Attributes
    ----------
    groups : list of (tuple of Finger, float)
        See :func:`finger_groups`.
    levels : list of float
        Per group, the command (plus offset) already turned into grip.
    added : list of float
        Per group, the grip added so far (units).

    Examples
    --------
    >>> from slipreflex.core.hardware import TRIPOD
    >>> g = Grip(100.0, TRIPOD, {Finger.MIDDLE: 20.0})
    >>> g.rise(110.0), g.rise(115.0), g.added
    ([10.0, 30.0], [5.0, 5.0], [15.0, 35.0])
    >>> Grip(100.0, TRIPOD, ceiling=100.0 + TRAVEL).rise(1e9)   # never more than one finger travel
    [500.0]
    """

    def __init__(self, start: float, fingers: Iterable[Finger],
                 offsets: Mapping[Finger, float] | None = None, ceiling: float | None = None) -> None:
        if isinstance(start, bool) or not isinstance(start, (int, float)) or not math.isfinite(start):
            raise ParameterError(f"grip: the reflex's start must be a finite number, got {start!r}")
        self.groups = finger_groups(fingers, offsets)
        self.levels = [float(start)] * len(self.groups)
        self.added = [0.0] * len(self.groups)
        self.ceiling = math.inf if ceiling is None else float(ceiling)

    def rise(self, command: float) -> list[float]:
        """Grip (units, >= 0) each group is to add for a new ``command``.

        Raises
        ------
        ParameterError
            For a command that is not a finite number (nothing is added).

        Examples
        --------
        >>> from slipreflex.core.hardware import TRIPOD
        >>> Grip(0.0, TRIPOD).rise(float("nan"))
        Traceback (most recent call last):
        ...
        slipreflex.core.errors.ParameterError: grip: the reflex's command must be a finite number, got nan
        """
        if isinstance(command, bool) or not isinstance(command, (int, float)) or not math.isfinite(command):
            raise ParameterError(f"grip: the reflex's command must be a finite number, got {command!r}")
        out = []
        for i, (_, off) in enumerate(self.groups):
            want = min(command + off, self.ceiling)
            g = want - self.levels[i] if want > self.levels[i] else 0.0
            if g > 0.0:
                self.levels[i] = want
                self.added[i] += g
            out.append(g)
        return out
