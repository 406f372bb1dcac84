"""Small validators shared by the baseline parameter classes (private)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import DataError, ParameterError
from ..hardware import TACTILE_SHAPE


def number(name: str, value: Any, *, lo: float | None = None, lo_open: bool = False) -> float:
    """Return ``value`` as a float after checking it is finite and >= (or >) ``lo``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) \
            or not math.isfinite(value):
        raise ParameterError(f"{name} must be a finite number, got {value!r}")
    if lo is not None and (value <= lo if lo_open else value < lo):
        rel = ">" if lo_open else ">="
        raise ParameterError(f"{name} must be a finite number {rel} {lo:g}, got {value!r}")
    return float(value)


def integer(name: str, value: Any, *, lo: int) -> int:
    """Return ``value`` as an int after checking it is an integer >= ``lo``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
        raise ParameterError(f"{name} must be an integer >= {lo}, got {value!r}")
    return int(value)


def setattr_frozen(obj: Any, name: str, value: Any) -> None:
    """Set an attribute on a frozen dataclass inside ``__post_init__``."""
    object.__setattr__(obj, name, value)


def build(cls: type, kwargs: dict[str, Any]):
    """Construct a params dataclass; an unknown keyword is a ParameterError naming it."""
    import dataclasses

    known = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(kwargs) - known)
    if unknown:
        raise ParameterError(
            f"unknown parameter(s) for {cls.__name__}: {', '.join(unknown)} "
            f"(known: {', '.join(sorted(known))})")
    return cls(**kwargs)


def resolve_params(cls: type, params: Any, kwargs: dict[str, Any]):
    """The parameters a streaming method runs with: ``params``, keyword overrides, or both.

    ``None`` builds ``cls`` from ``kwargs``; an instance with ``kwargs`` is copied with
    those fields replaced (unknown ones are an error); anything but a ``cls`` is refused.
    """
    import dataclasses

    if params is None:
        return build(cls, kwargs)
    if not isinstance(params, cls):
        raise ParameterError(f"params must be an {cls.__name__}, got {type(params).__name__}")
    if kwargs:
        fields = {f.name: getattr(params, f.name) for f in dataclasses.fields(params)}
        return build(cls, {**fields, **kwargs})
    return params


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
