"""One set of parameter checks for the whole package (low in the import order).

Every frozen parameter dataclass and every function that takes a user value
checks it with these few functions, so the same value is accepted or refused
the same way everywhere, and every refusal is a
:class:`~slipreflex.core.errors.ParameterError` whose message starts with the
parameter's name (pass ``"Cls.field"`` or ``"file.toml: field"`` as the name
when the caller knows more about where the value came from).

What counts as what:

* a **number** is a real ``int``, ``float``, numpy integer or numpy floating
  value, finite; ``bool`` is refused (``True`` is not a gain);
* an **integer** is anything that :func:`operator.index` accepts (``int``,
  numpy integers), except ``bool``; ``16.0`` is refused;
* a **flag** is ``True``/``False`` (or a numpy bool);
* a **choice** is one of a fixed set of strings.

Each check returns the value in its plain Python type (``float``, ``int``,
``bool``), so a dataclass stores the same thing whatever the caller passed.

The contract for "a parameters object plus keyword overrides", used by every
streaming object (``NMSD(params)``, ``NMSD(threshold=...)``,
``NMSD(params, threshold=...)``): :func:`resolve_params`.

Examples
--------
>>> import numpy as np
>>> number("gain", np.float32(2.5), lo=0.0)
2.5
>>> integer("n", np.int64(16), lo=1)
16
>>> integer("n", 16.0)
Traceback (most recent call last):
...
slipreflex.core.errors.ParameterError: n must be an integer, got 16.0
>>> number("cutoff", 0.0, lo=0.0, lo_open=True)
Traceback (most recent call last):
...
slipreflex.core.errors.ParameterError: cutoff must be a finite number > 0, got 0.0

In a frozen dataclass:

>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class Gain:
...     kp: float = 5.0
...     def __post_init__(self):
...         set_field(self, "kp", number("kp", self.kp, lo=0.0))
>>> Gain(np.int32(3)).kp, type(Gain(np.int32(3)).kp).__name__
(3.0, 'float')
>>> resolve_params(Gain, Gain(), {"kp": 2}).kp
2.0
>>> resolve_params(Gain, None, {"kd": 1})
Traceback (most recent call last):
...
slipreflex.core.errors.ParameterError: unknown parameter(s) for Gain: kd (known: kp)
"""

from __future__ import annotations

import dataclasses
import math
import operator
from collections.abc import Iterable
from typing import Any, TypeVar

import numpy as np

from .errors import ParameterError

__all__ = ["number", "positive", "integer", "flag", "choice", "choices", "text", "instance", "set_field",
           "build", "resolve_params", "Limit", "LIMITS", "within", "limits_markdown"]

T = TypeVar("T")

_REAL = (int, float, np.integer, np.floating)


def _bounds(lo: float | None, hi: float | None, lo_open: bool, hi_open: bool) -> str:
    parts = []
    if lo is not None:
        parts.append(f"{'>' if lo_open else '>='} {lo:g}")
    if hi is not None:
        parts.append(f"{'<' if hi_open else '<='} {hi:g}")
    return (" " + " and ".join(parts)) if parts else ""


def _outside(value: Any, lo: float | None, hi: float | None, lo_open: bool, hi_open: bool) -> bool:
    if lo is not None and (value <= lo if lo_open else value < lo):
        return True
    return hi is not None and (value >= hi if hi_open else value > hi)


def number(name: str, value: Any, *, lo: float | None = None, hi: float | None = None,
           lo_open: bool = False, hi_open: bool = False) -> float:
    """``value`` as a float, after checking it is a finite real within the bounds.

    Parameters
    ----------
    name : str
        The parameter's name, first word of the error message.
    value : object
        What the caller passed.
    lo, hi : float, optional
        Bounds; inclusive unless ``lo_open`` / ``hi_open``.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        ``"<name> must be a finite number [bounds], got <value>"``.

    Examples
    --------
    >>> number("mu", 0.4, lo=0.0, hi=2.0)
    0.4
    >>> number("mu", float("nan"))
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: mu must be a finite number, got nan
    >>> number("mu", 3, lo=0.0, hi=2.0)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: mu must be a finite number >= 0 and <= 2, got 3
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, _REAL) or not math.isfinite(value):
        raise ParameterError(f"{name} must be a finite number{_bounds(lo, hi, lo_open, hi_open)}, "
                             f"got {value!r}")
    if _outside(value, lo, hi, lo_open, hi_open):
        raise ParameterError(f"{name} must be a finite number{_bounds(lo, hi, lo_open, hi_open)}, "
                             f"got {value!r}")
    return float(value)


def positive(name: str, value: Any, *, zero_ok: bool = False) -> float:
    """``value`` as a float, checked finite and > 0 (>= 0 with ``zero_ok``).

    Examples
    --------
    >>> positive("speed", 520)
    520.0
    >>> positive("speed", 0)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: speed must be a finite number > 0, got 0
    """
    return number(name, value, lo=0.0, lo_open=not zero_ok)


def integer(name: str, value: Any, *, lo: int | None = None, hi: int | None = None) -> int:
    """``value`` as an int, after checking it is an integer (numpy integers too) within bounds.

    Floats are refused even when integral (``16.0``), and so is ``bool``.

    Examples
    --------
    >>> import numpy as np
    >>> integer("window", np.uint8(8), lo=1)
    8
    >>> integer("window", 0, lo=1)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: window must be an integer >= 1, got 0
    >>> integer("seq", 300, lo=0, hi=255)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: seq must be an integer >= 0 and <= 255, got 300
    """
    bounds = _bounds(lo, hi, False, False)
    if isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name} must be an integer{bounds}, got {value!r}")
    try:
        out = operator.index(value)
    except TypeError:
        raise ParameterError(f"{name} must be an integer{bounds}, got {value!r}") from None
    if _outside(out, lo, hi, False, False):
        raise ParameterError(f"{name} must be an integer{bounds}, got {value!r}")
    return int(out)


def flag(name: str, value: Any) -> bool:
    """``value`` as a bool, after checking it is ``True`` or ``False`` (numpy bools too).

    Examples
    --------
    >>> flag("dath", True)
    True
    >>> flag("dath", 1)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: dath must be True or False, got 1
    """
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def choice(name: str, value: Any, options: Iterable[T], *, any_case: bool = False) -> T:
    """``value`` after checking it is one of ``options``.

    With ``any_case``, a string matches an option that differs only in case and the
    option's spelling is returned.

    Examples
    --------
    >>> choice("experiment", "drop", ("drop", "pour"))
    'drop'
    >>> choice("method", "DATH", ("fixed", "dath"), any_case=True)
    'dath'
    >>> choice("experiment", "shake", ("drop", "pour"))
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: experiment: unknown 'shake' (known: drop, pour)
    """
    opts = tuple(options)
    if any_case and isinstance(value, str):
        folded = {o.casefold(): o for o in opts if isinstance(o, str)}
        value = folded.get(value.casefold(), value)
    try:
        ok = value in opts
    except TypeError:  # unhashable or incomparable
        ok = False
    if not ok:
        raise ParameterError(f"{name}: unknown {value!r} (known: {', '.join(map(str, opts))})")
    return value


def choices(name: str, values: Any, options: Iterable[T], *, allow_empty: bool = False,
            any_case: bool = False) -> tuple[T, ...]:
    """``values`` as a tuple, after checking each is one of ``options``, once.

    ``any_case`` as in :func:`choice` (the options' spellings are returned).

    A single string is refused (``"dath"`` is not a list of methods).

    Examples
    --------
    >>> choices("bottles", ["TR", "TX"], ("TR", "DK", "TX"))
    ('TR', 'TX')
    >>> choices("bottles", ("TR", "TR"), ("TR", "DK", "TX"))
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: bottles: repeated entries in ('TR', 'TR')
    """
    opts = tuple(options)
    if isinstance(values, (str, bytes)) or not isinstance(values, Iterable):
        raise ParameterError(f"{name} must be a sequence of {', '.join(map(str, opts))}, got {values!r}")
    vals = tuple(choice(name, v, opts, any_case=any_case) for v in values)
    if not vals and not allow_empty:
        raise ParameterError(f"{name}: choose at least one of {', '.join(map(str, opts))}")
    if len(set(vals)) != len(vals):
        raise ParameterError(f"{name}: repeated entries in {vals}")
    return vals


def text(name: str, value: Any) -> str:
    """``value`` after checking it is a non-empty string.

    Examples
    --------
    >>> text("Bottle.name", "TR")
    'TR'
    >>> text("Bottle.name", "")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: Bottle.name must be a non-empty string, got ''
    """
    if not isinstance(value, str) or not value:
        raise ParameterError(f"{name} must be a non-empty string, got {value!r}")
    return value


def instance(name: str, value: Any, cls: type[T]) -> T:
    """``value`` itself if it is a ``cls``; anything else is refused by name.

    Examples
    --------
    >>> instance("speed", 3.0, float)
    3.0
    >>> instance("speed", "3", float)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: speed must be a float, got str
    """
    if not isinstance(value, cls):
        raise ParameterError(f"{name} must be a {cls.__name__}, got {type(value).__name__}")
    return value


def set_field(obj: Any, name: str, value: Any) -> None:
    """Store a checked value on a frozen dataclass from inside its ``__post_init__``.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> @dataclass(frozen=True)
    ... class P:
    ...     n: int = 1
    ...     def __post_init__(self): set_field(self, "n", integer("n", self.n, lo=1))
    >>> P(n=np.int16(4)).n
    4
    """
    object.__setattr__(obj, name, value)


def build(cls: type[T], kwargs: dict[str, Any]) -> T:
    """Construct the dataclass ``cls`` from ``kwargs``; an unknown keyword is refused by name.

    Examples
    --------
    >>> import dataclasses
    >>> Window = dataclasses.make_dataclass("Window", [("n", int, 1)], frozen=True)
    >>> build(Window, {"n": 2}).n
    2
    >>> build(Window, {"m": 2})
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: unknown parameter(s) for Window: m (known: n)
    """
    known = {f.name for f in dataclasses.fields(cls)}  # pyright: ignore[reportArgumentType] (cls: a dataclass)
    unknown = sorted(set(kwargs) - known)
    if unknown:
        raise ParameterError(
            f"unknown parameter(s) for {cls.__name__}: {', '.join(unknown)} "
            f"(known: {', '.join(sorted(known))})")
    return cls(**kwargs)


def resolve_params(cls: type[T], params: Any, overrides: dict[str, Any]) -> T:
    """The one contract for "a parameters object plus keyword overrides".

    * ``params is None``: build ``cls`` from ``overrides`` (missing required
      fields and unknown keywords are errors);
    * ``params`` given and no overrides: ``params`` as is;
    * both: a copy of ``params`` with the overridden fields replaced (checked
      again by ``cls``); an unknown keyword is an error;
    * anything that is not a ``cls`` instance is refused.

    Parameters
    ----------
    cls : type
        A dataclass of parameters.
    params : cls or None
        The parameters object, if the caller gave one.
    overrides : dict
        The caller's keyword arguments.

    Examples
    --------
    >>> import dataclasses
    >>> Grid = dataclasses.make_dataclass("Grid", [("rows", int, 4), ("cols", int, 4)], frozen=True)
    >>> resolve_params(Grid, Grid(rows=5), {"cols": 7})
    Grid(rows=5, cols=7)
    >>> resolve_params(Grid, {"rows": 5}, {})
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: params must be a Grid, got dict
    """
    if params is None:
        return build(cls, dict(overrides))
    instance("params", params, cls)
    if overrides:
        fields = {f.name: getattr(params, f.name) for f in dataclasses.fields(params)}
        return build(cls, {**fields, **overrides})
    return params



@dataclasses.dataclass(frozen=True)
class Limit:
    """The plausible range of one size, duration, rate or count a user gives.

    Parameters
    ----------
    lo, hi : float
        Bounds (inclusive; ``lo`` exclusive with ``lo_open``).
    unit : str
    why : str
        Where the bounds come from (shown in docs/runtime.md's table).
    options : str
        The command-line options it bounds.
    lo_open : bool
    whole : bool
        An integer count.

    Examples
    --------
    >>> LIMITS["trials"].hi
    10000
    """

    lo: float
    hi: float
    unit: str
    why: str
    options: str
    lo_open: bool = False
    whole: bool = False


#: THE table of plausible ranges of every size, duration, rate and count option (checked
#: before any work starts; docs/runtime.md "Limits" prints it). The bounds are far outside any
#: real use and far inside what would run for days or exhaust memory.
LIMITS: dict[str, Limit] = {
    "trials": Limit(1, 10_000, "", "trials per bottle, experiment and method (the paper ran 10; a run "
                    "estimated over 10 minutes says how to shorten it)",
                    "reproduce/study --trials", whole=True),
    "plants": Limit(1, 100_000, "", "plants of a study (default 64); each plant runs the whole grid",
                    "study --plants", whole=True),
    "jobs": Limit(1, 1024, "", "worker processes", "reproduce --jobs, study --workers", whole=True),
    "rest_s": Limit(0, 600, "s", "recorded rest before the perturbation; every simulated second of every "
                    "trial is held in memory", "reproduce --rest", lo_open=True),
    "after_s": Limit(0, 600, "s", "recording after the load, held in memory as the rest",
                     "reproduce --after", lo_open=True),
    "calibration_s": Limit(0, 600, "s", "each at-rest calibration recording", "reproduce --calibration",
                           lo_open=True),
    "rest_k": Limit(0, 100, "sd", "NMSD/SWT-SD threshold in standard deviations at rest", "reproduce --rest-k",
                    lo_open=True),
    "swt_persist": Limit(0, 10_000, "samples", "SWT-SD persistence (30 s at the DAQ's rate)",
                         "reproduce --swt-persist", whole=True),
    "grasp_force_n": Limit(0, 20, "N", "contact force at which the grasp stops (the paper's 0.8 N, 25 times)",
                           "reproduce/virtual-rig --grasp-force", lo_open=True),
    "duration_s": Limit(0, 7 * 86400, "s", "a real-time run or virtual rig (a week; 0 stops at once)",
                        "run/virtual-rig --duration"),
    "fs_hz": Limit(0, 1e6, "Hz", "sampling rate of a recording (the DAQ's is 333.33 Hz)", "detect/run --fs",
                   lo_open=True),
    "scan_distance_mm": Limit(0, 500, "mm", "scan length (the paper's 50 mm, 10 times)", "scan --distance",
                              lo_open=True),
    "scan_speed_mm_s": Limit(0.01, 1000, "mm/s", "scan speed (the paper's 1 mm/s)", "scan --speed"),
    "scan_samples": Limit(1, 20_000_000, "samples", "distance / speed x the DAQ's rate (about 17 h of scan); "
                          "every sample is held in memory", "scan --distance/--speed", whole=True),
    "csv_samples": Limit(1, 50_000_000, "samples", "samples in a CSV recording (about 42 h at 333.33 Hz)",
                         "detect", whole=True),
    "csv_line_bytes": Limit(1, 1_000_000, "bytes", "one CSV line (a sample row is tens of bytes)",
                            "detect, claims", whole=True),
    "text_file_bytes": Limit(1, 64 * 1024 ** 2, "bytes", "a TOML or results file (64 MiB)",
                             "--objects, --ranges, claims", whole=True),
    "recording_bytes": Limit(1, 8e9, "bytes", "an MCAP recording; the reader holds the whole file in memory",
                             "replay, export, recover", whole=True),
    "recording_chunk_bytes": Limit(1, 64 * 1024 ** 2, "bytes", "one MCAP chunk, decompressed (mcap's writer "
                                   "makes 1 MiB, this package's 16-64 KiB)", "replay, export, recover", whole=True),
    "recording_expansion": Limit(1, 50, "times", "all the chunks of a recording, decompressed, over its size "
                                 "(a run's recording decompresses to a few times its size; a compression "
                                 "bomb to thousands)",
                                 "replay, export, recover"),
}


def within(name: str, value: Any, option: str | None = None) -> Any:
    """``value`` checked against ``LIMITS[name]`` (as an int for counts); one line naming ``option``.

    Examples
    --------
    >>> within("trials", 3)
    3
    >>> within("rest_s", 1e9, "--rest")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: --rest must be a finite number > 0 and <= 600, got 1000000000.0 ...
    """
    lim = LIMITS[name]
    label = option or name
    try:
        if lim.whole:
            return integer(label, value, lo=int(lim.lo), hi=int(lim.hi))
        return number(label, value, lo=lim.lo, hi=lim.hi, lo_open=lim.lo_open)
    except ParameterError as err:
        raise ParameterError(f"{err} (plausible range {'> ' if lim.lo_open else ''}{lim.lo:g}..{lim.hi:g}"
                             f"{' ' + lim.unit if lim.unit else ''}; docs/runtime.md, Limits)") from None


def limits_markdown() -> str:
    """The :data:`LIMITS` table as markdown (docs/runtime.md carries it).

    Examples
    --------
    >>> limits_markdown().splitlines()[0]
    '| limit | range | options | why |'
    """
    rows = ["| limit | range | options | why |", "|---|---|---|---|"]
    for name, lim in LIMITS.items():
        lo = f"> {lim.lo:g}" if lim.lo_open else f"{lim.lo:g}"
        rows.append(f"| {name} | {lo} .. {lim.hi:g} {lim.unit} | {lim.options} | {lim.why} |")
    return "\n".join(rows)
