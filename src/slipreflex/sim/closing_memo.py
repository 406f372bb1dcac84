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
import math
import weakref
from collections import OrderedDict
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core import hardware as hw
from ..core.errors import ParameterError
from ..core.hardware import Finger, HandCommand
from . import kernel as K

if TYPE_CHECKING:
    from .rig import Rig

__all__ = ["Closing", "ClosingMemo", "CLOSINGS", "CLOSINGS_KEEP", "friction_slots", "array_digest", "closing_key",
           "close", "closing_key_of", "closing_of", "restore_closing"]

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


def close(rig: Rig, force: float, speed: float, settle: float) -> float:
    """The grasp's closing phase on ``rig``: close until both arrays read ``force``, settle on the support.

    Returns when the first finger's array reached the force (s); the support is still there.

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> rig = Rig("TR"); t_contact = close(rig, 0.8, 150.0, 0.5)
    >>> 0 < t_contact < rig.t, bool(rig.kernel_arrays().S[K.S_SUPPORTED] > 0)
    (True, True)
    """
    hp = rig.hand_params
    pwm = speed / hp.speed_units_s * hw.PWM_MAX
    rig.hand.command(HandCommand.CLOSE, hw.TRIPOD, pwm)
    s_idx = rig.tactile_sampler(hp.grasp_poll_fs, Finger.INDEX)
    s_th = rig.tactile_sampler(hp.grasp_poll_fs, Finger.THUMB)
    stopped: set[Finger] = set()
    t_contact = math.nan
    t_limit = rig.t + 1.5 * hw.FINGER_MAX / speed + 1.0
    try:
        while len(stopped) < 2:
            if rig.t > t_limit:
                raise ParameterError(f"grasp: fingers closed fully without reaching {force} N "
                                     f"(bottle diameter {rig.bottle.diameter_m} m too small?)")
            rig.run_to(max(s_idx.next_time, rig.t + rig.physics.dt))
            _, fi = s_idx.read()
            _, ft = s_th.read()
            if Finger.INDEX not in stopped and fi.shape[0] and fi[-1].sum() >= force:
                rig.hand.command(HandCommand.STOP, [Finger.INDEX, Finger.MIDDLE])
                stopped.add(Finger.INDEX)
                t_contact = rig.t if math.isnan(t_contact) else t_contact
            if Finger.THUMB not in stopped and ft.shape[0] and ft[-1].sum() >= force:
                rig.hand.command(HandCommand.STOP, [Finger.THUMB])
                stopped.add(Finger.THUMB)
                t_contact = rig.t if math.isnan(t_contact) else t_contact
    finally:
        s_idx.close()
        s_th.close()
    rig.run_to(rig.t + settle)
    return t_contact


def closing_key_of(rig: Rig, force: float, speed: float, settle: float) -> bytes | None:
    """Everything the closing phase of ``rig.grasp(force, speed=speed, settle=settle)`` reads, as a key; None
    (closed in full, nothing kept) for a rig that has done something already.

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> closing_key_of(Rig("TR"), 0.8, 150.0, 0.5) == closing_key_of(Rig("TR"), 0.8, 150.0, 0.5)
    True
    >>> rig = Rig("TR"); _ = rig.run_to(0.01); closing_key_of(rig, 0.8, 150.0, 0.5) is None
    True
    """
    hand = rig.hand
    fresh = (rig.step_index == 0 and not rig.samplers and rig._n_samplers_made == 0 and rig._oneoff == 0
             and not rig.perturbations and not rig._daq_chunks and not rig._events
             and hand.next_due_step() is None and not hand.closing_until)
    if not fresh:
        return None
    text = repr((force, speed, settle, rig.history, rig.stepping, rig.hand_params, rig.tactile_params,
                 sorted(hand._others.items()), hand._count))
    a = rig.kernel_arrays()
    return closing_key(a.P, (a.S, a.C, a.keys, a.D, a.W, hand.targets, hand.speeds), rig.track.rho, text)


def closing_of(rig: Rig, t_contact: float) -> Closing:
    """``rig``'s state at the end of its closing phase (copies).

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> rig = Rig("TR"); kept = closing_of(rig, close(rig, 0.8, 150.0, 0.5))
    >>> kept.samplers_made, kept.S is rig.kernel_arrays().S
    (2, False)
    """
    hand = rig.hand
    a = rig.kernel_arrays()
    return Closing(S=a.S.copy(), C=a.C.copy(), D=a.D.copy(), W=a.W.copy(),
                   daq=tuple(c.copy() for c in rig._daq_chunks), events=tuple(e.copy() for e in rig._events),
                   hand=(list(hand._pending), hand._count, dict(hand._others), dict(hand.closing_until),
                         hand.targets.copy(), hand.speeds.copy()),
                   samplers_made=rig._n_samplers_made, oneoff=rig._oneoff, t_contact=t_contact)


def restore_closing(rig: Rig, kept: Closing) -> float:
    """Give ``rig`` a kept closing phase's state (copies; its parameters, so its friction, stay its own);
    return when the first finger's array reached the force (s).

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> a = Rig("TR"); kept = closing_of(a, close(a, 0.8, 150.0, 0.5))
    >>> b = Rig("TR"); _ = restore_closing(b, kept); b.t == a.t
    True
    """
    rig._S[:] = kept.S
    rig._C[:] = kept.C
    rig._D = kept.D.copy()
    rig._W = kept.W.copy()
    rig._daq_chunks = [c.copy() for c in kept.daq] if rig.history else []
    rig._events = [e.copy() for e in kept.events]
    hand = rig.hand
    pending, count, others, closing_until, targets, speeds = kept.hand
    hand.restore_queue(list(pending), count)
    hand._others = dict(others)
    hand.closing_until = dict(closing_until)
    hand.targets[:] = targets
    hand.speeds[:] = speeds
    rig._n_samplers_made = kept.samplers_made
    rig._oneoff = kept.oneoff
    rig._sync_samplers()
    return kept.t_contact
