"""Before the real-time loop's clock starts: the start positions, the safe start, and what the
reflex and the source are checked for (a one-line error before anything is sent).

Examples
--------
>>> start_positions(147)[Finger.MIDDLE]
147.0
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..core.errors import ParameterError
from ..core.hardware import FINGER_MAX, FINGER_MIN, THUMB_ROTATOR_MAX, TRIPOD, Finger
from ..core.interfaces import Hand, Reflex, SampleSource, TactileSource, missing, optional
from ..core.validation import number

__all__ = ["start_positions", "safe_start", "finger_offsets", "reflex_start"]


def start_positions(p0: float | Mapping[Any, float], fingers: Sequence[Finger] = TRIPOD,
                    *, where: str = "p0") -> dict[Finger, float]:
    """Validate ``p0`` and give one start position per finger.

    Parameters
    ----------
    p0 : float or mapping of Finger (or finger name) to float
        One position for every finger, or one per finger (every finger of
        ``fingers`` must be given). Positions are whole i-Limb units in the
        finger's range (0..500).
    fingers : sequence of Finger
    where : str
        Name used in error messages (e.g. ``"--p0"``).

    Returns
    -------
    dict of Finger to float
        The start position of every finger of ``fingers``, in that order.

    Raises
    ------
    ParameterError
        A missing or unknown finger, or a position that is not a whole
        number in range; the message names ``where`` and the finger.

    Examples
    --------
    >>> start_positions({"thumb": 149, "index": 147, "middle": 147})[Finger.THUMB]
    149.0
    >>> start_positions(600)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: p0: THUMB must be a whole position in 0..500, got 600
    """
    fingers = tuple(Finger(f) for f in fingers)
    if isinstance(p0, Mapping):
        given: dict[Finger, Any] = {}
        for k, v in p0.items():
            try:
                f = Finger[k.upper()] if isinstance(k, str) else Finger(k)
                if f not in fingers:
                    raise KeyError(k)
            except (KeyError, ValueError):
                raise ParameterError(f"{where}: finger {k!r} is not one of the grasping fingers "
                                     f"(fingers: {', '.join(x.name.lower() for x in fingers)})") from None
            given[f] = v
        missing = [f.name.lower() for f in fingers if f not in given]
        if missing:
            raise ParameterError(f"{where}: no position for {', '.join(missing)} "
                                 f"(give every finger, e.g. thumb=149,index=147,middle=147)")
    else:
        given = {f: p0 for f in fingers}
    out: dict[Finger, float] = {}
    for f in fingers:
        v = given[f]
        hi = THUMB_ROTATOR_MAX if f == Finger.THUMB_ROTATOR else FINGER_MAX
        try:
            v = number(f"{where}: {f.name}", v, lo=FINGER_MIN, hi=hi)
        except ParameterError:
            v = math.nan
        if not v.is_integer():  # the i-Limb takes whole units
            raise ParameterError(f"{where}: {f.name} must be a whole position in {FINGER_MIN}..{hi}, "
                                 f"got {given[f]!r}")
        out[f] = v
    return out


def safe_start(hand: Hand, p0: float | Mapping[Any, float],
               fingers: Sequence[Finger] = TRIPOD) -> dict[Finger, float]:
    """Hold the fingers where they are, then tell where each one holds.

    The hand is told to STOP (``hand.hold(fingers)``): the fingers are never
    moved to a value at start. Each finger's start position is the position
    the hand reports for it where it measures its fingers, else its ``p0``.
    The start is bookkeeping only (the reflex's frame, the recording): the
    loop adds grip as closing time and never sends a position. The i-Limb
    reports no positions over its serial protocol, so for it the start is
    the ``p0`` given.

    Parameters
    ----------
    hand : Hand
    p0 : float or mapping
        See :func:`start_positions`.
    fingers : sequence of Finger

    Returns
    -------
    dict of Finger to float
        Start position per finger.

    Raises
    ------
    ParameterError
        A bad ``p0`` (before anything is sent).

    Examples
    --------
    >>> class Hand:                        # a hand that measures its fingers
    ...     def __init__(self): self.sent = []
    ...     def set_positions(self, t): self.sent.append(t)
    ...     def positions(self): return {Finger.THUMB: 149.0, Finger.INDEX: 147.0, Finger.MIDDLE: 147.0}
    ...     def hold(self, fingers): self.sent.append("stop")
    >>> h = Hand()
    >>> safe_start(h, 500)[Finger.THUMB], h.sent
    (149.0, ['stop'])
    """
    start = start_positions(p0, fingers)
    hand.hold(tuple(start))
    reported = hand.positions()
    for f, v in reported.items():
        if f in start and isinstance(v, (int, float)) and math.isfinite(v):
            start[f] = float(v)
    return start


def finger_offsets(reflex: Any, fingers: Sequence[Finger] = TRIPOD) -> dict[Finger, float]:
    """The per-finger offsets a reflex asks the hand to add to its command, checked.

    A reflex may declare ``finger_offsets`` ({finger: units}; the authors' rig
    code, preset ``authors-gui``, sends the middle finger the command + 20).
    Offsets of fingers outside ``fingers`` are ignored, as in the simulator.

    Parameters
    ----------
    reflex : Reflex
    fingers : sequence of Finger

    Returns
    -------
    dict of Finger to float
        Offset (units) of each finger of ``fingers`` that has one; empty for most reflexes.

    Raises
    ------
    ParameterError
        An offset that is not a finite number (before anything is sent).

    Examples
    --------
    >>> from slipreflex.methods.chain import SlipReflex
    >>> finger_offsets(SlipReflex.from_preset("authors-gui", p0=147.0))
    {<Finger.MIDDLE: 2>: 20.0}
    >>> finger_offsets(SlipReflex())
    {}
    """
    out: dict[Finger, float] = {}
    for k, v in (optional(reflex, Reflex, "finger_offsets") or {}).items():
        f = Finger(k)
        if f not in fingers:
            continue
        if not (isinstance(v, (int, float)) and math.isfinite(v)):
            raise ParameterError(f"run_loop: reflex finger_offsets[{f.name.lower()}] must be a finite "
                                 f"number, got {v!r}")
        out[f] = float(v)
    return out


def reflex_start(reflex: Any) -> float | None:
    """Where a reflex's command starts: its ``command`` before the first step, else its
    ``params.p0`` (a board twin, a tactile method), else None (the loop then takes the
    measured grasp). Rises above it are the grip the loop adds.

    Examples
    --------
    >>> from slipreflex import methods
    >>> reflex_start(methods.make("dath", p0=148.0)), reflex_start(methods.make("dath-board", p0=148.0))
    (148.0, 148.0)
    >>> reflex_start(object()) is None
    True
    """
    for x in (optional(reflex, Reflex, "command"), optional(reflex, Reflex, "params.p0")):
        if isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x):
            return float(x)
    return None


class _FrameReader:
    """A :class:`~slipreflex.core.interfaces.TactileSource` as the loop reads a source."""

    def __init__(self, source: Any) -> None:
        self.tactile = source
        self.port_name = optional(source, TactileSource, "port_name")

    @property
    def last_arrival(self) -> float:
        return optional(self.tactile, TactileSource, "last_arrival")

    def read(self, timeout: float) -> list[Any]:
        return self.tactile.read_frames(timeout)

    def drop_buffered(self) -> int:
        # a source that reads on its own thread (the Ability Hand's pump) queues frames during the set-up
        drop: Any = optional(self.tactile, TactileSource, "drop_buffered")
        return int(drop()) if drop is not None else 0

    def close(self) -> None:
        self.tactile.close()


def _source_for(source: Any, reflex: Any) -> Any:
    """The source the loop reads for this reflex's input (a one-line error if it has none)."""
    kind, name = reflex.input_kind, reflex.name
    if kind == "tactile":
        if missing(source, TactileSource, ("read_frames",)):
            raise ParameterError(f"run_loop: reflex {name!r} reads tactile frames, but the source gives "
                                 f"none (a TactileSource, e.g. the Ability Hand's touch sites)")
        return _FrameReader(source)
    if kind != "slip" or missing(source, SampleSource, ("read",)):
        raise ParameterError(f"run_loop: reflex {name!r} reads {kind!r}, but the source gives "
                             f"slip-sensor samples only")
    return source


def _warm_up(reflex: Any) -> None:
    """Step a copy once, so that what the first step loads or compiles (about 0.3 s for the
    chain) happens before the clock starts, not on the first real sample (a stall that the
    staleness check and the stall guard would rightly report). The reflex itself is untouched."""
    try:
        twin = copy.deepcopy(reflex)
    except Exception:  # noqa: BLE001 - a reflex that cannot be copied is simply not warmed up
        return
    shape = optional(reflex, Reflex, "params.shape")
    try:
        twin.step(0.0 if reflex.input_kind == "slip" else np.zeros(shape), None)
    except Exception as err:  # noqa: BLE001 - a method that cannot take one sample is refused, nothing sent
        name = reflex.name
        raise ParameterError(f"run_loop: method {name!r} raised in step() on a warm-up sample "
                             f"({type(err).__name__}: {err}); nothing was sent to the hand") from None
