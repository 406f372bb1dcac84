"""The paper's claims in its own words, judged part by part from a run's results, each verdict with its reason.

Each of the paper's eleven claims (``docs/method.md``, "The paper's claims") is a
:class:`Claim`: the paper's sentence (:attr:`Claim.quote`, its short form
:attr:`Claim.text` for tables), where it is (:attr:`Claim.where`), the reading
judged, and a judge function over a :class:`ClaimInput` (the per-slip result rows
of a run, the characterization scan, the plant, a measured scan if one is given).
The judge returns the claim's **parts**; :func:`judge` returns one
:class:`ClaimResult` per claim, its class derived from its parts.

Classes (:data:`VERDICTS`): ``holds``; ``fails-definition`` (the method's
equations or the paired design make it impossible); ``fails-paper`` (the paper's
own table violates it as stated); ``fails-plant`` (the interval lies on the wrong
side of the criterion on this plant); ``depends-plant`` (a study: it holds on
some plausible plants and fails on others); ``unresolved`` (the interval
straddles the criterion); ``not-decidable`` (the run lacks what decides it, or
the quantity is an input the simulator was calibrated to: the part's
``qualifier`` says "calibrated input").

**The class of a claim from its parts.** Every part is judged and reported with
its own class (``claim_parts.csv``). A part is *primary* when it belongs to the
reading the paper's own summary gives (abstract, conclusion); the others are
alternative readings, reported beside it. A claim's class is the conjunction of
its primary parts: the first class, in the order of :data:`VERDICTS`, among
them (a definition beats the paper's numbers, which beat the plant; noise beats
a missing cell; "holds" needs every primary part). A secondary part never sets
the claim's class, and every part that holds is printed as holding.

**Statistics** (:mod:`slipreflex.analysis.stats`): every slip is a trial,
clustered by its trial (a pour's slips share a pour); intervals are cluster
bootstraps, paired where two methods faced the same trial seeds; a slip a
method never answered within the cutoff is a censored trial, and a comparison
with one uses the censoring-aware probabilistic index (non-response ranks
slowest) instead of a mean. A comparison is one-sided where the paper is ("less
than", "more than twice"): it holds when the whole interval lies on the claimed
side of the criterion, fails when it lies wholly on the other, and is unresolved
otherwise. The level of every interval is set by the replication design, one constant
boundary over its looks (:func:`looks_level`): with the truth on the criterion a decisive class comes
with probability at most 5 % over every look the replication may take.

Examples
--------
>>> rows = [{"experiment": "drop", "bottle": b, "method": m, "trial": k, "seed": k, "event": 0,
...          "n_events": 1, "response_ms": r + k, "total_ms": 100.0, "success": True}
...         for b in ("TR", "DK", "TX") for k in range(6) for m, r in (("dath", 40.0), ("fixed", 50.0))]
>>> res = {c.number: c for c in judge(rows)}
>>> res[3].verdict, [p.label for p in res[3].parts][:2]
('holds', ['TR', 'DK'])
>>> res[1].verdict, res[1].qualifier
('not-decidable', 'calibrated input')
"""

from __future__ import annotations

import csv
import functools
import math
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .. import hardware as hw
from ..csvfiles import cell_bool, cell_float
from ..methods import DATH, FIXED, NMSD, SWT
from ..methods import label as _label
from ..methods import names as method_names
from .paper import BOTTLE_ORDER, EXPERIMENTS, PAPER
from .stats import (
    FRACTION,
    INDEX,
    MEAN,
    MEAN_DIFF,
    RATIO,
    Sample,
    cluster_interval,
    km_median,
    look_level,
    newcombe_interval,
    rank_p,
    wilson_interval,
)

__all__ = [
    "HOLDS", "FAILS_DEFINITION", "FAILS_PAPER", "FAILS_PLANT", "DEPENDS_PLANT", "UNRESOLVED", "NOT_DECIDABLE",
    "VERDICTS", "FAILING", "DECISIVE", "CALIBRATED_INPUT", "CONFIDENCE", "CENTRAL", "BOOTSTRAP_SEED", "VOLT_TOL",
    "TIME_TOL_MS", "LENGTH_TOL_MM", "NEAR_ML", "MOST", "UNDER_MS", "TOLERANCES", "stated_tolerance", "Reading",
    "Part", "Claim", "ClaimInput", "ClaimResult", "CLAIMS", "CLAIMS_CSV_COLUMNS", "PARTS_CSV_COLUMNS", "judge",
    "judge_run", "scan_ensemble_for", "measured_scan", "write_claims_csv", "write_parts_csv", "read_claims_csv",
    "claims_section", "claims_markdown", "parts_markdown", "claims_terminal", "explain", "mean_interval",
    "difference_interval",
    "ratio_interval", "proportion_interval", "median_interval", "DropBounds", "drop_bounds", "Contradiction",
    "contradictions", "contradictions_markdown", "window_phase_sd_ms", "drop_slipout_capacity_n",
    "drop_momentum_capacity_n", "first_slip_capacity_n", "STATIC_OVER_KINETIC_MAX", "REPLICATES_MAX", "LOOKS",
    "looks_level", "plant_reading", "tilt_and_taper", "replicate_seed", "undecided_methods", "about_rate_band",
]

HOLDS = "holds"
FAILS_DEFINITION = "fails-definition"
FAILS_PAPER = "fails-paper"
FAILS_PLANT = "fails-plant"
DEPENDS_PLANT = "depends-plant"
UNRESOLVED = "unresolved"
NOT_DECIDABLE = "not-decidable"
#: The classes, in the order a claim's primary parts decide it (and tables list them).
VERDICTS: tuple[str, ...] = (FAILS_DEFINITION, FAILS_PAPER, FAILS_PLANT, DEPENDS_PLANT, UNRESOLVED, NOT_DECIDABLE,
                             HOLDS)
#: The classes that say a claim fails.
FAILING: tuple[str, ...] = (FAILS_DEFINITION, FAILS_PAPER, FAILS_PLANT)
#: The classes a comparison reaches when its interval clears the criterion.
DECISIVE: tuple[str, ...] = (HOLDS, FAILS_PLANT)
#: The qualifier of a quantity the simulator was calibrated to.
CALIBRATED_INPUT = "calibrated input"

#: Confidence level of one look's interval (a run judged alone); see :func:`looks_level`.
CONFIDENCE: float = 0.95
#: The scan claims: the model's spread is reported as this central fraction of its ensemble.
CENTRAL: float = 0.90
#: Seed of every bootstrap (the same rows give the same interval).
BOOTSTRAP_SEED: int = 0
_RESAMPLES = 4999

#: Response-time tolerance (ms): one DAQ sample, the resolution responses are measured with.
TIME_TOL_MS: float = 1e3 / hw.DAQ_FS
#: "about" a length (mm): one scan sample's travel at 1 mm/s, or half the paper's last digit if larger.
LENGTH_TOL_MM: float = max(1.0 / hw.DAQ_FS, 0.005)
#: "near 200 and 400 ml": the median volume at each slip within this many ml.
NEAR_ML: float = 50.0
#: "most": more than this fraction.
MOST: float = 0.5
#: Replicate grids the design allows after the run (fixed before looking: the per-look level is set by it).
REPLICATES_MAX: int = 2
#: Looks of the replication design: the run, then each replicate grid.
LOOKS: int = 1 + REPLICATES_MAX
#: The 85 ms of claim 8.
UNDER_MS: float = 85.0
#: Trials per bottle behind the paper's drop success rates (10 trials per bottle, three bottles).
PAPER_DROP_TRIALS: int = 30


def looks_level(looks: int = LOOKS) -> float:
    """Two-sided confidence level of every look of a design with ``looks`` looks (a constant boundary).

    See :func:`slipreflex.analysis.stats.look_level`: the Bonferroni bound, a shade wider
    than Pocock's constant, so the overall level holds for the claims' non-normal statistics.

    Examples
    --------
    >>> round(looks_level(1), 3), round(looks_level(LOOKS), 4)
    (0.95, 0.9833)
    """
    return look_level(int(looks), 1.0 - CONFIDENCE)


def about_rate_band(rate: float = 0.8, trials: int = PAPER_DROP_TRIALS) -> tuple[float, float]:
    """"About" a rate the paper measured on ``trials`` trials: Wilson's 95 % interval of it.

    Examples
    --------
    >>> [round(x, 3) for x in about_rate_band()]
    [0.627, 0.905]
    """
    _, lo, hi = wilson_interval(round(rate * trials), trials)
    return lo, hi


def stated_tolerance(text: str) -> float:
    """Half a unit of the last digit of a number as the paper writes it.

    Examples
    --------
    >>> stated_tolerance("3.35"), stated_tolerance("0.3"), stated_tolerance("85")
    (0.005, 0.05, 0.5)
    """
    decimals = len(text.split(".")[1]) if "." in text else 0
    return 0.5 * 10.0 ** (-decimals)


def VOLT_TOL(text: str) -> float:  # noqa: N802  (a tolerance, named as the others)
    """Voltage tolerance of a paper value: one ADC step (4.88 mV) or half its last digit, the larger.

    Examples
    --------
    >>> round(VOLT_TOL("3.32"), 5), round(VOLT_TOL("300"), 5)
    (0.005, 0.00488)
    """
    digit = stated_tolerance(text) * (1e-3 if "." not in text and float(text) >= 10 else 1.0)
    return max(hw.ADC_LSB, digit)


@dataclass(frozen=True)
class Reading:
    """The judge's choices a reading of the paper fixes (a study may vary them).

    Attributes
    ----------
    cutoff_ms : float
        A response later than this after the onset counts as none (a censored trial).
    time_tol_ms : float
        Claim 8's tolerance on a response time (one DAQ sample).
    near_ml : float
        Claim 6's "near 200 and 400 ml".
    looks : int
        Looks of the replication design (sets every interval's level, :func:`looks_level`).

    Examples
    --------
    >>> Reading().cutoff_ms, Reading(looks=1).level
    (1000.0, 0.95)
    """

    cutoff_ms: float = 1000.0
    time_tol_ms: float = TIME_TOL_MS
    near_ml: float = NEAR_ML
    looks: int = 1

    def __post_init__(self) -> None:
        for name in ("cutoff_ms", "time_tol_ms", "near_ml"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"Reading.{name}: {v!r} (a finite number >= 0)")
        if int(self.looks) != self.looks or self.looks < 1:
            raise ValueError(f"Reading.looks: {self.looks!r} (an integer >= 1)")

    @property
    def level(self) -> float:
        """Two-sided level of every interval."""
        return looks_level(int(self.looks))


#: Every tolerance in words, as the reports print it (each with its reason).
TOLERANCES: dict[str, str] = {
    "a voltage": f"one ADC step ({hw.ADC_LSB * 1e3:.2f} mV) or half the paper's last digit, the larger",
    "a response time": f"one DAQ sample ({TIME_TOL_MS:.1f} ms), the resolution responses are measured with",
    "a length": f"{LENGTH_TOL_MM:g} mm: half the last digit of the paper's 0.09 mm (one scan sample is 0.003 mm)",
    "about a rate": "the paper's rate inside Wilson's 95 % interval of its own 30 drop trials (10 per bottle): "
                    "about 80 % is {:.1f}-{:.1f} %".format(*(100 * x for x in about_rate_band())),
    "more than twice": "a ratio above 2 (one-sided)",
    "near a volume": f"median within ±{NEAR_ML:g} ml (a quarter of the 200 ml between the two slips)",
    "most": f"more than {100 * MOST:g} % of the pours",
    "censored": "a slip not answered within the cutoff (1 s) is a censored trial: counted, ranked slowest",
    "intervals": "cluster bootstrap (trials resampled whole, paired where methods share trial seeds; normal "
                 f"interval with Student's t), Wilson for a rate, Newcombe for two; level "
                 f"{100 * looks_level(1):g} % on one run, {100 * looks_level(LOOKS):.2f} % per look "
                 f"with the {REPLICATES_MAX} replicate grids the design allows (a constant boundary: Bonferroni)",
}

# --- intervals ---------------------------------------------------------------------------------

def _clean(x: Iterable[Any]) -> np.ndarray:
    a = np.asarray([_num(v) for v in x], dtype=float)
    return a[np.isfinite(a)]


def _mean(x: np.ndarray, axis: int = -1) -> np.ndarray:
    return np.mean(x, axis=axis)


def _median(x: np.ndarray, axis: int = -1) -> np.ndarray:
    return np.median(x, axis=axis)


def _mean_diff(x: np.ndarray, y: np.ndarray, axis: int = -1) -> np.ndarray:
    return np.mean(x, axis=axis) - np.mean(y, axis=axis)


def _mean_ratio(x: np.ndarray, y: np.ndarray, axis: int = -1) -> np.ndarray:
    return np.mean(x, axis=axis) / np.mean(y, axis=axis)


def _boot(data: tuple, stat: Callable, *, paired: bool = False, method: str = "BCa",
          level: float = CONFIDENCE) -> tuple[float, float]:
    """A 95 % bootstrap interval of ``stat`` (vectorized, with an ``axis``); NaN with fewer than 2 values."""
    from scipy.stats import bootstrap  # deferred: heavy (scipy)

    if min(len(d) for d in data) < 2:
        return math.nan, math.nan
    if all(np.ptp(d) == 0 for d in data):        # no spread: the interval is the point
        v = float(stat(*data, axis=-1))
        return v, v
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = bootstrap(data, stat, paired=paired, confidence_level=level, n_resamples=_RESAMPLES,
                      method=method, vectorized=True, rng=np.random.default_rng(BOOTSTRAP_SEED))
    lo, hi = float(r.confidence_interval.low), float(r.confidence_interval.high)
    if not (math.isfinite(lo) and math.isfinite(hi)) and method == "BCa":
        return _boot(data, stat, paired=paired, method="percentile", level=level)
    return lo, hi


def mean_interval(x: Iterable[Any]) -> tuple[float, float, float, int]:
    """(mean, low, high, n) of the finite values of ``x``: a 95 % BCa bootstrap interval.

    Examples
    --------
    >>> m, lo, hi, n = mean_interval([10, 12, 11, 13, 9, 10])
    >>> lo < m < hi, n
    (True, 6)
    >>> mean_interval([5.0, 5.0])[:3]
    (5.0, 5.0, 5.0)
    """
    a = _clean(x)
    if not a.size:
        return math.nan, math.nan, math.nan, 0
    lo, hi = _boot((a,), _mean)
    return float(a.mean()), lo, hi, int(a.size)


def median_interval(x: Iterable[Any], level: float = CONFIDENCE) -> tuple[float, float, float, int]:
    """(median, low, high, n): a 95 % percentile bootstrap interval of the median.

    Examples
    --------
    >>> m, lo, hi, n = median_interval([200, 205, 210, 190, 195, 220])
    >>> lo <= m <= hi
    True
    """
    a = _clean(x)
    if not a.size:
        return math.nan, math.nan, math.nan, 0
    lo, hi = _boot((a,), _median, method="percentile", level=level)
    return float(np.median(a)), lo, hi, int(a.size)


def difference_interval(x: Iterable[Any], y: Iterable[Any], *, paired: bool = False
                        ) -> tuple[float, float, float, int]:
    """(mean of x minus mean of y, low, high, n): paired differences, or a two-sample bootstrap.

    ``paired=True`` takes ``x`` and ``y`` as pairs (same length; a pair with a NaN is
    left out) and bootstraps the mean of their differences.

    Examples
    --------
    >>> d, lo, hi, n = difference_interval([1, 2, 3, 4], [2, 3, 4, 5], paired=True)
    >>> d, lo, hi, n
    (-1.0, -1.0, -1.0, 4)
    """
    if paired:
        a = np.asarray([_num(v) for v in x], dtype=float) - np.asarray([_num(v) for v in y], dtype=float)
        m, lo, hi, n = mean_interval(a)
        return m, lo, hi, n
    a, b = _clean(x), _clean(y)
    if not a.size or not b.size:
        return math.nan, math.nan, math.nan, 0
    lo, hi = _boot((a, b), _mean_diff)
    return float(a.mean() - b.mean()), lo, hi, int(min(a.size, b.size))


def ratio_interval(x: Iterable[Any], y: Iterable[Any]) -> tuple[float, float, float, int]:
    """(mean of x over mean of y, low, high, n): a two-sample bootstrap interval of the ratio.

    Examples
    --------
    >>> r, lo, hi, n = ratio_interval([600, 640, 700, 660], [300, 310, 290, 330])
    >>> round(r, 2), lo < r < hi
    (2.11, True)
    """
    a, b = _clean(x), _clean(y)
    if not a.size or not b.size or not b.mean() > 0:
        return math.nan, math.nan, math.nan, 0
    lo, hi = _boot((a, b), _mean_ratio)
    return float(a.mean() / b.mean()), lo, hi, int(min(a.size, b.size))


def proportion_interval(k: int, n: int) -> tuple[float, float, float]:
    """(k / n, low, high): the Wilson score interval (``scipy.stats.binomtest``), NaN for ``n == 0``.

    Examples
    --------
    >>> [round(v, 4) for v in proportion_interval(8, 10)]
    [0.8, 0.4902, 0.9433]
    """
    if n == 0:
        return math.nan, math.nan, math.nan
    from scipy.stats import binomtest  # deferred: heavy (scipy)

    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=CONFIDENCE, method="wilson")
    return k / n, float(ci.low), float(ci.high)



# --- parts, claims, results ------------------------------------------------------------------

@dataclass(frozen=True)
class Part:
    """One part of a claim judged: its class, why, and the interval behind it.

    Attributes
    ----------
    verdict, reason : str
    value, low, high : float
        The estimate and its interval (NaN where none applies).
    criterion : str
    label : str
        Which part ("b", "TR DATH<NMSD", "the paper's table", ...).
    primary : bool
        Part of the reading the paper's summary gives (sets the claim's class).
    qualifier : str
        Why a part is not decidable in a word ("calibrated input"), else "".

    Examples
    --------
    >>> Part(HOLDS, "ok", 1.0, "x < 2", 0.5, 1.5, label="a").primary
    True
    """

    verdict: str
    reason: str
    value: float = math.nan
    criterion: str = ""
    low: float = math.nan
    high: float = math.nan
    label: str = ""
    primary: bool = True
    qualifier: str = ""


@dataclass(frozen=True)
class ClaimResult:
    """The class of one claim, its reason, the numbers behind it and every part.

    Attributes
    ----------
    number : int
    text : str
        The short quote (tables).
    verdict : str
        One of :data:`VERDICTS`, from the primary parts.
    reason : str
        Why: the deciding part's reason (every primary part's when it holds).
    value, low, high : float
        The deciding part's estimate and its interval (NaN where none applies).
    criterion : str
    numbers : str
        Every part, labelled, with its class.
    tolerance : str
        How the paper's words were made numbers.
    parts : tuple of Part
    quote, where : str
        The paper's whole sentence(s) and where they are.
    qualifier : str
        The deciding part's qualifier.

    Examples
    --------
    >>> ClaimResult(9, "t", HOLDS, "r", 1.0, 0.5, 2.0, "c", "n", "tol").verdict
    'holds'
    """

    number: int
    text: str
    verdict: str
    reason: str
    value: float
    low: float
    high: float
    criterion: str
    numbers: str
    tolerance: str
    parts: tuple = ()
    quote: str = ""
    where: str = ""
    qualifier: str = ""

    @property
    def class_text(self) -> str:
        """The class with its qualifier: ``"not-decidable (calibrated input)"``."""
        return f"{self.verdict} ({self.qualifier})" if self.qualifier else self.verdict

    def parts_text(self) -> str:
        """Every part in a few words: ``"a holds; b* fails-plant"`` (``*``: primary).

        Examples
        --------
        >>> r = ClaimResult(1, "t", HOLDS, "r", 1.0, 0.5, 2.0, "c", "n", "t", (Part(HOLDS, "x", label="a"),))
        >>> r.parts_text()
        'a* holds'
        """
        return "; ".join(f"{p.label or '-'}{'*' if p.primary else ''} {p.verdict}" for p in self.parts)


@dataclass(frozen=True)
class ClaimInput:
    """What the claims are judged from.

    Parameters
    ----------
    rows : sequence of mapping
        Per-slip result rows (results.csv columns); values may be strings as
        read from a CSV.
    scan : ScanEnsemble, optional
        The simulated characterization scan over texture seeds
        (:func:`slipreflex.sim.scan.scan_ensemble`); None: claim 2 is not decidable.
    plant : Plant, optional
        The simulated plant (claim 4's bounds; default: the built-in bottles).
    measured : ScanEnsemble, optional
        A real or replayed scan (:func:`measured_scan`): claim 1 is judged on it.
    reading : Reading
        The judge's choices (cutoff, tolerances, the replication's looks).

    Examples
    --------
    >>> ClaimInput([]).values("drop", "TR", "dath", "response_ms")
    []
    """

    rows: Sequence[Any]
    scan: Any = None
    plant: Any = None
    measured: Any = None
    reading: Reading = field(default_factory=Reading)
    _cells: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def level(self) -> float:
        """Two-sided level of every interval."""
        return self.reading.level

    def cell(self, experiment: str, bottle: str, method: str) -> list[Any]:
        """Rows of one experiment, bottle and method.

        Examples
        --------
        >>> len(ClaimInput([{"experiment": "drop", "bottle": "TR", "method": "dath"}]).cell(
        ...     "drop", "TR", "dath"))
        1
        """
        if not self._cells:
            for r in self.rows:
                key = (str(_get(r, "experiment")), str(_get(r, "bottle")), str(_get(r, "method")))
                self._cells.setdefault(key, []).append(r)
        return self._cells.get((experiment, bottle, method), [])

    def values(self, experiment: str, bottle: str, method: str, column: str) -> list[float]:
        """The finite values of a column over one cell's rows.

        Examples
        --------
        >>> ClaimInput([{"experiment": "pour", "bottle": "TX", "method": "swt", "response_ms": "80"},
        ...             {"experiment": "pour", "bottle": "TX", "method": "swt", "response_ms": ""}]
        ...           ).values("pour", "TX", "swt", "response_ms")
        [80.0]
        """
        return [x for x in (_num(_get(r, column)) for r in self.cell(experiment, bottle, method)) if x == x]

    def slips(self, experiment: str, bottles: Iterable[str], method: str, column: str = "response_ms") -> Sample:
        """Every slip of a method as a trial, clustered by its trial; no answer within the cutoff is ``+inf``.

        A row whose trial showed no slip (``n_events`` 0) is no trial to answer. The
        cluster key is (experiment, bottle, trial, seed), so one pour's slips stay together
        and two methods on the same trial seeds share keys (a paired design).

        Examples
        --------
        >>> rows = [{"experiment": "pour", "bottle": "TR", "method": "dath", "trial": 0, "seed": 1, "event": e,
        ...          "n_events": 2, "response_ms": v} for e, v in ((0, 60.0), (1, ""))]
        >>> s = ClaimInput(rows).slips("pour", ["TR"], "dath")
        >>> s.n, s.censored, len(s.keys)
        (2, 1, 1)
        """
        cutoff = self.reading.cutoff_ms
        clusters: dict[tuple, list[float]] = {}
        for b in bottles:
            for r in self.cell(experiment, b, method):
                if _count(_get(r, "n_events")) == 0:
                    continue
                v = _num(_get(r, column))
                first = _num(_get(r, "response_ms"))
                answered = v == v and first == first and first <= cutoff
                key = (experiment, b, str(_get(r, "trial")), str(_get(r, "seed")))
                clusters.setdefault(key, []).append(v if answered else math.inf)
        return Sample.of(clusters)

    def pairs(self, experiment: str, bottle: str, a: str, b: str, column: str = "response_ms"
              ) -> tuple[list[float], list[float]]:
        """Values of methods ``a`` and ``b`` on the same trial seed and slip (both present; no answer is inf).

        Examples
        --------
        >>> rows = [{"experiment": "drop", "bottle": "TR", "method": m, "trial": 0, "seed": 5, "event": 0,
        ...          "n_events": 1, "response_ms": v} for m, v in (("dath", 30), ("fixed", 30))]
        >>> ClaimInput(rows).pairs("drop", "TR", "dath", "fixed")
        ([30.0], [30.0])
        """
        def keyed(m: str) -> dict:
            out = {}
            for r in self.cell(experiment, bottle, m):
                if _count(_get(r, "n_events")) == 0:
                    continue
                v = _num(_get(r, column))
                out[(str(_get(r, "trial")), str(_get(r, "seed")), _count(_get(r, "event")))] = \
                    v if v == v and v <= self.reading.cutoff_ms else math.inf
            return out
        ka, kb = keyed(a), keyed(b)
        common = sorted(set(ka) & set(kb))
        return [ka[k] for k in common], [kb[k] for k in common]

    def success(self, experiment: str, bottles: Iterable[str], method: str) -> tuple[int, int]:
        """(successful trials, trials) over the rows of ``bottles`` (one per trial: its first slip's row).

        Examples
        --------
        >>> ClaimInput([{"experiment": "drop", "bottle": "TR", "method": "dath", "success": "True", "trial": 0},
        ...             {"experiment": "drop", "bottle": "TR", "method": "dath", "success": False, "trial": 1}]
        ...           ).success("drop", ["TR"], "dath")
        (1, 2)
        """
        s = [cell_bool(_get(r, "success")) for b in bottles for r in self.cell(experiment, b, method)
             if _count(_get(r, "event")) == 0]
        return sum(s), len(s)


@dataclass(frozen=True)
class Claim:
    """One claim of the paper and the function that judges it.

    Attributes
    ----------
    number : int
    text : str
        The paper's words, shortened for tables (a quote, with "..." where cut).
    quote : str
        The paper's whole sentence(s).
    where : str
        Section and figure.
    reading : str
        What is judged, and which part is primary.
    tolerance : str
        How the paper's words were made numbers.
    judge : callable
        ``judge(ClaimInput) -> list of Part``.
    methods : tuple of str
        The methods whose trials decide it: what a replicate grid runs when one run
        leaves it unresolved (empty: the trials do not decide it, as for the scan).

    Examples
    --------
    >>> CLAIMS[0].number, CLAIMS[-1].number, CLAIMS[7].where
    (1, 11, 'IV; abstract')
    """

    number: int
    text: str
    quote: str
    where: str
    reading: str
    tolerance: str
    judge: Callable[[ClaimInput], list[Part]]
    methods: tuple[str, ...] = ()


def _get(row: Any, key: str) -> Any:
    if isinstance(row, Mapping):
        return row.get(key)
    return getattr(row, key, None)


def _num(x: Any) -> float:
    """A cell of a table being judged: blank, missing or unreadable is NaN."""
    return cell_float(x, lenient=True)


def _count(x: Any) -> int:
    """A count cell as int; a missing or unreadable cell counts 0."""
    v = _num(x)
    return int(v) if math.isfinite(v) else 0


def _f(x: float, digits: int = 0) -> str:
    return "-" if x != x else ("never" if math.isinf(x) else f"{x:.{digits}f}")


def _ci(lo: float, hi: float, digits: int = 0) -> str:
    return "no interval" if lo != lo else f"[{_f(lo, digits)}, {_f(hi, digits)}]"


INF = math.inf


def _side(lo: float, hi: float, band: tuple[float, float], strict: tuple[bool, bool]) -> str:
    """HOLDS when the interval lies inside ``band``, FAILS_PLANT when it misses it, else UNRESOLVED.

    ``strict`` says which ends of the band are open.
    """
    if lo != lo:
        return UNRESOLVED
    a, b = band

    def inside(x: float) -> bool:
        return (x > a if strict[0] else x >= a) and (x < b if strict[1] else x <= b)

    if inside(lo) and inside(hi):
        return HOLDS
    below = hi < a or (strict[0] and hi == a)
    above = lo > b or (strict[1] and lo == b)
    return FAILS_PLANT if below or above else UNRESOLVED


def _part(lo: float, hi: float, band: tuple[float, float], value: float, criterion: str, numbers: str,
          physics: str, strict: tuple[bool, bool] = (True, True), *, label: str = "", primary: bool = True,
          level: float = CONFIDENCE) -> Part:
    """A part decided by an interval against ``band``: holds / fails on this plant (``physics``) / unresolved."""
    v = _side(lo, hi, band, strict)
    reason = {HOLDS: numbers, FAILS_PLANT: f"{numbers}; on this plant: {physics}",
              UNRESOLVED: f"{numbers}: the {100 * level:.4g} % interval {_ci(lo, hi, 2)} straddles "
                          f"the criterion ({criterion})"}[v]
    return Part(v, reason, value, criterion, lo, hi, label=label, primary=primary)


def _combine(claim: Claim, parts: list[Part]) -> ClaimResult:
    """The claim's class: the first class (in :data:`VERDICTS` order) among its primary parts."""
    order = {v: i for i, v in enumerate(VERDICTS)}
    parts = parts or [Part(NOT_DECIDABLE, "nothing to judge")]
    primary = [p for p in parts if p.primary] or parts
    d = min(primary, key=lambda p: order[p.verdict])
    numbers = "; ".join(f"({p.label or '-'}{', primary' if p.primary else ''}) {p.verdict}: {p.reason}"
                        for p in parts)
    reason = "; ".join(p.reason for p in primary) if d.verdict == HOLDS else d.reason
    return ClaimResult(claim.number, claim.text, d.verdict, reason, d.value, d.low, d.high, d.criterion, numbers,
                       claim.tolerance, tuple(parts), claim.quote, claim.where, d.qualifier)


# --- comparisons -------------------------------------------------------------------------------

def _describe(s: Sample, column: str = "response") -> str:
    """A cell in a few words: its mean (every trial answered) or Kaplan-Meier median, and n of N."""
    if not s.n:
        return "no trials"
    if not s.censored:
        return f"mean {_f(s.mean())} ms (n {s.n})"
    return f"KM median {_f(km_median(s))} ms, {s.responders} of {s.n} answered"


def _compare(ci: ClaimInput, experiment: str, bottles: Sequence[str], fast: str, slow: str, *, label: str,
             physics: str, column: str = "response_ms", factor: float = 1.0, primary: bool = True,
             slow_bottles: Sequence[str] | None = None) -> Part:
    """Is ``factor x fast`` below ``slow``: clustered, paired where the trial seeds match, censoring-aware.

    Every trial answered in both: the difference of mean (``factor`` 1, criterion < 0) or
    the ratio ``mean slow / mean fast`` (criterion > ``factor``). A censored trial in
    either: the probabilistic index ``P(factor fast < slow) + P(=) / 2`` (criterion > 0.5).
    """
    a = ci.slips(experiment, bottles, fast, column)
    b = ci.slips(experiment, slow_bottles or bottles, slow, column)
    who = f"{_label(fast)} {'x' + format(factor, 'g') + ' ' if factor != 1 else ''}< {_label(slow)}"
    note = ""
    if column == "total_ms":     # a total is the span of the controller's commands: none where it never acted
        note = f" (totals of the answered slips: {_label(fast)} {a.responders} of {a.n}, {_label(slow)} " \
               f"{b.responders} of {b.n})"
        a, b = a.answered(), b.answered()
    if not a.n or not b.n:
        gone = " and ".join(_label(m) for m, s in ((fast, a), (slow, b)) if not s.n)
        return Part(NOT_DECIDABLE, f"{label}: this run has no {experiment} slips of {gone}", label=label,
                    primary=primary)
    paired = slow_bottles is None and bool(set(a.keys) & set(b.keys))
    what = "total" if column == "total_ms" else "response"
    seed = BOOTSTRAP_SEED
    if not a.censored and not b.censored:
        kind, crit = (MEAN_DIFF, f"{who}: mean {what} difference < 0 ms") if factor == 1 else \
            (RATIO, f"{who}: mean {what} ratio > {factor:g}")
        est, lo, hi = cluster_interval(kind, [a, b], paired=paired, level=ci.level, factor=factor, seed=seed)
        band = (-INF, 0.0) if factor == 1 else (factor, INF)
    else:
        kind, crit = INDEX, f"{who}: P({what} below) > 0.5 (censoring-aware)"
        est, lo, hi = cluster_interval(INDEX, [a, b], paired=paired, level=ci.level, factor=factor, seed=seed)
        band = (0.5, INF)
    stat = {MEAN_DIFF: "difference", RATIO: "ratio", INDEX: "P(below)"}[kind]
    numbers = (f"{label}: {_label(fast)} {_describe(a)} vs {_label(slow)} {_describe(b)}; "
               f"{'paired ' if paired else ''}{stat} {_f(est, 2)} {_ci(lo, hi, 2)}{note}")
    if kind == INDEX:
        numbers += f" (Mann-Whitney one-sided p {rank_p(a, b, factor):.3g}, trials as independent)"
    return _part(lo, hi, band, est, crit, numbers, physics, label=label, primary=primary, level=ci.level)


def _same_encoder(ci: ClaimInput, experiment: str, bottles: Sequence[str] = BOTTLE_ORDER) -> Part | None:
    """A fails-definition part when DATH and fixed answer at the same sample on every paired slip (2 or more)."""
    pairs = [p for b in bottles for p in zip(*ci.pairs(experiment, b, DATH, FIXED))]
    if len(pairs) < 2 or any(x != y for x, y in pairs):
        return None
    return Part(FAILS_DEFINITION, (
        f"DATH and the fixed threshold answer alike (the same sample, or neither within the cutoff) on "
        f"{len(pairs)} of {len(pairs)} paired {experiment} slips: they are the same encoder until the first "
        "spike (Eq. 1-4: DATH changes the "
        "threshold only after one), so on the same input DATH cannot be faster"), 0.0,
        "DATH minus fixed response < 0 ms", 0.0, 0.0, label="DATH = fixed by definition")


def _missing(ci: ClaimInput, experiment: str, methods: Sequence[str], bottles: Sequence[str] = BOTTLE_ORDER
             ) -> list[Part]:
    """A not-decidable part when the run lacks a cell the claim needs."""
    gone = [f"{_label(m)} {b}" for m in methods for b in bottles if not ci.cell(experiment, b, m)]
    return [Part(NOT_DECIDABLE, f"this run has no {experiment} rows of " + ", ".join(gone), label="cells")] \
        if gone else []

# --- the paper's own numbers -----------------------------------------------------------------

def _paper_mean(experiment: str, bottle: str, method: str) -> float:
    v = PAPER.get((experiment, "response_ms", bottle, method))
    return math.nan if v is None or v.mean is None else float(v.mean)


def _paper_mean_total(experiment: str, bottle: str, method: str) -> float:
    v = PAPER.get((experiment, "total_ms", bottle, method))
    return math.nan if v is None or v.mean is None else float(v.mean)


def _paper_part(bad: list[str], what: str) -> list[Part]:
    """A fails-paper part when the paper's own table breaks the claim (``bad``: its cells)."""
    if not bad:
        return []
    return [Part(FAILS_PAPER, f"the paper's own table breaks it: {', '.join(bad)} ({what})",
                 label="the paper's table")]


def tilt_and_taper(plant: Any = None) -> str:
    """What of the tilt and the shoulder the plant's paper bottles model ("" when neither).

    The drop's 1-DOF bounds (:func:`drop_bounds`) leave out the bottle's tilt in the grasp
    (an impact off the axis rocks it) and a tapering shoulder (the normal force falls as the
    fingertips slide onto it). A plant whose bottles carry both decides claim 4 by simulation.

    Examples
    --------
    >>> isinstance(tilt_and_taper(), str)
    True
    """
    from ..sim import BOTTLES  # deferred: heavy (numba kernels)

    bottles = BOTTLES if plant is None else plant.bottles
    ecc = [float(getattr(bottles[n], "drop_eccentricity_m", 0.0)) for n in BOTTLE_ORDER]
    slope = [float(getattr(bottles[n], "shoulder_slope", 0.0)) for n in BOTTLE_ORDER]
    if min(ecc) <= 0.0 or min(slope) <= 0.0:
        return ""
    def span(lo: float, hi: float) -> str:
        return f"{lo:g}" if lo == hi else f"{lo:g}-{hi:g}"

    return (f"the bottle's tilt in the grasp, rocked by the mass landing {span(100 * min(ecc), 100 * max(ecc))} cm "
            f"off the axis, and a shoulder taper of {span(min(slope), max(slope))} (radius lost per length slid)")



# --- the judges ------------------------------------------------------------------------------

#: What decides each claim on this plant when it fails there (docs/reproduce.md gives the evidence).
PHYSICS: dict[int, str] = {
    1: "the sensor's levels on the scanned surface",
    2: "the test surface's texture spectrum, seen through the sensor's spot, sets how close fixed-threshold "
       "spikes come",
    3: "DATH's lowered threshold acts only after the first spike",
    5: "the hand's own motion: as the fingers close, the middle fingertip rolls over the bottle and the slip "
       "sensor sees texture move, so DATH keeps spiking and closing after a drop (docs/simulator.md)",
    6: "each MPI tightening raises the grasp's capacity by more than the rest of the water weighs (grip "
       "gain per unit, docs/simulator.md), so the second slip rarely comes",
    7: "a pour's rate-and-state slip creeps before it accelerates; the rest-calibrated thresholds of NMSD "
       "(tactile array) and SWT-SD see it late or never",
    8: "a pour's slip creeps before the accelerometer sees it, and the sensor's signal grows slowly",
    9: "the bottles' surfaces (reflectance, texture) and the tactile methods' rest-calibrated thresholds",
    10: "the bottles' surfaces (reflectance, texture) and how the hand's own motion shows on them",
    11: "the hand's own motion under the slip sensor keeps DATH closing after the slip",
}

_WANT_LEVELS = (("white_lo", 0.3, "300"), ("white_hi", 0.5, "500"), ("black_lo", 3.32, "3.32"),
                ("black_hi", 3.35, "3.35"))


def _scan_levels(ci: ClaimInput) -> list[Part]:
    """Claim 1: a measured scan's levels against the paper's, or not decidable (the model is calibrated to them)."""
    tol = {stat: VOLT_TOL(text) for stat, _, text in _WANT_LEVELS}
    crit = "white inside 0.3-0.5 V and black inside 3.32-3.35 V (± the voltage tolerance)"
    if ci.measured is not None:
        m = ci.measured
        got = {stat: float(np.nanmin(getattr(m, stat)) if stat.endswith("lo") else np.nanmax(getattr(m, stat)))
               for stat, _, _ in _WANT_LEVELS}
        ok = (got["white_lo"] >= 0.3 - tol["white_lo"] and got["white_hi"] <= 0.5 + tol["white_hi"]
              and got["black_lo"] >= 3.32 - tol["black_lo"] and got["black_hi"] <= 3.35 + tol["black_hi"])
        text = (f"the measured scan: white {got['white_lo']:.3f}-{got['white_hi']:.3f} V, black "
                f"{got['black_lo']:.3f}-{got['black_hi']:.3f} V")
        return [Part(HOLDS if ok else FAILS_PLANT, text if ok else f"{text}; on this sensor: {PHYSICS[1]}",
                     float(ok), crit, label="measured scan")]
    model = ""
    if ci.scan is not None:
        model = f" The model's central {100 * CENTRAL:g} % over {len(ci.scan)} texture seeds: " + ", ".join(
            "{} {:.3f}-{:.3f} V".format(stat.replace("_", " "), *ci.scan.band(stat, CENTRAL))
            for stat, _, _ in _WANT_LEVELS) + "."
    return [Part(NOT_DECIDABLE, (
        "these are measurements of the paper's own sensor and test surface, and the simulated test surface is "
        "calibrated to them (sim.scan.calibrate_surface: the ensemble's median levels set to the paper's), so "
        "the model reproduces them by construction and tests nothing." + model + " A real or replayed scan "
        "decides it: slipreflex claims RESULTS.csv --scan scan.csv"), criterion=crit, label="scan levels",
        qualifier=CALIBRATED_INPUT)]


def _scan_spikes(ci: ClaimInput) -> list[Part]:
    """Claim 2: (a) DATH more spikes, (b, primary) a 0.09 mm slide suffices for both, (c) spacing >= 0.09 mm."""
    e = ci.scan
    if e is None:
        return [Part(NOT_DECIDABLE, "this run judged no characterization scan", label="scan")]
    n, lvl = len(e), ci.level
    more = e.dath_spikes > e.fixed_spikes
    m, mlo, mhi = wilson_interval(int(more.sum()), n, lvl)
    parts = [_part(mlo, mhi, (MOST, INF), m, "DATH more spikes than fixed on most texture seeds",
                   f"DATH gives more spikes than fixed on {int(more.sum())} of {n} seeds", PHYSICS[2],
                   label="a", primary=False, level=lvl)]
    for meth, gap in ((FIXED, e.fixed_gap), (DATH, e.dath_gap)):
        g = np.asarray(gap, dtype=float)
        k = int((g <= 0.09 + LENGTH_TOL_MM).sum())
        f, flo, fhi = wilson_interval(k, n, lvl)
        lo, hi = e.band("fixed_gap" if meth == FIXED else "dath_gap", CENTRAL)
        parts.append(_part(flo, fhi, (MOST, INF), f, f"{_label(meth)}: a slide of at most about 0.09 mm between "
                           "two spikes on most texture seeds",
                           f"{_label(meth)}'s smallest spike spacing {lo:.3f}-{hi:.3f} mm (central "
                           f"{100 * CENTRAL:g} %); at most 0.09 mm on {k} of {n} seeds", PHYSICS[2],
                           label=f"b {_label(meth)}", level=lvl))
    g = np.asarray(e.fixed_gap, dtype=float)
    k = int((g >= 0.09 - LENGTH_TOL_MM).sum())
    f, flo, fhi = wilson_interval(k, n, lvl)
    parts.append(_part(flo, fhi, (MOST, INF), f, "fixed: spacing at least about 0.09 mm on most seeds",
                       f"fixed's smallest spacing at least 0.09 mm on {k} of {n} seeds", PHYSICS[2],
                       label="c fixed", primary=False, level=lvl))
    one = np.isclose(e.dath_gap, e.step_mm, rtol=0.01)
    d, dlo, dhi = wilson_interval(int(one.sum()), n, lvl)
    if dlo > CENTRAL - 0.1 or d >= CENTRAL:
        parts.append(Part(FAILS_DEFINITION, (
            f"DATH's smallest spacing is one sample ({e.step_mm:.3f} mm at 1 mm/s) on {int(one.sum())} of {n} "
            "seeds: after an arming spike Eq. 4 lowers the threshold for a window and fires on consecutive "
            "samples while the slope grows, so 'at least 0.09 mm' cannot hold for DATH"),
            d, "DATH's spacing at least 0.09 mm", dlo, dhi, label="c DATH", primary=False))
    else:
        g = np.asarray(e.dath_gap, dtype=float)
        k = int((g >= 0.09 - LENGTH_TOL_MM).sum())
        f, flo, fhi = wilson_interval(k, n, lvl)
        parts.append(_part(flo, fhi, (MOST, INF), f, "DATH: spacing at least about 0.09 mm on most seeds",
                           f"DATH's smallest spacing at least 0.09 mm on {k} of {n} seeds", PHYSICS[2],
                           label="c DATH", primary=False, level=lvl))
    return parts


def _drop_faster(ci: ClaimInput) -> list[Part]:
    bad = [f"drop {b} DATH {_paper_mean('drop', b, DATH):g} vs fixed {_paper_mean('drop', b, FIXED):g}"
           for b in BOTTLE_ORDER if not _paper_mean("drop", b, DATH) < _paper_mean("drop", b, FIXED)]
    paper = _paper_part(bad, "DATH not faster")
    if gone := _missing(ci, "drop", (DATH, FIXED)):
        return paper + gone
    same = _same_encoder(ci, "drop")
    return paper + ([same] if same else []) + [
        _compare(ci, "drop", [b], DATH, FIXED, label=b, physics=PHYSICS[3]) for b in BOTTLE_ORDER]


def _nmsd_twice(ci: ClaimInput) -> list[Part]:
    bottles = [b for b in BOTTLE_ORDER if ci.cell("drop", b, DATH) and ci.cell("drop", b, NMSD)]
    if not bottles:
        return [Part(NOT_DECIDABLE, "this run has no drop trials of DATH and NMSD on one bottle", label="cells")]
    nmsd = [_paper_mean_total("drop", b, NMSD) for b in BOTTLE_ORDER]
    dath = [_paper_mean_total("drop", b, DATH) for b in BOTTLE_ORDER]
    paper = [n / d for n, d in zip(nmsd, dath)]
    ratio = float(np.mean(nmsd) / np.mean(dath))
    own = Part(HOLDS if ratio > 2 else FAILS_PAPER, f"the paper's own drop totals: NMSD / DATH {ratio:.2f} over the "
               f"bottles ({', '.join(f'{x:.2f}' for x in paper)} per bottle)", ratio, "ratio > 2",
               label="the paper's table")
    run = _compare(ci, "drop", bottles, DATH, NMSD, label="all bottles", physics=PHYSICS[5],
                   column="total_ms", factor=2.0)
    return [own, replace(run, reason=run.reason + _magnitudes(ci, bottles, ((DATH, dath), (NMSD, nmsd))))]


def _magnitudes(ci: ClaimInput, bottles: list[str], paper: Iterable[tuple[str, list[float]]]) -> str:
    """Where a ratio is judged, whether the run's totals are of the paper's size at all.

    A ratio can hold while both totals are a fraction of the paper's; a reader of the
    class alone would take the magnitudes for reproduced too, so the reason says so.
    """
    said = []
    for method, cells in paper:
        run = [t for b in bottles for r in ci.cell("drop", b, method) if math.isfinite(t := _num(_get(r, "total_ms")))]
        if run and cells and not min(cells) / 2 <= float(np.mean(run)) <= 2 * max(cells):
            said.append(f"{_label(method)} {np.mean(run):.0f} ms against the paper's "
                        f"{min(cells):g}-{max(cells):g} ms")
    return ("; the ratio holds or fails on totals not of the paper's size: " + ", ".join(said)
            + " (docs/simulator.md, the plant against the paper's figures)") if said else ""


def _dath_pours(ci: ClaimInput) -> list[list[Any]]:
    trials: dict[tuple, list[Any]] = {}
    for b in BOTTLE_ORDER:
        for r in ci.cell("pour", b, DATH):
            trials.setdefault((b, str(_get(r, "trial")), str(_get(r, "seed"))), []).append(r)
    return list(trials.values())


def _two_slips(ci: ClaimInput) -> Part:
    """Claim 6 (b): more than half of all pour trials (every method) show two slips."""
    pours: dict[tuple, int] = {}
    for m in method_names(paper=True):
        for b in BOTTLE_ORDER:
            for r in ci.cell("pour", b, m):
                pours[(m, b, str(_get(r, "trial")), str(_get(r, "seed")))] = _count(_get(r, "n_events"))
    two = sum(v >= 2 for v in pours.values())
    f, lo, hi = wilson_interval(two, len(pours), ci.level)
    return _part(lo, hi, (MOST, INF), f, "more than half of all pour trials show two slips",
                 f"{two} of {len(pours)} pour trials (every method) show two or more slips", PHYSICS[6],
                 label="b two slips", level=ci.level)


def _pour_dath(ci: ClaimInput) -> list[Part]:
    pours = _dath_pours(ci)
    if not pours:
        return [Part(NOT_DECIDABLE, "this run has no DATH pours", label="cells")]
    k, n = ci.success("pour", BOTTLE_ORDER, DATH)
    s, slo, shi = wilson_interval(k, n, ci.level)
    parts = [Part(HOLDS if k == n else FAILS_PLANT, f"DATH held {k} of {n} pours" + (
        "" if k == n else "; on this plant: a pour's slip creeps before it accelerates and DATH's grip came late"),
        s, "every DATH pour succeeds", slo, shi, label="a success"), _two_slips(ci)]
    near = ci.reading.near_ml
    for e, want in ((0, 200.0), (1, 400.0)):
        vols = [_num(_get(r, "load_at_onset")) for t in pours for r in t
                if _count(_get(r, "event")) == e and _count(_get(r, "n_events")) > e]
        m, lo, hi, nv = median_interval(vols, ci.level)
        label = f"c slip {e + 1}"
        if not nv:
            parts.append(Part(NOT_DECIDABLE, f"no DATH pour shows a slip {e + 1}", label=label))
            continue
        parts.append(_part(lo, hi, (want - near, want + near), m,
                           f"median volume at slip {e + 1} within {want:g} ± {near:g} ml",
                           f"slip {e + 1} at a median {_f(m)} ml {_ci(lo, hi)} (n {nv})",
                           "the plant's capacity after the reflex's tightening", (False, False), label=label,
                           level=ci.level))
    return parts


#: Claim 7's comparisons: per bottle, (faster, slower).
POUR_ORDER: dict[str, tuple[tuple[str, str], ...]] = {
    "TR": ((DATH, NMSD), (DATH, FIXED), (SWT, NMSD), (SWT, FIXED)),
    "DK": ((DATH, NMSD), (DATH, FIXED), (SWT, NMSD), (SWT, FIXED)),
    "TX": ((DATH, FIXED),),
}


def _pour_faster(ci: ClaimInput) -> list[Part]:
    bad = [f"pour {b} {_label(f)} {_paper_mean('pour', b, f):g} vs {_label(s)} {_paper_mean('pour', b, s):g}"
           for b, pairs in POUR_ORDER.items() for f, s in pairs
           if not _paper_mean("pour", b, f) < _paper_mean("pour", b, s)]
    paper = _paper_part(bad, "not faster")
    if gone := _missing(ci, "pour", (DATH, SWT, NMSD, FIXED)):
        return paper + gone
    same = _same_encoder(ci, "pour")
    parts = [_compare(ci, "pour", [b], f, s, label=f"{b} {_label(f)}<{_label(s)}", physics=PHYSICS[7])
             for b, pairs in POUR_ORDER.items() for f, s in pairs]
    return paper + ([same] if same else []) + parts


def _overall_under(ci: ClaimInput) -> Part:
    """Claim 8's primary reading: DATH's mean response over every bottle and both experiments < 85 ms."""
    samples = [ci.slips(e, BOTTLE_ORDER, DATH) for e in EXPERIMENTS]
    s = Sample(tuple(k for x in samples for k in x.keys), tuple(v for x in samples for v in x.values))
    limit = UNDER_MS + ci.reading.time_tol_ms
    if not s.n:
        return Part(NOT_DECIDABLE, "this run has no DATH slips", label="overall")
    if not s.censored:
        m, lo, hi = cluster_interval(MEAN, [s], level=ci.level, seed=BOOTSTRAP_SEED)
        crit = f"DATH's overall mean response < {UNDER_MS:g} ms (+ one sample)"
        return _part(lo, hi, (-INF, limit), m, crit, f"DATH's overall mean {_f(m)} ms {_ci(lo, hi)} over "
                     f"{s.n} slips", PHYSICS[8], label="overall", level=ci.level)
    f, lo, hi = cluster_interval(FRACTION, [s], level=ci.level, below=limit, seed=BOOTSTRAP_SEED)
    crit = f"more than half of DATH's slips answered within {UNDER_MS:g} ms (+ one sample; censoring-aware)"
    return _part(lo, hi, (0.5, INF), f, crit, f"DATH answered {s.responders} of {s.n} slips (KM median "
                 f"{_f(km_median(s))} ms); within {UNDER_MS:g} ms: {100 * f:.0f} % {_ci(100 * lo, 100 * hi)} %",
                 PHYSICS[8], label="overall", level=ci.level)


def _under_85(ci: ClaimInput) -> list[Part]:
    cells = {(e, b): _paper_mean(e, b, DATH) for e in EXPERIMENTS for b in BOTTLE_ORDER}
    mean = float(np.mean(list(cells.values())))
    parts = [Part(HOLDS if mean < UNDER_MS else FAILS_PAPER, f"the paper's six DATH cells average {mean:.1f} ms",
                  mean, f"mean < {UNDER_MS:g} ms", label="the paper's table, overall")]
    bad = [f"{e} {b} {v:g} ms" for (e, b), v in cells.items() if not v < UNDER_MS]
    if bad:
        parts.append(Part(FAILS_PAPER, f"the paper's own table breaks it: {', '.join(bad)} (not under "
                          f"{UNDER_MS:g} ms)", criterion="every cell < 85 ms", label="the paper's table, per cell",
                          primary=False))
    parts.append(_overall_under(ci))
    limit = UNDER_MS + ci.reading.time_tol_ms
    for e in EXPERIMENTS:
        for b in BOTTLE_ORDER:
            s = ci.slips(e, [b], DATH)
            if not s.n:
                continue
            if s.censored:
                f, lo, hi = cluster_interval(FRACTION, [s], level=ci.level, below=limit)
                parts.append(_part(lo, hi, (0.5, INF), f, f"most slips answered within {UNDER_MS:g} ms",
                                   f"{e} {b}: {_describe(s)}", PHYSICS[8], label=f"{e} {b}", primary=False,
                                   level=ci.level))
                continue
            m, lo, hi = cluster_interval(MEAN, [s], level=ci.level)
            parts.append(_part(lo, hi, (-INF, limit), m, f"DATH mean response < {UNDER_MS:g} ms (+ one sample)",
                               f"{e} {b} {_f(m)} ms {_ci(lo, hi)} (n {s.n})", PHYSICS[8], label=f"{e} {b}",
                               primary=False, level=ci.level))
    return parts


def _majority(ci: ClaimInput) -> list[Part]:
    """Claim 9: drop, DATH faster than NMSD and SWT-SD on TR and TX; SWT-SD the fastest method on DK."""
    if gone := _missing(ci, "drop", (DATH, NMSD, SWT, FIXED)):
        return gone
    parts = [_compare(ci, "drop", [b], DATH, other, label=f"{b} DATH<{_label(other)}", physics=PHYSICS[9])
             for b in ("TR", "TX") for other in (NMSD, SWT)]
    parts += [_compare(ci, "drop", ["DK"], SWT, other, label=f"DK SWT-SD<{_label(other)}", physics=PHYSICS[9])
              for other in (DATH, NMSD, FIXED)]
    return parts


def _tx_best(ci: ClaimInput) -> list[Part]:
    """Claim 10: drop, DATH: TX's success the highest of the three bottles and TX's total time the lowest."""
    totals = {b: _paper_mean_total("drop", b, DATH) for b in BOTTLE_ORDER}
    bad = [] if all(totals["TX"] < totals[b] for b in ("TR", "DK")) else \
        [", ".join(f"{b} {v:g}" for b, v in totals.items())]
    parts = _paper_part(bad, "TX's DATH drop total not the lowest")
    if gone := _missing(ci, "drop", (DATH,)):
        return parts + gone
    tx = ci.success("drop", ["TX"], DATH)
    for other in ("TR", "DK"):
        o = ci.success("drop", [other], DATH)
        d, lo, hi = newcombe_interval(*tx, *o, level=ci.level)
        parts.append(_part(lo, hi, (0.0, INF), d, f"TX's success above {other}'s",
                           f"success TX {tx[0]}/{tx[1]} vs {other} {o[0]}/{o[1]}: difference {_f(100 * d)} points "
                           f"{_ci(100 * lo, 100 * hi)}", PHYSICS[10], label=f"success TX>{other}", level=ci.level))
    for other in ("TR", "DK"):
        parts.append(_compare(ci, "drop", ["TX"], DATH, DATH, label=f"total TX<{other}", physics=PHYSICS[10],
                              column="total_ms", slow_bottles=[other]))
    return parts


def _totals(ci: ClaimInput) -> list[Part]:
    """Claim 11: total time, DATH < NMSD and DATH < fixed, per bottle, both experiments."""
    bad = []
    for e in EXPERIMENTS:
        for b in BOTTLE_ORDER:
            for other in (NMSD, FIXED):
                d, o = _paper_mean_total(e, b, DATH), _paper_mean_total(e, b, other)
                if d == d and o == o and not d < o:
                    bad.append(f"{e} {b} DATH {d:g} vs {_label(other)} {o:g}")
    parts = _paper_part(bad, "DATH's total not below")
    for e in EXPERIMENTS:
        if gone := _missing(ci, e, (DATH, NMSD, FIXED)):
            parts += [replace(g, label=f"{e} cells") for g in gone]
            continue
        parts += [_compare(ci, e, [b], DATH, other, label=f"{e} {b} DATH<{_label(other)}", physics=PHYSICS[11],
                           column="total_ms") for b in BOTTLE_ORDER for other in (NMSD, FIXED)]
    return parts

#: Generous upper bound of static over sliding friction for polymer and elastomer contacts on PET.
STATIC_OVER_KINETIC_MAX: float = 2.0
#: What claim 4's bounds assume, named in every report that prints them.
DROP_ASSUMPTIONS: str = ("one degree of freedom (the bottle slides along its axis, no tilt), a constant normal "
                         "force (the grasp neither loosens nor tightens), complete slippage = sliding the whole "
                         "grip travel to the shoulder, static/sliding friction ratio r")


def first_slip_capacity_n(bottle_mass_kg: float, volume_ml: float, *, rate_l_min: float = 1.0,
                          fall_height_m: float = 0.10) -> float:
    """Static capacity (N) of a grasp whose first pour slip comes at ``volume_ml``.

    At the first slip the grasp's friction capacity equals the load:
    ``C = (M + rho V) g + rho Q sqrt(2 g h)``, the bottle and water weight
    plus the jet's momentum flux (water 1 g/ml, flow Q, jet falling h).

    Examples
    --------
    >>> round(first_slip_capacity_n(0.040, 200.0), 2)
    2.38
    """
    rho_q = rate_l_min / 60.0  # kg/s of water
    return (bottle_mass_kg + volume_ml * 1e-3) * hw.GRAVITY + rho_q * math.sqrt(2 * hw.GRAVITY * fall_height_m)


def drop_slipout_capacity_n(bottle_mass_kg: float, drop_mass_kg: float, height_m: float, travel_m: float,
                            static_over_kinetic: float = STATIC_OVER_KINETIC_MAX) -> float:
    """Energy bound: the largest static capacity (N) at which a drop can end in complete slippage.

    The mass falls ``h`` (release height plus the bottle's depth) and the bottle
    then slides the grip travel ``d``. Generously, no energy is lost in the
    impact and friction falls to ``C / r`` the moment sliding starts. The work
    friction does over ``d`` must not exceed what falling supplies:
    ``(C / r) d <= m g (h + d) + M g d``, so ``C <= r [(M + m) g + m g h / d]``.

    Examples
    --------
    >>> round(drop_slipout_capacity_n(0.040, 0.010, 0.18, 0.03, 2.0), 2)
    2.16
    """
    g = hw.GRAVITY
    return static_over_kinetic * ((bottle_mass_kg + drop_mass_kg) * g + drop_mass_kg * g * height_m / travel_m)


def drop_momentum_capacity_n(bottle_mass_kg: float, drop_mass_kg: float, height_m: float, travel_m: float,
                             static_over_kinetic: float) -> float:
    """Momentum bound: the largest static capacity (N) at which a drop can end in complete slippage.

    The mass lands at ``v = sqrt(2 g h)`` in a fully inelastic impact, so the
    bottle and mass move on at ``u = m v / (M + m)``, then slide against
    ``C / r`` less their weight. They cover the grip travel ``d`` only if
    ``u^2 >= 2 d (C / r - (M + m) g) / (M + m)``, so
    ``C <= r [(M + m) g + m^2 g h / (d (M + m))]``.

    Examples
    --------
    >>> round(drop_momentum_capacity_n(0.040, 0.010, 0.18, 0.03, 2.0), 2)
    1.22
    """
    g, mm = hw.GRAVITY, bottle_mass_kg + drop_mass_kg
    return static_over_kinetic * (mm * g + drop_mass_kg ** 2 * g * height_m / (travel_m * mm))


@dataclass(frozen=True)
class DropBounds:
    """Claim 4's bounds for one bottle: can the paper's 10 g drop end in complete slippage?

    Attributes
    ----------
    bottle : str
    fall_height_m : float
        How far the mass falls: the drop's release height plus the bottle's depth (the rig's geometry).
    pour_capacity_n : float
        The grasp's static capacity that the paper's first pour slip (about 200 ml) implies.
    energy_n : float
        Energy bound with r = :data:`STATIC_OVER_KINETIC_MAX` (no impact loss).
    momentum_n, momentum_generous_n : float
        Momentum bound with the bottle's own r = mu_s / mu_k, and with r = 2.
    r_own : float

    Examples
    --------
    >>> b = drop_bounds()[0]
    >>> b.bottle, round(b.fall_height_m, 2), b.possible
    ('TR', 0.18, False)
    """

    bottle: str
    fall_height_m: float
    pour_capacity_n: float
    energy_n: float
    momentum_n: float
    momentum_generous_n: float
    r_own: float

    @property
    def possible(self) -> bool:
        """Whether even the energy bound allows a slip-out of the pour-calibrated grasp."""
        return self.energy_n >= self.pour_capacity_n

    def text(self) -> str:
        """One line: the bounds beside the pour's capacity."""
        return (f"{self.bottle}: fall {100 * self.fall_height_m:.0f} cm; slip-out needs C <= {self.energy_n:.2f} N "
                f"(energy, r {STATIC_OVER_KINETIC_MAX:g}) or {self.momentum_n:.2f}-{self.momentum_generous_n:.2f} N "
                f"(momentum, r {self.r_own:.2f}-{STATIC_OVER_KINETIC_MAX:g}); the first pour slip implies "
                f"C = {self.pour_capacity_n:.2f} N")


def drop_bounds(plant: Any = None, first_slip_ml: float = 200.0) -> list[DropBounds]:
    """Claim 4's bounds for every paper bottle of ``plant`` (default: the built-in bottles).

    Examples
    --------
    >>> [round(b.energy_n, 2) for b in drop_bounds()]
    [2.16, 2.16, 2.16]
    """
    from ..sim import BOTTLES, PAPER_DROP, PAPER_POUR  # deferred: heavy (numba kernels)

    bottles = BOTTLES if plant is None else plant.bottles
    out = []
    for name in BOTTLE_ORDER:
        b = bottles[name]
        h = PAPER_DROP.height_m + b.height_m
        args = (b.mass_kg, PAPER_DROP.mass_kg, h, b.grip_travel_m)
        out.append(DropBounds(name, h, first_slip_capacity_n(b.mass_kg, first_slip_ml, rate_l_min=PAPER_POUR.rate_l_min,
                                                             fall_height_m=PAPER_POUR.fall_height_m),
                              drop_slipout_capacity_n(*args), drop_momentum_capacity_n(*args, b.mu_s / b.mu_k),
                              drop_momentum_capacity_n(*args, STATIC_OVER_KINETIC_MAX), b.mu_s / b.mu_k))
    return out


def _drop_success(ci: ClaimInput) -> list[Part]:
    kd, nd = ci.success("drop", BOTTLE_ORDER, DATH)
    kf, nf = ci.success("drop", BOTTLE_ORDER, FIXED)
    if not nd or not nf:
        return [Part(NOT_DECIDABLE, "this run has no drop trials of DATH or of the fixed threshold", label="cells")]
    d, dlo, dhi = wilson_interval(kd, nd, ci.level)
    f, flo, fhi = wilson_interval(kf, nf, ci.level)
    band = about_rate_band()
    parts = [_part(dlo, dhi, band, d, "DATH's drop success about 80 % ({:.1f}-{:.1f} %)".format(
                       *(100 * x for x in band)), f"DATH {kd}/{nd} ({100 * d:.0f} %)", "see the bounds",
                   (False, False), label="DATH about 80 %", level=ci.level),
             _part(flo, fhi, (-INF, 0.5), f, "fixed's drop success under 50 %",
                   f"fixed {kf}/{nf} ({100 * f:.0f} %)", "see the bounds", label="fixed under 50 %",
                   level=ci.level)]
    if all(p.verdict == HOLDS for p in parts):
        return parts
    bounds = drop_bounds(ci.plant)
    if any(b.possible for b in bounds):
        return parts
    worst = max(bounds, key=lambda b: b.energy_n / b.pour_capacity_n)
    shape = tilt_and_taper(ci.plant)
    if shape:
        return [Part(FAILS_PLANT, (
            f"drop success DATH {kd}/{nd}, fixed {kf}/{nf}: no drop knocks the bottle out. Sliding alone cannot "
            f"({worst.text()}; the bounds assume {DROP_ASSUMPTIONS}), and on this plant neither can the "
            f"degrees of freedom the bounds leave out: {shape}. A grasp calibrated to the paper's first pour "
            "slip holds the 10 g drop; the paper's slip-outs need a weaker grasp, a larger or farther-off-axis "
            "impact, or a softer tilt than these (docs/study.md: the fraction of plants on which it holds)"), d,
            "DATH about 80 % and fixed under 50 %, needing slip-outs", dlo, dhi, label="slip-outs")]
    return [Part(NOT_DECIDABLE, (
        f"drop success DATH {kd}/{nd}, fixed {kf}/{nf}: no drop knocks the bottle out, and none can on a plant "
        f"calibrated to the paper's first pour slip if the bottle only slides: {worst.text()}. The bounds assume "
        f"{DROP_ASSUMPTIONS}; the simulator has exactly this one degree of freedom, so the paper's slip-outs need "
        "what it lacks (tilt, fingertips moving onto a tapering shoulder)"), d,
        "DATH about 80 % and fixed under 50 %, needing slip-outs", dlo, dhi, label="slip-outs")]




_CLUSTER = "every slip a trial, clustered by its trial; " + TOLERANCES["censored"] + "; " + TOLERANCES["intervals"]
_ALL = (DATH, FIXED, NMSD, SWT)

#: The paper's eleven claims, in order: its own sentences, where they are, the reading judged.
CLAIMS: tuple[Claim, ...] = (
    Claim(1, '"oscillated around a low value (300 to 500 mV)"; "around 3.32 and 3.35 V"',
          'White: "oscillated around a low value (300 to 500 mV)"; black: "oscillated around 3.32 and 3.35 V '
          'during motion"', "III-A, Figs. 6B, 8B",
          "the scan's levels on white and black; the simulated surface is calibrated to them (not decidable: "
          "calibrated input); a real or replayed scan decides it", TOLERANCES["a voltage"], _scan_levels),
    Claim(2, '"spikes could be generated after relative movements (slip) as low as 0.09 mm"',
          '"the fixed threshold strategy ... produced a smaller number of spikes than DATH"; "for both cases, the '
          'spikes would be generated within a minimum distance of 0.09 mm"; conclusion: "spikes could be '
          'generated after relative movements (slip) as low as 0.09 mm"', "III-A, Figs. 6D, 7D; V",
          "(a) DATH more spikes than fixed on the same scan; (b, primary: the conclusion's reading) a slide of "
          "about 0.09 mm suffices for a spike, for both; (c) consecutive spikes at least about 0.09 mm apart",
          f"{TOLERANCES['a length']}; on most of the texture seeds (Wilson)", _scan_spikes),
    Claim(3, '"The response time decreased for bottles TR, DK, and TX" (DATH vs fixed)',
          '"DATH improved both slip detection and suppression performance when compared to using a fixed '
          'threshold. The response time decreased for bottles TR, DK, and TX (DATH: 50 ± 6.48 ms, 88.2 ± 24 ms '
          'and 31.3 ± 4.16 ms, respectively; fixed threshold: 55 ± 9.16 ms, 93.75 ± 66 ms and 45 ± 4.24 ms, '
          'respectively)"', "III-B, Fig. 13", "drop: DATH's mean response below fixed's, per bottle (one-sided)",
          _CLUSTER, _drop_faster, (DATH, FIXED)),
    Claim(4, '"less than 50% of successful trials" (fixed); "increased to 80% on average" (DATH)',
          '"The fixed threshold strategy showed a poor performance in preventing slip (less than 50% of successful '
          'trials). However, by employing DATH, the number of successful trials increased to 80% on average"; '
          'abstract: "suppressed before complete object slippage in 80% of all experimental trials"',
          "III-B; abstract", "drop: fixed's success under 50 % (one-sided), DATH's about 80 %",
          TOLERANCES["about a rate"] + "; slip-out bounds with named assumptions", _drop_success, (DATH, FIXED)),
    Claim(5, '"The total time required to suppress slip by NMSD was, on average, more than twice of that '
             'achieved by DATH"',
          '"The total time required to suppress slip by NMSD was, on average, more than twice of that achieved '
          'by DATH"', "III-B", "drop: mean over the bottles of NMSD's total over DATH's > 2 (one-sided)",
          TOLERANCES["more than twice"] + "; " + _CLUSTER, _nmsd_twice, (DATH, NMSD)),
    Claim(6, '"DATH successfully prevented complete slippage in all trials"; two slips, "about 200 ml" and '
             '"about 400 ml"',
          '"two distinct slips were observed in most of the trials" (pour, all methods); Fig. 15 (DATH, DK): '
          '"the first slip occurred at about 200 ml, and the second ... about 400 ml"; "DATH successfully '
          'prevented complete slippage in all trials"', "II-D, III-C, Fig. 15",
          "(a) DATH's pour success 100 %; (b) more than half of all pour trials show two slips; (c) DATH's pours "
          "slip near 200 and 400 ml (all primary)",
          f"most: {TOLERANCES['most']}; near: {TOLERANCES['near a volume']}", _pour_dath, _ALL),
    Claim(7, '"DATH and SWT-SD showed a faster response when compared to the NMSD and fixed threshold" (pour)',
          'TR: "DATH and SWT-SD showed a faster response when compared to the NMSD and fixed threshold"; DK: '
          '"DATH and SWT-SD showed a similar response time, and both were again faster than NMSD and the fixed '
          'threshold"; TX: "DATH showed the fastest response time"', "III-C, Fig. 16",
          "pour, per bottle, every slip: TR and DK: DATH and SWT-SD each below NMSD and fixed; TX: DATH below "
          "fixed", _CLUSTER, _pour_faster, _ALL),
    Claim(8, '"an overall response time of less than 85 ms"',
          '"the DATH method was capable of achieving an overall response time of less than 85 ms"; abstract: '
          '"The response time (Δt < 85 ms)"', "IV; abstract",
          "primary: DATH's mean response over every bottle and both experiments < 85 ms; part: every cell < 85 ms",
          TOLERANCES["a response time"] + "; " + _CLUSTER, _under_85, (DATH,)),
    Claim(9, '"DATH performed better for the majority of the cases ... For the dark bottle (DK), SWT-SD showed '
             'the fastest response."',
          '"DATH performed better for the majority of the cases, showing faster reaction time for bottles TR and '
          'TX. For the dark bottle (DK), SWT-SD showed the fastest response."', "III-B, Fig. 13",
          "drop: DATH faster than NMSD and SWT-SD on TR and TX; SWT-SD the fastest method on DK", _CLUSTER,
          _majority, _ALL),
    Claim(10, '"for the textured bottle (TX), DATH showed the best results"',
          '"for the textured bottle (TX), DATH showed the best results, where complete slippage was prevented in '
          '90% of the trials and took the least amount of time to suppress slip (DATH: 274.4 ms)"', "III-B",
          "drop, DATH: TX's success the highest of the three bottles and TX's total time the lowest",
          "Newcombe's interval of two rates; " + _CLUSTER, _tx_best, (DATH,)),
    Claim(11, '"DATH performed consistently better than the NMSD and fixed threshold strategies" (total time)',
          '"In terms of the total time required to suppress object slippage, DATH performed consistently better '
          'than the NMSD and fixed threshold strategies" (drop); pour: "DATH again performed consistently better '
          'than NMSD and the fixed threshold"', "III-B, III-C, Figs. 14, 17",
          "total time: DATH below NMSD and below fixed, per bottle, in both experiments", _CLUSTER, _totals,
          (DATH, NMSD, FIXED)),
)


def undecided_methods(results: Sequence[ClaimResult]) -> tuple[str, ...]:
    """The methods whose trials decide the claims ``results`` leaves unresolved (what to replicate).

    Examples
    --------
    >>> r = ClaimResult(10, "t", UNRESOLVED, "", 0.0, -1.0, 1.0, "", "", "")
    >>> undecided_methods([r])
    ('dath',)
    >>> undecided_methods([])
    ()
    """
    by_number = {c.number: c for c in CLAIMS}
    wanted = {m for r in results if r.verdict == UNRESOLVED for m in by_number[r.number].methods}
    return tuple(m for m in method_names(paper=True) if m in wanted)


def replicate_seed(master: int, k: int) -> int:
    """Master seed of replicate ``k`` (1, 2, ...) of a run with master seed ``master``.

    Derived with ``numpy.random.SeedSequence`` so that replicates of nearby master seeds
    never share trials; the same ``(master, k)`` gives the same seed on every machine.

    Examples
    --------
    >>> replicate_seed(20191215, 1) == replicate_seed(20191215, 1) != replicate_seed(20191215, 2)
    True
    """
    if k < 1:
        raise ValueError(f"replicate k: {k} (replicates count from 1; 0 is the run itself)")
    return int(np.random.SeedSequence([int(master), int(k)]).generate_state(1, np.uint32)[0])




def judge(rows: Sequence[Any], scan: Any = None, plant: Any = None, *, measured: Any = None,
          reading: Reading | None = None) -> list[ClaimResult]:
    """Judge every claim of :data:`CLAIMS` from a run's rows, its scan ensemble and its plant.

    Parameters
    ----------
    rows : sequence of mapping
        Per-slip result rows (see :class:`ClaimInput`).
    scan : ScanEnsemble, optional
        The simulated characterization scan over texture seeds (claim 2).
    plant : Plant, optional
        The simulated plant (claim 4's bounds).
    measured : ScanEnsemble, optional
        A real or replayed scan (claim 1; :func:`measured_scan`).
    reading : Reading, optional
        The judge's choices (default: :class:`Reading`, one look).

    Returns
    -------
    list of ClaimResult
        One per claim, in order.

    Examples
    --------
    >>> [r.verdict for r in judge([])][:3]
    ['not-decidable', 'not-decidable', 'not-decidable']
    """
    ci = ClaimInput(list(rows), scan, plant, measured, reading or plant_reading(plant))
    return [_combine(c, c.judge(ci)) for c in CLAIMS]


def plant_reading(plant: Any, looks: int = 1) -> Reading:
    """The judge's reading a plant carries (a study draws the cutoff and tolerances), else the default.

    Examples
    --------
    >>> from slipreflex.sim.uncertain import plant_from_values
    >>> plant_reading(plant_from_values({"response_cutoff": 800.0})).cutoff_ms
    800.0
    >>> plant_reading(None) == Reading()
    True
    """
    got = dict(getattr(plant, "readings", None) or {})
    keys = ("cutoff_ms", "time_tol_ms", "near_ml")
    return Reading(**{k: float(got[k]) for k in keys if k in got}, looks=looks)


def scan_ensemble_for(seed: int, sensor: Any = None, n: int | None = None):
    """The scan ensemble a run judges claim 2 on: ``n`` texture seeds from ``seed`` (cached).

    Examples
    --------
    >>> len(scan_ensemble_for(3, n=2))
    2
    """
    from ..sim.scan import ENSEMBLE_SEEDS  # deferred: heavy (llvmlite, numba, scipy)

    return _ensemble(int(seed), sensor, int(ENSEMBLE_SEEDS if n is None else n))


@functools.lru_cache(maxsize=4)
def _ensemble(seed: int, sensor: Any, n: int):
    from ..sim.scan import scan_ensemble  # deferred: heavy (llvmlite, numba, scipy)

    return scan_ensemble(n, base=seed, sensor=sensor)


def measured_scan(path: str | Path):
    """A recorded scan (CSV with ``t``, ``position_mm`` and ``volts``, as ``slipreflex scan`` writes) as one entry.

    The paper's layout (:data:`slipreflex.sim.scan.PAPER_LAYOUT`) says where white and
    black lie along the path; the levels and spikes are found as for a simulated scan.
    Raises ``ValueError`` naming the file and what is wrong.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from slipreflex.sim.scan import scan
    >>> r = scan(seed=4)
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "scan.csv"
    >>> _ = p.write_text("t,position_mm,volts\\n" + "".join(
    ...     f"{float(a)!r},{float(b)!r},{float(c)!r}\\n" for a, b, c in zip(r.t, r.position * 1e3, r.volts)))
    >>> round(float(measured_scan(p).black_hi[0]), 2) > 3
    True
    """
    from ..sim.scan import PAPER_LAYOUT, ScanEnsemble, ScanResult  # deferred: heavy (numba kernels)

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such scan file")
    with path.open(newline="") as fh:
        reader = csv.DictReader(line for line in fh if not line.startswith("#"))
        gone = [c for c in ("t", "position_mm", "volts") if c not in (reader.fieldnames or ())]
        if gone:
            raise ValueError(f"{path}: not a scan recording: no column {', '.join(gone)}")
        cols: dict[str, list[float]] = {"t": [], "position_mm": [], "volts": []}
        for i, d in enumerate(reader, start=2):
            for k in cols:
                v = _num(d.get(k))
                if v != v:
                    raise ValueError(f"{path}, line {i}: {k} is not a number ({d.get(k)!r})")
                cols[k].append(v)
    t, pos, volts = (np.asarray(cols[k]) for k in ("t", "position_mm", "volts"))
    if t.size < 3 or not np.all(np.diff(t) > 0):
        raise ValueError(f"{path}: need at least 3 samples with increasing t")
    regions, start = [], 0.0
    for surface, length in PAPER_LAYOUT:
        name = surface if isinstance(surface, str) else surface.name
        regions.append((name, start, start + length))
        start += length
    fs = float(1.0 / np.median(np.diff(t)))
    speed = float((pos[-1] - pos[0]) * 1e-3 / (t[-1] - t[0]))
    a = ScanResult(t, pos * 1e-3, volts, regions, speed, fs).analyse()
    nan = (math.nan, math.nan)
    lv = {f"{r}_{e}": np.array([a.ranges.get(r, nan)[i]]) for r in ("white", "black")
          for i, e in enumerate(("lo", "hi"))}
    gaps = {m: [v for (mm, r), v in a.min_spacing_mm.items() if mm == m and r in ("white", "black") and v is not None]
            for m in (FIXED, DATH)}
    return ScanEnsemble(seeds=np.array([0]), step_mm=speed * 1e3 / fs, **lv,
                        fixed_gap=np.array([min(gaps[FIXED], default=math.nan)]),
                        dath_gap=np.array([min(gaps[DATH], default=math.nan)]),
                        fixed_spikes=np.array([a.spikes[FIXED]]), dath_spikes=np.array([a.spikes[DATH]]))


def judge_run(rows: Sequence[Any], *, seed: int = 0, plant: Any = None, scan_seeds: int | None = None,
              measured: Any = None, looks: int = LOOKS) -> list[ClaimResult]:
    """Judge the claims of a run: its rows, a scan ensemble of its slip sensor, its plant, the design's looks.

    The ensemble (:func:`scan_ensemble_for`: :data:`slipreflex.sim.scan.ENSEMBLE_SEEDS`
    texture seeds from ``seed``, with the plant's slip sensor) supplies claim 2; every
    interval is at the level of the replication design's ``looks`` (:func:`looks_level`).

    Examples
    --------
    >>> [r.verdict for r in judge_run([], seed=0, scan_seeds=4)][2]
    'not-decidable'
    """
    sensor = None if plant is None else plant.slip_sensor
    return judge(rows, scan_ensemble_for(seed, sensor, scan_seeds), plant, measured=measured,
                 reading=plant_reading(plant, looks))


#: Columns of claims.csv (``reproduce``, ``claims`` and, with a study's counts, ``study``).
CLAIMS_CSV_COLUMNS: tuple[str, ...] = ("claim", "verdict", "qualifier", "parts", "reason", "value", "criterion",
                                       "low", "high", "text", "where", "numbers")
#: Columns of claim_parts.csv: one row per part of every claim.
PARTS_CSV_COLUMNS: tuple[str, ...] = ("claim", "part", "primary", "verdict", "qualifier", "value", "low", "high",
                                      "criterion", "reason")


def _cell(v: Any) -> str:
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    return "" if v is None else str(v)


def write_claims_csv(path: str | Path, results: Sequence[Any], columns: Sequence[str] = CLAIMS_CSV_COLUMNS
                     ) -> Path:
    """Write the claims table as CSV (one row per claim; NaN as an empty cell).

    ``results`` holds :class:`ClaimResult` s or mappings with the columns.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = write_claims_csv(pathlib.Path(tempfile.mkdtemp()) / "claims.csv", judge([]))
    >>> p.read_text().splitlines()[0]
    'claim,verdict,qualifier,parts,reason,value,criterion,low,high,text,where,numbers'
    """
    path = Path(path)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(columns)
        for r in results:
            if isinstance(r, Mapping):
                d = r
            else:
                d = {c: getattr(r, "number" if c == "claim" else c, "") for c in columns if c != "parts"}
                d["parts"] = r.parts_text()
            w.writerow([_cell(d.get(c, "")) for c in columns])
    return path


def write_parts_csv(path: str | Path, results: Sequence[ClaimResult]) -> Path:
    """Write claim_parts.csv: every part of every claim with its class, interval and reason.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = write_parts_csv(pathlib.Path(tempfile.mkdtemp()) / "claim_parts.csv", judge([]))
    >>> p.read_text().splitlines()[1].split(",")[:4]
    ['1', 'scan levels', 'True', 'not-decidable']
    """
    path = Path(path)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(PARTS_CSV_COLUMNS)
        for r in results:
            for p in r.parts:
                w.writerow([_cell(x) for x in (r.number, p.label, str(p.primary), p.verdict, p.qualifier, p.value,
                                               p.low, p.high, p.criterion, p.reason)])
    return path


def read_claims_csv(path: str | Path) -> list[dict[str, str]]:
    """The rows of a claims.csv as dicts of strings.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = write_claims_csv(pathlib.Path(tempfile.mkdtemp()) / "c.csv", judge([]))
    >>> read_claims_csv(p)[0]["verdict"]
    'not-decidable'
    """
    with Path(path).open(newline="") as fh:
        return list(csv.DictReader(fh))


def _value(r: Any) -> str:
    if r.value != r.value:
        return "-"
    v = f"{r.value:.3g}"
    return v if r.low != r.low else f"{v} [{r.low:.3g}, {r.high:.3g}]"


def claims_markdown(results: Sequence[ClaimResult]) -> str:
    """The claims table as markdown (claim, where, class, parts, reason, value and interval, criterion).

    Examples
    --------
    >>> claims_markdown(judge([])).splitlines()[2].startswith('| 1 | "oscillated around')
    True
    """
    lines = ["| # | the paper says | where | class | parts (* primary) | reason | value [interval] | criterion |",
             "|---|---|---|---|---|---|---|---|"]
    for r in results:
        lines.append(f"| {r.number} | {r.text} | {r.where} | **{r.class_text}** | {r.parts_text()} | {r.reason} | "
                     f"{_value(r)} | {r.criterion or '-'} |")
    return "\n".join(lines)


def parts_markdown(results: Sequence[ClaimResult]) -> str:
    """Every part of every claim as markdown (claim, part, primary, class, value, reason).

    Examples
    --------
    >>> parts_markdown(judge([])).splitlines()[2].startswith("| 1 | scan levels | yes | not-decidable")
    True
    """
    lines = ["| # | part | primary | class | value [interval] | reason |", "|---|---|---|---|---|---|"]
    for r in results:
        for p in r.parts:
            lines.append(f"| {r.number} | {p.label or '-'} | {'yes' if p.primary else 'no'} | "
                         f"{p.verdict}{f' ({p.qualifier})' if p.qualifier else ''} | {_value(p)} | {p.reason} |")
    return "\n".join(lines)


def _counts(results: Sequence[ClaimResult]) -> str:
    n = {v: sum(r.verdict == v for r in results) for v in VERDICTS}
    return ", ".join(f"{n[v]} {v}" for v in VERDICTS if n[v]) or "none"


def claims_terminal(results: Sequence[ClaimResult]) -> str:
    """The claims table for the terminal: per claim, its class and short quote, its parts, its reason.

    Examples
    --------
    >>> print(claims_terminal(judge([])).splitlines()[0])
    paper's claims: 1 fails-paper, 10 not-decidable
    """
    lines = [f"paper's claims: {_counts(results)}"]
    for r in results:
        lines += [f"{r.number:>3} {r.class_text:18} {r.text} ({r.where})", f"{'':22}parts: {r.parts_text()}",
                  f"{'':22}{r.reason}"]
    return "\n".join(lines)


def explain(result: ClaimResult) -> str:
    """One claim in full: the paper's whole sentence, where, the reading, the tolerance, every part.

    Examples
    --------
    >>> print(explain(judge([])[10]).splitlines()[0])
    claim 11 (III-B, III-C, Figs. 14, 17): fails-paper
    """
    claim = {c.number: c for c in CLAIMS}[result.number]
    lines = [f"claim {result.number} ({result.where}): {result.class_text}", f"  the paper: {claim.quote}",
             f"  judged: {claim.reading}", f"  tolerance: {claim.tolerance}",
             "  class: the first, in the order " + ", ".join(VERDICTS) + ", among the primary parts", "  parts:"]
    for p in result.parts:
        lines.append(f"    [{p.label or '-'}]{' (primary)' if p.primary else ''} "
                     f"{p.verdict}{f' ({p.qualifier})' if p.qualifier else ''}: {p.reason}")
    return "\n".join(lines)


@dataclass(frozen=True)
class Contradiction:
    """One finding about the paper's own numbers.

    Attributes
    ----------
    topic : str
    finding : str
        What was computed, with the numbers, formulas and assumptions.
    inconsistent : bool
        True when the paper's numbers cannot all be true (under the assumptions named).

    Examples
    --------
    >>> Contradiction("t", "x", True).inconsistent
    True
    """

    topic: str
    finding: str
    inconsistent: bool


def window_phase_sd_ms(n: int = hw.WINDOW_N, fs: float = hw.DAQ_FS) -> float:
    """Sd (ms) a free-running window of ``n`` samples adds to a response time.

    The first command comes at the end of the window holding the first spike;
    with the slip's onset at a uniform phase inside a window of length
    ``T = n / fs``, that wait is uniform on [0, T): sd ``T / sqrt(12)``.

    Examples
    --------
    >>> round(window_phase_sd_ms(16, 1000 / 3), 2)
    13.86
    """
    return 1e3 * n / fs / math.sqrt(12.0)


def _bounds_item(plant: Any, first_slip_ml: float, simulate: bool) -> Contradiction:
    bounds = drop_bounds(plant, first_slip_ml)
    text = ("; ".join(b.text() for b in bounds) + ". Energy: C <= r[(M+m)g + mgh/d], no impact loss; momentum: "
            "C <= r[(M+m)g + m^2 g h/(d(M+m))], a fully inelastic impact, then sliding out against the grip; "
            "h = release height + bottle depth. Both assume " + DROP_ASSUMPTIONS + ".")
    if simulate:
        from ..sim import BOTTLES  # deferred: heavy (llvmlite, numba, scipy)
        from ..sim.calibration import drop_fall_capacity  # deferred: heavy (numba kernels)

        kw = None if plant is None else plant.rig_kwargs()
        sim = drop_fall_capacity((BOTTLES if plant is None else plant.bottles)["TR"], rig_kwargs=kw, iterations=8)
        text += (f" The simulated plant (open loop, sim.calibration.drop_fall_capacity) lets a 10 g drop knock TR "
                 f"out only below a capacity of {sim['capacity_g']:.0f} g, while its pour-calibrated grasp holds "
                 f"{sim['bottle_capacity_g']:.0f} g.")
    text += (" Under these assumptions the paper's drop slip-outs and its first pour slip near 200 ml cannot "
             "share one 0.8 N grasp; tilt or fingertips moving onto a tapering shoulder may change that.")
    return Contradiction("drop slip-outs beside the first pour slip (bounds, with their assumptions)", text,
                         not any(b.possible for b in bounds))


def _identical_totals() -> Contradiction:
    same, parts = 0, []
    for b in BOTTLE_ORDER:
        d, f = PAPER[("pour", "total_ms", b, DATH)], PAPER[("pour", "total_ms", b, FIXED)]
        hits = [fv is not None and math.floor(fv) == dv for dv, fv in ((d.mean, f.mean), (d.sd, f.sd))]
        same += sum(hits)
        parts.append(f"{b} DATH {d.text()} vs fixed {f.text()}")
    return Contradiction(
        "pour totals: fixed and DATH identical",
        f"{same} of {2 * len(BOTTLE_ORDER)} pour-total means and sds of DATH equal the fixed threshold's "
        f"truncated to whole ms ({'; '.join(parts)}); separate physical runs cannot agree to the digit",
        same == 2 * len(BOTTLE_ORDER))


def _window_sd() -> Contradiction:
    floor = window_phase_sd_ms()
    low = [(e, b, m, v.sd) for (e, metric, b, m), v in PAPER.items()
           if metric == "response_ms" and m in (FIXED, DATH) and v.sd is not None and v.sd < floor]
    cells = ", ".join(f"{e} {b} {_label(m)} {sd:g}" for e, b, m, sd in low)
    return Contradiction(
        "response sd below the window's phase",
        f"a free-running {hw.WINDOW_N}-sample window at {hw.DAQ_FS:.2f} Hz "
        f"({1e3 * hw.WINDOW_N / hw.DAQ_FS:.0f} ms) alone gives a response sd of "
        f"{floor:.1f} ms (T/sqrt(12), onset phase uniform); the paper reports less in "
        f"{len(low)} fixed/DATH cells ({cells} ms): only windows aligned to the perturbation allow it",
        bool(low))


def _own_table() -> list[Contradiction]:
    ci = ClaimInput([])
    out = []
    for c in CLAIMS:
        for p in c.judge(ci):
            if p.verdict == FAILS_PAPER:
                out.append(Contradiction(f"claim {c.number} on the paper's own table", f"{c.text}: {p.reason}", True))
    return out


def contradictions(first_slip_ml: float = 200.0, *, plant: Any = None, simulate: bool = True
                   ) -> list[Contradiction]:
    """What the paper's own numbers say about themselves: bounds, identical totals, sds, its table vs its claims.

    Parameters
    ----------
    first_slip_ml : float
        Volume at the paper's first pour slip (its Fig. 15: about 200 ml).
    plant : slipreflex.sim.uncertain.Plant, optional
        The simulated plant (default: the package's) whose open-loop drop is simulated.
    simulate : bool
        Also find, on the simulated plant, the largest capacity at which the
        drop still ends in complete slippage (about a second).

    Returns
    -------
    list of Contradiction

    Examples
    --------
    >>> [c.inconsistent for c in contradictions(simulate=False)][:3]
    [True, True, True]
    """
    return [_bounds_item(plant, first_slip_ml, simulate), _identical_totals(), _window_sd(), *_own_table()]


def contradictions_markdown(items: Sequence[Contradiction]) -> str:
    """The findings as a markdown list.

    Examples
    --------
    >>> contradictions_markdown([Contradiction("a", "b", True)])
    '- **a** (inconsistent): b'
    """
    return "\n".join(f"- **{c.topic}** ({'inconsistent' if c.inconsistent else 'consistent'}): {c.finding}"
                     for c in items)


def claims_section(results: Sequence[ClaimResult], items: Sequence[Contradiction] | None = None, *,
                   plant: Any = None) -> list[str]:
    """The report.md sections: the claims judged, the tolerances, the paper's own numbers.

    Examples
    --------
    >>> claims_section(judge([]), [])[0]
    "## The paper's claims, judged on this run"
    """
    lines = ["## The paper's claims, judged on this run", "",
             "Each claim of the paper (docs/method.md) judged from this run's results.csv, a characterization "
             "scan over texture seeds and the plant (`slipreflex.analysis.claims`; the same table is in "
             f"claims.csv). Classes: {', '.join(VERDICTS)}. Count: {_counts(results)}.", "",
             claims_markdown(results), "",
             "Every part of every claim (claim_parts.csv; a claim's class is the first, in the order "
             + ", ".join(VERDICTS) + ", among its primary parts):", "", parts_markdown(results), "",
             "Tolerances (one definition each, none finer than the instrument or the paper's last digit): "
             + "; ".join(f"{k}: {v}" for k, v in TOLERANCES.items()) + ".", ""]
    items = contradictions(plant=plant) if items is None else items
    if items:
        lines += ["## The paper's own numbers", "",
                  "Computed from the paper's numbers (and the rig's geometry); reported, not chased.", "",
                  contradictions_markdown(items), ""]
    return lines
