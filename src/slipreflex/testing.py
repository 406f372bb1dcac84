"""Conformance checks any reflex can run, in the spirit of Gymnasium's ``env_checker``.

:func:`check_reflex` drives a reflex through a synthetic trial (rest, then a
slip) and checks the :class:`slipreflex.core.interfaces.Reflex` contract:

* the attributes: ``name``, ``input_kind`` ("slip" or "tactile"), a finite
  positive ``fs``, callable ``step`` / ``reset``, and the diagnostics
  ``last_event``, ``last_filtered``, ``last_threshold``, ``last_count`` with
  their declared types after every step;
* ``step`` returns None or a finite float;
* ``reset()`` restores the initial state bit for bit (every attribute of the
  reflex and of the objects it holds, arrays compared by their bytes);
* the same input gives the same bits (a run, a reset and a second run agree
  exactly, and so does a deep copy of the fresh reflex);
* a non-finite sample is handled: it is skipped or refused with
  :class:`~slipreflex.core.errors.DataError` (any other exception fails), it never
  yields a command below the hand's measured position or the last command (a
  fault never opens the hand), and the reflex still answers the slip after it;
* the optional members the real-time loop reads (``command``, ``params.p0``, ``params.hi``,
  ``finger_offsets``, ``last_board``, ``last_mismatch``), where the reflex has them, of the
  kind :data:`slipreflex.core.interfaces.CONTRACTS` declares;
* a :class:`~slipreflex.core.interfaces.CompiledReflex`: ``compiled()`` returns the
  live state, and its step on that state gives ``step``'s commands and
  diagnostics bit for bit (what the compiled closed loop relies on).

:func:`check_hand` and :func:`check_source` (from :mod:`slipreflex.core.contract_checks`) check a
hand and a sample source the same way.

:func:`reflex_for_check` builds any registered method ready for the check
(thresholds of calibrated methods from the synthetic rest recording, by the
package's one rule).

Examples
--------
>>> from slipreflex.methods.chain import SlipReflex
>>> report = check_reflex(SlipReflex(dath=True, p0=100.0))
>>> report.commands > 0, report.events > 0
(True, True)
>>> check_reflex(reflex_for_check("nmsd")).commands > 0
True
"""

from __future__ import annotations

import copy
import math
import numbers
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import methods
from .core import experiment_specs
from .core import hardware as hw
from .core.contract_checks import ContractError, check_hand, check_reflex_members, check_source
from .core.errors import DataError
from .core.interfaces import Reflex
from .methods.baselines import REST_K, rest_statistic
from .reproduce.experiments import Cell, ReproduceConfig, run_trial, trial_seed
from .reproduce.thresholds import calibrate

__all__ = ["ContractError", "CheckReport", "check_reflex", "check_method", "synthetic_input", "check_hand",
           "check_source",
           "reflex_for_check", "check_experiment"]

#: Synthetic trial: seconds of rest, then seconds of slip.
REST_S, SLIP_S = 1.0, 1.0
#: Grasp position the checked reflexes start from (finger units).
CHECK_P0: float = 100.0


@dataclass(frozen=True)
class CheckReport:
    """What :func:`check_reflex` saw on the synthetic trial.

    Attributes
    ----------
    samples : int
        Samples fed per run.
    commands : int
        Commands the reflex issued (a check is only telling if this is > 0).
    events : int
        Steps with ``last_event`` true.

    Examples
    --------
    >>> CheckReport(10, 1, 2).commands
    1
    """

    samples: int
    commands: int
    events: int


def synthetic_input(input_kind: str, fs: float, *, shape: tuple[int, ...] = hw.TACTILE_SHAPE,
                    seed: int = 0) -> tuple[np.ndarray, int]:
    """A synthetic trial for a reflex: ``REST_S`` at rest, then ``SLIP_S`` of slip.

    Slip sensor: 0.4 V with 2 mV noise, then a growing 8 Hz oscillation (the
    sensor's ridges passing). Tactile: 1 N per taxel with 2 mN noise, then one
    taxel loses 0.3 N at once and another unloads at 2 N/s.

    Returns
    -------
    (numpy.ndarray, int)
        The samples (K,) or frames (K, *shape), and K_rest, the index where slip starts.

    Examples
    --------
    >>> x, k = synthetic_input("tactile", 260.0)
    >>> x.shape, k
    ((520, 4, 4), 260)
    """
    rng = np.random.default_rng(seed)
    k_rest, k_slip = int(round(REST_S * fs)), int(round(SLIP_S * fs))
    t = np.arange(k_slip) / fs
    if input_kind == "slip":
        x = 0.4 + rng.normal(0.0, 0.002, k_rest + k_slip)
        x[k_rest:] += 0.05 * np.minimum(1.0, 4 * t) * np.sin(2 * np.pi * 8.0 * t)
        return x, k_rest
    x = 1.0 + rng.normal(0.0, 0.002, (k_rest + k_slip, *shape))
    flat = x.reshape(len(x), -1)
    flat[k_rest:, 0] -= 0.3
    flat[k_rest:, -1] -= 2.0 * t
    return x, k_rest


def reflex_for_check(name: str, *, shape: tuple[int, ...] | None = None, **params: Any) -> Reflex:
    """A fresh reflex of the registered method ``name``, ready for :func:`check_reflex`.

    A method with a rest statistic gets its threshold by the package's one rule
    (:data:`slipreflex.methods.baselines.REST_K` sd of the statistic) from the rest part
    of :func:`synthetic_input`. ``shape`` (a tactile method's frame shape) is
    passed on to the method as its ``shape`` parameter.

    Examples
    --------
    >>> reflex_for_check("swt").params.threshold > 0
    True
    >>> reflex_for_check("nmsd", shape=(7,)).params.shape
    (7,)
    """

    spec = methods.get(name)
    if shape is not None:
        params["shape"] = tuple(shape)
    thresholds = {}
    if spec.rest_statistic is not None:
        x, k_rest = synthetic_input(spec.input_kind, spec.fs, shape=shape or hw.TACTILE_SHAPE)
        thresholds[spec.name] = REST_K * float(np.std(rest_statistic(x[:k_rest], spec.rest_statistic,
                                                                     spec.fs)))
    ctx = methods.MethodContext(thresholds=thresholds, speed=500.0)
    return methods.make(name, p0=CHECK_P0, context=ctx, **params)


def _fail(reflex: Any, what: str) -> None:
    raise ContractError(f"{type(reflex).__name__} ({getattr(reflex, 'name', '?')}): {what}")


def _check_attributes(reflex: Any) -> None:
    if not isinstance(getattr(reflex, "name", None), str) or not reflex.name:
        _fail(reflex, f"name must be a non-empty str, got {getattr(reflex, 'name', None)!r}")
    if getattr(reflex, "input_kind", None) not in ("slip", "tactile"):
        _fail(reflex, f"input_kind must be 'slip' or 'tactile', got {getattr(reflex, 'input_kind', None)!r}")
    fs = getattr(reflex, "fs", None)
    if not isinstance(fs, numbers.Real) or isinstance(fs, bool) or not math.isfinite(fs) or fs <= 0:
        _fail(reflex, f"fs must be a finite number > 0, got {fs!r}")
    for m in ("step", "reset"):
        if not callable(getattr(reflex, m, None)):
            _fail(reflex, f"{m} must be callable")
    if not isinstance(reflex, Reflex):
        members = [n for n, v in vars(Reflex).items() if isinstance(v, property)]
        missing = [a for a in (*members, "step", "reset") if not hasattr(reflex, a)]
        _fail(reflex, f"is not a slipreflex.core.interfaces.Reflex (missing: {', '.join(missing)})")


def _diagnostics(reflex: Any) -> tuple:
    ev, filt, thr, count = reflex.last_event, reflex.last_filtered, reflex.last_threshold, reflex.last_count
    if not isinstance(ev, (bool, np.bool_)):
        _fail(reflex, f"last_event must be a bool, got {ev!r}")
    if not isinstance(filt, numbers.Real) or isinstance(filt, bool):
        _fail(reflex, f"last_filtered must be a float (NaN when not defined), got {filt!r}")
    if thr is not None and (not isinstance(thr, numbers.Real) or isinstance(thr, bool)):
        _fail(reflex, f"last_threshold must be a float or None, got {thr!r}")
    if count is not None and (not isinstance(count, numbers.Integral) or isinstance(count, bool)):
        _fail(reflex, f"last_count must be an int or None, got {count!r}")
    return (bool(ev), _bits(float(filt)), None if thr is None else _bits(float(thr)),
            None if count is None else int(count))


def _bits(x: float) -> bytes:
    return np.float64(x).tobytes()


def _command(reflex: Any, out: Any, k: int) -> bytes | None:
    if out is None:
        return None
    if not isinstance(out, numbers.Real) or isinstance(out, bool) or not math.isfinite(out):
        _fail(reflex, f"step must return None or a finite float, got {out!r} at sample {k}")
    return _bits(float(out))


def _run(reflex: Any, x: np.ndarray) -> list[tuple]:
    """Feed ``x`` (positions on every 4th sample); one (command, diagnostics) per sample."""
    trace = []
    for k, sample in enumerate(x):
        pos = CHECK_P0 + 0.01 * k if k % 4 == 0 else None
        out = reflex.step(sample if reflex.input_kind == "tactile" else float(sample), pos)
        trace.append((_command(reflex, out, k), _diagnostics(reflex)))
    return trace


def _state(obj: Any, seen: set[int] | None = None, depth: int = 0) -> Any:
    """A comparable snapshot of an object's whole state (floats and arrays by their bits)."""
    seen = set() if seen is None else seen
    if isinstance(obj, (bool, int, str, bytes, type(None), np.bool_)):
        return obj
    if isinstance(obj, (float, np.floating)):
        return ("f", _bits(float(obj)))
    if isinstance(obj, np.ndarray):
        return ("a", obj.dtype.str, obj.shape, np.ascontiguousarray(obj).tobytes())
    if isinstance(obj, np.integer):
        return int(obj)
    if id(obj) in seen or depth > 8 or callable(obj) and not hasattr(obj, "__dict__"):
        return ("ref", type(obj).__name__)
    seen.add(id(obj))
    if isinstance(obj, (list, tuple)):
        return (type(obj).__name__, tuple(_state(v, seen, depth + 1) for v in obj))
    if isinstance(obj, dict):
        return ("d", tuple((repr(k), _state(v, seen, depth + 1)) for k, v in obj.items()))
    attrs = dict(getattr(obj, "__dict__", {}))
    for cls in type(obj).__mro__:
        for s in getattr(cls, "__slots__", ()):
            if hasattr(obj, s):
                attrs[s] = getattr(obj, s)
    return (type(obj).__name__, tuple((k, _state(v, seen, depth + 1)) for k, v in sorted(attrs.items())))


def _first_difference(a: list[tuple], b: list[tuple]) -> int:
    return next((k for k, (u, v) in enumerate(zip(a, b)) if u != v), min(len(a), len(b)))


def _check_compiled(reflex: Any, x: np.ndarray, reference: list[tuple]) -> None:
    """A :class:`~slipreflex.core.interfaces.CompiledReflex`: its step on its live state is ``step`` itself."""
    if not callable(getattr(reflex, "compiled", None)):
        return
    reflex.reset()
    step, S, P = reflex.compiled()
    if reflex.compiled()[1] is not S:
        _fail(reflex, "compiled() must return the reflex's own live state vector, not a copy")
    trace = []
    for k, sample in enumerate(x):
        pos = CHECK_P0 + 0.01 * k if k % 4 == 0 else math.nan
        inp = (np.ascontiguousarray(sample, dtype=np.float64).reshape(-1) if reflex.input_kind == "tactile"
               else float(sample))
        out = float(step(S, P, inp, pos))
        trace.append((_command(reflex, None if out != out else out, k), _diagnostics(reflex)))
    if trace != reference:
        _fail(reflex, f"its compiled step on its state disagrees with step (first difference at sample "
                      f"{_first_difference(reference, trace)}): the compiled closed loop would run another reflex")


def _check_non_finite(reflex: Any, x: np.ndarray, k_bad: int, k_rest: int, reference: list[tuple]) -> None:
    """A NaN sample at ``k_bad`` is skipped or refused, never opens the hand, and the reflex goes on."""
    reflex.reset()
    bad = np.array(x, dtype=float, copy=True)
    bad[k_bad] = np.nan
    floor, after = -math.inf, 0        # the hand must not be told to open below this
    for k, sample in enumerate(bad):
        pos = CHECK_P0 + 0.01 * k if k % 4 == 0 else None
        floor = max(floor, -math.inf if pos is None else pos)
        inp = sample if reflex.input_kind == "tactile" else float(sample)
        try:
            out = reflex.step(inp, pos)
        except DataError:
            if k == k_bad:
                continue
            raise
        _command(reflex, out, k)
        _diagnostics(reflex)
        if out is not None and k == k_bad and out < floor:
            _fail(reflex, f"a non-finite sample produced the command {out!r}, below the hand's "
                          f"position or last command {floor!r} (it would open the hand)")
        if out is not None:
            floor = max(floor, float(out))
            after += k > k_rest
    if after == 0 and any(c is not None for c, _ in reference[k_rest:]):
        _fail(reflex, "after a non-finite sample the reflex never commands again on the slip")


def check_reflex(reflex: Any, *, shape: tuple[int, ...] | None = None, seed: int = 0) -> CheckReport:
    """Check that ``reflex`` keeps the :class:`~slipreflex.core.interfaces.Reflex` contract.

    Parameters
    ----------
    reflex : Reflex
        A freshly built reflex (its state is reset by the check).
    shape : tuple of int, optional
        Frame shape of a tactile reflex (default: ``reflex.params.shape`` if it
        has one, else the 4 x 4 array).
    seed : int
        Seed of the synthetic input.

    Returns
    -------
    CheckReport

    Raises
    ------
    ContractError
        Naming the broken rule.

    Examples
    --------
    >>> class Opens:
    ...     name, input_kind, fs = "opens", "slip", 100.0
    ...     last_event, last_filtered, last_threshold, last_count = False, float("nan"), None, None
    ...     def step(self, sample, position=None): return 0.0 if sample != sample else None
    ...     def reset(self): pass
    >>> check_reflex(Opens())
    Traceback (most recent call last):
    ...
    slipreflex.core.contract_checks.ContractError: Opens (opens): a non-finite sample produced the command 0.0, ...
    """
    _check_attributes(reflex)
    check_reflex_members(reflex)
    if shape is None:
        shape = tuple(getattr(getattr(reflex, "params", None), "shape", hw.TACTILE_SHAPE))
    x, k_rest = synthetic_input(reflex.input_kind, float(reflex.fs), shape=shape, seed=seed)
    twin = copy.deepcopy(reflex)
    reflex.reset()
    initial = _state(reflex)
    first = _run(reflex, x)
    reflex.reset()
    if _state(reflex) != initial:
        _fail(reflex, "reset() does not restore the initial state bit for bit")
    second = _run(reflex, x)
    if second != first:
        _fail(reflex, f"the same input after reset() gives other bits (first difference at sample "
                      f"{_first_difference(first, second)})")
    twin.reset()
    if _run(twin, x) != first:
        _fail(reflex, "a copy of the fresh reflex gives other bits on the same input")
    check_reflex_members(reflex)  # the optional members the loop reads, after a run
    _check_compiled(reflex, x, first)
    _check_non_finite(reflex, x, k_rest // 2, k_rest, first)
    reflex.reset()
    return CheckReport(samples=len(x), commands=sum(c is not None for c, _ in first),
                       events=sum(d[0] for _, d in first))


def check_method(name: str, *, shape: tuple[int, ...] | None = None) -> CheckReport:
    """Check a registered method: its reflex keeps the contract and agrees with its specification.

    Runs :func:`check_reflex` on :func:`reflex_for_check` and checks that the
    reflex reads the stream and runs at the rate its
    :class:`~slipreflex.methods.MethodSpec` says, and that the specification's
    ``detections`` (when given) draws one value and one detection flag per
    input sample, and its ``rest_statistic`` (when given) returns finite values.

    Examples
    --------
    >>> check_method("swt").commands > 0
    True
    """

    spec = methods.get(name)
    reflex = reflex_for_check(name, shape=shape)
    if reflex.input_kind != spec.input_kind or not math.isclose(reflex.fs, spec.fs):
        _fail(reflex, f"the specification says {spec.input_kind!r} at {spec.fs:g} Hz, the reflex reads "
                      f"{reflex.input_kind!r} at {reflex.fs:g} Hz")
    report = check_reflex(reflex, shape=shape)
    x, k_rest = synthetic_input(spec.input_kind, spec.fs, shape=shape or hw.TACTILE_SHAPE)
    if spec.detections is not None:
        d = spec.detections(reflex, x)
        if np.shape(d.sensor) != (len(x),) or np.shape(d.events) != (len(x),) \
                or np.asarray(d.events).dtype != bool:
            _fail(reflex, f"detections() must give a trace and a bool flag per sample ({len(x)}), got "
                          f"{np.shape(d.sensor)} and {np.shape(d.events)} {np.asarray(d.events).dtype}")
    if spec.rest_statistic is not None:
        stat = np.asarray(spec.rest_statistic(x[:k_rest], spec.fs), dtype=float)
        if stat.ndim != 1 or not stat.size or not np.isfinite(stat).all():
            _fail(reflex, "rest_statistic() must give a non-empty 1-D array of finite values")
    return report


def check_experiment(name: str, config: Any = None, *, method: str = "fixed") -> list[Any]:
    """Check a registered experiment: its specification holds and one trial of it runs and is read.

    The perturbation it builds from ``config`` is one the simulated rig applies; its
    description is words; its load and settle times are finite, not negative, and slips are
    looked for inside the recording; one trial (the first bottle, ``method``) runs, and its
    rows carry the experiment's name, a whole number of slip events (one at most for
    ``slip_events="single"``) and, with ``records_load``, a load at every onset found.

    Parameters
    ----------
    name : str
        A registered experiment (:mod:`slipreflex.core.experiment_specs`).
    config : ReproduceConfig, optional
        The run to build its perturbation from (default: the paper's, this experiment only).
    method : str
        The method of the trial.

    Returns
    -------
    list of TrialRow
        The trial's rows.

    Raises
    ------
    ContractError
        Naming the experiment and the broken rule.

    Examples
    --------
    >>> [r.experiment for r in check_experiment("drop")]
    ['drop']
    """
    from .sim import Rig  # deferred: heavy (numba kernels)

    spec = experiment_specs.get(name)

    def fail(what: str) -> None:
        raise ContractError(f"experiment {name!r}: {what}")

    cfg = config or ReproduceConfig(trials=1, methods=(method,), experiments=(name,))
    what = spec.perturbation(cfg)
    try:
        Rig(cfg.bottles[0]).perturb(what, at=0.0)
    except Exception as err:  # noqa: BLE001 - any refusal is the experiment's to fix
        fail(f"the simulated rig refuses its perturbation {what!r}: {err}")
    text = spec.describe(what)
    if not isinstance(text, str) or not text.strip():
        fail(f"describe() must give words, got {text!r}")
    load, settle = float(spec.load_s(what)), float(spec.settle_s(what))
    if not (math.isfinite(load) and load >= 0.0):
        fail(f"load_s() must be finite and >= 0, got {load!r}")
    if not (math.isfinite(settle) and 0.0 <= settle < load + cfg.after_s):
        fail(f"settle_s() must be >= 0 and inside the recording (load {load:g} s + after {cfg.after_s:g} s), "
             f"got {settle!r}")
    cell = Cell(name, cfg.bottles[0], method, 0, trial_seed(cfg.seed, name, cfg.bottles[0], 0))
    thresholds = calibrate(cfg) if method in methods.calibrated() else {}
    rows, _ = run_trial(cell, cfg, thresholds)
    if not rows or any(r.experiment != name for r in rows):
        fail(f"a trial's rows must carry the experiment's name, got {[r.experiment for r in rows]}")
    n = rows[0].n_events
    if spec.slip_events == "single" and n > 1:
        fail(f"slip_events='single' but the trial found {n} slips")
    if spec.records_load and any(r.n_events and not math.isfinite(r.load_at_onset) for r in rows):
        fail("records_load=True but an onset has no load")
    return rows
