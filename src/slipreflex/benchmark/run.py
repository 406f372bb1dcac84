"""Every registered detector on every recorded trial (docs/benchmark.md).

For each trial and each method that applies, at the data's own rate and/or resampled to
the rate the method was specified at:

1. **Input.** A chain method (``input_kind="slip"``: the paper's fixed and DATH, the
   authors' preset, the variants) reads one channel: with a layout, the chosen
   *reduction* of the arrays (:data:`REDUCTIONS`: ``z-sum``, the normal component summed
   over every taxel, by default); without one, every channel on its own (a detection on
   any channel counts). A tactile method (NMSD, SWT-SD) reads the normal component of
   every taxel of every array (a detection on any taxel counts, as their rules say).
   Chain channels start at 0 (their first value subtracted): the encoder answers changes,
   and the authors' preset's moving mean starts from zero.
2. **Rate.** ``"data"``: the method runs on the recorded samples, taken as evenly spaced at
   the trial's mean rate, with every length that its specification gives in samples at its
   own rate converted to the same time at the data's rate (:data:`SAMPLE_FIELDS`).
   ``"method"``: the inputs are resampled to the method's rate by
   :func:`scipy.signal.resample_poly` (a polyphase FIR low-pass, Kaiser window, the
   ratio the nearest fraction with a denominator <= 64) and the method runs unchanged.
3. **Threshold** by one rule for every method, from the calibration span only (the first
   ``calibration_s`` of the trial, which must end before the labelled onset): ``rest_k``
   standard deviations of the method's own statistic there. NMSD and SWT-SD use their
   registered rest statistics (:func:`slipreflex.methods.baselines.rest_threshold`, as in
   simulation); a chain method uses its own low-passed channel minus its mean over the
   span (what its accumulator measures from a reference sample). A DATH floor of one ADC
   step becomes the channel's own step (its smallest non-zero change).
4. **Detections** are the method's registered ones
   (:attr:`slipreflex.methods.MethodSpec.detections`: a chain's spikes, NMSD's rising
   edges, SWT-SD's ON starts), scored by :func:`slipreflex.benchmark.scoring.score`.

Examples
--------
>>> from slipreflex.benchmark import read_folder, shipped_dataset
>>> trial = read_folder(shipped_dataset())[-1]
>>> runs = run_trial(trial, BenchmarkConfig(methods=("nmsd",), rates=("data",)))
>>> runs[0].method, runs[0].rate, runs[0].score.slips
('nmsd', 'data', True)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from .. import methods as registry
from ..core.errors import DataError, ParameterError
from ..core.validation import number
from ..methods.baselines import rest_threshold
from ..methods.baselines.calibration import REST_K
from ..methods.chain import SlipReflex, run_chain
from .scoring import Score, score
from .trials import RecordedTrial

__all__ = ["BenchmarkConfig", "MethodRun", "Skipped", "REDUCTIONS", "RATES", "SAMPLE_FIELDS",
           "applicable", "plan", "run_trial", "run_benchmark", "reduce_channels", "to_rate"]

#: Chain inputs from a layout: the normal force summed over every taxel (the load on the
#: fingers, what NMSD and SWT-SD read, in one channel), or the shear: per array, the length of
#: the change of its summed tangential components since the first sample, summed over arrays.
REDUCTIONS: tuple[str, ...] = ("z-sum", "shear-norm")
#: Where a method runs: at the recording's rate, or resampled to the method's own.
RATES: tuple[str, ...] = ("data", "method")
#: Parameters that are lengths in samples at the method's own rate (converted at the data's).
SAMPLE_FIELDS: dict[str, int] = {"n": 1, "dath_samples": 1, "mean_samples": 1, "acc_reset": 1,
                                 "persist": 0, "acc_leak": -1}
#: Largest denominator of the resampling ratio: puts the achieved rate within about 0.01 % of the
#: method's (259.98-260.02 Hz on the shipped set) while keeping the polyphase filter short.
_MAX_DENOMINATOR = 64


@dataclass(frozen=True)
class BenchmarkConfig:
    """What ``slipreflex benchmark`` runs.

    Parameters
    ----------
    methods : tuple of str or None
        Methods to run (registered names); None: every registered method that applies.
    calibration_s : float
        The span at the start of every trial whose data set the thresholds (s).
    rest_k : float
        Standard deviations of the rest statistic that make a threshold.
    reduction : str
        The chain's input from a layout (:data:`REDUCTIONS`).
    rates : tuple of str
        ``"data"``, ``"method"`` or both (:data:`RATES`).

    Examples
    --------
    >>> BenchmarkConfig(rates=("fast",))
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: rates: unknown 'fast' (known: data, method)
    """

    methods: tuple[str, ...] | None = None
    calibration_s: float = 1.0
    rest_k: float = REST_K
    reduction: str = "z-sum"
    rates: tuple[str, ...] = RATES

    def __post_init__(self) -> None:
        number("calibration_s", self.calibration_s, lo=0.0, lo_open=True)
        number("rest_k", self.rest_k, lo=0.0, lo_open=True)
        if self.reduction not in REDUCTIONS:
            raise ParameterError(f"reduction: unknown {self.reduction!r} (known: {', '.join(REDUCTIONS)})")
        if not self.rates:
            raise ParameterError("rates: give at least one of data, method")
        for r in self.rates:
            if r not in RATES:
                raise ParameterError(f"rates: unknown {r!r} (known: {', '.join(RATES)})")
        if self.methods is not None:
            object.__setattr__(self, "methods", tuple(registry.canonical(m) for m in self.methods))


@dataclass(frozen=True)
class MethodRun:
    """One method on one trial at one rate.

    Attributes
    ----------
    trial, method, label, rate : str
    fs : float
        The rate it ran at (Hz).
    threshold : float
        Its threshold by the rule (the largest over channels when it read several).
    params : dict
        The parameters it ran with that differ from its registered ones.
    t : numpy.ndarray
        Times of its samples (s).
    detections : numpy.ndarray of bool
        Its detections, one per sample of ``t``.
    trace, trace_label : numpy.ndarray, str
        What it read (its low-passed channel, or the arrays' total normal force).
    score : Score

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> (r,) = run_trial(read_folder(shipped_dataset())[0], BenchmarkConfig(methods=("swt",), rates=("data",)))
    >>> r.key, r.params["persist"], len(r.t) == len(r.detections)
    ('swt@data', 0, True)
    """

    trial: str
    method: str
    label: str
    rate: str
    fs: float
    threshold: float
    params: dict
    t: np.ndarray
    detections: np.ndarray
    trace: np.ndarray
    trace_label: str
    score: Score

    @property
    def key(self) -> str:
        """``method@rate`` (``nmsd@data``)."""
        return f"{self.method}@{self.rate}"


@dataclass(frozen=True)
class Skipped:
    """A method that does not apply to the data, and why.

    Examples
    --------
    >>> Skipped("dath-board", "runs on volts").method
    'dath-board'
    """

    method: str
    reason: str


def _trial_reflex(name: str) -> Any:
    """The method's reflex as registered (default parameters), for its params and type."""
    spec = registry.get(name)
    if spec.input_kind == "tactile":
        return registry.make(name, context=registry.MethodContext(thresholds={name: 1.0}, speed=1.0))
    return registry.make(name)


def applicable(name: str, trial: RecordedTrial) -> str | None:
    """None if method ``name`` can run on ``trial``, else the reason it cannot.

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> tr = read_folder(shipped_dataset())[0]
    >>> applicable("dath", tr) is None, applicable("nmsd", tr) is None
    (True, True)
    >>> applicable("dath-board", tr)
    "runs the microcontroller's fixed-point chain on 0-5 V DAQ volts, not on this data's units"
    """

    spec = registry.get(name)
    if spec.detections is None:
        return "registers no detections"
    reflex = _trial_reflex(name)
    if spec.input_kind == "slip":
        if not isinstance(reflex, SlipReflex):
            if "board" in name:
                return "runs the microcontroller's fixed-point chain on 0-5 V DAQ volts, not on this data's units"
            return "not the paper's chain: no threshold rule for it on recorded data"
        return None
    if trial.layout is None:
        return "needs a tactile array: the trial has no '# layout' line"
    if spec.rest_statistic is None:
        return "has no rest statistic, so no threshold rule"
    if not hasattr(getattr(reflex, "params", None), "threshold"):
        return "has no threshold parameter"
    return None


def reduce_channels(trial: RecordedTrial, reduction: str) -> list[tuple[str, np.ndarray]]:
    """The chain's input channel(s), each starting at 0.

    With a layout, one channel: the reduction (:data:`REDUCTIONS`); without one, every
    channel.

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> tr = read_folder(shipped_dataset())[0]
    >>> [(n, float(x[0])) for n, x in reduce_channels(tr, "shear-norm")]
    [('shear-norm', 0.0)]
    """
    if trial.layout is None:
        return [(n, trial.channels[:, i] - trial.channels[0, i]) for i, n in enumerate(trial.channel_names)]
    lay = trial.layout
    if reduction == "z-sum":
        x = trial.normal_frames().reshape(len(trial.t), -1).sum(axis=1)
        return [(reduction, x - x[0])]
    shear = [k for k in range(lay.values) if k != lay.normal]
    if len(shear) < 2:
        raise DataError(f"{trial.path}: reduction shear-norm needs two tangential components per taxel, "
                        f"the layout has {lay.values} component(s)")
    s = np.stack([trial.components(k).sum(axis=(2, 3)) for k in shear[:2]], axis=-1)   # (K, A, 2)
    x = np.linalg.norm(s - s[0], axis=-1).sum(axis=1)
    return [(reduction, x)]


def to_rate(t: np.ndarray, x: np.ndarray, fs_target: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Resample samples ``x`` (first axis) to about ``fs_target`` with a polyphase FIR filter.

    The samples are taken as evenly spaced at their mean rate; the ratio is the nearest
    fraction ``up/down`` with ``down <= 64``; the new samples' times are read off ``t`` at
    their fractional positions, so both rates share the recording's clock.

    Returns
    -------
    (t_new, x_new, fs_new)

    Examples
    --------
    >>> t = np.arange(60) / 60.0
    >>> t2, x2, fs2 = to_rate(t, np.sin(2 * np.pi * 2 * t), 240.0)
    >>> fs2, len(t2), round(float(np.abs(x2[8:-8] - np.sin(2 * np.pi * 2 * t2[8:-8])).max()), 2) < 0.05
    (240.0, 237, True)
    """
    from scipy.signal import resample_poly  # deferred: heavy (scipy.signal)

    fs = (len(t) - 1) / (t[-1] - t[0])
    ratio = Fraction(fs_target / fs).limit_denominator(_MAX_DENOMINATOR)
    up, down = ratio.numerator, ratio.denominator
    y = resample_poly(np.asarray(x, dtype=float), up, down, axis=0, padtype="line")
    pos = np.arange(len(y)) * down / up
    keep = pos <= len(t) - 1
    t_new = np.interp(pos[keep], np.arange(len(t)), t)
    return t_new, y[keep], float(fs * up / down)


def _scaled(reflex: Any, native_fs: float, fs: float) -> dict[str, Any]:
    """Sample-count parameters of ``reflex`` converted from ``native_fs`` to ``fs`` (same times)."""
    out = {}
    p = reflex.params
    for name, lo in SAMPLE_FIELDS.items():
        v = getattr(p, name, None)
        if v is None:
            continue
        if lo < 0:
            out[name] = float(v) * fs / native_fs
        else:
            out[name] = max(lo, int(round(v * fs / native_fs)))
    return out


def _quantum(x: np.ndarray) -> float:
    d = np.abs(np.diff(x))
    d = d[d > 0]
    return float(d.min()) if d.size else 0.0


def _chain_run(name: str, trial: RecordedTrial, cfg: BenchmarkConfig, rate: str):

    spec = registry.get(name)
    base = _trial_reflex(name)
    detect = spec.detections
    assert detect is not None                                  # applicable() checked it
    outs = []
    for ch_name, x in reduce_channels(trial, cfg.reduction):
        step = _quantum(x[trial.t < trial.t[0] + cfg.calibration_s])      # the recorded channel's step
        if rate == "data":
            t, fs = trial.t, trial.fs
            over: dict[str, Any] = {"fs": fs, **_scaled(base, spec.fs, fs)}
        else:
            t, x, fs = to_rate(trial.t, x, spec.fs)
            over = {"fs": fs}
        if base.params.dath_floor > 0:
            over["dath_floor"] = step or base.params.dath_floor
        cal = t < t[0] + cfg.calibration_s
        filtered = run_chain(x[cal], dataclasses.replace(base.params, **over)).filtered
        sd = float(np.std(filtered))
        if not sd > 0:
            raise DataError(f"{trial.path}: channel {ch_name} does not change in the first "
                            f"{cfg.calibration_s:g} s: no threshold for {name}")
        over["threshold"] = cfg.rest_k * sd
        reflex = registry.make(name, **over)
        det = detect(reflex, x)
        outs.append((t, fs, over, det))
    t, fs, over, det = outs[0]
    events = np.logical_or.reduce([o[3].events for o in outs])
    thr = max(o[2]["threshold"] for o in outs)
    label = det.sensor_label if len(outs) == 1 else "first channel"
    return t, fs, thr, over, events, det.sensor, label


def _tactile_run(name: str, trial: RecordedTrial, cfg: BenchmarkConfig, rate: str):

    spec = registry.get(name)
    base = _trial_reflex(name)
    detect = spec.detections
    assert detect is not None                                  # applicable() checked it
    frames = trial.normal_frames()
    frames = frames - frames[0]
    if rate == "data":
        t, fs = trial.t, trial.fs
        over = _scaled(base, spec.fs, fs)
    else:
        t, frames, fs = to_rate(trial.t, frames, spec.fs)
        over = {}
    cal = t < t[0] + cfg.calibration_s
    over["threshold"] = rest_threshold(frames[cal], name, fs, k=cfg.rest_k)
    reflex = registry.make(name, context=registry.MethodContext(speed=1.0), fs=fs, **over)
    det = detect(reflex, frames)
    return t, fs, over["threshold"], {"fs": fs, **over}, det.events, det.sensor, det.sensor_label


def run_trial(trial: RecordedTrial, cfg: BenchmarkConfig = BenchmarkConfig(),
              method_names: Sequence[str] | None = None) -> list[MethodRun]:
    """Run every applicable method (or ``method_names``) on one trial at every rate of ``cfg``.

    Raises
    ------
    DataError
        When the calibration span does not end before the trial's onset, or holds too few samples.

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> tr = read_folder(shipped_dataset())[0]
    >>> [r.key for r in run_trial(tr, BenchmarkConfig(methods=("dath",)))]
    ['dath@data', 'dath@method']
    """
    _check_calibration(trial, cfg)
    names = method_names or cfg.methods or registry.names()
    runs = []
    for name in names:
        if applicable(name, trial) is not None:
            continue
        spec = registry.get(name)
        for rate in cfg.rates:
            fn = _chain_run if spec.input_kind == "slip" else _tactile_run
            t, fs, thr, over, events, trace, trace_label = fn(name, trial, cfg, rate)
            slip = _label_on(trial, t)
            sc = score(t, slip, events, calibration_end=float(trial.t[0] + cfg.calibration_s))
            runs.append(MethodRun(trial.name, name, spec.label, rate, fs, thr, over, t,
                                  np.asarray(events, bool), np.asarray(trace, float), trace_label, sc))
    return runs


def _label_on(trial: RecordedTrial, t: np.ndarray) -> np.ndarray:
    """The label at times ``t``: that of the last recorded sample at or before each."""
    idx = np.searchsorted(trial.t, t + 1e-9, side="right") - 1
    return trial.slip[np.clip(idx, 0, len(trial.t) - 1)]


def _check_calibration(trial: RecordedTrial, cfg: BenchmarkConfig) -> None:
    end = trial.t[0] + cfg.calibration_s
    on = trial.onset_t
    if on is not None and end > on:
        raise DataError(f"{trial.path}: the calibration span (first {cfg.calibration_s:g} s) reaches past "
                        f"the labelled slip onset at {on:g} s; pass a shorter --calibration-s")
    n = int(np.count_nonzero(trial.t < end))
    if n < 8:
        raise DataError(f"{trial.path}: {n} samples in the first {cfg.calibration_s:g} s; a threshold needs "
                        "at least 8 (pass a longer --calibration-s)")
    if end >= trial.t[-1]:
        raise DataError(f"{trial.path}: the trial ({trial.duration:g} s) is no longer than the calibration "
                        f"span ({cfg.calibration_s:g} s)")


def plan(trials: Sequence[RecordedTrial], cfg: BenchmarkConfig = BenchmarkConfig()
         ) -> tuple[list[str], list[Skipped]]:
    """Check every trial against ``cfg`` before any work; the methods to run and those that do not apply.

    Raises
    ------
    DataError
        A calibration span that reaches past a trial's onset, or holds too few samples.
    ParameterError
        A method asked for by ``cfg.methods`` that applies to no trial.

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> names, skipped = plan(read_folder(shipped_dataset()))
    >>> "nmsd" in names, [s.method for s in skipped]
    (True, ['dath-board', 'fixed-board', 'nir'])
    """
    for tr in trials:
        _check_calibration(tr, cfg)
    names = cfg.methods or registry.names()
    reasons = {n: [applicable(n, tr) for tr in trials] for n in names}
    if "data" in cfg.rates:
        _check_data_rate([n for n, rs in reasons.items() if not all(rs)], trials)
    skipped = [Skipped(n, next(r for r in rs if r)) for n, rs in reasons.items() if rs and all(rs)]
    if cfg.methods is not None and skipped:
        s = skipped[0]
        raise ParameterError(f"--methods: {s.method} does not apply to this data: it {s.reason}")
    return [n for n in names if n not in {s.method for s in skipped}], skipped


def _check_data_rate(names: Sequence[str], trials: Sequence[RecordedTrial]) -> None:
    """Every chain method's parameters are valid at every trial's own rate (its low-pass below Nyquist)."""
    for name in names:
        spec = registry.get(name)
        if spec.input_kind != "slip":
            continue
        base = _trial_reflex(name)
        for tr in trials:
            try:
                dataclasses.replace(base.params, fs=tr.fs, **_scaled(base, spec.fs, tr.fs))
            except ParameterError as err:
                raise DataError(f"{tr.path}: {name} cannot run at the data's {tr.fs:.3g} Hz ({err}); "
                                "pass --rates method") from None


def run_benchmark(trials: Sequence[RecordedTrial], cfg: BenchmarkConfig = BenchmarkConfig()
                  ) -> tuple[list[MethodRun], list[Skipped]]:
    """Run the benchmark over a data set (all trials checked first, :func:`plan`).

    Returns
    -------
    (runs, skipped)
        Every method run, trial by trial in method order; the methods that applied to no
        trial, with the reason.

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> runs, skipped = run_benchmark(read_folder(shipped_dataset())[:1], BenchmarkConfig(methods=("fixed",)))
    >>> len(runs), skipped
    (2, [])
    """
    names, skipped = plan(trials, cfg)
    runs = []
    for tr in trials:
        runs.extend(run_trial(tr, cfg, names))
    return runs, skipped
