"""Refinement: a second stage of plants where a claim's class changes between neighbours.

Two-phase (double) sampling for stratification (Neyman 1938; Cochran, *Sampling
Techniques*, 3rd ed., 1977, section 12.2), over the unit cube the design maps onto the
uncertain constants:

1. **Pilot.** The study's ``--plants`` scrambled Sobol' plants run as always. Their
   results decide the strata and nothing else: a point of the cube is *boundary* when its
   :data:`NEIGHBOURS` nearest pilot plants do not all agree on whether a claim holds, for
   any claim; otherwise *interior*.
2. **First phase.** :func:`candidates` continues the same Sobol' sequence for many
   points (no simulation: only the rule is evaluated); the share of them in each stratum
   is the stratum's weight ``w_h``.
3. **Second phase.** ``--refine N`` plants are a simple random sample (without
   replacement, seeded) of the candidates of each stratum, ``n_h`` of them by Neyman's
   allocation (``n_h ~ w_h S_h``, ``S_h`` the largest pilot spread of a claim's indicator
   in the stratum, at least :data:`SPREAD_FLOOR`; at least 2 per stratum).
4. **Estimate.** Per claim, the fraction of the accepted plant space (not rejected, no
   error) where it holds is ``R = sum_h w_h k_h/n_h / sum_h w_h m_h/n_h`` (``k_h`` plants
   where it holds, ``m_h`` accepted, of the ``n_h`` second-phase plants), a ratio of two
   two-phase stratified means; its variance is Cochran's two-phase form (section 12.2)
   applied to the linearized ratio, and its interval is Wilson's score interval at the
   effective sample size ``R (1 - R) / v`` (the form Korn and Graubard 1998 use for
   proportions from complex samples).

The pilot's plants do not enter the estimate: the strata are drawn around them, so in a
stratum they are no random sample (where the indicator is noisy, the interior holds
exactly the pilot plants whose neighbours agreed with them, and their mean is biased
towards 0 or 1). Given the pilot, the second phase is an ordinary two-phase stratified
sample, so the estimate is unbiased for the candidates' stratum means and, the candidates
being scrambled Sobol' points (each uniform on the cube), for the cube's.

Examples
--------
>>> import numpy as np
>>> pilot = candidates(2, 16, 0, seed=1)[:16]
>>> holds = (pilot[:, :1] < 0.5)              # one claim: holds on half the cube
>>> plan = make_plan(pilot, holds, 32, seed=1, n_candidates=1024)
>>> len(plan.points), round(float(plan.weights.sum()), 6)
(32, 1.0)
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..core.errors import ParameterError

__all__ = ["NEIGHBOURS", "SPREAD_FLOOR", "MIN_CANDIDATES", "candidates", "boundary", "RefinePlan", "make_plan",
           "ratio_estimate"]

#: Nearest pilot plants a point's stratum is decided by (itself excluded: a point is not a pilot plant).
NEIGHBOURS: int = 4
#: Least spread the allocation assumes in a stratum: an interior that looks uniform on the pilot
#: still gets plants (the pilot may have missed an island of the other class).
SPREAD_FLOOR: float = 0.2
#: Fewest first-phase candidates; a study takes 16 per plant it runs, rounded up to a power of two.
MIN_CANDIDATES: int = 4096


def candidates(d: int, n: int, skip: int, seed: int) -> np.ndarray:
    """Points ``skip`` .. ``skip + n - 1`` of the study's scrambled Sobol' sequence, shape ``(n, d)``.

    With ``skip=0`` these are the plants of ``design="sobol"`` (the same generator and seed
    as :func:`slipreflex.study.design.unit_design`).

    Examples
    --------
    >>> from slipreflex.study.design import unit_design
    >>> bool((candidates(3, 8, 0, seed=4) == unit_design("sobol", 8, 3, seed=4)).all())
    True
    >>> bool((candidates(3, 4, 4, seed=4) == candidates(3, 8, 0, seed=4)[4:]).all())
    True
    """
    from scipy.stats import qmc  # deferred: heavy (scipy.stats)

    rng = np.random.default_rng(np.random.SeedSequence(seed))
    with warnings.catch_warnings():   # balance is lost unless n is a power of two: documented
        warnings.simplefilter("ignore", UserWarning)
        sob = qmc.Sobol(d, scramble=True, rng=rng)
        if skip:
            sob.fast_forward(skip)
        return sob.random(n)


def boundary(pilot: np.ndarray, holds: np.ndarray, points: np.ndarray, k: int = NEIGHBOURS) -> np.ndarray:
    """Whether each point's ``k`` nearest pilot plants disagree on some claim (True: boundary).

    Parameters
    ----------
    pilot : array, shape (n, d)
        The pilot plants' points in the unit cube.
    holds : array of bool, shape (n, c)
        Whether each claim holds on each pilot plant.
    points : array, shape (m, d)

    Examples
    --------
    >>> import numpy as np
    >>> pilot = np.array([[0.1], [0.2], [0.8], [0.9]])
    >>> boundary(pilot, np.array([[1], [1], [0], [0]], bool), np.array([[0.0], [0.5], [1.0]]), k=2)
    array([False,  True, False])
    """
    from scipy.spatial import KDTree  # deferred: heavy (scipy.spatial)

    k = min(int(k), len(pilot))
    _, idx = KDTree(pilot).query(points, k=k)
    idx = np.asarray(idx).reshape(len(points), k)
    h = np.asarray(holds, dtype=np.int8)[idx]            # (m, k, c)
    return np.asarray((h.max(axis=1) - h.min(axis=1)).max(axis=1) > 0)


@dataclass(frozen=True)
class RefinePlan:
    """The second phase: where its plants are, and the strata's weights.

    Attributes
    ----------
    points : numpy.ndarray
        The second-phase plants' points in the unit cube, shape ``(N, d)``, in plant order.
    strata : numpy.ndarray
        Each second-phase plant's stratum (0 interior, 1 boundary).
    weights : numpy.ndarray
        ``w_h``: the share of the first-phase candidates in each stratum.
    n_candidates : int
        First-phase candidates (``n'``).

    Examples
    --------
    >>> RefinePlan(np.zeros((2, 3)), np.array([0]), np.array([1.0, 0.0]), 64)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: RefinePlan: 2 points but 1 strata
    """

    points: np.ndarray
    strata: np.ndarray
    weights: np.ndarray
    n_candidates: int

    def __post_init__(self) -> None:
        if len(self.points) != len(self.strata):
            raise ParameterError(f"RefinePlan: {len(self.points)} points but {len(self.strata)} strata")


def _allocation(weights: np.ndarray, spread: np.ndarray, available: np.ndarray, n: int) -> np.ndarray:
    """Neyman's allocation of exactly ``n`` plants, at least 2 per stratum with candidates, within what is
    available (rounded to the nearest counts, the largest shortfall first).

    Examples
    --------
    >>> _allocation(np.array([0.99, 0.01]), np.array([0.5, 0.5]), np.array([990, 10]), 8).tolist()
    [6, 2]
    """
    live = available > 0
    if n < 2 * int(live.sum()):
        raise ParameterError(f"--refine {n}: too few for 2 plants in each of {int(live.sum())} strata")
    want = np.where(live, weights * np.maximum(spread, SPREAD_FLOOR), 0.0)
    share = want / want.sum() * n
    alloc = np.where(live, np.minimum(np.maximum(2, np.floor(share)), available), 0).astype(int)
    while alloc.sum() > n:
        over = np.where(alloc > 2, alloc - share, -np.inf)
        alloc[int(np.argmax(over))] -= 1
    while alloc.sum() < n:
        short = np.where(alloc < available, share - alloc, -np.inf)
        alloc[int(np.argmax(short))] += 1
    return alloc


def make_plan(pilot: np.ndarray, holds: np.ndarray, n: int, seed: int, *, skip: int | None = None,
              n_candidates: int | None = None, k: int = NEIGHBOURS) -> RefinePlan:
    """Strata from the pilot, weights from the candidates, and ``n`` second-phase plants.

    Parameters
    ----------
    pilot : array, shape (n1, d)
        The pilot plants' points (the study's first ``n1`` Sobol' points).
    holds : array of bool, shape (n1, c)
        Whether each claim holds (and the plant was accepted) on each pilot plant.
    n : int
        Second-phase plants.
    seed : int
        The study's seed: the Sobol' continuation and the sampling within strata.
    skip : int, optional
        Sobol' points before the candidates (default: the pilot's).
    n_candidates : int, optional
        First-phase candidates (default: 16 per plant of both stages, a power of two, at least
        :data:`MIN_CANDIDATES`).

    Returns
    -------
    RefinePlan

    Examples
    --------
    >>> import numpy as np
    >>> pilot = candidates(2, 8, 0, seed=0)
    >>> plan = make_plan(pilot, np.zeros((8, 1), bool), 4, seed=0, n_candidates=64)
    >>> plan.weights.tolist(), plan.strata.tolist()      # no boundary: every plant is interior
    ([1.0, 0.0], [0, 0, 0, 0])
    """
    pilot = np.asarray(pilot, dtype=float)
    holds = np.asarray(holds, dtype=bool).reshape(len(pilot), -1)
    n1, d = pilot.shape
    if n1 < 1:
        raise ParameterError("refinement needs at least one pilot plant")
    first = n1 if skip is None else int(skip)
    if n_candidates is None:
        n_candidates = max(MIN_CANDIDATES, 2 ** math.ceil(math.log2(16 * (n1 + n))))
    cand = candidates(d, n_candidates, first, seed)
    stratum = boundary(pilot, holds, cand, k).astype(int)
    weights = np.bincount(stratum, minlength=2) / len(cand)
    own = boundary(pilot, holds, pilot, k + 1).astype(int)   # a pilot plant's neighbours, itself included
    spread = np.zeros(2)
    for h in (0, 1):
        if (own == h).any():
            p = holds[own == h].mean(axis=0)
            spread[h] = float(np.sqrt(p * (1 - p)).max())
    available = np.bincount(stratum, minlength=2)
    if n > available.sum():
        raise ParameterError(f"--refine {n}: more than the {available.sum()} candidates")
    alloc = _allocation(weights, spread, available, n)
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 0x5EF1]))
    picked = [np.sort(rng.choice(np.flatnonzero(stratum == h), size=alloc[h], replace=False)) for h in (0, 1)]
    order = np.concatenate(picked)
    return RefinePlan(points=cand[order], strata=stratum[order], weights=weights, n_candidates=len(cand))


def ratio_estimate(holds: Sequence[bool], accepted: Sequence[bool], strata: Sequence[int], weights: Sequence[float],
                   n_candidates: int, confidence: float = 0.95) -> tuple[float, float, float, float]:
    """The fraction of the accepted plant space where a claim holds, its variance and interval.

    ``R = sum_h w_h kbar_h / sum_h w_h abar_h`` over the second-phase plants; the variance is
    Cochran's two-phase stratified form (1977, section 12.2; large first phase, sampling
    within a stratum without replacement from many candidates) for the linearized ratio
    ``z = (y - R a) / A``:
    ``v = sum_h w_h^2 s_zh^2 / n_h + sum_h w_h (zbar_h - zbar)^2 / n'``;
    the interval is Wilson's at the effective size ``R (1 - R) / v`` (``scipy.stats.norm``
    for the quantile). A stratum with one plant contributes no variance of its own.

    Returns
    -------
    (estimate, variance, low, high)
        NaN where no second-phase plant was accepted.

    Examples
    --------
    >>> r = ratio_estimate([1, 0, 0, 1], [1, 1, 1, 1], [0, 0, 1, 1], [0.5, 0.5], 1000)
    >>> round(r[0], 3), r[2] < 0.5 < r[3]
    (0.5, True)
    """
    from scipy.stats import norm  # deferred: heavy (scipy.stats)

    y = np.asarray(holds, dtype=float)
    a = np.asarray(accepted, dtype=float)
    s = np.asarray(strata, dtype=int)
    w = np.asarray(weights, dtype=float)
    live = [h for h in range(len(w)) if (s == h).any()]
    num = sum(w[h] * y[s == h].mean() for h in live)
    den = sum(w[h] * a[s == h].mean() for h in live)
    if den <= 0:
        return float("nan"), float("nan"), float("nan"), float("nan")
    r = num / den
    z = (y - r * a) / den
    zbar = {h: z[s == h].mean() for h in live}
    zst = sum(w[h] * zbar[h] for h in live)
    var = sum(w[h] ** 2 * z[s == h].var(ddof=1) / (s == h).sum() for h in live if (s == h).sum() > 1)
    var += sum(w[h] * (zbar[h] - zst) ** 2 for h in live) / n_candidates
    q = float(norm.ppf(0.5 + confidence / 2))
    n_eff = r * (1 - r) / var if var > 0 else float(a.sum())
    n_eff = max(n_eff, 1.0)
    centre = (r + q * q / (2 * n_eff)) / (1 + q * q / n_eff)
    half = q / (1 + q * q / n_eff) * math.sqrt(r * (1 - r) / n_eff + q * q / (4 * n_eff ** 2))
    return float(r), float(var), float(max(0.0, centre - half)), float(min(1.0, centre + half))
