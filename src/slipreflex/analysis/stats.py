"""The statistics the claims are judged with: clustered, censoring-aware, with a sequential boundary.

* **Trials and clusters.** Every slip is a trial (the paper analysed "all slips ...
  individually, as if they belonged to a separate trial"), but a pour's slips share
  one pour: a :class:`Sample` keeps each cluster's (one pour's, one drop's) values
  together, and :func:`cluster_interval` resamples whole clusters (the cluster
  bootstrap: Davison and Hinkley 1997, section 3.8; Field and Welsh 2007). Where two
  methods faced the same trial seeds the clusters are resampled jointly (paired).
* **Censoring.** A slip a method never answered within the cutoff is a censored
  trial, kept as ``+inf`` ("non-response ranks slowest"), never dropped. A mean is
  undefined with one such trial, so a comparison then uses the probabilistic index
  ``P(X < Y) + P(X = Y) / 2`` (the Mann-Whitney statistic divided by ``n m``;
  ``scipy.stats.mannwhitneyu`` gives its p-value) and a cell's typical value is its
  Kaplan-Meier median (``scipy.stats.ecdf`` of ``scipy.stats.CensoredData``).
* **Intervals.** :func:`cluster_interval` is the bootstrap normal interval with
  Student's t quantile on ``C - 1`` degrees of freedom (``C`` clusters): the estimate
  plus or minus ``t * se``, ``se`` the bootstrap standard deviation inflated by
  ``sqrt(C / (C - 1))`` (Davison and Hinkley 1997, section 5.2). It keeps its level
  at the small cluster counts a reproduction has, where percentile intervals are
  too narrow.
* **Replication.** A claim one run leaves unresolved is looked at again with more
  replicates, at most a number of looks fixed in advance; every look uses one
  constant nominal level, as in Pocock's boundary (Pocock 1977; Jennison and
  Turnbull 2000, chapter 2), so that over all the looks a decisive class (holds or
  fails) comes, when the truth sits on the criterion, with probability at most
  :data:`ALPHA`. Pocock's exact constant (:func:`pocock_z`) assumes normal statistics
  with equal increments; the claims' statistics (clustered ratios, rank indices,
  bootstrap intervals) are only near that, so the level used is the Bonferroni bound
  ``ALPHA / looks`` per look (:func:`look_level`), a constant boundary slightly wider
  than Pocock's that keeps the overall level for any joint distribution of the looks.
* **Rates.** Wilson's interval for one rate (``scipy.stats.binomtest``) and
  Newcombe's hybrid score interval for a difference of two (Newcombe 1998, method 10).

Examples
--------
>>> s = Sample.of({"a": [40.0], "b": [42.0], "c": [math.inf]})
>>> s.n, s.responders
(3, 2)
>>> round(km_median(s), 1)
42.0
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["ALPHA", "RESAMPLES", "Sample", "cluster_interval", "km_median", "rank_p", "pocock_z", "pocock_level",
           "newcombe_interval", "wilson_interval", "look_level", "MEAN_DIFF", "RATIO", "INDEX", "FRACTION", "MEAN",
           "sequential"]

#: Overall probability of a decisive class when the truth sits on the criterion (2.5 % each side).
ALPHA: float = 0.05
#: Bootstrap resamples of every interval.
RESAMPLES: int = 2999

MEAN = "mean"
MEAN_DIFF = "mean difference"
RATIO = "ratio of means"
INDEX = "probabilistic index"
FRACTION = "fraction below"


@dataclass(frozen=True)
class Sample:
    """Values grouped by cluster; ``+inf`` is a censored trial (no response within the cutoff).

    Examples
    --------
    >>> s = Sample.of({"p1": [50.0, 80.0], "p2": [math.inf]})
    >>> s.keys, s.n, s.censored
    (('p1', 'p2'), 3, 1)
    """

    keys: tuple
    values: tuple

    @classmethod
    def of(cls, clusters: Mapping) -> Sample:
        """A sample from ``{cluster key: [values]}`` (NaN values are left out, empty clusters too).

        Examples
        --------
        >>> Sample.of({"a": [float("nan")], "b": [1.0]}).keys
        ('b',)
        """
        items = [(k, tuple(float(v) for v in vs if v == v)) for k, vs in clusters.items()]
        items = [(k, vs) for k, vs in items if vs]
        return cls(tuple(k for k, _ in items), tuple(vs for _, vs in items))

    @property
    def n(self) -> int:
        """Trials."""
        return sum(len(v) for v in self.values)

    @property
    def censored(self) -> int:
        """Trials without a response."""
        return sum(math.isinf(x) for v in self.values for x in v)

    @property
    def responders(self) -> int:
        """Trials with a response."""
        return self.n - self.censored

    def flat(self) -> np.ndarray:
        """Every value, cluster after cluster."""
        return np.asarray([x for v in self.values for x in v], dtype=float)

    def answered(self) -> Sample:
        """The trials with a response only (a total exists only where the controller acted).

        Examples
        --------
        >>> Sample.of({"a": [1.0, math.inf], "b": [math.inf]}).answered().n
        1
        """
        return Sample.of({k: [x for x in v if math.isfinite(x)] for k, v in zip(self.keys, self.values)})

    def mean(self) -> float:
        """Mean over the trials (``inf`` when one is censored)."""
        return float(self.flat().mean()) if self.n else math.nan


def _weights(n_clusters: int, rng: np.random.Generator, resamples: int) -> np.ndarray:
    """Bootstrap counts: row b says how often each cluster was drawn in resample b."""
    idx = rng.integers(0, n_clusters, size=(resamples, n_clusters))
    flat = (np.arange(resamples)[:, None] * n_clusters + idx).ravel()
    return np.bincount(flat, minlength=resamples * n_clusters).reshape(resamples, n_clusters).astype(float)


def _sums(s: Sample, keys: Sequence) -> tuple[np.ndarray, np.ndarray]:
    pos = {k: i for i, k in enumerate(s.keys)}
    tot = np.array([sum(s.values[pos[k]]) if k in pos else 0.0 for k in keys])
    cnt = np.array([len(s.values[pos[k]]) if k in pos else 0.0 for k in keys])
    return tot, cnt


def _kernel(a: Sample, b: Sample, keys_a: Sequence, keys_b: Sequence, factor: float) -> np.ndarray:
    """K[i, j]: over the trial pairs of cluster i of ``a`` and j of ``b``, [factor x < y] + [factor x = y] / 2."""
    pa, pb = {k: i for i, k in enumerate(a.keys)}, {k: i for i, k in enumerate(b.keys)}
    out = np.zeros((len(keys_a), len(keys_b)))
    for i, ka in enumerate(keys_a):
        if ka not in pa:
            continue
        x = factor * np.asarray(a.values[pa[ka]])[:, None]
        for j, kb in enumerate(keys_b):
            if kb in pb:
                y = np.asarray(b.values[pb[kb]])[None, :]
                out[i, j] = float(np.sum(x < y) + 0.5 * np.sum(x == y))
    return out


def _statistic(kind: str, samples: Sequence[Sample], keys: Sequence[Sequence], w: Sequence[np.ndarray],
               factor: float, below: float) -> np.ndarray:
    """The statistic on every resample (rows of ``w``; one weight matrix per sample)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        if kind == MEAN:
            t, c = _sums(samples[0], keys[0])
            return (w[0] @ t) / (w[0] @ c)
        if kind == FRACTION:
            s = samples[0]
            pos = {k: i for i, k in enumerate(s.keys)}
            hit = np.array([sum(x < below for x in s.values[pos[k]]) for k in keys[0]], dtype=float)
            _, c = _sums(s, keys[0])
            return (w[0] @ hit) / (w[0] @ c)
        (ta, ca), (tb, cb) = _sums(samples[0], keys[0]), _sums(samples[1], keys[1])
        ma, mb = (w[0] @ ta) / (w[0] @ ca), (w[1] @ tb) / (w[1] @ cb)
        if kind == MEAN_DIFF:
            return ma - mb
        if kind == RATIO:
            return mb / ma
        k = _kernel(samples[0], samples[1], keys[0], keys[1], factor)
        return np.einsum("bi,ij,bj->b", w[0], k, w[1]) / ((w[0] @ ca) * (w[1] @ cb))


def _point(kind: str, samples: Sequence[Sample], factor: float, below: float) -> float:
    keys = [s.keys for s in samples]
    w = [np.ones((1, len(s.keys))) for s in samples]
    return float(_statistic(kind, samples, keys, w, factor, below)[0])


def cluster_interval(kind: str, samples: Sequence[Sample], *, paired: bool = False, level: float = 1 - ALPHA,
                     factor: float = 1.0, below: float = math.nan, seed: int = 0,
                     resamples: int = RESAMPLES) -> tuple[float, float, float]:
    """(estimate, low, high) of a statistic of one or two clustered samples.

    Parameters
    ----------
    kind : str
        :data:`MEAN` (one sample), :data:`FRACTION` (one sample: share of trials below
        ``below``, censored ones never), :data:`MEAN_DIFF` (a minus b), :data:`RATIO`
        (mean of b over mean of a) or :data:`INDEX` (``P(factor a < b) + P(=) / 2``,
        censoring-aware).
    samples : sequence of Sample
    paired : bool
        Resample the clusters of both samples jointly (the same trial seeds).
    level : float
        Two-sided confidence level.

    Returns
    -------
    tuple of float
        NaN interval with fewer than two clusters; the point when nothing varies.

    Examples
    --------
    >>> a = Sample.of({i: [40.0 + i % 3] for i in range(12)})
    >>> b = Sample.of({i: [50.0 + i % 4] for i in range(12)})
    >>> d, lo, hi = cluster_interval(MEAN_DIFF, [a, b], paired=True)
    >>> round(d, 2), hi < 0
    (-10.5, True)
    >>> p, lo, hi = cluster_interval(INDEX, [a, b])
    >>> p, lo <= p <= hi
    (1.0, True)
    """
    from scipy.stats import t as student  # deferred: heavy (scipy.stats)

    est = _point(kind, samples, factor, below)
    if paired:
        union = tuple(dict.fromkeys(k for s in samples for k in s.keys))
        keys: list[Sequence] = [union] * len(samples)
    else:
        keys = [s.keys for s in samples]
    n_clusters = min(len(k) for k in keys)
    if n_clusters < 2 or not math.isfinite(est) and kind != INDEX:
        return est, math.nan, math.nan
    rng = np.random.default_rng(seed)
    if paired:
        w0 = _weights(len(keys[0]), rng, resamples)
        w = [w0] * len(samples)
    else:
        w = [_weights(len(k), rng, resamples) for k in keys]
    boot = _statistic(kind, samples, keys, w, factor, below)
    boot = boot[np.isfinite(boot)]
    if boot.size < 2 or np.ptp(boot) == 0:
        return est, est, est
    se = float(np.std(boot, ddof=1)) * math.sqrt(n_clusters / (n_clusters - 1))
    q = float(student.ppf(0.5 + level / 2, df=n_clusters - 1))
    return est, est - q * se, est + q * se


def km_median(s: Sample, cutoff: float = math.inf) -> float:
    """Kaplan-Meier median of a sample whose censored trials are ``+inf`` (censored at ``cutoff``).

    ``scipy.stats.ecdf`` of ``scipy.stats.CensoredData``; ``inf`` when fewer than half responded.

    Examples
    --------
    >>> km_median(Sample.of({1: [10.0], 2: [math.inf], 3: [math.inf], 4: [math.inf]}), cutoff=1000.0)
    inf
    >>> km_median(Sample.of({1: [10.0], 2: [20.0], 3: [30.0], 4: [math.inf]}), cutoff=1000.0)
    20.0
    """
    from scipy.stats import CensoredData, ecdf  # deferred: heavy (scipy.stats)

    x = s.flat()
    if not x.size:
        return math.nan
    done = x[np.isfinite(x)]
    if not done.size:
        return math.inf
    right = np.full(int(np.isinf(x).sum()), cutoff if math.isfinite(cutoff) else float(done.max()) + 1.0)
    res = ecdf(CensoredData(uncensored=done, right=right))
    sf = res.sf
    below = np.flatnonzero(sf.probabilities <= 0.5)
    return float(sf.quantiles[below[0]]) if below.size else math.inf


def rank_p(a: Sample, b: Sample, factor: float = 1.0) -> float:
    """One-sided p of ``factor a`` tending to lie below ``b`` (Mann-Whitney U, non-response slowest).

    ``scipy.stats.mannwhitneyu(..., alternative="less")``; it treats trials as independent,
    so it is printed beside the clustered interval, never used alone.

    Examples
    --------
    >>> rank_p(Sample.of({i: [i] for i in range(8)}), Sample.of({i: [10 + i] for i in range(8)})) < 0.01
    True
    """
    from scipy.stats import mannwhitneyu  # deferred: heavy (scipy.stats)

    x, y = factor * a.flat(), b.flat()
    if not x.size or not y.size:
        return math.nan
    big = max(1.0, float(np.max(np.abs(np.r_[x, y][np.isfinite(np.r_[x, y])]), initial=1.0))) * 10.0
    return float(mannwhitneyu(np.where(np.isinf(x), big, x), np.where(np.isinf(y), big, y),
                              alternative="less").pvalue)


@functools.lru_cache(maxsize=16)
def pocock_z(looks: int, alpha: float = ALPHA) -> float:
    """Pocock's constant two-sided critical value for ``looks`` equally spaced looks.

    The value ``c`` with ``P(max_k |Z_k| > c) = alpha`` for the partial sums of
    equal increments (``corr(Z_i, Z_j) = sqrt(i / j)``), from scipy's multivariate
    normal distribution.

    Examples
    --------
    >>> round(pocock_z(1), 3), round(pocock_z(3), 2)
    (1.96, 2.29)
    """
    from scipy.optimize import brentq  # deferred: heavy (scipy.optimize)
    from scipy.stats import multivariate_normal, norm  # deferred: heavy (scipy.stats)

    if looks < 1:
        raise ValueError(f"looks: {looks} (at least 1)")
    if looks == 1:
        return float(norm.ppf(1 - alpha / 2))
    i = np.arange(1, looks + 1)
    cov = np.sqrt(np.minimum.outer(i, i) / np.maximum.outer(i, i))
    mvn: Any = multivariate_normal(mean=np.zeros(looks), cov=cov, seed=0)   # type: ignore[arg-type]

    def excess(c: float) -> float:
        inside = float(mvn.cdf(np.full(looks, c), lower_limit=np.full(looks, -c)))
        return (1.0 - inside) - alpha

    root: Any = brentq(excess, 1.5, 4.0, xtol=1e-4)
    return float(root)


def pocock_level(looks: int, alpha: float = ALPHA) -> float:
    """The two-sided confidence level every look uses so ``looks`` looks keep ``alpha`` overall.

    Examples
    --------
    >>> round(pocock_level(1), 3), round(pocock_level(3), 4)
    (0.95, 0.9779)
    """
    from scipy.stats import norm  # deferred: heavy (scipy.stats)

    return float(1.0 - 2.0 * norm.sf(pocock_z(looks, alpha)))


def look_level(looks: int, alpha: float = ALPHA) -> float:
    """Two-sided level of every look of a design with ``looks`` looks: the Bonferroni bound.

    ``1 - alpha / looks``; never below Pocock's (:func:`pocock_level`), which it bounds
    for any joint distribution of the looks' statistics.

    Examples
    --------
    >>> round(look_level(3), 4), look_level(3) > pocock_level(3)
    (0.9833, True)
    """
    if looks < 1:
        raise ValueError(f"looks: {looks} (at least 1)")
    return 1.0 - alpha / looks


def wilson_interval(k: int, n: int, level: float = 1 - ALPHA) -> tuple[float, float, float]:
    """(k / n, low, high): Wilson's score interval (``scipy.stats.binomtest``); NaN for ``n == 0``.

    Examples
    --------
    >>> [round(v, 4) for v in wilson_interval(8, 10)]
    [0.8, 0.4902, 0.9433]
    """
    if n == 0:
        return math.nan, math.nan, math.nan
    from scipy.stats import binomtest  # deferred: heavy (scipy.stats)

    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=level, method="wilson")
    return k / n, float(ci.low), float(ci.high)


def newcombe_interval(k1: int, n1: int, k2: int, n2: int, level: float = 1 - ALPHA
                      ) -> tuple[float, float, float]:
    """(p1 - p2, low, high): Newcombe's hybrid score interval of a difference of two rates.

    Examples
    --------
    >>> d, lo, hi = newcombe_interval(20, 20, 20, 20)
    >>> d, lo < 0 < hi
    (0.0, True)
    """
    p1, l1, u1 = wilson_interval(k1, n1, level)
    p2, l2, u2 = wilson_interval(k2, n2, level)
    d = p1 - p2
    return d, d - math.sqrt((p1 - l1) ** 2 + (u2 - p2) ** 2), d + math.sqrt((u1 - p1) ** 2 + (p2 - l2) ** 2)


def sequential(looks: Iterable[tuple[float, float]], criterion: float) -> tuple[str, int]:
    """The class a group-sequential rule reaches: the first look whose interval excludes ``criterion``.

    ``looks`` yields each look's (low, high), computed at :func:`pocock_level`; returns
    ("above" | "below" | "straddles", looks used).

    Examples
    --------
    >>> sequential([(-1.0, 2.0), (0.5, 1.5)], 0.0)
    ('above', 2)
    """
    k = 0
    for k, (lo, hi) in enumerate(looks, start=1):
        if lo > criterion:
            return "above", k
        if hi < criterion:
            return "below", k
    return "straddles", k
