"""The paper's claims as data, judged from a results table with intervals, each verdict with its reason.

Each of the paper's ten claims (``docs/method.md``, "The paper's claims") is a
:class:`Claim` with a judge function over a :class:`ClaimInput` (the per-slip
result rows of a run, the characterization scan over an ensemble of texture
seeds for claims 1-2, and the plant). :func:`judge` returns one
:class:`ClaimResult` per claim with one of six verdicts (:data:`VERDICTS`):

* ``holds``;
* ``fails-definition``: the method's equations or the paired design make it
  impossible (the reason says which);
* ``fails-paper``: the paper's own table violates it as stated;
* ``fails-plant``: the interval lies on the wrong side of the criterion on this
  plant (the reason names the physics that decides it);
* ``unresolved``: the run's 95 % interval straddles the criterion;
* ``not-decidable``: the run or the simulator lacks what decides it (the
  reason says what).

A claim with several parts takes the first of these classes, in the order
above, among its parts' verdicts (a definition beats the paper's numbers,
which beat the plant; noise beats a missing cell; "holds" needs every part).

**Noise is judged as noise.** A claim about a random quantity is never decided
by comparing two means: paired differences where the design is paired (every
method faces the same trial seeds), a two-sample bootstrap otherwise
(``scipy.stats.bootstrap``, BCa, 95 %, a fixed seed so the same rows give the
same interval), Wilson's interval for a success rate
(``scipy.stats.binomtest(...).proportion_ci(method="wilson")``). A comparison
holds when its whole interval satisfies the criterion, fails when the whole
interval violates it and is unresolved otherwise (for "about" claims this is
the two-one-sided-tests logic of an equivalence test).

**Tolerances, defined once** (:data:`TOLERANCES`; none finer than the
instrument or the paper's stated precision): a voltage within one ADC step
(4.88 mV) or half a unit of the paper's last digit, whichever is larger; a
time within one DAQ sample (3 ms: the response is measured on the DAQ's
samples); a length within one scan sample's travel (0.003 mm) or half the
paper's last digit (0.005 mm of "0.09 mm"); "about 80 %" within 10 points;
"about twice" a ratio within a factor 1.5 of 2 (the paper's own per-bottle
ratios, 2.2-2.8, lie inside); "near 200 and 400 ml" within 50 ml (a quarter
of the distance between them); "most" more than half. The scan claims ask
whether the paper's value lies inside the model's central 90 % over the
ensemble's texture seeds.

**Replication where one run cannot decide.** A claim whose interval straddles
its criterion on one run's trials is not left to that run's draws: ``slipreflex
reproduce`` runs the grid again on derived master seeds (:func:`replicate_seed`),
only for the methods the undecided claims read (:attr:`Claim.methods`), and
judges every claim on the pooled rows, until no claim is unresolved or
:data:`REPLICATES_MAX` replicates ran (``slipreflex.replication.replicate_undecided``).
The pooled rows are written as ``replicates.csv``; ``slipreflex claims`` reads
it beside the results it judges.

Claim 4 rests on :func:`drop_bounds`: the largest grasp capacity at which the
10 g drop (falling its release height plus the bottle's depth) can end in
complete slippage, by energy and by momentum, with the assumptions named.

Examples
--------
>>> rows = [{"experiment": "drop", "bottle": b, "method": m, "trial": k, "seed": k, "event": 0,
...          "n_events": 1, "response_ms": r + k, "total_ms": 100.0, "success": True}
...         for b in ("TR", "DK", "TX") for k in range(6) for m, r in (("dath", 40.0), ("fixed", 50.0))]
>>> res = {c.number: c for c in judge(rows)}
>>> res[3].verdict, res[3].criterion
('holds', 'DATH minus fixed mean response < 0 ms on every bottle')
>>> res[1].verdict
'not-decidable'
"""

from __future__ import annotations

import csv
import functools
import math
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import hardware as hw
from ..csvfiles import cell_bool, cell_float
from ..methods import DATH, FIXED, NMSD, SWT
from ..methods import label as _label
from ..methods import names as method_names
from .paper import BOTTLE_ORDER, EXPERIMENTS, PAPER

__all__ = [
    "HOLDS", "FAILS_DEFINITION", "FAILS_PAPER", "FAILS_PLANT", "UNRESOLVED", "NOT_DECIDABLE", "VERDICTS",
    "FAILING", "CONFIDENCE", "CENTRAL", "BOOTSTRAP_SEED", "VOLT_TOL", "TIME_TOL_MS", "LENGTH_TOL_MM",
    "ABOUT_RATE_POINTS", "ABOUT_RATIO_FACTOR", "NEAR_ML", "MOST", "TOLERANCES", "stated_tolerance",
    "Part", "Claim", "ClaimInput", "ClaimResult", "CLAIMS", "CLAIMS_CSV_COLUMNS", "judge", "judge_run",
    "scan_ensemble_for", "write_claims_csv", "read_claims_csv", "claims_section", "claims_markdown",
    "claims_terminal", "mean_interval", "difference_interval", "ratio_interval", "proportion_interval",
    "median_interval", "DropBounds", "drop_bounds", "Contradiction", "contradictions",
    "contradictions_markdown", "window_phase_sd_ms", "drop_slipout_capacity_n", "drop_momentum_capacity_n",
    "first_slip_capacity_n", "STATIC_OVER_KINETIC_MAX", "REPLICATES_MAX", "tilt_and_taper", "replicate_seed",
    "undecided_methods",
]

HOLDS = "holds"
FAILS_DEFINITION = "fails-definition"
FAILS_PAPER = "fails-paper"
FAILS_PLANT = "fails-plant"
UNRESOLVED = "unresolved"
NOT_DECIDABLE = "not-decidable"
#: The six verdicts, in the order a claim's parts decide it (and tables list them).
VERDICTS: tuple[str, ...] = (FAILS_DEFINITION, FAILS_PAPER, FAILS_PLANT, UNRESOLVED, NOT_DECIDABLE, HOLDS)
#: The verdicts that say a claim fails.
FAILING: tuple[str, ...] = (FAILS_DEFINITION, FAILS_PAPER, FAILS_PLANT)

#: Confidence level of every interval of a mean, difference, ratio or rate.
CONFIDENCE: float = 0.95
#: The scan claims: the paper's value must lie inside this central fraction of the model's ensemble.
CENTRAL: float = 0.90
#: Seed of every bootstrap (the same rows give the same interval).
BOOTSTRAP_SEED: int = 0
_RESAMPLES = 4999

#: Response-time tolerance (ms): one DAQ sample, the resolution responses are measured with.
TIME_TOL_MS: float = 1e3 / hw.DAQ_FS
#: "about" a length (mm): one scan sample's travel at 1 mm/s, or half the paper's last digit if larger.
LENGTH_TOL_MM: float = max(1.0 / hw.DAQ_FS, 0.005)
#: "about" a success rate: within this many percentage points (as a fraction).
ABOUT_RATE_POINTS: float = 0.10
#: "about twice": the ratio within a factor ABOUT_RATIO_FACTOR of 2 (1.33 .. 3.0).
ABOUT_RATIO_FACTOR: float = 1.5
#: "near 200 and 400 ml": the median volume at each slip within this many ml.
NEAR_ML: float = 50.0
#: "most": more than this fraction.
MOST: float = 0.5
#: At most this many replicate grids (on derived master seeds) for claims one run leaves unresolved.
REPLICATES_MAX: int = 10
#: The 85 ms of claim 8.
UNDER_MS: float = 85.0


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


#: Every tolerance in words, as the reports print it (each with its reason).
TOLERANCES: dict[str, str] = {
    "a voltage": f"one ADC step ({hw.ADC_LSB * 1e3:.2f} mV) or half the paper's last digit, the larger",
    "a response time": f"one DAQ sample ({TIME_TOL_MS:.1f} ms), the resolution responses are measured with",
    "a length": f"{LENGTH_TOL_MM:g} mm: half the last digit of the paper's 0.09 mm (one scan sample is 0.003 mm)",
    "about a rate": f"within ±{100 * ABOUT_RATE_POINTS:g} percentage points",
    "about twice": f"a ratio of {2 / ABOUT_RATIO_FACTOR:.2f} .. {2 * ABOUT_RATIO_FACTOR:.1f} (the paper's own "
                   "per-bottle ratios are 2.2-2.8)",
    "near a volume": f"median within ±{NEAR_ML:g} ml (a quarter of the 200 ml between the two slips)",
    "most": f"more than {100 * MOST:g} % of DATH's pours",
    "intervals": f"{100 * CONFIDENCE:g} %: bootstrap (BCa) of means, paired differences and ratios, Wilson for "
                 f"rates; scan: the model's central {100 * CENTRAL:g} % over its texture seeds",
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


def _boot(data: tuple, stat: Callable, *, paired: bool = False, method: str = "BCa") -> tuple[float, float]:
    """A 95 % bootstrap interval of ``stat`` (vectorized, with an ``axis``); NaN with fewer than 2 values."""
    from scipy.stats import bootstrap  # deferred: heavy (scipy)

    if min(len(d) for d in data) < 2:
        return math.nan, math.nan
    if all(np.ptp(d) == 0 for d in data):        # no spread: the interval is the point
        v = float(stat(*data, axis=-1))
        return v, v
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = bootstrap(data, stat, paired=paired, confidence_level=CONFIDENCE, n_resamples=_RESAMPLES,
                      method=method, vectorized=True, rng=np.random.default_rng(BOOTSTRAP_SEED))
    lo, hi = float(r.confidence_interval.low), float(r.confidence_interval.high)
    if not (math.isfinite(lo) and math.isfinite(hi)) and method == "BCa":
        return _boot(data, stat, paired=paired, method="percentile")
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


def median_interval(x: Iterable[Any]) -> tuple[float, float, float, int]:
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
    lo, hi = _boot((a,), _median, method="percentile")
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
    """One part of a claim judged: its verdict, why, and the interval behind it.

    Examples
    --------
    >>> Part(HOLDS, "ok", 1.0, "x < 2", 0.5, 1.5).verdict
    'holds'
    """

    verdict: str
    reason: str
    value: float = math.nan
    criterion: str = ""
    low: float = math.nan
    high: float = math.nan


@dataclass(frozen=True)
class ClaimResult:
    """The verdict on one claim, its reason and the numbers behind it.

    Attributes
    ----------
    number : int
    text : str
    verdict : str
        One of :data:`VERDICTS`.
    reason : str
        Why: the equation, the paper's cell, the physics, the interval or what is missing.
    value, low, high : float
        The deciding part's estimate and its interval (NaN where none applies).
    criterion : str
        What the value was held against.
    numbers : str
        Every part's numbers.
    tolerance : str
        How the paper's words were made numbers.

    Examples
    --------
    >>> ClaimResult(9, "DK is DATH's slowest bottle", HOLDS, "r", 1.0, 0.5, 2.0, "c", "n", "t").verdict
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


@dataclass(frozen=True)
class ClaimInput:
    """What the claims are judged from.

    Parameters
    ----------
    rows : sequence of mapping
        Per-slip result rows (results.csv columns); values may be strings as
        read from a CSV.
    scan : ScanEnsemble, optional
        The characterization scan over texture seeds
        (:func:`slipreflex.sim.scan.scan_ensemble`); None: claims 1-2 are not decidable.
    plant : Plant, optional
        The simulated plant (claim 4's bounds; default: the built-in bottles).

    Examples
    --------
    >>> ClaimInput([]).values("drop", "TR", "dath", "response_ms")
    []
    """

    rows: Sequence[Any]
    scan: Any = None
    plant: Any = None
    _cells: dict = field(default_factory=dict, init=False, repr=False, compare=False)

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

    def pairs(self, experiment: str, bottle: str, a: str, b: str, column: str = "response_ms",
              first_only: bool = False) -> tuple[list[float], list[float]]:
        """Values of methods ``a`` and ``b`` on the same trial seed and slip (both finite).

        Examples
        --------
        >>> rows = [{"experiment": "drop", "bottle": "TR", "method": m, "trial": 0, "seed": 5, "event": 0,
        ...          "response_ms": v} for m, v in (("dath", 30), ("fixed", 30))]
        >>> ClaimInput(rows).pairs("drop", "TR", "dath", "fixed")
        ([30.0], [30.0])
        """
        def keyed(m: str) -> dict:
            out = {}
            for r in self.cell(experiment, bottle, m):
                if first_only and _count(_get(r, "event")) != 0:
                    continue
                v = _num(_get(r, column))
                if v == v:
                    out[(str(_get(r, "trial")), str(_get(r, "seed")), _count(_get(r, "event")))] = v
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
        The claim in the paper's words.
    tolerance : str
        How those words were made numbers.
    judge : callable
        ``judge(ClaimInput) -> list of Part``.
    methods : tuple of str
        The methods whose trials decide it: what a replicate grid runs when one run
        leaves it unresolved (empty: the trials do not decide it, as for the scan).

    Examples
    --------
    >>> CLAIMS[0].number, CLAIMS[-1].text
    (1, "TX is DATH's best bottle")
    """

    number: int
    text: str
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
    return "-" if x != x else f"{x:.{digits}f}"


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
          physics: str, strict: tuple[bool, bool] = (True, True)) -> Part:
    """A part decided by an interval against ``band``: holds / fails on this plant (``physics``) / unresolved."""
    v = _side(lo, hi, band, strict)
    reason = {HOLDS: numbers, FAILS_PLANT: f"{numbers}; on this plant: {physics}",
              UNRESOLVED: f"{numbers}: the {100 * CONFIDENCE:g} % interval {_ci(lo, hi, 2)} straddles "
                          f"the criterion ({criterion})"}[v]
    return Part(v, reason, value, criterion, lo, hi)


def _combine(number: int, text: str, tolerance: str, parts: list[Part]) -> ClaimResult:
    order = {v: i for i, v in enumerate(VERDICTS)}
    parts = parts or [Part(NOT_DECIDABLE, "nothing to judge")]
    d = min(parts, key=lambda p: order[p.verdict])
    numbers = "; ".join(p.reason for p in parts)
    reason = numbers if d.verdict == HOLDS else d.reason      # a claim holds on all its parts: say them all
    return ClaimResult(number, text, d.verdict, reason, d.value, d.low, d.high, d.criterion, numbers, tolerance)


# --- the paper's own numbers -----------------------------------------------------------------

def _paper_mean(experiment: str, bottle: str, method: str) -> float:
    v = PAPER.get((experiment, "response_ms", bottle, method))
    return math.nan if v is None or v.mean is None else float(v.mean)


def _paper_part(bad: list[str], what: str) -> list[Part]:
    """A fails-paper part when the paper's own table breaks the claim (``bad``: its cells)."""
    if not bad:
        return []
    return [Part(FAILS_PAPER, f"the paper's own table breaks it: {', '.join(bad)} ({what})")]


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
    1: "the model's test surface (reflectance and texture, calibrated to the ensemble's median ranges) "
       "puts the paper's level outside the spread of its texture draws",
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
    9: "the bottles' surfaces (reflectance, texture) and how the hand's own motion shows on them",
    10: "the hand's own motion shows most on the textured TX, so its response and totals are not the best",
}


def _scan_levels(ci: ClaimInput) -> list[Part]:
    e = ci.scan
    if e is None:
        return [Part(NOT_DECIDABLE, "this run judged no characterization scan")]
    # as the paper states them: "300 to 500 mV" (its results text) and "3.32 and 3.35 V"
    want = (("white_lo", 0.3, "300"), ("white_hi", 0.5, "500"), ("black_lo", 3.32, "3.32"),
            ("black_hi", 3.35, "3.35"))
    inside, parts = [], []
    tol = {stat: VOLT_TOL(text) for stat, _, text in want}
    for stat, volts, _ in want:
        lo, hi = e.band(stat, CENTRAL)
        inside.append(lo - tol[stat] <= volts <= hi + tol[stat])
        parts.append(f"{stat.replace('_', ' ')} {lo:.3f}-{hi:.3f} V (paper {volts:g})")
    ok = ((e.white_lo >= 0.3 - tol["white_lo"]) & (e.white_hi <= 0.5 + tol["white_hi"])
          & (e.black_lo >= 3.32 - tol["black_lo"]) & (e.black_hi <= 3.35 + tol["black_hi"]))
    frac, flo, fhi = proportion_interval(int(ok.sum()), len(e))
    criterion = (f"each paper level inside the model's central {100 * CENTRAL:g} % over {len(e)} texture seeds "
                 "(± the voltage tolerance)")
    numbers = (f"central {100 * CENTRAL:g} %: " + ", ".join(parts)
               + f"; the paper's ranges hold as stated on {100 * frac:.0f} % of the seeds")
    verdict = HOLDS if all(inside) else FAILS_PLANT
    reason = numbers if verdict == HOLDS else f"{numbers}; on this plant: {PHYSICS[1]}"
    return [Part(verdict, reason, frac, criterion, flo, fhi)]


def _scan_spikes(ci: ClaimInput) -> list[Part]:
    e = ci.scan
    if e is None:
        return [Part(NOT_DECIDABLE, "this run judged no characterization scan")]
    parts = []
    lo, hi = e.band("fixed_gap", CENTRAL)
    ok = lo - LENGTH_TOL_MM <= 0.09 <= hi + LENGTH_TOL_MM
    fg = e.fixed_gap[np.isfinite(e.fixed_gap)]
    frac, flo, fhi = proportion_interval(int((fg >= 0.09 - LENGTH_TOL_MM).sum()), len(e))
    text = (f"fixed threshold's smallest spacing: central {100 * CENTRAL:g} % {lo:.3f}-{hi:.3f} mm "
            f"(paper 0.09; at least 0.09 mm on {100 * frac:.0f} % of {len(e)} seeds)")
    parts.append(Part(HOLDS if ok else FAILS_PLANT, text if ok else f"{text}; on this plant: {PHYSICS[2]}",
                      frac, "the paper's 0.09 mm inside the model's central 90 %", flo, fhi))
    dlo, dhi = e.band("dath_gap", CENTRAL)
    one = np.isclose(e.dath_gap, e.step_mm, rtol=0.01)
    dfrac, dflo, dfhi = proportion_interval(int(one.sum()), len(e))
    if dhi < 0.09 - LENGTH_TOL_MM and dfrac >= CENTRAL:
        parts.append(Part(FAILS_DEFINITION, (
            f"DATH's smallest spacing is one sample ({e.step_mm:.3f} mm at 1 mm/s) on {100 * dfrac:.0f} % of "
            f"{len(e)} seeds: after an arming spike Eq. 4 lowers the threshold for a window and fires on "
            "consecutive samples while the slope grows, so 'at least 0.09 mm' cannot hold for DATH"),
            dfrac, "DATH's spacing at least 0.09 mm", dflo, dfhi))
    else:
        parts.append(Part(HOLDS if dlo >= 0.09 - LENGTH_TOL_MM else FAILS_PLANT,
                          f"DATH's smallest spacing: central 90 % {dlo:.3f}-{dhi:.3f} mm", dfrac))
    more = e.dath_spikes > e.fixed_spikes
    m, mlo, mhi = proportion_interval(int(more.sum()), len(e))
    parts.append(_part(mlo, mhi, (MOST, INF), m, "DATH more spikes than fixed on most seeds",
                       f"DATH gives more spikes than fixed on {100 * m:.0f} % of seeds", PHYSICS[2]))
    return parts


def _missing(ci: ClaimInput, experiment: str, methods: Sequence[str], bottles: Sequence[str] = BOTTLE_ORDER,
             column: str = "response_ms") -> list[Part]:
    """A not-decidable part when the run lacks a cell the claim needs."""
    gone = [f"{_label(m)} {b}" for m in methods for b in bottles if not ci.cell(experiment, b, m)]
    return [Part(NOT_DECIDABLE, f"this run has no {experiment} rows of " + ", ".join(gone))] if gone else []


def _faster(ci: ClaimInput, experiment: str, bottle: str, fast: str, slow: str, physics: str) -> Part:
    """Is ``fast`` faster than ``slow`` on one bottle: paired differences, or a two-sample bootstrap."""
    a, b = ci.pairs(experiment, bottle, fast, slow, first_only=experiment == "pour")
    crit = f"{_label(fast)} minus {_label(slow)} mean response < 0 ms"
    xs, ys = ci.values(experiment, bottle, fast, "response_ms"), ci.values(experiment, bottle, slow, "response_ms")
    if not xs or not ys:
        who = " and ".join(_label(m) for m, v in ((fast, xs), (slow, ys)) if not v)
        n = len(ci.cell(experiment, bottle, fast if not xs else slow))
        return Part(FAILS_PLANT, f"{bottle}: {who} responded to none of {n} {experiment} slips; on this plant: "
                    f"{physics}", math.nan, crit)
    if len(a) >= 2 and all(x == y for x, y in zip(a, b)) and {fast, slow} == {DATH, FIXED}:
        return Part(FAILS_DEFINITION, (
            f"{bottle}: DATH and the fixed threshold respond at the same sample on {len(a)} of {len(a)} paired "
            "trials: they are the same encoder until the first spike (Eq. 1-4: DATH changes the threshold "
            "only after one), so on the same input DATH cannot be faster"), 0.0, crit, 0.0, 0.0)
    paired = len(a) >= 2
    d, lo, hi, n = difference_interval(a, b, paired=True) if paired else difference_interval(xs, ys)
    numbers = (f"{bottle}: {_label(fast)} {_f(float(np.mean(xs)))} vs {_label(slow)} {_f(float(np.mean(ys)))} ms, "
               f"{'paired' if paired else 'unpaired'} difference {_f(d, 1)} {_ci(lo, hi, 1)} (n {n})")
    return _part(lo, hi, (-INF, 0.0), d, crit, numbers, physics)


def _same_encoder(ci: ClaimInput, experiment: str) -> Part | None:
    """A fails-definition part when DATH and fixed answer at the same sample on every paired trial (2 or more)."""
    pairs = [p for b in BOTTLE_ORDER for p in zip(*ci.pairs(experiment, b, DATH, FIXED, first_only=True))]
    if len(pairs) < 2 or any(x != y for x, y in pairs):
        return None
    return Part(FAILS_DEFINITION, (
        f"DATH and the fixed threshold respond at the same sample on {len(pairs)} of {len(pairs)} paired "
        f"{experiment} trials: they are the same encoder until the first spike (Eq. 1-4: DATH changes the "
        "threshold only after one), so on the same input DATH cannot be faster"), 0.0,
        "DATH minus fixed mean response < 0 ms", 0.0, 0.0)


def _drop_faster(ci: ClaimInput) -> list[Part]:
    bad = [f"drop {b} DATH {_paper_mean('drop', b, DATH):g} vs fixed {_paper_mean('drop', b, FIXED):g}"
           for b in BOTTLE_ORDER if not _paper_mean("drop", b, DATH) < _paper_mean("drop", b, FIXED)]
    if gone := _missing(ci, "drop", (DATH, FIXED)):
        return _paper_part(bad, "DATH not faster") + gone
    if same := _same_encoder(ci, "drop"):
        return _paper_part(bad, "DATH not faster") + [same]
    out = [_faster(ci, "drop", b, DATH, FIXED, PHYSICS[3]) for b in BOTTLE_ORDER]
    return _paper_part(bad, "DATH not faster") + [
        Part(p.verdict, p.reason, p.value, p.criterion + " on every bottle", p.low, p.high) for p in out]


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
        return [Part(NOT_DECIDABLE, "this run has no drop trials of DATH or of the fixed threshold")]
    d, dlo, dhi = proportion_interval(kd, nd)
    f, flo, fhi = proportion_interval(kf, nf)
    parts = [_part(dlo, dhi, (0.8 - ABOUT_RATE_POINTS - 1e-12, 0.8 + ABOUT_RATE_POINTS + 1e-12), d,
                   "DATH's drop success within 80 ± 10 %", f"DATH {kd}/{nd} ({100 * d:.0f} %)", "see the bounds",
                   (False, False)),
             _part(flo, fhi, (-INF, 0.5), f, "fixed's drop success under 50 %",
                   f"fixed {kf}/{nf} ({100 * f:.0f} %)", "see the bounds")]
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
            "DATH 80 ± 10 % and fixed under 50 %, needing slip-outs", dlo, dhi)]
    return [Part(NOT_DECIDABLE, (
        f"drop success DATH {kd}/{nd}, fixed {kf}/{nf}: no drop knocks the bottle out, and none can on a plant "
        f"calibrated to the paper's first pour slip if the bottle only slides: {worst.text()}. The bounds assume "
        f"{DROP_ASSUMPTIONS}; the simulator has exactly this one degree of freedom, so the paper's slip-outs need "
        "what it lacks (tilt, fingertips moving onto a tapering shoulder)"), d,
        "DATH 80 ± 10 % and fixed under 50 %, needing slip-outs", dlo, dhi)]


def _nmsd_twice(ci: ClaimInput) -> list[Part]:
    bottles = [b for b in BOTTLE_ORDER if ci.cell("drop", b, DATH) and ci.cell("drop", b, NMSD)]
    if not bottles:
        return [Part(NOT_DECIDABLE, "this run has no drop trials of DATH and NMSD on one bottle")]
    num = [x for b in bottles for x in ci.values("drop", b, NMSD, "total_ms")]
    den = [x for b in bottles for x in ci.values("drop", b, DATH, "total_ms")]
    r, lo, hi, n = ratio_interval(num, den)
    if r != r:
        return [Part(NOT_DECIDABLE, "no drop totals of DATH (or none above 0 ms) or of NMSD in this run")]
    crit = f"NMSD / DATH mean drop total within {2 / ABOUT_RATIO_FACTOR:.2f}-{2 * ABOUT_RATIO_FACTOR:g}"
    return [_part(lo, hi, (2 / ABOUT_RATIO_FACTOR, 2 * ABOUT_RATIO_FACTOR), r, crit,
                  f"drop total NMSD {_f(float(np.mean(num)))} ms / DATH {_f(float(np.mean(den)))} ms = {r:.2f} "
                  f"{_ci(lo, hi, 2)} ({', '.join(bottles)})", PHYSICS[5], (False, False))]


def _dath_pours(ci: ClaimInput) -> list[list[Any]]:
    trials: dict[tuple, list[Any]] = {}
    for b in BOTTLE_ORDER:
        for r in ci.cell("pour", b, DATH):
            trials.setdefault((b, str(_get(r, "trial")), str(_get(r, "seed"))), []).append(r)
    return list(trials.values())


def _pour_dath(ci: ClaimInput) -> list[Part]:
    pours = _dath_pours(ci)
    if not pours:
        return [Part(NOT_DECIDABLE, "this run has no DATH pours")]
    k, n = ci.success("pour", BOTTLE_ORDER, DATH)
    s, slo, shi = proportion_interval(k, n)
    parts = [Part(HOLDS if k == n else FAILS_PLANT, f"DATH held {k} of {n} pours" + (
        "" if k == n else "; on this plant: a pour's slip creeps before it accelerates and DATH's grip came late"),
        s, "every DATH pour succeeds", slo, shi)]
    two = sum(_count(_get(t[0], "n_events")) >= 2 for t in pours)
    f, flo, fhi = proportion_interval(two, len(pours))
    parts.append(_part(flo, fhi, (MOST, INF), f, "more than half of DATH's pours show two slips",
                       f"{two} of {len(pours)} DATH pours show two or more slips", PHYSICS[6]))
    for e, want in ((0, 200.0), (1, 400.0)):
        vols = [_num(_get(r, "load_at_onset")) for t in pours for r in t
                if _count(_get(r, "event")) == e and _count(_get(r, "n_events")) > e]
        m, lo, hi, nv = median_interval(vols)
        if not nv:
            parts.append(Part(NOT_DECIDABLE, f"no DATH pour shows a slip {e + 1}"))
            continue
        parts.append(_part(lo, hi, (want - NEAR_ML, want + NEAR_ML), m,
                           f"median volume at slip {e + 1} within {want:g} ± {NEAR_ML:g} ml",
                           f"slip {e + 1} at a median {_f(m)} ml {_ci(lo, hi)} (n {nv})",
                           "the plant's capacity after the reflex's tightening", (False, False)))
    return parts


def _pour_faster(ci: ClaimInput) -> list[Part]:
    fast, slow = (DATH, SWT), (NMSD, FIXED)
    bad = [f"pour {b} {_label(f)} {_paper_mean('pour', b, f):g} vs {_label(s)} {_paper_mean('pour', b, s):g}"
           for b in BOTTLE_ORDER for f in fast for s in slow
           if _paper_mean("pour", b, f) >= _paper_mean("pour", b, s)]
    if gone := _missing(ci, "pour", fast + slow):
        return _paper_part(bad, "not faster") + gone
    same = _same_encoder(ci, "pour")
    parts = [_faster(ci, "pour", b, f, s, PHYSICS[7]) for b in BOTTLE_ORDER for f in fast for s in slow
             if not (same and (f, s) == (DATH, FIXED))]
    return _paper_part(bad, "not faster") + ([same] if same else []) + parts


def _under_85(ci: ClaimInput) -> list[Part]:
    cells = [(e, b) for e in EXPERIMENTS for b in BOTTLE_ORDER if ci.values(e, b, DATH, "response_ms")]
    limit = UNDER_MS + TIME_TOL_MS
    bad = [f"{e} {b} {_paper_mean(e, b, DATH):g} ms" for e in EXPERIMENTS for b in BOTTLE_ORDER
           if not _paper_mean(e, b, DATH) < limit]
    parts = _paper_part(bad, f"not under {UNDER_MS:g} ms + {TIME_TOL_MS:.0f} ms")
    if not cells:
        return parts + [Part(NOT_DECIDABLE, "this run has no DATH responses")]
    for e, b in cells:
        m, lo, hi, n = mean_interval(ci.values(e, b, DATH, "response_ms"))
        parts.append(_part(lo, hi, (-INF, limit), m, f"DATH mean response < {UNDER_MS:g} ms (+ one sample)",
                           f"{e} {b} {_f(m)} ms {_ci(lo, hi)} (n {n})", PHYSICS[8]))
    return parts


def _order_parts(ci: ClaimInput, bottle: str, slower: bool, physics: str) -> list[Part]:
    """Is ``bottle`` DATH's slowest (``slower``) or fastest bottle in each experiment: unpaired intervals."""
    parts = []
    for e in EXPERIMENTS:
        if not all(ci.values(e, b, DATH, "response_ms") for b in BOTTLE_ORDER):
            continue
        for other in (b for b in BOTTLE_ORDER if b != bottle):
            d, lo, hi, n = difference_interval(ci.values(e, bottle, DATH, "response_ms"),
                                               ci.values(e, other, DATH, "response_ms"))
            crit = f"{bottle} minus other bottles' DATH mean response {'>' if slower else '<'} 0 ms"
            parts.append(_part(lo, hi, (0.0, INF) if slower else (-INF, 0.0), d, crit,
                               f"{e} {bottle} - {other} {_f(d, 1)} ms {_ci(lo, hi, 1)}", physics))
    return parts or [Part(NOT_DECIDABLE, "this run has no experiment with DATH responses on TR, DK and TX")]


def _dk_slowest(ci: ClaimInput) -> list[Part]:
    bad = []
    for e in EXPERIMENTS:
        v = {b: _paper_mean(e, b, DATH) for b in BOTTLE_ORDER}
        if any(v[b] >= v["DK"] for b in BOTTLE_ORDER if b != "DK"):
            bad.append(f"{e} " + ", ".join(f"{b} {x:g}" for b, x in v.items()))
    return _paper_part(bad, "DK not the slowest") + _order_parts(ci, "DK", True, PHYSICS[9])


def _tx_best(ci: ClaimInput) -> list[Part]:
    bad = []
    for e in EXPERIMENTS:
        v = {b: _paper_mean(e, b, DATH) for b in BOTTLE_ORDER}
        if any(v[b] <= v["TX"] for b in BOTTLE_ORDER if b != "TX"):
            bad.append(f"{e} " + ", ".join(f"{b} {x:g}" for b, x in v.items()))
    parts = _paper_part(bad, "TX not the fastest") + _order_parts(ci, "TX", False, PHYSICS[10])
    for e in EXPERIMENTS:
        rates = {b: ci.success(e, [b], DATH) for b in BOTTLE_ORDER}
        if not all(n for _, n in rates.values()):
            continue
        iv = {b: proportion_interval(k, n) for b, (k, n) in rates.items()}
        best = max(iv[b][0] for b in BOTTLE_ORDER)
        text = f"{e} DATH success " + ", ".join(f"{b} {k}/{n}" for b, (k, n) in rates.items())
        if iv["TX"][0] >= best:
            parts.append(Part(HOLDS, text + " (TX's is the highest, ties count)", iv["TX"][0]))
        elif any(iv["TX"][2] < iv[b][1] for b in BOTTLE_ORDER):
            parts.append(Part(FAILS_PLANT, f"{text}; on this plant: {PHYSICS[10]}", *iv["TX"][:1],
                              "TX's success the highest", *iv["TX"][1:]))
        else:
            parts.append(Part(UNRESOLVED, f"{text}: TX's rate {_ci(*iv['TX'][1:], 2)} overlaps the best",
                              iv["TX"][0], "TX's success the highest", *iv["TX"][1:]))
    return parts


_PAIRED = "paired differences (same trial seeds), else a two-sample bootstrap; " + TOLERANCES["intervals"]

#: The paper's ten claims, in order.
CLAIMS: tuple[Claim, ...] = (
    Claim(1, "Scan: white about 0.3-0.5 V, black about 3.32-3.35 V",
          f"{TOLERANCES['a voltage']}; central {100 * CENTRAL:g} % over texture seeds", _scan_levels),
    Claim(2, "Scan: spikes at least about 0.09 mm apart; DATH gives more spikes than fixed",
          f"{TOLERANCES['a length']}; central {100 * CENTRAL:g} % over texture seeds", _scan_spikes),
    Claim(3, "Drop: DATH responds faster than the fixed threshold on TR, DK and TX", _PAIRED, _drop_faster,
          (DATH, FIXED)),
    Claim(4, "Drop: DATH succeeds in about 80 % of trials, the fixed threshold in under 50 %",
          TOLERANCES["about a rate"] + "; Wilson intervals; slip-out bounds with named assumptions", _drop_success,
          (DATH, FIXED)),
    Claim(5, "Drop: NMSD's total time is about twice DATH's", TOLERANCES["about twice"] + "; bootstrap of the "
          "ratio of means over every bottle", _nmsd_twice, (DATH, NMSD)),
    Claim(6, "Pour: DATH succeeds in every trial; most pours show two slips, near 200 and 400 ml",
          "every: all of DATH's pours; most: " + TOLERANCES["most"] + "; near: " + TOLERANCES["near a volume"]
          + " (bootstrap of the median)", _pour_dath, (DATH,)),
    Claim(7, "Pour: DATH and SWT-SD respond faster than NMSD and the fixed threshold",
          _PAIRED + "; first slip of each pour, every bottle", _pour_faster, (DATH, SWT, NMSD, FIXED)),
    Claim(8, "DATH responds in under 85 ms on every bottle and experiment",
          TOLERANCES["a response time"] + "; bootstrap of each cell's mean", _under_85, (DATH,)),
    Claim(9, "DK is DATH's slowest bottle", "two-sample bootstrap of the differences of means, in every "
          "experiment run", _dk_slowest, (DATH,)),
    Claim(10, "TX is DATH's best bottle", "fastest mean response (two-sample bootstrap) and highest success "
          "(Wilson; ties count), in every experiment run", _tx_best, (DATH,)),
)


def undecided_methods(results: Sequence[ClaimResult]) -> tuple[str, ...]:
    """The methods whose trials decide the claims ``results`` leaves unresolved (what to replicate).

    Examples
    --------
    >>> r = ClaimResult(10, "TX is DATH's best bottle", UNRESOLVED, "", 0.0, -1.0, 1.0, "", "", "")
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


def judge(rows: Sequence[Any], scan: Any = None, plant: Any = None) -> list[ClaimResult]:
    """Judge every claim of :data:`CLAIMS` from a run's rows, its scan ensemble and its plant.

    Parameters
    ----------
    rows : sequence of mapping
        Per-slip result rows (see :class:`ClaimInput`).
    scan : ScanEnsemble, optional
        The characterization scan over texture seeds (claims 1-2).
    plant : Plant, optional
        The simulated plant (claim 4's bounds).

    Returns
    -------
    list of ClaimResult
        One per claim, in order.

    Examples
    --------
    >>> [r.verdict for r in judge([])][:3]
    ['not-decidable', 'not-decidable', 'not-decidable']
    """
    ci = ClaimInput(list(rows), scan, plant)
    return [_combine(c.number, c.text, c.tolerance, c.judge(ci)) for c in CLAIMS]


def scan_ensemble_for(seed: int, sensor: Any = None, n: int | None = None):
    """The scan ensemble a run judges claims 1-2 on: ``n`` texture seeds from ``seed`` (cached).

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


def judge_run(rows: Sequence[Any], *, seed: int = 0, plant: Any = None, scan_seeds: int | None = None
              ) -> list[ClaimResult]:
    """Judge the claims of a run: its rows, a scan ensemble of its slip sensor, its plant.

    The ensemble (:func:`scan_ensemble_for`: :data:`slipreflex.sim.scan.ENSEMBLE_SEEDS`
    texture seeds from ``seed``, with the plant's slip sensor) supplies claims 1-2.

    Examples
    --------
    >>> [r.verdict for r in judge_run([], seed=0, scan_seeds=4)][2]
    'not-decidable'
    """
    sensor = None if plant is None else plant.slip_sensor
    return judge(rows, scan_ensemble_for(seed, sensor, scan_seeds), plant)


#: Columns of claims.csv (``reproduce``, ``claims`` and, with a study's counts, ``study``).
CLAIMS_CSV_COLUMNS: tuple[str, ...] = ("claim", "verdict", "reason", "value", "criterion", "low", "high",
                                       "text", "numbers")


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
    'claim,verdict,reason,value,criterion,low,high,text,numbers'
    """
    path = Path(path)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(columns)
        for r in results:
            d = r if isinstance(r, Mapping) else {c: getattr(r, "number" if c == "claim" else c) for c in columns}
            w.writerow([_cell(d[c]) for c in columns])
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


def _value(r: ClaimResult) -> str:
    if r.value != r.value:
        return "-"
    v = f"{r.value:.3g}"
    return v if r.low != r.low else f"{v} [{r.low:.3g}, {r.high:.3g}]"


def claims_markdown(results: Sequence[ClaimResult]) -> str:
    """The claims table as markdown (claim, verdict, reason, value and interval, criterion).

    Examples
    --------
    >>> claims_markdown(judge([])).splitlines()[2].startswith("| 1 | Scan: white about 0.3-0.5 V")
    True
    """
    lines = ["| # | claim | verdict | reason | value [interval] | criterion |", "|---|---|---|---|---|---|"]
    for r in results:
        lines.append(f"| {r.number} | {r.text} | **{r.verdict}** | {r.reason} | {_value(r)} | {r.criterion or '-'} |")
    return "\n".join(lines)


def _counts(results: Sequence[ClaimResult]) -> str:
    n = {v: sum(r.verdict == v for r in results) for v in VERDICTS}
    return ", ".join(f"{n[v]} {v}" for v in VERDICTS if n[v]) or "none"


def claims_terminal(results: Sequence[ClaimResult]) -> str:
    """The claims table for the terminal: per claim, its verdict and text, then its reason.

    Examples
    --------
    >>> print(claims_terminal(judge([])).splitlines()[0])
    paper's claims: 2 fails-paper, 8 not-decidable
    """
    lines = [f"paper's claims: {_counts(results)}"]
    for r in results:
        lines += [f"{r.number:>3} {r.verdict:16} {r.text}", f"{'':20}{r.reason}"]
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
             f"claims.csv). Verdicts: {', '.join(VERDICTS)}. Count: {_counts(results)}.", "",
             claims_markdown(results), "",
             "Tolerances (one definition each, none finer than the instrument or the paper's last digit): "
             + "; ".join(f"{k}: {v}" for k, v in TOLERANCES.items()) + ".", ""]
    items = contradictions(plant=plant) if items is None else items
    if items:
        lines += ["## The paper's own numbers", "",
                  "Computed from the paper's numbers (and the rig's geometry); reported, not chased.", "",
                  contradictions_markdown(items), ""]
    return lines
