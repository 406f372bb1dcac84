"""Conformance checks of the device contracts: a sample source, a hand, a reflex's optional members.

Each checks an implementation against what :data:`slipreflex.core.interfaces.CONTRACTS` declares:
the required members present (a method callable), and every optional member it has of the
kind the loop reads. :func:`check_hand` sends the hand a STOP, a CLOSE and a STOP with its
guard on: run it on a virtual twin or a ``loop://`` port, never on a hand holding anything.
:mod:`slipreflex.testing` re-exports them beside :func:`~slipreflex.testing.check_reflex`.

Examples
--------
>>> class Still:
...     def read(self, timeout): return []
...     def close(self): pass
>>> check_source(Still())
0
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .grip import FINGER_SPEED_UNITS_S
from .hardware import FINGER_MAX, FINGER_MIN, TRIPOD, Finger
from .interfaces import (
    CONTRACTS,
    DaqSample,
    Hand,
    Reflex,
    SampleSource,
    TactileSample,
    TactileSource,
    missing,
    optional,
)

__all__ = ["ContractError", "check_source", "check_hand", "check_reflex_members"]


class ContractError(AssertionError):
    """An implementation breaks its protocol's contract; the message says how.

    Examples
    --------
    >>> issubclass(ContractError, AssertionError)
    True
    """


def _fail(obj: Any, what: str) -> None:
    raise ContractError(f"{type(obj).__name__} ({getattr(obj, 'name', '-')}): {what}")


def _finite(x: Any) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, bool) and math.isfinite(x)


def _required(obj: Any, protocol: type) -> None:
    lacks = missing(obj, protocol)
    if lacks:
        _fail(obj, f"is not a slipreflex.core.interfaces.{protocol.__name__} (missing: {', '.join(lacks)})")


def _optional_methods(obj: Any, protocol: type) -> None:
    for m in CONTRACTS[protocol]:
        if not m.required and m.kind == "method" and "." not in m.name:
            value = optional(obj, protocol, m.name)
            if value is not None and not callable(value):
                _fail(obj, f"{m.name} must be callable (or absent), got {value!r}")


def check_source(source: Any, *, timeout: float = 0.01) -> int:
    """Check a :class:`~slipreflex.core.interfaces.SampleSource` (or a ``TactileSource``) and its optional members.

    Reads once (``timeout`` seconds at most), then checks what it returned and, where the
    source has them, ``last_arrival``, ``stats.to_dict()``, ``drop_buffered()`` and ``port_name``.

    Returns
    -------
    int
        Samples (or frames) the read returned.

    Raises
    ------
    ContractError
        Naming the broken rule.

    Examples
    --------
    >>> class Counts:
    ...     stats = None
    ...     port_name = 7
    ...     def read(self, timeout): return []
    ...     def close(self): pass
    >>> check_source(Counts())
    Traceback (most recent call last):
    ...
    slipreflex.core.contract_checks.ContractError: Counts (-): port_name must be a str, got 7
    """
    tactile = not missing(source, TactileSource, ("read_frames",))
    protocol = TactileSource if tactile else SampleSource
    _required(source, protocol)
    _optional_methods(source, protocol)
    got = source.read_frames(timeout) if tactile else source.read(timeout)
    kind = TactileSample if tactile else DaqSample
    if not isinstance(got, list) or not all(isinstance(s, kind) for s in got):
        _fail(source, f"a read must return a list of {kind.__name__}, got {got!r:.80}")
    if tactile:
        shape = tuple(source.shape)
        if any(np.shape(s.frame) != shape for s in got):
            _fail(source, f"every frame must have the source's shape {shape}")
        if not (_finite(source.fs) and source.fs > 0):
            _fail(source, f"fs must be a finite rate > 0, got {source.fs!r}")
    arrival = optional(source, protocol, "last_arrival")
    if not isinstance(arrival, float):
        _fail(source, f"last_arrival must be a float (NaN when unknown), got {arrival!r}")
    name = optional(source, protocol, "port_name")
    if not isinstance(name, str):
        _fail(source, f"port_name must be a str, got {name!r}")
    if not tactile:
        stats = optional(source, SampleSource, "stats")
        if stats is not None:
            to_dict: Any = getattr(stats, "to_dict", None)
            counts: Any = to_dict() if callable(to_dict) else None
            if not isinstance(counts, Mapping) or not all(
                    isinstance(k, str) and isinstance(v, numbers.Integral) for k, v in counts.items()):
                _fail(source, "stats must have to_dict() giving counters {name: int}")
    drop = optional(source, protocol, "drop_buffered")
    if drop is not None:
        n = drop()
        if not isinstance(n, numbers.Integral) or n < 0:
            _fail(source, f"drop_buffered() must return how many frames it dropped (an int >= 0), got {n!r}")
    return len(got)


def check_hand(hand: Any, fingers: Sequence[Finger] = TRIPOD) -> None:
    """Check a :class:`~slipreflex.core.interfaces.Hand` and its optional members.

    With its guard on (``reflex_running(True)`` where it has one) the hand must take a STOP, a
    CLOSE and a STOP of ``fingers``; ``positions()`` must give finite positions in range of
    fingers, ``stalled()`` (where it has one) fingers. Do not run it on a hand holding anything.

    Raises
    ------
    ContractError
        Naming the broken rule.

    Examples
    --------
    >>> class Still:
    ...     def set_positions(self, targets): pass
    ...     def close_fingers(self, fingers, speed): pass
    ...     def hold(self, fingers): pass
    ...     def positions(self): return {Finger.INDEX: 600.0}
    >>> check_hand(Still())
    Traceback (most recent call last):
    ...
    slipreflex.core.contract_checks.ContractError: Still (-): positions() must give a finger position in 0..500 ...
    """
    _required(hand, Hand)
    _optional_methods(hand, Hand)
    fingers = tuple(Finger(f) for f in fingers)
    guard = optional(hand, Hand, "reflex_running")
    if guard is not None:
        guard(True)
    try:
        hand.hold(fingers)
        hand.close_fingers(fingers, FINGER_SPEED_UNITS_S)
        hand.hold(fingers)
    finally:
        if guard is not None:
            guard(False)
    where = hand.positions()
    if not isinstance(where, Mapping) or not all(
            isinstance(f, Finger) and _finite(v) and FINGER_MIN <= v <= FINGER_MAX for f, v in where.items()):
        _fail(hand, f"positions() must give a finger position in {FINGER_MIN}..{FINGER_MAX} per finger, "
                    f"got {where!r}")
    report = optional(hand, Hand, "stalled")
    if report is not None:
        stalled = report()
        try:
            [Finger(f) for f in stalled]
        except (TypeError, ValueError):
            _fail(hand, f"stalled() must give fingers, got {stalled!r}")


def check_reflex_members(reflex: Any) -> None:
    """Check the optional members of a :class:`~slipreflex.core.interfaces.Reflex` the loop reads.

    ``command`` and ``params.p0`` None or finite, ``params.hi`` finite, ``finger_offsets`` finite
    units per finger, ``last_board`` None or a dict, ``last_mismatch`` None or a str.

    Examples
    --------
    >>> from slipreflex.methods.chain import SlipReflex
    >>> check_reflex_members(SlipReflex(p0=100.0))
    """
    _optional_methods(reflex, Reflex)
    for name in ("command", "params.p0"):
        value = optional(reflex, Reflex, name)
        if value is not None and not _finite(value):
            _fail(reflex, f"{name} must be None or a finite number, got {value!r}")
    if not _finite(optional(reflex, Reflex, "params.hi")):
        _fail(reflex, f"params.hi must be a finite number, got {optional(reflex, Reflex, 'params.hi')!r}")
    offsets = optional(reflex, Reflex, "finger_offsets") or {}
    try:
        bad = {k: v for k, v in dict(offsets).items() if not _finite(v) or Finger(k) is None}
    except (TypeError, ValueError):
        bad = offsets
    if bad:
        _fail(reflex, f"finger_offsets must give finite units per finger, got {offsets!r}")
    board = optional(reflex, Reflex, "last_board")
    if board is not None and not isinstance(board, dict):
        _fail(reflex, f"last_board must be None or a dict, got {board!r}")
    mismatch = optional(reflex, Reflex, "last_mismatch")
    if mismatch is not None and not isinstance(mismatch, str):
        _fail(reflex, f"last_mismatch must be None or a str, got {mismatch!r}")
