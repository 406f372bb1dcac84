"""Operating points chosen on training trials and reported on held-out ones (docs/benchmark.md, "Protocol").

For each method (and rate) every trial is swept over one grid of thresholds in the data's
units (:mod:`slipreflex.benchmark.sweep`). The trials are split *by trial*, never by sample:
leave-one-trial-out (every trial held out once, the rest training it) or one declared split.

* **Onset-labelled sets.** On the training trials the threshold is the lowest of the grid
  at and above which the pooled false-alarm rate over their negative time is at most
  ``fa_per_min``; the held-out trials are scored at it. Pooled over the held-out trials:
  slips detected (Wilson interval), median latency, false alarms per minute (exact Poisson
  interval), time in alarm, and the chance line: what a Poisson alarm at that false-alarm
  rate would detect in the same detection windows, and its mean latency.
* **Trial-level sets.** The threshold maximises the training trials' accuracy (first alarm
  or none); the held-out accuracy with its Wilson interval, and the AUC of the sweep.
* **Curves.** Detection rate against false alarms per minute over the whole grid, pooled
  over trials (the learned baseline's out of fold); the area under it from 0 to
  ``fa_max_per_min`` divided by that span (1: every slip at no false alarm), with a
  percentile bootstrap over trials.

Examples
--------
>>> wilson(3, 3)[0] > 0.29, round(wilson(3, 3)[1], 6)
(True, 1.0)
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import ParameterError
from ..core.validation import integer, number
from .sweep import Sweep

__all__ = ["ProtocolConfig", "OperatingPoint", "folds", "choose_index", "operating_point", "curve", "area",
           "wilson", "poisson_rate_ci", "chance", "roc_auc", "ALARM_WARNING"]

#: Time in alarm (of the negative time) above which the table warns: the detector is in alarm
#: most of the time, so its detections say little.
ALARM_WARNING: float = 0.5


@dataclass(frozen=True)
class ProtocolConfig:
    """How operating points are chosen and scored.

    Parameters
    ----------
    fa_per_min : float
        Target false-alarm rate on the training trials (per minute of negative time).
    refractory_s : float
        Detections closer than this are one alarm episode (s).
    tolerance_s : float
        The label may lag or lead the sensor by this much (s): the detection window opens this
        long before the labelled onset and closes this long after the labelled slip ends.
    test : tuple of str or None
        Trial names held out as the test set; None: leave-one-trial-out.
    fa_max_per_min : float
        The curves' area spans false-alarm rates 0 to this.
    bootstrap, seed : int
        Bootstrap resamples of the trials for the area's interval, and their seed.
    confidence : float
        Level of every interval.

    Examples
    --------
    >>> ProtocolConfig(fa_per_min=-1)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: fa_per_min must be a finite number >= 0 and <= 1e+06, got -1
    """

    fa_per_min: float = 10.0
    refractory_s: float = 0.25
    tolerance_s: float = 0.1
    test: tuple[str, ...] | None = None
    fa_max_per_min: float = 60.0
    bootstrap: int = 1000
    seed: int = 1
    confidence: float = 0.95

    def __post_init__(self) -> None:
        number("fa_per_min", self.fa_per_min, lo=0.0, hi=1e6)
        number("refractory_s", self.refractory_s, lo=0.0, hi=600.0)
        number("tolerance_s", self.tolerance_s, lo=0.0, hi=600.0)
        number("fa_max_per_min", self.fa_max_per_min, lo=0.0, lo_open=True, hi=1e6)
        integer("bootstrap", self.bootstrap, lo=0, hi=100_000)
        integer("seed", self.seed, lo=0)
        number("confidence", self.confidence, lo=0.0, hi=1.0, lo_open=True, hi_open=True)
        if self.test is not None and not self.test:
            raise ParameterError("test: name at least one held-out trial")


@dataclass(frozen=True)
class OperatingPoint:
    """One method (and rate) at its operating point, scored on the held-out trials.

    ``kind`` is ``"onset"`` or ``"trial"``; the fields of the other kind are NaN.

    Examples
    --------
    >>> OperatingPoint("nmsd", "data", "onset", (1.0,)).thresholds
    (1.0,)
    """

    method: str
    rate: str
    kind: str
    thresholds: tuple[float, ...]
    slip_trials: int = 0
    detected: int = 0
    detected_ci: tuple[float, float] = (math.nan, math.nan)
    median_latency_ms: float = math.nan
    false_alarms: int = 0
    negative_min: float = 0.0
    fa_ci: tuple[float, float] = (math.nan, math.nan)
    alarm_fraction: float = math.nan
    chance_detected: float = math.nan
    chance_latency_ms: float = math.nan
    trials: int = 0
    negatives_alarmed: int = 0
    correct: int = 0
    accuracy_ci: tuple[float, float] = (math.nan, math.nan)
    area: float = math.nan
    area_ci: tuple[float, float] = (math.nan, math.nan)
    curve: tuple[np.ndarray, np.ndarray] = field(default=(np.zeros(0), np.zeros(0)), repr=False)

    @property
    def fa_per_min(self) -> float:
        """Held-out false alarms per minute of negative time (NaN without any)."""
        return self.false_alarms / self.negative_min if self.negative_min > 0 else math.nan

    @property
    def point(self) -> tuple[float, float]:
        """Where the operating point sits on the curve: (false alarms/min, detection rate) or (FPR, TPR)."""
        tpr = self.detected / self.slip_trials if self.slip_trials else math.nan
        if self.kind == "onset":
            return self.fa_per_min, tpr
        negatives = self.trials - self.slip_trials
        return (self.negatives_alarmed / negatives if negatives else math.nan), tpr


def wilson(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of ``k`` successes in ``n`` (NaN when ``n`` is 0).

    Examples
    --------
    >>> [round(v, 2) for v in wilson(3, 3)]
    [0.44, 1.0]
    """
    if n <= 0:
        return math.nan, math.nan
    from scipy.stats import binomtest  # deferred: heavy (scipy.stats)

    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=confidence, method="wilson")
    return float(ci.low), float(ci.high)


def poisson_rate_ci(k: int, minutes: float, confidence: float = 0.95) -> tuple[float, float]:
    """Exact (Garwood) interval of a rate per minute: ``k`` events in ``minutes``.

    Examples
    --------
    >>> [round(v, 2) for v in poisson_rate_ci(0, 1.0)]
    [0.0, 3.69]
    """
    if minutes <= 0:
        return math.nan, math.nan
    from scipy.stats import chi2  # deferred: heavy (scipy.stats)

    a = 1.0 - confidence
    lo = 0.0 if k == 0 else float(chi2.ppf(a / 2, 2 * k)) / 2
    return lo / minutes, float(chi2.ppf(1 - a / 2, 2 * k + 2)) / 2 / minutes


def chance(rate_per_s: float, windows_s: Sequence[float], tolerance_s: float) -> tuple[float, float]:
    """A Poisson alarm at ``rate_per_s``: expected slips detected in ``windows_s``, and its mean latency (ms).

    The latency is from the labelled onset, the window opening ``tolerance_s`` before it.

    Examples
    --------
    >>> d, lat = chance(1.0, [1.0, 1.0], 0.0)
    >>> round(d, 3), round(lat, 1)
    (1.264, 418.0)
    """
    w = np.asarray([x for x in windows_s if math.isfinite(x)], float)
    if not w.size or not rate_per_s > 0:
        return 0.0, math.nan
    p = -np.expm1(-rate_per_s * w)
    wait = 1.0 / rate_per_s - w * np.exp(-rate_per_s * w) / p          # E[first alarm | within the window]
    return float(p.sum()), float(1000.0 * (np.sum(p * wait) / p.sum() - tolerance_s))


def folds(names: Sequence[str], test: Sequence[str] | None) -> list[tuple[list[int], list[int]]]:
    """``(training, held-out)`` trial indices: leave-one-trial-out, or the declared test set.

    Raises
    ------
    ParameterError
        A test name that is no trial, or a split that leaves no training trial.

    Examples
    --------
    >>> folds(["a", "b", "c"], None)[0], folds(["a", "b", "c"], ["c"])
    (([1, 2], [0]), [([0, 1], [2])])
    """
    if test is None:
        if len(names) < 2:
            raise ParameterError("leave-one-trial-out needs at least two trials")
        return [([j for j in range(len(names)) if j != i], [i]) for i in range(len(names))]
    unknown = [n for n in test if n not in names]
    if unknown:
        raise ParameterError(f"--test-trials: {unknown[0]!r} is not a trial of the data set")
    held = [i for i, n in enumerate(names) if n in test]
    train = [i for i in range(len(names)) if i not in held]
    if not train:
        raise ParameterError("--test-trials: holds out every trial; none is left to choose thresholds on")
    return [(train, held)]


def _pooled(sweeps: Sequence[Sweep]) -> tuple[np.ndarray, np.ndarray]:
    """Pooled (false alarms per minute, detection rate) at every threshold."""
    neg = sum(s.negative_s for s in sweeps)
    fa = np.sum([s.false_alarms for s in sweeps], axis=0) if sweeps else np.zeros(0)
    slips = [s for s in sweeps if s.positive]
    det = np.mean([s.hit for s in slips], axis=0) if slips else np.full(len(fa), math.nan)
    return (60.0 * fa / neg if neg > 0 else np.full(len(fa), math.nan)), det


def choose_index(train: Sequence[Sweep], kind: str, fa_per_min: float) -> int:
    """The grid index of the operating threshold chosen on ``train``.

    Onset sets: the lowest threshold at and above which the pooled false-alarm rate stays at
    most ``fa_per_min`` (the top of the grid when the training trials hold no negative time).
    Trial-level sets: the highest threshold of best training accuracy.

    Examples
    --------
    >>> s = Sweep("c", False, np.arange(4.0), np.zeros(4, bool), np.full(4, np.nan), np.array([9, 1, 3, 0]),
    ...           60.0, np.zeros(4), np.nan)
    >>> choose_index([s], "onset", 2.0)
    3
    """
    if kind == "trial":
        acc = np.mean([s.hit == s.positive for s in train], axis=0)
        return int(len(acc) - 1 - np.argmax(acc[::-1]))
    rate, _ = _pooled(train)
    if not np.isfinite(rate).all():
        return len(rate) - 1
    bad = np.flatnonzero(rate > fa_per_min)
    return int(bad[-1] + 1) if bad.size else 0


def _step_area(fa: np.ndarray, det: np.ndarray, fa_max: float) -> float:
    """Mean over [0, fa_max] of the best detection rate at or below each false-alarm rate."""
    ok = np.isfinite(fa) & np.isfinite(det)
    fa, det = fa[ok], det[ok]
    xs = np.linspace(0.0, fa_max, 601)
    order = np.argsort(fa, kind="stable")
    best = np.r_[0.0, np.maximum.accumulate(det[order])] if fa.size else np.zeros(1)
    return float(best[np.searchsorted(fa[order], xs, side="right")].mean())


def roc_auc(sweeps: Sequence[Sweep]) -> float:
    """Area under the ROC of "the trial alarmed" over the threshold sweep (trial-level sets).

    Examples
    --------
    >>> p = Sweep("p", True, np.arange(2.0), np.array([True, True]), np.full(2, np.nan), np.zeros(2, int),
    ...           0.0, np.zeros(2), np.nan)
    >>> n = Sweep("n", False, np.arange(2.0), np.array([True, False]), np.full(2, np.nan), np.zeros(2, int),
    ...           1.0, np.zeros(2), np.nan)
    >>> roc_auc([p, n])
    1.0
    """
    pos = [s.hit for s in sweeps if s.positive]
    neg = [s.hit for s in sweeps if not s.positive]
    if not pos or not neg:
        return math.nan
    tpr, fpr = np.mean(pos, axis=0), np.mean(neg, axis=0)
    order = np.lexsort((tpr, fpr))
    x = np.r_[0.0, fpr[order], 1.0]
    y = np.r_[0.0, np.maximum.accumulate(tpr[order]), 1.0]
    return float(np.sum(np.diff(x) * (y[1:] + y[:-1]) / 2))


def curve(sweeps: Sequence[Sweep], kind: str) -> tuple[np.ndarray, np.ndarray]:
    """The sweep pooled over trials: (false alarms/min, detection rate), or (FPR, TPR) for trial-level sets.

    Examples
    --------
    >>> curve([], "onset")[0].size
    0
    """
    if kind == "onset":
        return _pooled(sweeps)
    pos = [s.hit for s in sweeps if s.positive]
    neg = [s.hit for s in sweeps if not s.positive]
    n = len(sweeps[0].hit) if sweeps else 0
    nan = np.full(n, math.nan)
    return (np.mean(neg, axis=0) if neg else nan), (np.mean(pos, axis=0) if pos else nan)


def area(sweeps: Sequence[Sweep], kind: str, cfg: ProtocolConfig) -> tuple[float, tuple[float, float]]:
    """The curve's area (detection-vs-false-alarm up to ``fa_max_per_min``, or the ROC's) and its
    percentile bootstrap interval over trials.

    Examples
    --------
    >>> area([], "onset", ProtocolConfig(bootstrap=10))[0]
    0.0
    """
    def one(ss: Sequence[Sweep]) -> float:
        if kind == "trial":
            return roc_auc(ss)
        fa, det = _pooled(ss)
        return _step_area(fa, det, cfg.fa_max_per_min) if ss else 0.0

    est = one(sweeps)
    rng = np.random.default_rng(cfg.seed)
    boot = []
    for _ in range(cfg.bootstrap if sweeps else 0):
        pick = [sweeps[i] for i in rng.integers(0, len(sweeps), len(sweeps))]
        if any(s.positive for s in pick) and (kind == "trial" or sum(s.negative_s for s in pick) > 0):
            v = one(pick)
            if math.isfinite(v):
                boot.append(v)
    a = (1.0 - cfg.confidence) / 2
    ci = (float(np.quantile(boot, a)), float(np.quantile(boot, 1 - a))) if boot else (math.nan, math.nan)
    return est, ci


def operating_point(method: str, rate: str, kind: str, fold_sweeps: Sequence[Sequence[Sweep]],
                    held_out: Sequence[Sweep], splits: Sequence[tuple[list[int], list[int]]],
                    cfg: ProtocolConfig, fixed: int | None = None) -> OperatingPoint:
    """Choose on each fold's training trials, score its held-out ones, pool, and attach the curve.

    Parameters
    ----------
    kind : str
        ``"onset"`` (labelled onsets) or ``"trial"`` (trial-level labels).
    fold_sweeps : sequence of sequences of Sweep
        Per fold, every trial's sweep as that fold sees it (the learned baseline's differ).
    held_out : sequence of Sweep
        Every trial's sweep as the fold that held it out sees it (drawn as the curve).
    splits : from :func:`folds`
    fixed : int, optional
        A grid index to use in every fold instead of choosing (a given threshold).

    Examples
    --------
    >>> s = [Sweep(n, n == "p", np.arange(2.0), np.array([n == "p", False]), np.array([50.0, np.nan]),
    ...            np.array([1, 0]), 30.0, np.zeros(2), 0.5) for n in ("p", "c")]
    >>> op = operating_point("m", "data", "onset", [s, s], s, folds(["p", "c"], None), ProtocolConfig(bootstrap=0))
    >>> op.detected, op.false_alarms, op.thresholds
    (1, 2, (0.0, 0.0))
    """
    chosen, test = [], []
    for (train, held), sw in zip(splits, fold_sweeps):
        g = fixed if fixed is not None else choose_index([sw[i] for i in train], kind, cfg.fa_per_min)
        chosen.append(float(sw[train[0]].thresholds[g]))
        test.extend((sw[i], g) for i in held)
    slips = [(s, g) for s, g in test if s.positive]
    detected = sum(bool(s.hit[g]) for s, g in slips)
    lat = [s.latency_ms[g] for s, g in slips if s.hit[g] and math.isfinite(s.latency_ms[g])]
    fa = int(sum(int(s.false_alarms[g]) for s, g in test))
    neg_s = sum(s.negative_s for s, _ in test)
    alarm = sum(float(s.alarm_s[g]) for s, _ in test)
    minutes = neg_s / 60.0
    a, ci = area(held_out, kind, cfg)
    base = OperatingPoint(method, rate, kind, tuple(chosen), slip_trials=len(slips), detected=detected,
                          detected_ci=wilson(detected, len(slips), cfg.confidence), false_alarms=fa,
                          negative_min=minutes, fa_ci=poisson_rate_ci(fa, minutes, cfg.confidence),
                          trials=len(test), area=a, area_ci=ci, curve=curve(held_out, kind))
    if kind == "trial":
        correct = sum(bool(s.hit[g]) == s.positive for s, g in test)
        return dataclasses.replace(base, negatives_alarmed=sum(bool(s.hit[g]) for s, g in test if not s.positive),
                                   correct=correct, accuracy_ci=wilson(correct, len(test), cfg.confidence))
    rate_s = fa / neg_s if neg_s > 0 else math.nan
    ch_det, ch_lat = chance(rate_s, [s.window_s for s, _ in slips], cfg.tolerance_s)
    return dataclasses.replace(base, median_latency_ms=float(np.median(lat)) if lat else math.nan,
                               alarm_fraction=alarm / neg_s if neg_s > 0 else math.nan,
                               chance_detected=ch_det, chance_latency_ms=ch_lat)

