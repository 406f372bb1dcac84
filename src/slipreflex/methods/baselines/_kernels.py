"""numba kernels of the comparison methods: one tactile step over a state array, composed.

:func:`tactile_step` is NMSD's or SWT-SD's whole streaming reflex for one frame
(detector, rising edge, closing rule) on the vectors of
:mod:`slipreflex.methods.baselines._layout`; :class:`~slipreflex.methods.baselines.NMSD`,
:class:`~slipreflex.methods.baselines.SWTSD` and :class:`~slipreflex.methods.baselines.Closer`
call these kernels and nothing else, and a compiled closed loop may call
``tactile_step`` from its own numba code on the object's live ``S``. The
arithmetic is the batch functions' (same IEEE operations in the same order, no
fastmath), so batch and streaming agree bit for bit. Imported lazily: ``import
slipreflex`` does not pay for numba.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...core._numba_cache import stamped_cache
from . import _layout
from ._layout import (
    KIND_SWT,
    P_FS,
    P_HI,
    P_HOLD,
    P_KIND,
    P_LO,
    P_PERSIST,
    P_SPC,
    P_STEP,
    P_TAXELS,
    P_THRESHOLD,
    P_WEIGHTS,
    P_WINDOW,
    S_ARRAYS,
    S_CLOSING,
    S_DETECTIONS,
    S_EPISODE,
    S_EVENT,
    S_FRAMES,
    S_LEVEL,
    S_REMAINING,
    S_RING,
    S_STAT,
    S_TARGET,
    S_TRIGGERS,
)

#: these kernels compile in the layout's slot constants: their cache is stamped with it too
_CACHE = stamped_cache(__file__, _layout.__file__)


@njit(cache=_CACHE, inline="always")
def _feed(S, P, trig, hold):
    """Closer.feed: a trigger adds a quantum ("events"), or starts one when none runs ("hold")."""
    if trig and (not hold or S[S_REMAINING] <= 0.0):
        S[S_REMAINING] += P[P_SPC]
        S[S_TRIGGERS] += 1.0


@njit(cache=_CACHE, inline="always")
def _close(S, P, position):
    """Closer.step: one sample of the ramp; the new target, or NaN when it does not change.

    A closing episode starts from ``max(target, position)`` (clipped) when the
    position is known (not NaN).
    """
    if S[S_REMAINING] <= 0.0:
        return np.nan
    target = S[S_TARGET]
    if S[S_EPISODE] == 0.0 and not np.isnan(position):
        m = position if position > target else target
        if m < P[P_LO]:
            m = P[P_LO]
        elif m > P[P_HI]:
            m = P[P_HI]
        target = m
    old = target
    up = target + P[P_STEP]
    target = up if up < P[P_HI] else P[P_HI]
    remaining = S[S_REMAINING] - 1.0
    S[S_TARGET] = target
    S[S_REMAINING] = remaining
    S[S_CLOSING] += 1.0
    S[S_EPISODE] = 0.0 if remaining == 0.0 else S[S_EPISODE] + 1.0
    return target if target != old else np.nan


@njit(cache=_CACHE, inline="always")
def _nmsd_detect(S, P, frame):
    """NMSD on one flat frame: (largest |d_k - d_(k-1)|, any taxel over threshold)."""
    taxels = int(P[P_TAXELS])
    fs = P[P_FS]
    n = S[S_FRAMES]
    prev = S_ARRAYS
    prev_d = S_ARRAYS + taxels
    stat = 0.0
    for t in range(taxels):
        if n >= 1.0:
            d = (frame[t] - S[prev + t]) * fs
            if n >= 2.0:
                a = abs(d - S[prev_d + t])
                if a > stat:
                    stat = a
            S[prev_d + t] = d
        S[prev + t] = frame[t]
    return stat, stat > P[P_THRESHOLD]


@njit(cache=_CACHE, inline="always")
def _swt_detect(S, P, frame):
    """SWT-SD on one flat frame: (largest |c_k|, some taxel over threshold for persist + 1 frames).

    The coefficients ``c_k`` are the window weights applied to the ring oldest
    first, row by row (each taxel's sum in the batch function's order), kept in
    ``S``; they stay 0 until the window is full.
    """
    taxels = int(P[P_TAXELS])
    w = int(P[P_WINDOW])
    run = S_ARRAYS + w * taxels
    coef = run + taxels
    slot = int(S[S_RING])
    base = S_ARRAYS + slot * taxels
    for t in range(taxels):
        S[base + t] = frame[t]
    row = slot + 1 if slot + 1 < w else 0
    S[S_RING] = row
    if S[S_FRAMES] + 1.0 >= w:
        base = S_ARRAYS + row * taxels
        for t in range(taxels):
            S[coef + t] = P[P_WEIGHTS] * S[base + t]
        for j in range(1, w):
            row = row + 1 if row + 1 < w else 0
            base = S_ARRAYS + row * taxels
            weight = P[P_WEIGHTS + j]
            for t in range(taxels):
                S[coef + t] += weight * S[base + t]
    stat = 0.0
    level = False
    for t in range(taxels):
        a = abs(S[coef + t])
        if a > stat:
            stat = a
        r = S[run + t] + 1.0 if a > P[P_THRESHOLD] else 0.0
        S[run + t] = r
        if r > P[P_PERSIST]:
            level = True
    return stat, level


@njit(cache=_CACHE, inline="always")
def _tactile_step(S, P, frame, position):
    taxels = int(P[P_TAXELS])
    if frame.size != taxels:
        raise ValueError("tactile_step: the frame's size is not the state's taxel count")
    for t in range(taxels):
        if not np.isfinite(frame[t]):
            return np.nan
    if P[P_KIND] == KIND_SWT:
        stat, level = _swt_detect(S, P, frame)
    else:
        stat, level = _nmsd_detect(S, P, frame)
    S[S_FRAMES] += 1.0
    event = level and S[S_LEVEL] == 0.0
    S[S_STAT] = stat
    S[S_EVENT] = 1.0 if event else 0.0
    S[S_LEVEL] = 1.0 if level else 0.0
    S[S_DETECTIONS] += 1.0 if event else 0.0
    hold = P[P_HOLD] != 0.0
    _feed(S, P, level if hold else event, hold)
    return _close(S, P, position)


@njit(cache=_CACHE)
def tactile_step(S, P, frame, position):
    """One tactile frame through NMSD or SWT-SD (``P[P_KIND]``) and the closing rule.

    ``frame`` is the frame's taxels as a flat float64 array (row-major), ``position`` the
    measured slip-finger position (NaN unknown); returns the new finger target, or NaN when
    it does not change. A frame holding a non-finite value changes nothing and returns NaN
    (the objects refuse it before calling); a frame of the wrong size raises ValueError.
    """
    return _tactile_step(S, P, frame, position)


@njit(cache=_CACHE)
def closer_feed(S, P, trig, hold):
    """Closer.feed on a Closer's state."""
    _feed(S, P, trig, hold)


@njit(cache=_CACHE)
def closer_step(S, P, position):
    """Closer.step on a Closer's state (NaN position: unknown; NaN result: no change)."""
    return _close(S, P, position)


@njit(cache=_CACHE)
def closing_kernel(triggers, positions, hold, S, P, out):
    """The closing rule over whole arrays (closing_commands): ``out[k]`` the target or NaN."""
    for k in range(triggers.size):
        _feed(S, P, triggers[k], hold)
        out[k] = _close(S, P, positions[k])


@njit(cache=_CACHE)
def tactile_kernel(frames, positions, S, P, out):
    """tactile_step over ``(K, taxels)`` frames (benchmarks and tests)."""
    for k in range(frames.shape[0]):
        out[k] = _tactile_step(S, P, frames[k], positions[k])
