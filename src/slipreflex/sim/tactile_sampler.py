"""A rig's tactile sampler: one finger's 4 x 4 array at a fixed rate (:meth:`slipreflex.sim.Rig.tactile_sampler`)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..core import hardware as hw
from ..core.hardware import Finger
from . import kernel as K
from .params import (
    TactileParams,
)

if TYPE_CHECKING:
    from .rig import Rig

__all__ = ["TactileSampler"]


class TactileSampler:
    """Frames of one finger's 4 x 4 tactile array at a fixed rate.

    Created by :meth:`Rig.tactile_sampler`; frames accumulate as the rig
    advances and :meth:`read` returns those not yet read. With
    ``keep=True`` every frame is also kept for :attr:`history`.

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> from slipreflex.core.hardware import NMSD_FS
    >>> rig = Rig("TR")
    >>> s = rig.tactile_sampler(NMSD_FS)
    >>> _ = rig.advance(0.1)
    >>> t, frames = s.read()
    >>> frames.shape[1:], len(t)
    ((4, 4), 27)
    """

    def __init__(self, rig: Rig, fs: float, finger: Finger, key: np.uint64, keep: bool) -> None:
        self.fs = float(fs)
        self.finger = Finger(finger)
        self.gain = rig.tactile_gain(self.finger)
        self._rig = rig
        self._key = key
        self._keep = keep
        self._t: list[np.ndarray] = []
        self._f: list[np.ndarray] = []
        self._hist_t: list[np.ndarray] = []
        self._hist_f: list[np.ndarray] = []
        self._state = np.full((2,) + hw.TACTILE_SHAPE, np.nan)   # the taxels' low-pass and play
        # the first frame strictly after now (a frame at the current instant was due in the past)
        self.next_index = 0 if rig.step_index == 0 else int(math.floor(rig.t * self.fs + 1e-9)) + 1

    @property
    def key(self) -> int:
        """The noise stream key of this sampler's frames (a compiled loop builds frames with it).

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> rig = Rig("TR"); rig.tactile_sampler(100.0).key == rig.tactile_sampler(100.0).key
        False
        """
        return int(self._key)

    @property
    def filter_state(self) -> np.ndarray:
        """A copy of the taxels' low-pass and play state ``(2, 4, 4)`` (NaN before the first frame).

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> bool(np.isnan(Rig("TR").tactile_sampler(100.0).filter_state).all())
        True
        """
        return self._state.copy()

    @property
    def next_time(self) -> float:
        """Time (s) of the next frame not produced yet.

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> Rig("TR").tactile_sampler(100.0).next_time
        0.0
        """
        return self.next_index / self.fs

    def feed(self, snapshots: np.ndarray, params: TactileParams) -> None:
        """Turn the rig's contact snapshots (kernel rows) into frames and queue them (called by the rig).

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> s = Rig("TR").tactile_sampler(100.0)
        >>> s.feed(np.zeros((0, 8)), TactileParams()); s.read()[0].size
        0
        """
        if not snapshots.shape[0]:
            return
        out = np.empty((snapshots.shape[0],) + hw.TACTILE_SHAPE)
        alpha = 1.0 - math.exp(-2.0 * math.pi * params.bandwidth_hz / self.fs)
        K.tactile_frames(snapshots, self._key, self.gain, params.patch_sigma_taxels, params.shear_shift_taxels,
                         params.noise_n, params.resolution_n, alpha, params.hysteresis_n,
                         params.drift_per_decade, self._state, out)
        self._push(snapshots[:, K.T_T].copy(), out)

    def take(self, t: np.ndarray, frames: np.ndarray, state: np.ndarray) -> None:
        """Queue frames built elsewhere from this sampler's snapshots (by a compiled loop, with
        :func:`~slipreflex.sim.kernel.tactile_frames`, :attr:`key`, :attr:`gain` and
        :attr:`filter_state`), and take the filter state they left: as if fed.

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> s = Rig("TR").tactile_sampler(100.0)
        >>> s.take(np.zeros(1), np.ones((1, 4, 4)), np.zeros((2, 4, 4)))
        >>> float(s.read()[1].sum()), float(s.filter_state.sum())
        (16.0, 0.0)
        """
        self._state[...] = state
        self._push(t, frames)

    def _push(self, t: np.ndarray, frames: np.ndarray) -> None:
        self._t.append(t)
        self._f.append(frames)
        if self._keep:
            self._hist_t.append(t)
            self._hist_f.append(frames)

    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """Frames produced since the last call: times (s) and ``(n, 4, 4)`` newtons.

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> Rig("TR").tactile_sampler(380.0).read()[1].shape
        (0, 4, 4)
        """
        t = np.concatenate(self._t) if self._t else np.zeros(0)
        f = np.concatenate(self._f) if self._f else np.zeros((0,) + hw.TACTILE_SHAPE)
        self._t.clear()
        self._f.clear()
        return t, f

    @property
    def history(self) -> tuple[np.ndarray, np.ndarray]:
        """All frames since creation (only with ``keep=True``).

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> Rig("TR").tactile_sampler(260.0, keep=True).history[0].size
        0
        """
        t = np.concatenate(self._hist_t) if self._hist_t else np.zeros(0)
        f = np.concatenate(self._hist_f) if self._hist_f else np.zeros((0,) + hw.TACTILE_SHAPE)
        return t, f

    def close(self) -> None:
        """Stop sampling (the rig forgets this sampler).

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> rig = Rig("TR"); s = rig.tactile_sampler(100.0); s.close()
        >>> s in rig.samplers
        False
        """
        self._rig.detach_sampler(self)
