"""The classes of a verdict, the judge's tolerances and intervals, and the types a claim is judged with.

:class:`Part` (one reading of a claim, with its interval and class), :class:`ClaimResult`
(a claim's class from its primary parts), :class:`ClaimInput` (what a judge reads: the
run's rows, the scan, the plant), :class:`Claim` (the paper's sentence and its judge), and
the intervals every judge uses. Re-exported by :mod:`slipreflex.analysis.claims`.

Examples
--------
>>> VERDICTS[0], VERDICTS[-1], LOOKS
('fails-definition', 'holds', 3)
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...core import hardware as hw
from ...files.csvfiles import cell_bool, cell_float
from ..stats import (
    Sample,
    look_level,
    wilson_interval,
)

__all__ = [
    "HOLDS", "FAILS_DEFINITION", "FAILS_PAPER", "FAILS_PLANT", "DEPENDS_PLANT", "UNRESOLVED", "NOT_DECIDABLE",
    "VERDICTS", "FAILING", "DECISIVE", "CALIBRATED_INPUT", "CONFIDENCE", "CENTRAL", "BOOTSTRAP_SEED", "VOLT_TOL",
    "TIME_TOL_MS", "LENGTH_TOL_MM", "NEAR_ML", "MOST", "UNDER_MS", "TOLERANCES", "stated_tolerance", "Reading",
    "Part", "Claim", "ClaimInput", "ClaimResult", "mean_interval", "difference_interval", "ratio_interval",
    "proportion_interval", "median_interval", "REPLICATES_MAX", "LOOKS", "looks_level", "about_rate_band"
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
    >>> from slipreflex.analysis.claims import CLAIMS
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


