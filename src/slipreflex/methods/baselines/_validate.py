"""Tactile-frame checks of the baselines (private); scalar checks live in :mod:`slipreflex.core.validation`.

A tactile array is any grid of taxels: frames of shape (rows, cols) or
(channels,), so recordings have shape (K, rows, cols) or (K, channels).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...core.errors import DataError, ParameterError
from ...core.hardware import TACTILE_SHAPE
from ...core.validation import integer


def frame_shape(name: str, shape: Any) -> tuple[int, ...]:
    """``shape`` as a tuple of one or two positive ints (a taxel grid or a channel list)."""
    try:
        dims = tuple(shape)
    except TypeError:
        raise ParameterError(f"{name} must be (rows, cols) or (channels,), got {shape!r}") from None
    if len(dims) not in (1, 2):
        raise ParameterError(f"{name} must be (rows, cols) or (channels,), got {shape!r}")
    return tuple(integer(name, d, lo=1) for d in dims)


def as_frames(name: str, frames: Any) -> np.ndarray:
    """Return tactile frames as a finite float64 array of shape (K, rows, cols) or (K, channels)."""
    arr = np.asarray(frames, dtype=np.float64)
    if arr.ndim not in (2, 3):
        raise DataError(f"{name} must have shape (K, rows, cols) or (K, channels), e.g. "
                        f"(K, {TACTILE_SHAPE[0]}, {TACTILE_SHAPE[1]}), got {arr.shape}")
    finite = np.isfinite(arr)
    if not finite.all():
        k = int(np.argwhere(~finite)[0][0])
        raise DataError(f"{name}[{k}] holds a non-finite value: frames must be finite")
    return arr


def as_frame(name: str, frame: Any, shape: tuple[int, ...] = TACTILE_SHAPE) -> np.ndarray:
    """Return one tactile frame of ``shape`` as a finite flat float64 array (row-major)."""
    arr = np.asarray(frame, dtype=np.float64)
    if arr.shape != tuple(shape):
        raise DataError(f"{name} must have shape {tuple(shape)}, got {arr.shape}")
    if not np.isfinite(arr).all():
        raise DataError(f"{name} holds a non-finite value: frames must be finite")
    return arr.reshape(-1)
