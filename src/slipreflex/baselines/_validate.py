"""Tactile-frame checks of the baselines (private); scalar checks live in :mod:`slipreflex.validation`."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError
from ..hardware import TACTILE_SHAPE


def as_frames(name: str, frames: Any) -> np.ndarray:
    """Return tactile frames as a finite float64 array of shape (K, 4, 4)."""
    arr = np.asarray(frames, dtype=np.float64)
    if arr.ndim != 3 or arr.shape[1:] != TACTILE_SHAPE:
        raise DataError(f"{name} must have shape (K, {TACTILE_SHAPE[0]}, {TACTILE_SHAPE[1]}), "
                        f"got {arr.shape}")
    finite = np.isfinite(arr)
    if not finite.all():
        k = int(np.argwhere(~finite)[0][0])
        raise DataError(f"{name}[{k}] holds a non-finite value: frames must be finite")
    return arr


def as_frame(name: str, frame: Any) -> np.ndarray:
    """Return one tactile frame as a finite float64 array of 16 values (row-major)."""
    arr = np.asarray(frame, dtype=np.float64)
    if arr.shape != TACTILE_SHAPE:
        raise DataError(f"{name} must have shape {TACTILE_SHAPE}, got {arr.shape}")
    if not np.isfinite(arr).all():
        raise DataError(f"{name} holds a non-finite value: frames must be finite")
    return arr.reshape(-1)
