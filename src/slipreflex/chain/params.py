"""Frozen, validated parameters of the reflex chain (shared SPEC section 1).

Each stage has its own parameter class; :class:`ReflexParams` gathers them all
flat, with the names and defaults of the batch functions, so one object
describes a whole chain (and is what a recording stores to be replayed).
Validation happens at construction: a bad value raises
:class:`~slipreflex.errors.ParameterError` naming the parameter.

Examples
--------
>>> ReflexParams(dath=True).encoder
EncoderParams(threshold=0.008, dath=True, dath_samples=16, x0=None, dath_floor=0.0)
>>> ReflexParams(threshold=-1.0)
Traceback (most recent call last):
...
slipreflex.errors.ParameterError: threshold must be a finite number >= 0, got -1.0
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from ..errors import ParameterError
from ..hardware import DAQ_FS, FINGER_MAX, FINGER_MIN, PAPER_LSB, WINDOW_N

__all__ = ["FilterParams", "EncoderParams", "WindowParams", "MPIParams", "ReflexParams"]

#: Base threshold of the paper: twice the ADC LSB as the paper rounds it.
DEFAULT_THRESHOLD: float = 2 * PAPER_LSB


def _number(name: str, value: Any, *, lo: float | None = None, lo_open: bool = False) -> float:
    """Return ``value`` as float after checking it is a finite real (>= or > lo)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(f"{name} must be a finite number, got {value!r}")
    if lo is not None and (value <= lo if lo_open else value < lo):
        rel = ">" if lo_open else ">="
        raise ParameterError(f"{name} must be a finite number {rel} {lo:g}, got {value!r}")
    return float(value)


def _integer(name: str, value: Any, *, lo: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < lo:
        raise ParameterError(f"{name} must be an integer >= {lo}, got {value!r}")
    return int(value)


def _flag(name: str, value: Any) -> bool:
    if not isinstance(value, bool):
        raise ParameterError(f"{name} must be True or False, got {value!r}")
    return value


def _set(obj: Any, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


@dataclass(frozen=True, slots=True)
class FilterParams:
    """Low-pass stage: 2nd-order Butterworth, causal (SPEC 1.1).

    Parameters
    ----------
    fs : float
        Sampling rate in Hz (> 0).
    cutoff : float
        Cutoff in Hz, 0 < cutoff < fs / 2.
    enabled : bool
        False passes samples through unchanged (input already filtered).

    Examples
    --------
    >>> FilterParams(fs=333.0, cutoff=10.0).cutoff
    10.0
    >>> FilterParams(fs=20.0, cutoff=10.0)
    Traceback (most recent call last):
    ...
    slipreflex.errors.ParameterError: cutoff must be below fs/2 = 10 Hz, got 10.0
    """

    fs: float = DAQ_FS
    cutoff: float = 10.0
    enabled: bool = True

    def __post_init__(self) -> None:
        _set(self, "fs", _number("fs", self.fs, lo=0.0, lo_open=True))
        _set(self, "cutoff", _number("cutoff", self.cutoff, lo=0.0, lo_open=True))
        _set(self, "enabled", _flag("enabled", self.enabled))
        if self.cutoff >= self.fs / 2:
            raise ParameterError(f"cutoff must be below fs/2 = {self.fs / 2:g} Hz, got {self.cutoff!r}")


@dataclass(frozen=True, slots=True)
class EncoderParams:
    """Event encoder: send-on-delta with a fixed threshold or DATH (SPEC 1.2).

    Parameters
    ----------
    threshold : float
        Base threshold theta0 in volts (>= 0); the paper uses 0.008 V.
    dath : bool
        Enable the Dynamic Adaptive Threshold.
    dath_samples : int
        DATH duration D in samples (>= 1).
    x0 : float or None
        Initial reference; None takes the first sample (no start-up spike),
        0.0 reproduces the paper literally.
    dath_floor : float
        Lower bound of the DATH threshold in volts (>= 0).

    Examples
    --------
    >>> EncoderParams(dath=True, dath_samples=16).dath_samples
    16
    """

    threshold: float = DEFAULT_THRESHOLD
    dath: bool = False
    dath_samples: int = WINDOW_N
    x0: float | None = None
    dath_floor: float = 0.0

    def __post_init__(self) -> None:
        _set(self, "threshold", _number("threshold", self.threshold, lo=0.0))
        _set(self, "dath", _flag("dath", self.dath))
        _set(self, "dath_samples", _integer("dath_samples", self.dath_samples, lo=1))
        if self.x0 is not None:
            _set(self, "x0", _number("x0", self.x0))
        _set(self, "dath_floor", _number("dath_floor", self.dath_floor, lo=0.0))


@dataclass(frozen=True, slots=True)
class WindowParams:
    """Spike-count windows of ``n`` samples (SPEC 1.3).

    Examples
    --------
    >>> WindowParams(n=0)
    Traceback (most recent call last):
    ...
    slipreflex.errors.ParameterError: n must be an integer >= 1, got 0
    """

    n: int = WINDOW_N

    def __post_init__(self) -> None:
        _set(self, "n", _integer("n", self.n, lo=1))


@dataclass(frozen=True, slots=True)
class MPIParams:
    """Monotonic PI controller (SPEC 1.4).

    Parameters
    ----------
    p0 : float
        Initial finger position P0.
    kp, ki : float
        Proportional and integral gains (>= 0).
    reset_after : int
        Zero-count windows in a row that reset P0 and the integral (>= 1).
    lo, hi : float
        Saturation range of the command, lo <= hi.

    Examples
    --------
    >>> MPIParams(lo=10.0, hi=0.0)
    Traceback (most recent call last):
    ...
    slipreflex.errors.ParameterError: lo must be <= hi, got lo=10.0, hi=0.0
    """

    p0: float = 0.0
    kp: float = 5.0
    ki: float = 5.0
    reset_after: int = 10
    lo: float = float(FINGER_MIN)
    hi: float = float(FINGER_MAX)

    def __post_init__(self) -> None:
        _set(self, "p0", _number("p0", self.p0))
        _set(self, "kp", _number("kp", self.kp, lo=0.0))
        _set(self, "ki", _number("ki", self.ki, lo=0.0))
        _set(self, "reset_after", _integer("reset_after", self.reset_after, lo=1))
        _set(self, "lo", _number("lo", self.lo))
        _set(self, "hi", _number("hi", self.hi))
        if self.lo > self.hi:
            raise ParameterError(f"lo must be <= hi, got lo={self.lo!r}, hi={self.hi!r}")


@dataclass(frozen=True, slots=True)
class ReflexParams:
    """Every parameter of the composed chain, flat, with the batch functions' names.

    ``filter`` switches the low-pass stage on or off. The stage views
    (``.lowpass``, ``.encoder``, ``.windows``, ``.mpi``) are validated
    parameter objects of each stage.

    Examples
    --------
    >>> p = ReflexParams(fs=333.33, dath=True)
    >>> p.name, p.windows.n
    ('dath', 16)
    >>> ReflexParams.from_dict(p.to_dict()) == p
    True
    """

    fs: float = DAQ_FS
    cutoff: float = 10.0
    filter: bool = True
    threshold: float = DEFAULT_THRESHOLD
    dath: bool = False
    dath_samples: int = WINDOW_N
    x0: float | None = None
    dath_floor: float = 0.0
    n: int = WINDOW_N
    p0: float = 0.0
    kp: float = 5.0
    ki: float = 5.0
    reset_after: int = 10
    lo: float = float(FINGER_MIN)
    hi: float = float(FINGER_MAX)

    def __post_init__(self) -> None:
        # Building the stage views validates every field and normalises types.
        f, e, w, m = self.lowpass, self.encoder, self.windows, self.mpi
        for stage in (f, e, w, m):
            for field in dataclasses.fields(stage):
                name = "filter" if field.name == "enabled" else field.name
                _set(self, name, getattr(stage, field.name))

    @property
    def name(self) -> str:
        """Method name: ``"dath"`` or ``"fixed"``."""
        return "dath" if self.dath else "fixed"

    @property
    def lowpass(self) -> FilterParams:
        """Parameters of the low-pass stage."""
        return FilterParams(fs=self.fs, cutoff=self.cutoff, enabled=self.filter)

    @property
    def encoder(self) -> EncoderParams:
        """Parameters of the event encoder."""
        return EncoderParams(threshold=self.threshold, dath=self.dath, dath_samples=self.dath_samples,
                             x0=self.x0, dath_floor=self.dath_floor)

    @property
    def windows(self) -> WindowParams:
        """Parameters of the window counter."""
        return WindowParams(n=self.n)

    @property
    def mpi(self) -> MPIParams:
        """Parameters of the MPI controller."""
        return MPIParams(p0=self.p0, kp=self.kp, ki=self.ki, reset_after=self.reset_after,
                         lo=self.lo, hi=self.hi)

    def to_dict(self) -> dict[str, Any]:
        """Plain dict of every field (JSON-serialisable).

        Examples
        --------
        >>> ReflexParams().to_dict()["threshold"]
        0.008
        """
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "ReflexParams":
        """Build from a dict; unknown keys are an error naming them.

        Examples
        --------
        >>> ReflexParams.from_dict({"thresh": 1})
        Traceback (most recent call last):
        ...
        slipreflex.errors.ParameterError: unknown reflex parameter(s): thresh
        """
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - names)
        if unknown:
            raise ParameterError(f"unknown reflex parameter(s): {', '.join(unknown)}")
        return cls(**data)
