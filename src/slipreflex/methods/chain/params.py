"""Frozen, validated parameters of the reflex chain (docs/method.md section 1).

Each stage has its own parameter class; :class:`ReflexParams` gathers them all
flat, with the names and defaults of the batch functions, so one object
describes a whole chain (and is what a recording stores to be replayed).
Validation happens at construction: a bad value raises
:class:`~slipreflex.core.errors.ParameterError` naming the parameter.

Examples
--------
>>> ReflexParams(dath=True).encoder
EncoderParams(threshold=0.008, dath=True, dath_samples=16, x0=None, dath_floor=0.0, acc_reset=None, acc_leak=None)
>>> ReflexParams(threshold=-1.0)
Traceback (most recent call last):
...
slipreflex.core.errors.ParameterError: threshold must be a finite number >= 0, got -1.0
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from ...core.errors import ParameterError
from ...core.hardware import DAQ_FS, FINGER_MAX, FINGER_MIN, PAPER_LSB, WINDOW_N
from ...core.validation import build, choice, flag, integer, number, set_field

__all__ = ["FilterParams", "EncoderParams", "WindowParams", "MPIParams", "ReflexParams",
           "FILTER_KINDS", "MPI_MODES"]

#: Base threshold of the paper: twice the ADC LSB as the paper rounds it.
DEFAULT_THRESHOLD: float = 2 * PAPER_LSB

#: The low-pass stages: the paper's Butterworth, or the authors' rig code's moving mean.
FILTER_KINDS: tuple[str, ...] = ("butterworth", "mean")

#: The controllers: the paper's MPI per window, or the event-driven MPI per sample.
MPI_MODES: tuple[str, ...] = ("window", "event")


def _optional(check, name: str, value: Any, **bounds: Any) -> Any:
    """``None`` (the option is off) or ``value`` checked by ``check``."""
    return None if value is None else check(name, value, **bounds)


@dataclass(frozen=True, slots=True)
class FilterParams:
    """Low-pass stage: 2nd-order Butterworth, causal (docs/method.md section 1.1).

    Parameters
    ----------
    fs : float
        Sampling rate in Hz (> 0).
    cutoff : float
        Cutoff in Hz, 0 < cutoff < fs / 2.
    enabled : bool
        False passes samples through unchanged (input already filtered).
    kind : {"butterworth", "mean"}
        The paper's Butterworth, or the authors' rig code's moving mean of the
        last ``mean_samples`` raw samples (the mean of those so far until that
        many have arrived); ``cutoff`` then plays no part.
    mean_samples : int or None
        Length M of the moving mean (>= 1); None takes round(fs / 5), the
        authors' choice (67 at 333 Hz).

    Examples
    --------
    >>> FilterParams(fs=333.0, cutoff=10.0).cutoff
    10.0
    >>> FilterParams(fs=333.0, kind="mean").window
    67
    >>> FilterParams(fs=20.0, cutoff=10.0)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: cutoff must be below fs/2 = 10 Hz, got 10.0
    """

    fs: float = DAQ_FS
    cutoff: float = 10.0
    enabled: bool = True
    kind: str = "butterworth"
    mean_samples: int | None = None

    def __post_init__(self) -> None:
        set_field(self, "fs", number("fs", self.fs, lo=0.0, lo_open=True))
        set_field(self, "cutoff", number("cutoff", self.cutoff, lo=0.0, lo_open=True))
        set_field(self, "enabled", flag("enabled", self.enabled))
        set_field(self, "kind", choice("filter_kind", self.kind, FILTER_KINDS))
        set_field(self, "mean_samples", _optional(integer, "mean_samples", self.mean_samples, lo=1))
        if self.cutoff >= self.fs / 2:
            raise ParameterError(f"cutoff must be below fs/2 = {self.fs / 2:g} Hz, got {self.cutoff!r}")

    @property
    def window(self) -> int:
        """Length of the moving mean in samples (``mean_samples`` or round(fs / 5))."""
        return self.mean_samples if self.mean_samples is not None else max(1, round(self.fs / 5))


@dataclass(frozen=True, slots=True)
class EncoderParams:
    """Event encoder: send-on-delta with a fixed threshold or DATH (docs/method.md section 1.2).

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
    acc_reset : int or None
        Clear the accumulator every ``acc_reset`` samples (the authors' rig
        code: every 0.1 s); None (default) never, as the paper.
    acc_leak : float or None
        Let the accumulator forget with this time constant, in samples (> 0):
        ``acc = acc * exp(-1 / acc_leak) + d``; None (default) never, as the paper.

    Examples
    --------
    >>> EncoderParams(dath=True, dath_samples=16).dath_samples
    16
    >>> EncoderParams(acc_reset=0)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: acc_reset must be an integer >= 1, got 0
    """

    threshold: float = DEFAULT_THRESHOLD
    dath: bool = False
    dath_samples: int = WINDOW_N
    x0: float | None = None
    dath_floor: float = 0.0
    acc_reset: int | None = None
    acc_leak: float | None = None

    def __post_init__(self) -> None:
        set_field(self, "threshold", number("threshold", self.threshold, lo=0.0))
        set_field(self, "dath", flag("dath", self.dath))
        set_field(self, "dath_samples", integer("dath_samples", self.dath_samples, lo=1))
        if self.x0 is not None:
            set_field(self, "x0", number("x0", self.x0))
        set_field(self, "dath_floor", number("dath_floor", self.dath_floor, lo=0.0))
        set_field(self, "acc_reset", _optional(integer, "acc_reset", self.acc_reset, lo=1))
        set_field(self, "acc_leak", _optional(number, "acc_leak", self.acc_leak, lo=0.0, lo_open=True))

    @property
    def leak_factor(self) -> float:
        """The accumulator's factor per sample, exp(-1 / acc_leak) (1.0 without a leak)."""
        return 1.0 if self.acc_leak is None else math.exp(-1.0 / self.acc_leak)


@dataclass(frozen=True, slots=True)
class WindowParams:
    """Spike-count windows of ``n`` samples (docs/method.md section 1.3).

    Examples
    --------
    >>> WindowParams(n=0)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: n must be an integer >= 1, got 0
    """

    n: int = WINDOW_N

    def __post_init__(self) -> None:
        set_field(self, "n", integer("n", self.n, lo=1))


@dataclass(frozen=True, slots=True)
class MPIParams:
    """Monotonic PI controller (docs/method.md section 1.4).

    Parameters
    ----------
    p0 : float
        Initial finger position P0.
    kp, ki : float
        Proportional and integral gains (>= 0).
    reset_after : int or None
        Zero-count windows in a row that reset P0 and the integral (>= 1);
        None never resets (the authors' rig code).
    lo, hi : float
        Saturation range of the command, lo <= hi.
    mode : {"window", "event"}
        ``"window"``: the paper's MPI, one command per window of counts;
        ``"event"``: the event-driven MPI, updated on every sample from the
        spike count over the last window length (docs/method.md).

    Examples
    --------
    >>> MPIParams(lo=10.0, hi=0.0)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: lo must be <= hi, got lo=10.0, hi=0.0
    """

    p0: float = 0.0
    kp: float = 5.0
    ki: float = 5.0
    reset_after: int | None = 10
    lo: float = float(FINGER_MIN)
    hi: float = float(FINGER_MAX)
    mode: str = "window"

    def __post_init__(self) -> None:
        set_field(self, "p0", number("p0", self.p0))
        set_field(self, "kp", number("kp", self.kp, lo=0.0))
        set_field(self, "ki", number("ki", self.ki, lo=0.0))
        set_field(self, "reset_after", _optional(integer, "reset_after", self.reset_after, lo=1))
        set_field(self, "lo", number("lo", self.lo))
        set_field(self, "hi", number("hi", self.hi))
        set_field(self, "mode", choice("mpi_mode", self.mode, MPI_MODES))
        if self.lo > self.hi:
            raise ParameterError(f"lo must be <= hi, got lo={self.lo!r}, hi={self.hi!r}")


#: The stages' defaults, which are also the flat defaults of :class:`ReflexParams`.
_F, _E, _W, _M = FilterParams(), EncoderParams(), WindowParams(), MPIParams()


@dataclass(frozen=True, slots=True)
class ReflexParams:
    """Every parameter of the composed chain, flat, with the batch functions' names.

    ``filter`` switches the low-pass stage on or off. The stage views
    (``.lowpass``, ``.encoder``, ``.windows``, ``.mpi``) are validated
    parameter objects of each stage; ``filter_kind`` and ``mean_samples`` are
    the filter's ``kind`` and ``mean_samples``, ``mpi_mode`` the MPI's ``mode``.
    ``slip_finger_offset`` is part of the hand rule, not of the chain: a hand
    that follows it sends the command plus this offset to the finger carrying
    the slip sensor (the middle finger) and the command to the others (the
    authors' rig code uses +20).

    The defaults are the paper's chain; :meth:`preset` gives the named
    variants (``"paper"``, ``"authors-gui"``, ``"dath-event"``).

    Examples
    --------
    >>> p = ReflexParams(fs=333.33, dath=True)
    >>> p.name, p.windows.n, p.variants
    ('dath', 16, ())
    >>> ReflexParams.from_dict(p.to_dict()) == p
    True
    >>> ReflexParams(dath=True, mpi_mode="event", acc_leak=32.0).variants
    ('acc_leak', 'mpi_mode')
    """

    # The defaults are the stages' (one definition each).
    fs: float = _F.fs
    cutoff: float = _F.cutoff
    filter: bool = _F.enabled
    threshold: float = _E.threshold
    dath: bool = _E.dath
    dath_samples: int = _E.dath_samples
    x0: float | None = _E.x0
    dath_floor: float = _E.dath_floor
    n: int = _W.n
    p0: float = _M.p0
    kp: float = _M.kp
    ki: float = _M.ki
    reset_after: int | None = _M.reset_after
    lo: float = _M.lo
    hi: float = _M.hi
    filter_kind: str = _F.kind
    mean_samples: int | None = _F.mean_samples
    acc_reset: int | None = _E.acc_reset
    acc_leak: float | None = _E.acc_leak
    mpi_mode: str = _M.mode
    slip_finger_offset: float = 0.0

    def __post_init__(self) -> None:
        # Building the stage views validates every field and normalises types.
        f, e, w, m = self.lowpass, self.encoder, self.windows, self.mpi
        for stage in (f, e, w, m):
            for field in dataclasses.fields(stage):
                name = _FLAT_NAMES.get((type(stage).__name__, field.name), field.name)
                set_field(self, name, getattr(stage, field.name))
        set_field(self, "slip_finger_offset", number("slip_finger_offset", self.slip_finger_offset))

    @property
    def name(self) -> str:
        """Method name: ``"dath"`` or ``"fixed"``, with ``"-event"`` for the event-driven MPI."""
        return ("dath" if self.dath else "fixed") + ("-event" if self.mpi_mode == "event" else "")

    @property
    def variants(self) -> tuple[str, ...]:
        """The fields that differ from the paper's chain in kind (not in value), sorted.

        Thresholds, gains, lengths and p0 are values of the paper's chain; a
        moving-mean filter, an accumulator that forgets, an MPI that never
        resets, the event-driven MPI and a finger offset are other methods.
        """
        out = [name for name, paper in _PAPER_KINDS.items() if getattr(self, name) != paper]
        if self.reset_after is None:
            out.append("reset_after")
        return tuple(sorted(out))

    @classmethod
    def preset(cls, name: str, fs: float = DAQ_FS, **overrides: Any) -> ReflexParams:
        """The parameters of a named method, at sampling rate ``fs``.

        Parameters
        ----------
        name : {"paper", "dath", "fixed", "authors-gui", "dath-event"}
            ``"paper"`` is the default chain (fixed threshold); ``"authors-gui"``
            the authors' rig code (docs/method.md); ``"dath-event"`` DATH with
            the event-driven MPI.
        fs : float
            Sampling rate (Hz); the authors-gui lengths are derived from it.
        **overrides
            Fields to change afterwards (``p0=...``).

        Examples
        --------
        >>> p = ReflexParams.preset("authors-gui", fs=333.0)
        >>> p.mean_samples, p.acc_reset, p.n, p.threshold, p.p0, p.reset_after
        (67, 33, 9, 0.005, 125.0, None)
        >>> ReflexParams.preset("dath-event").mpi_mode
        'event'
        """
        key = choice("preset", name, tuple(PRESETS), any_case=True)
        fs = number("fs", fs, lo=0.0, lo_open=True)
        return build(cls, {"fs": fs, **PRESETS[key](fs), **overrides})

    @property
    def lowpass(self) -> FilterParams:
        """Parameters of the low-pass stage."""
        return FilterParams(fs=self.fs, cutoff=self.cutoff, enabled=self.filter, kind=self.filter_kind,
                            mean_samples=self.mean_samples)

    @property
    def encoder(self) -> EncoderParams:
        """Parameters of the event encoder."""
        return EncoderParams(threshold=self.threshold, dath=self.dath, dath_samples=self.dath_samples,
                             x0=self.x0, dath_floor=self.dath_floor, acc_reset=self.acc_reset,
                             acc_leak=self.acc_leak)

    @property
    def windows(self) -> WindowParams:
        """Parameters of the window counter."""
        return WindowParams(n=self.n)

    @property
    def mpi(self) -> MPIParams:
        """Parameters of the MPI controller."""
        return MPIParams(p0=self.p0, kp=self.kp, ki=self.ki, reset_after=self.reset_after,
                         lo=self.lo, hi=self.hi, mode=self.mpi_mode)

    def to_dict(self) -> dict[str, Any]:
        """Plain dict of every field (JSON-serialisable).

        Examples
        --------
        >>> ReflexParams().to_dict()["threshold"]
        0.008
        """
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ReflexParams:
        """Build from a dict; unknown keys are an error naming them.

        Examples
        --------
        >>> ReflexParams.from_dict({"thresh": 1})
        Traceback (most recent call last):
        ...
        slipreflex.core.errors.ParameterError: unknown reflex parameter(s): thresh
        """
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - names)
        if unknown:
            raise ParameterError(f"unknown reflex parameter(s): {', '.join(unknown)}")
        return cls(**data)


#: Stage field -> flat ReflexParams field, where the names differ.
_FLAT_NAMES = {("FilterParams", "enabled"): "filter", ("FilterParams", "kind"): "filter_kind",
               ("MPIParams", "mode"): "mpi_mode"}

#: The paper's value of every field that selects a kind of method rather than a value.
_PAPER_KINDS = {"filter_kind": "butterworth", "acc_reset": None, "acc_leak": None, "mpi_mode": "window",
                "slip_finger_offset": 0.0}


def _authors_gui(fs: float) -> dict[str, Any]:
    """The authors' rig code (formSlipExp.py) at ``fs``: docs/method.md section 1.6."""
    return {"filter_kind": "mean", "mean_samples": max(1, round(fs / 5)), "threshold": 0.005,
            "dath": False, "x0": 0.0, "acc_reset": max(1, int(0.1 * fs)), "n": max(1, int(0.03 * fs)),
            "p0": 125.0, "reset_after": None, "slip_finger_offset": 20.0}


#: Named parameter sets, by name: a function of fs giving the fields that differ from the defaults.
PRESETS = {"paper": lambda fs: {}, "fixed": lambda fs: {}, "dath": lambda fs: {"dath": True},
           "authors-gui": _authors_gui, "dath-event": lambda fs: {"dath": True, "mpi_mode": "event"}}

