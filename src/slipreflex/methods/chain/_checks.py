"""Input checks shared by the batch functions."""

from __future__ import annotations

import numpy as np

from ...core.errors import DataError


def as_samples(name: str, values) -> np.ndarray:
    """Return ``values`` as a contiguous 1-D float64 array with only finite values.

    Raises :class:`~slipreflex.core.errors.DataError` (a ValueError) naming the first
    non-finite index, or the shape when the input is not one-dimensional.
    """
    arr = as_vector(name, values, np.float64)
    finite = np.isfinite(arr)
    if not finite.all():
        i = int(np.argmin(finite))
        raise DataError(f"{name}[{i}] is {arr[i]!r}: samples must be finite (first bad index {i})")
    return arr


def as_vector(name: str, values, dtype=None) -> np.ndarray:
    """``values`` as a contiguous 1-D array; MATLAB's (1, N) and (N, 1) shapes are flattened.

    Raises :class:`~slipreflex.core.errors.DataError` naming the shape for anything else.
    """
    arr = np.ascontiguousarray(values, dtype=dtype)
    if arr.ndim == 2 and 1 in arr.shape:      # a MATLAB row or column vector
        arr = arr.reshape(-1)
    if arr.ndim != 1:
        raise DataError(f"{name} must be one-dimensional (or (1, N) / (N, 1)), got shape {arr.shape}")
    return arr
