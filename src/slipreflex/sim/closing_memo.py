"""Grasps closed once: the closing phase of :meth:`slipreflex.sim.Rig.grasp`, kept by every input.

While the bottle stands on its support (the grasp's closing and its first settle, until the
support is taken away) the contacts' friction enters nothing the rig computes: the kernel
skips the contacts (their tangential forces stay zero), the adaptive stepping asks about
friction only once the support is gone, and a tactile frame's shear is zero whatever the
friction (the Cattaneo-Mindlin shear of a zero tangential force is zero for any positive
friction coefficient, and the clamp ``1.5 mu_s N`` of a zero shear leaves it zero). So the
rig's whole state at the end of the closing phase does not depend on the pads' or the cuff's
friction, and a calibration, whose open-loop pours differ only in the pads' friction, can
close each seed's grasp once and continue it under every candidate's friction.

:data:`CLOSINGS` keeps the last few closing phases. The key is a digest of everything the
closing phase reads: the rig's parameter vector with the friction slots blanked (so every
other constant of the bottle, the hand, the sensors and the physics is in it), its state,
counters and random stream keys before the grasp, the slip sensor's track, the hand's
parameters and servo targets, the tactile parameters, the grasp's force, speed and settle
time and whether the rig keeps its history. Only a rig that has done nothing yet (no step,
no command, no sampler, no perturbation) is kept or restored; any other grasp runs in full.
A restored rig holds copies: nothing it does reaches the kept closing.

Examples
--------
>>> from slipreflex.sim import BOTTLES, Rig
>>> from dataclasses import replace
>>> CLOSINGS.clear()
>>> a = Rig(BOTTLES["TR"], seed=3); _ = a.grasp()
>>> b = Rig(replace(BOTTLES["TR"], mu_s=0.9, mu_k=0.7), seed=3); _ = b.grasp()    # closed from a's
>>> CLOSINGS.hits, len(CLOSINGS)
(1, 1)
"""

from __future__ import annotations

import contextlib
import hashlib
import weakref
from collections import OrderedDict
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from . import kernel as K

__all__ = ["Closing", "ClosingMemo", "CLOSINGS", "CLOSINGS_KEEP", "friction_slots", "array_digest"]

#: Closing phases :data:`CLOSINGS` keeps (each about 0.1-0.2 MB: its DAQ rows; a plant's calibration
#: needs at most one per bottle and seed, three seeds and three bottles).
CLOSINGS_KEEP: int = 16


def friction_slots() -> np.ndarray:
    """Indices of the kernel parameter vector holding the contacts' friction (``mu_s``, ``mu_k``, the rate term).

    Examples
    --------
    >>> int(friction_slots()[0]) == K.P_C0 + K.PC_MUS, friction_slots().size
    (True, 9)
    """
    return np.array([K.P_C0 + i * K.PC_SIZE + s for i in range(3) for s in (K.PC_MUS, K.PC_MUK, K.PC_A)])


_FRICTION = friction_slots()
#: Digests of the tracks' reflectance arrays, by the array (a track is built once and shared, read-only).
_DIGESTS: dict[int, tuple[weakref.ref, bytes]] = {}
_DIGESTS_KEEP = 64


def array_digest(a: np.ndarray) -> bytes:
    """A digest of a read-only array's bytes, computed once per array object.

    Examples
    --------
    >>> x = np.arange(4.0); array_digest(x) == array_digest(x.copy())
    True
    """
    hit = _DIGESTS.get(id(a))
    if hit is not None and hit[0]() is a:
        return hit[1]
    d = hashlib.blake2b(np.ascontiguousarray(a).tobytes(), digest_size=16).digest()
    if len(_DIGESTS) >= _DIGESTS_KEEP:
        for k in [k for k, (ref, _) in _DIGESTS.items() if ref() is None] or list(_DIGESTS)[:_DIGESTS_KEEP // 2]:
            del _DIGESTS[k]
    _DIGESTS[id(a)] = (weakref.ref(a), d)
    return d


def closing_key(P: np.ndarray, arrays: tuple[np.ndarray, ...], track: np.ndarray, text: str) -> bytes | None:
    """The key of a closing phase: ``P`` with its friction blanked, ``arrays`` and ``track`` by content, ``text``.

    None (nothing kept) if a friction coefficient is not positive: the zero shear of a supported
    bottle's tactile frames needs a positive one.

    Examples
    --------
    >>> P = np.ones(K.P_SIZE); Q = P.copy(); Q[friction_slots()] = 2.0
    >>> closing_key(P, (), np.zeros(3), "x") == closing_key(Q, (), np.zeros(3), "x")
    True
    >>> Q[friction_slots()[0]] = 0.0; closing_key(Q, (), np.zeros(3), "x") is None
    True
    """
    if not bool(np.all(P[_FRICTION] > 0.0)):
        return None
    blank = P.copy()
    blank[_FRICTION] = 0.0
    h = hashlib.blake2b(digest_size=32)
    for a in (blank, *arrays):
        h.update(str(a.dtype).encode() + str(a.shape).encode())
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(array_digest(track))
    h.update(text.encode())
    return h.digest()


@dataclass(frozen=True)
class Closing:
    """A rig's state at the end of a grasp's closing phase (copies, never handed out).

    Attributes
    ----------
    S, C, D, W : ndarray
        The kernel's state, counters and load tables.
    daq : tuple of ndarray
        The DAQ history's chunks.
    events : tuple of ndarray
        The physics events' chunks.
    hand : tuple
        The hand's pending commands, their next number, the other digits, ``closing_until``, targets, speeds.
    samplers_made, oneoff : int
        Counters of the tactile streams handed out.
    t_contact : float
        When the first finger's array reached the grasp force.

    Examples
    --------
    >>> Closing(*(np.zeros(1),) * 4, (), (), ([], 0, {}, {}, np.zeros(3), np.zeros(3)), 2, 0, 0.5).t_contact
    0.5
    """

    S: np.ndarray
    C: np.ndarray
    D: np.ndarray
    W: np.ndarray
    daq: tuple
    events: tuple
    hand: tuple
    samplers_made: int
    oneoff: int
    t_contact: float


class ClosingMemo:
    """The last ``keep`` closing phases by key (least recently used dropped first), with hit counts.

    Examples
    --------
    >>> m = ClosingMemo(keep=1); m.put(b"a", 1); m.put(b"b", 2)
    >>> m.get(b"a"), m.get(b"b"), len(m)
    (None, 2, 1)
    >>> with m.disabled():
    ...     m.get(b"b")
    """

    def __init__(self, keep: int = CLOSINGS_KEEP) -> None:
        self.keep = int(keep)
        self.enabled = True
        self.hits = 0
        self._kept: OrderedDict[bytes, Closing] = OrderedDict()

    def __len__(self) -> int:
        return len(self._kept)

    def get(self, key: bytes | None):
        """The closing kept under ``key`` (None if none, or while disabled)."""
        if key is None or not self.enabled:
            return None
        hit = self._kept.get(key)
        if hit is not None:
            self._kept.move_to_end(key)
            self.hits += 1
        return hit

    def put(self, key: bytes | None, closing) -> None:
        """Keep ``closing`` under ``key`` (nothing while disabled or without a key)."""
        if key is None or not self.enabled or self.keep <= 0:
            return
        self._kept[key] = closing
        self._kept.move_to_end(key)
        while len(self._kept) > self.keep:
            self._kept.popitem(last=False)

    def clear(self) -> None:
        """Forget every kept closing and the hit count."""
        self._kept.clear()
        self.hits = 0

    @contextlib.contextmanager
    def disabled(self) -> Iterator[None]:
        """Every grasp inside runs its closing phase in full (the plain path, for comparisons)."""
        old, self.enabled = self.enabled, False
        try:
            yield
        finally:
            self.enabled = old


#: This process's kept closing phases (:meth:`slipreflex.sim.Rig.grasp` reads and fills it).
CLOSINGS = ClosingMemo()
