"""Input checks shared by the batch functions."""

from __future__ import annotations

import numpy as np

from ..errors import DataError


def as_samples(name: str, values) -> np.ndarray:
    """Return ``values`` as a contiguous 1-D float64 array with only finite values.

    Raises :class:`~slipreflex.errors.DataError` (a ValueError) naming the first
    non-finite index, or the shape when the input is not one-dimensional.
    """
    arr = np.ascontiguousarray(values, dtype=np.float64)
    if arr.ndim != 1:
        raise DataError(f"{name} must be one-dimensional, got shape {arr.shape}")
    finite = np.isfinite(arr)
    if not finite.all():
        i = int(np.argmin(finite))
        raise DataError(f"{name}[{i}] is {arr[i]!r}: samples must be finite (first bad index {i})")
    return arr
