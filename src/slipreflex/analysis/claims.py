"""The paper's claims as data, judged from a results table (docs/method.md section 4.1), and its self-contradictions.

Each of the ten claims of docs/method.md section 4.1 is a :class:`Claim` with a
judge function over a :class:`ClaimInput` (the per-slip result rows of a
run, and the characterization scan's numbers for claims 1-2). :func:`judge`
returns one :class:`ClaimResult` per claim: *holds*, *fails* or *not testable
here*, with the numbers behind the verdict and the tolerance used.

The paper's words are turned into numbers once, here (:data:`TOLERANCES`):

* "about" a voltage range: the range widened by one of the paper's ADC LSBs
  (0.004 V) on each side;
* "about 0.09 mm": at least 90 % of it (:data:`ABOUT_REL`);
* "about 80 %": within 10 percentage points (:data:`ABOUT_RATE_POINTS`);
* "about twice": a ratio within a factor 1.5 of 2, i.e. 1.33-3.0
  (:data:`ABOUT_RATIO_FACTOR`; the paper's own per-bottle ratios, 2.2-2.8,
  lie inside);
* "near 200 and 400 ml": the median volume at the first and second slip
  within 50 ml of them (:data:`NEAR_ML`, a quarter of the 200 ml between the
  two, so no slip is near both);
* "most": more than half; "under", "faster", "slowest": strict comparisons
  of means (ms), with no tolerance.

Means are over slip events (one row per slip, NaN responses left out), as
the paper averages its slips; success rates are over rows.

:func:`contradictions` computes where the paper's numbers cannot all be true
(docs/method.md section 4.1, last paragraph): the largest static capacity at which an open-loop
10 g drop could end in complete slippage beside the capacity the pour's first
slip implies; the fixed and DATH pour totals identical to the digit; response
standard deviations below what a free-running 48 ms window allows; and the
claims the paper's own table contradicts.

Examples
--------
>>> rows = [{"experiment": "drop", "bottle": b, "method": m, "trial": 0, "seed": 1, "event": 0,
...          "n_events": 1, "response_ms": r, "total_ms": 100.0, "success": True,
...          "load_at_onset": float("nan")}
...         for b in ("TR", "DK", "TX") for m, r in (("dath", 40.0), ("fixed", 50.0))]
>>> res = {c.number: c for c in judge(rows)}
>>> res[3].verdict, res[3].numbers
('holds', 'DATH vs fixed mean response (ms): TR 40 vs 50, DK 40 vs 50, TX 40 vs 50')
>>> res[1].verdict
'not testable here'
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import hardware as hw
from ..csvfiles import cell_bool, cell_float
from ..methods import DATH, FIXED, NMSD, SWT
from ..methods import label as _label
from .paper import BOTTLE_ORDER, EXPERIMENTS, PAPER

__all__ = [
    "HOLDS", "FAILS", "NOT_TESTABLE", "VERDICTS", "ABOUT_VOLTS", "ABOUT_REL", "ABOUT_RATE_POINTS",
    "ABOUT_RATIO_FACTOR", "NEAR_ML", "MOST", "TOLERANCES", "Claim", "ClaimInput", "ClaimResult",
    "CLAIMS", "judge", "judge_run", "claims_section", "claims_markdown", "claims_terminal",
    "Contradiction", "contradictions",
    "contradictions_markdown", "window_phase_sd_ms", "drop_slipout_capacity_n",
    "first_slip_capacity_n", "STATIC_OVER_KINETIC_MAX",
]

HOLDS = "holds"
FAILS = "fails"
NOT_TESTABLE = "not testable here"
#: The three verdicts, in the order tables list them.
VERDICTS: tuple[str, ...] = (HOLDS, FAILS, NOT_TESTABLE)

#: "about" a voltage range: widened by this much on each side (V): one of the paper's ADC LSBs.
ABOUT_VOLTS: float = hw.PAPER_LSB
#: "about" a length: at least (1 - ABOUT_REL) of it.
ABOUT_REL: float = 0.10
#: "about" a success rate: within this many percentage points (as a fraction).
ABOUT_RATE_POINTS: float = 0.10
#: "about twice": the ratio within a factor ABOUT_RATIO_FACTOR of 2 (1.33 .. 3.0).
ABOUT_RATIO_FACTOR: float = 1.5
#: "near 200 and 400 ml": the median volume at each slip within this many ml.
NEAR_ML: float = 50.0
#: "most": more than this fraction.
MOST: float = 0.5

#: Every tolerance in words, as the reports print it.
TOLERANCES: dict[str, str] = {
    "about a voltage range": f"the range widened by {ABOUT_VOLTS * 1e3:g} mV (one paper LSB) each side",
    "about a length": f"at least {100 * (1 - ABOUT_REL):g} % of it",
    "about a rate": f"within ±{100 * ABOUT_RATE_POINTS:g} percentage points",
    "about twice": f"a ratio of {2 / ABOUT_RATIO_FACTOR:.2f} .. {2 * ABOUT_RATIO_FACTOR:.1f}",
    "near a volume": f"median within ±{NEAR_ML:g} ml",
    "most": f"more than {100 * MOST:g} % of trials",
    "under, faster, slowest": "strict comparison of means, no tolerance",
}


@dataclass(frozen=True)
class ClaimResult:
    """The verdict on one claim, with the numbers behind it.

    Attributes
    ----------
    number : int
        1..10 (docs/method.md section 4.1).
    text : str
        The claim in words.
    verdict : str
        :data:`HOLDS`, :data:`FAILS` or :data:`NOT_TESTABLE`.
    numbers : str
        The values the verdict rests on (or why it is not testable).
    tolerance : str
        How the paper's words were made numbers.

    Examples
    --------
    >>> ClaimResult(9, "DK is DATH's slowest bottle", HOLDS, "DK 90 ms", "strict").verdict
    'holds'
    """

    number: int
    text: str
    verdict: str
    numbers: str
    tolerance: str


@dataclass(frozen=True)
class ClaimInput:
    """What the claims are judged from.

    Parameters
    ----------
    rows : sequence of mapping
        Per-slip result rows (results.csv columns: experiment, bottle, method,
        trial, seed, event, n_events, response_ms, total_ms, success,
        load_at_onset); values may be strings as read from a CSV. Objects
        with those attributes work too.
    scan : object, optional
        The characterization scan's numbers, a
        :class:`slipreflex.sim.ScanSummary` (``ranges``, ``spikes``,
        ``min_spacing_mm``); None: claims 1-2 are not testable.

    Examples
    --------
    >>> ClaimInput([]).cell_mean("drop", "TR", "dath", "response_ms")
    nan
    """

    rows: Sequence[Any]
    scan: Any = None
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

    def cell_mean(self, experiment: str, bottle: str, method: str, column: str) -> float:
        """Mean of a column over one cell's rows (NaN left out; NaN when none).

        Examples
        --------
        >>> ClaimInput([{"experiment": "pour", "bottle": "TX", "method": "swt", "response_ms": "80"},
        ...             {"experiment": "pour", "bottle": "TX", "method": "swt", "response_ms": ""}]
        ...           ).cell_mean("pour", "TX", "swt", "response_ms")
        80.0
        """
        v = [x for x in (_lenient_float(_get(r, column)) for r in self.cell(experiment, bottle, method)) if x == x]
        return float(np.mean(v)) if v else float("nan")

    def success(self, experiment: str, bottles: Iterable[str], method: str) -> tuple[float, int]:
        """Success rate over the rows of ``bottles`` and its row count (NaN, 0 when none).

        Examples
        --------
        >>> ClaimInput([{"experiment": "drop", "bottle": "TR", "method": "dath", "success": "True"},
        ...             {"experiment": "drop", "bottle": "TR", "method": "dath", "success": False}]
        ...           ).success("drop", ["TR"], "dath")
        (0.5, 2)
        """
        s = [cell_bool(_get(r, "success")) for b in bottles for r in self.cell(experiment, b, method)]
        return (float(np.mean(s)), len(s)) if s else (float("nan"), 0)

    def bottles(self, experiment: str, method: str) -> list[str]:
        """Bottles with rows for ``experiment`` and ``method``, in the paper's order.

        Examples
        --------
        >>> ClaimInput([{"experiment": "drop", "bottle": "TX", "method": "dath"}]).bottles("drop", "dath")
        ['TX']
        """
        return [b for b in BOTTLE_ORDER if self.cell(experiment, b, method)]


@dataclass(frozen=True)
class Claim:
    """One claim of the paper and the function that judges it.

    Attributes
    ----------
    number : int
        Its number in the paper's list of claims (docs/method.md section 4.1).
    text : str
        The claim in the paper's words.
    tolerance : str
        How those words were made numbers.
    judge : callable
        ``judge(ClaimInput) -> (verdict, numbers)``.

    Examples
    --------
    >>> CLAIMS[0].number, CLAIMS[-1].text
    (1, "TX is DATH's best bottle")
    """

    number: int
    text: str
    tolerance: str
    judge: Callable[[ClaimInput], tuple[str, str]]


def _get(row: Any, key: str) -> Any:
    if isinstance(row, Mapping):
        return row.get(key)
    return getattr(row, key, None)


def _lenient_float(x: Any) -> float:
    """A cell of a table being judged: blank, missing or unreadable is NaN."""
    return cell_float(x, lenient=True)


def _count(x: Any) -> int:
    """A count cell as int; a missing or unreadable cell counts 0."""
    v = _lenient_float(x)
    return int(v) if math.isfinite(v) else 0


def _ms(x: float) -> str:
    return "-" if x != x else f"{x:.0f}"


def _verdict(ok: bool) -> str:
    return HOLDS if ok else FAILS


def _scan_levels(ci: ClaimInput) -> tuple[str, str]:
    if ci.scan is None:
        return NOT_TESTABLE, "no scan in this run"
    want = {"white": (0.3, 0.5), "black": (3.32, 3.35)}
    parts, ok = [], True
    for region, (lo, hi) in want.items():
        if region not in ci.scan.ranges:
            return NOT_TESTABLE, f"the scan has no {region} region"
        a, b = ci.scan.ranges[region]
        ok &= a >= lo - ABOUT_VOLTS and b <= hi + ABOUT_VOLTS
        parts.append(f"{region} {a:.3f}-{b:.3f} V (paper {lo:g}-{hi:g})")
    return _verdict(ok), ", ".join(parts)


def _scan_spikes(ci: ClaimInput) -> tuple[str, str]:
    if ci.scan is None:
        return NOT_TESTABLE, "no scan in this run"
    gap = {m: [g for (mm, region), g in ci.scan.min_spacing_mm.items()
               if mm == m and region in ("white", "black") and g is not None] for m in (FIXED, DATH)}
    if not all(gap.values()) or not {FIXED, DATH} <= set(ci.scan.spikes):
        return NOT_TESTABLE, "the scan has fewer than two spikes on white or black for a method"
    small = {m: min(v) for m, v in gap.items()}
    f, d = ci.scan.spikes[FIXED], ci.scan.spikes[DATH]
    ok = min(small.values()) >= (1 - ABOUT_REL) * 0.09 and d > f
    return _verdict(ok), (f"smallest spike spacing on white/black: fixed {small[FIXED]:.3f} mm, DATH "
                          f"{small[DATH]:.3f} mm (paper 0.09 for both); spikes DATH {d} vs fixed {f}")


def _need(ci: ClaimInput, experiment: str, methods: Sequence[str], bottles: Sequence[str] = BOTTLE_ORDER,
          column: str = "response_ms") -> str | None:
    """Why a claim is not testable (missing cells or values), or None."""
    miss = [f"{_label(m)} {b}" for m in methods for b in bottles
            if math.isnan(ci.cell_mean(experiment, b, m, column))]
    return f"no {column} for {experiment}: " + ", ".join(miss) if miss else None


def _drop_faster(ci: ClaimInput) -> tuple[str, str]:
    if why := _need(ci, "drop", (DATH, FIXED)):
        return NOT_TESTABLE, why
    v = {b: (ci.cell_mean("drop", b, DATH, "response_ms"), ci.cell_mean("drop", b, FIXED, "response_ms"))
         for b in BOTTLE_ORDER}
    return (_verdict(all(d < f for d, f in v.values())),
            "DATH vs fixed mean response (ms): " + ", ".join(f"{b} {_ms(d)} vs {_ms(f)}" for b, (d, f) in v.items()))


def _drop_success(ci: ClaimInput) -> tuple[str, str]:
    d, nd = ci.success("drop", BOTTLE_ORDER, DATH)
    f, nf = ci.success("drop", BOTTLE_ORDER, FIXED)
    if not nd or not nf:
        return NOT_TESTABLE, "needs drop rows of DATH and fixed"
    ok = abs(d - 0.8) <= ABOUT_RATE_POINTS + 1e-12 and f < 0.5
    return _verdict(ok), f"drop success DATH {100 * d:.0f}% of {nd}, fixed {100 * f:.0f}% of {nf}"


def _nmsd_twice(ci: ClaimInput) -> tuple[str, str]:
    bottles = [b for b in BOTTLE_ORDER if ci.cell("drop", b, DATH) and ci.cell("drop", b, NMSD)]
    if not bottles or _need(ci, "drop", (DATH, NMSD), bottles, "total_ms"):
        return NOT_TESTABLE, "needs drop total times of DATH and NMSD"
    num = [_lenient_float(_get(r, "total_ms")) for b in bottles for r in ci.cell("drop", b, NMSD)]
    den = [_lenient_float(_get(r, "total_ms")) for b in bottles for r in ci.cell("drop", b, DATH)]
    n, d = float(np.nanmean(num)), float(np.nanmean(den))
    if not d > 0:
        return NOT_TESTABLE, f"DATH's mean drop total is {_ms(d)} ms"
    ratio = n / d
    ok = 2 / ABOUT_RATIO_FACTOR <= ratio <= 2 * ABOUT_RATIO_FACTOR
    return _verdict(ok), f"drop total NMSD {_ms(n)} ms / DATH {_ms(d)} ms = {ratio:.2f} ({', '.join(bottles)})"


def _pour_trials(ci: ClaimInput) -> list[list[Any]]:
    trials: dict[tuple, list[Any]] = {}
    for r in ci.rows:
        if _get(r, "experiment") == "pour":
            key = (_get(r, "bottle"), _get(r, "method"), str(_get(r, "trial")), str(_get(r, "seed")))
            trials.setdefault(key, []).append(r)
    return list(trials.values())


def _pour_dath(ci: ClaimInput) -> tuple[str, str]:
    s, n = ci.success("pour", BOTTLE_ORDER, DATH)
    trials = _pour_trials(ci)
    if not n or not trials:
        return NOT_TESTABLE, "needs pour rows of DATH"
    two = float(np.mean([_count(_get(t[0], "n_events")) >= 2 for t in trials]))
    vols = [[], []]
    for t in trials:
        for r in t:
            e = _count(_get(r, "event"))
            if e < 2 and _count(_get(r, "n_events")) > e:
                vols[e].append(_lenient_float(_get(r, "load_at_onset")))
    med = [float(np.nanmedian(v)) if any(x == x for x in v) else float("nan") for v in vols]
    near = all(abs(m - want) <= NEAR_ML for m, want in zip(med, (200.0, 400.0)))
    ok = s == 1.0 and two > MOST and near
    return _verdict(ok), (f"DATH pour success {100 * s:.0f}% of {n}; {100 * two:.0f}% of {len(trials)} "
                          f"pours with 2+ slips; median ml at slip 1 {_ms(med[0])}, slip 2 {_ms(med[1])}")


def _pour_faster(ci: ClaimInput) -> tuple[str, str]:
    fast, slow = (DATH, SWT), (NMSD, FIXED)
    bottles = [b for b in BOTTLE_ORDER if all(ci.cell("pour", b, m) for m in fast + slow)]
    if not bottles or _need(ci, "pour", fast + slow, bottles):
        return NOT_TESTABLE, "needs pour responses of DATH, SWT-SD, NMSD and fixed on one bottle"
    parts, ok = [], True
    for b in bottles:
        v = {m: ci.cell_mean("pour", b, m, "response_ms") for m in fast + slow}
        ok &= max(v[m] for m in fast) < min(v[m] for m in slow)
        parts.append(f"{b} " + ", ".join(f"{_label(m)} {_ms(v[m])}" for m in fast + slow))
    return _verdict(ok), "pour mean response (ms): " + "; ".join(parts)


def _under_85(ci: ClaimInput) -> tuple[str, str]:
    v = {(e, b): ci.cell_mean(e, b, DATH, "response_ms") for e in EXPERIMENTS for b in BOTTLE_ORDER
         if ci.cell(e, b, DATH)}
    v = {k: x for k, x in v.items() if x == x}
    if not v:
        return NOT_TESTABLE, "no DATH responses"
    worst = max(v, key=v.get)
    return (_verdict(all(x < 85.0 for x in v.values())),
            f"DATH mean response, largest of {len(v)} cells: {worst[0]} {worst[1]} {_ms(v[worst])} ms")


def _bottle_order(ci: ClaimInput, experiment: str, column: str = "response_ms") -> dict[str, float]:
    v = {b: ci.cell_mean(experiment, b, DATH, column) for b in BOTTLE_ORDER}
    return v if all(x == x for x in v.values()) else {}


def _dk_slowest(ci: ClaimInput) -> tuple[str, str]:
    orders = {e: v for e in EXPERIMENTS if (v := _bottle_order(ci, e))}
    if not orders:
        return NOT_TESTABLE, "needs DATH responses on TR, DK and TX in one experiment"
    ok = all(v["DK"] > max(x for b, x in v.items() if b != "DK") for v in orders.values())
    return _verdict(ok), "DATH mean response (ms): " + "; ".join(
        f"{e} " + ", ".join(f"{b} {_ms(x)}" for b, x in v.items()) for e, v in orders.items())


def _tx_best(ci: ClaimInput) -> tuple[str, str]:
    orders = {e: v for e in EXPERIMENTS if (v := _bottle_order(ci, e))}
    if not orders:
        return NOT_TESTABLE, "needs DATH responses on TR, DK and TX in one experiment"
    ok, parts = True, []
    for e, v in orders.items():
        succ = {b: ci.success(e, [b], DATH)[0] for b in BOTTLE_ORDER}
        ok &= v["TX"] < min(x for b, x in v.items() if b != "TX") and succ["TX"] >= max(succ.values())
        parts.append(f"{e} " + ", ".join(f"{b} {_ms(v[b])} ms {100 * succ[b]:.0f}%" for b in BOTTLE_ORDER))
    return _verdict(ok), "DATH mean response and success: " + "; ".join(parts)


_STRICT = TOLERANCES["under, faster, slowest"]

#: The ten claims of docs/method.md section 4.1, in order.
CLAIMS: tuple[Claim, ...] = (
    Claim(1, "Scan: white about 0.3-0.5 V, black about 3.32-3.35 V", TOLERANCES["about a voltage range"],
          _scan_levels),
    Claim(2, "Scan: spikes at least about 0.09 mm apart; DATH gives more spikes than fixed",
          TOLERANCES["about a length"] + "; more spikes: strict", _scan_spikes),
    Claim(3, "Drop: DATH responds faster than the fixed threshold on TR, DK and TX", _STRICT, _drop_faster),
    Claim(4, "Drop: DATH succeeds in about 80 % of trials, the fixed threshold in under 50 %",
          TOLERANCES["about a rate"] + " of 80 %; under 50 %: strict", _drop_success),
    Claim(5, "Drop: NMSD's total time is about twice DATH's", TOLERANCES["about twice"] + " (means over "
          "every bottle run)", _nmsd_twice),
    Claim(6, "Pour: DATH succeeds in every trial; most pours show two slips, near 200 and 400 ml",
          "every: 100 %; most: " + TOLERANCES["most"] + " (every method's pours); near: "
          + TOLERANCES["near a volume"], _pour_dath),
    Claim(7, "Pour: DATH and SWT-SD respond faster than NMSD and the fixed threshold",
          _STRICT + ", on every bottle with all four methods", _pour_faster),
    Claim(8, "DATH responds in under 85 ms on every bottle and experiment", _STRICT + " (cell means)",
          _under_85),
    Claim(9, "DK is DATH's slowest bottle", _STRICT + ", in every experiment run", _dk_slowest),
    Claim(10, "TX is DATH's best bottle", "fastest mean response (strict) and highest success (ties count), "
          "in every experiment run", _tx_best),
)


def judge(rows: Sequence[Any], scan: Any = None) -> list[ClaimResult]:
    """Judge every claim of :data:`CLAIMS` from a run's rows (and its scan).

    Parameters
    ----------
    rows : sequence of mapping
        Per-slip result rows (see :class:`ClaimInput`).
    scan : ScanSummary, optional
        The characterization scan's numbers (claims 1-2).

    Returns
    -------
    list of ClaimResult
        One per claim, in order.

    Examples
    --------
    >>> [r.verdict for r in judge([])][:3]
    ['not testable here', 'not testable here', 'not testable here']
    """
    ci = ClaimInput(list(rows), scan)
    out = []
    for c in CLAIMS:
        verdict, numbers = c.judge(ci)
        out.append(ClaimResult(c.number, c.text, verdict, numbers, c.tolerance))
    return out


def judge_run(rows: Sequence[Any], *, seed: int = 0, plant: Any = None) -> list[ClaimResult]:
    """Judge the claims of a run: its rows, and a characterization scan of its slip sensor.

    The scan (:func:`slipreflex.sim.scan`, seeded with the run's master
    seed, with the plant's slip sensor when ``plant`` is given) supplies
    claims 1-2; it takes milliseconds.

    Examples
    --------
    >>> [r.verdict for r in judge_run([], seed=0)][2]
    'not testable here'
    """
    sensor = None if plant is None else plant.slip_sensor
    return judge(rows, _scan_analysis(seed, sensor))


@functools.lru_cache(maxsize=4)
def _scan_analysis(seed: int, sensor: Any):
    """The analysed characterization scan of a run (kept: the report and the terminal both judge it)."""
    from ..sim import scan  # deferred: heavy (numba kernels)

    return scan(seed=seed, sensor=sensor).analyse()


def claims_section(results: Sequence[ClaimResult], items: Sequence[Contradiction] | None = None, *,
                   plant: Any = None) -> list[str]:
    """The report.md sections: the claims judged, the tolerances, the paper's contradictions.

    Examples
    --------
    >>> claims_section(judge([]), [])[0]   # items None: computed, with the plant's open-loop drop
    "## The paper's claims, judged on this run"
    """
    lines = ["## The paper's claims, judged on this run", "",
             "Each claim of the paper (docs/method.md section 4.1) judged from this run's results.csv and a "
             "characterization scan (`slipreflex.analysis.claims`): *holds*, *fails*, or *not testable "
             "here* (the run lacks the cells or values it needs).", "", claims_markdown(results), "",
             "Tolerances (one definition each): " + "; ".join(f"{k}: {v}" for k, v in TOLERANCES.items())
             + ".", ""]
    items = contradictions(plant=plant) if items is None else items
    if items:
        lines += ["## Where the paper contradicts itself", "",
                  "Computed from the paper's own numbers; reported as inconsistent, not chased.", "",
                  contradictions_markdown(items), ""]
    return lines


def claims_markdown(results: Sequence[ClaimResult]) -> str:
    """The claims table as markdown (claim, verdict, numbers, tolerance).

    Examples
    --------
    >>> claims_markdown(judge([])).splitlines()[2].startswith("| 1 | Scan: white about 0.3-0.5 V")
    True
    """
    lines = ["| # | claim | verdict | numbers | tolerance |", "|---|---|---|---|---|"]
    for r in results:
        lines.append(f"| {r.number} | {r.text} | **{r.verdict}** | {r.numbers} | {r.tolerance} |")
    return "\n".join(lines)


def claims_terminal(results: Sequence[ClaimResult]) -> str:
    """The claims table for the terminal: per claim, its verdict and text, then its numbers.

    Examples
    --------
    >>> print(claims_terminal(judge([])).splitlines()[0])
    paper's claims (docs/method.md section 4.1): 0 hold, 0 fail, 10 not testable here
    """
    n = {v: sum(r.verdict == v for r in results) for v in VERDICTS}
    lines = [f"paper's claims (docs/method.md section 4.1): {n[HOLDS]} hold, {n[FAILS]} fail, "
             f"{n[NOT_TESTABLE]} not testable here"]
    for r in results:
        lines += [f"{r.number:>3} {r.verdict:17} {r.text}", f"{'':21}{r.numbers}"]
    return "\n".join(lines)


@dataclass(frozen=True)
class Contradiction:
    """One place where the paper's own numbers cannot all be true.

    Attributes
    ----------
    topic : str
    finding : str
        What was computed, with the numbers and formulas.
    inconsistent : bool
        True when the paper's numbers contradict each other.

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
                            static_over_kinetic: float = 2.0) -> float:
    """Largest static capacity (N) at which an open-loop drop can end in complete slippage.

    Complete slippage means sliding the whole grip travel ``d``. Generously,
    no energy is lost in the impact and friction falls to ``C / r`` the
    moment sliding starts (``r = static_over_kinetic``). The work friction does
    over ``d`` must then not exceed what falling supplies:
    ``(C / r) d <= m g (h + d) + M g d``, so
    ``C <= r [(M + m) g + m g h / d]``.

    Examples
    --------
    >>> round(drop_slipout_capacity_n(0.040, 0.010, 0.02, 0.03, 2.0), 2)
    1.11
    """
    g = hw.GRAVITY
    return static_over_kinetic * ((bottle_mass_kg + drop_mass_kg) * g + drop_mass_kg * g * height_m / travel_m)


#: Generous upper bound of static over sliding friction for polymer and elastomer contacts on PET.
STATIC_OVER_KINETIC_MAX: float = 2.0


def _capacity_contradiction(first_slip_ml: float = 200.0, plant: Any = None, simulate: bool = True
                            ) -> Contradiction:
    from ..sim import BOTTLES, PAPER_DROP, PAPER_POUR  # deferred: heavy (numba kernels)

    bottles = BOTTLES if plant is None else plant.bottles
    parts, worst = [], 0.0
    for name in BOTTLE_ORDER:
        b = bottles[name]
        pour_c = first_slip_capacity_n(b.mass_kg, first_slip_ml, rate_l_min=PAPER_POUR.rate_l_min,
                                       fall_height_m=PAPER_POUR.fall_height_m)
        drop_c = drop_slipout_capacity_n(b.mass_kg, PAPER_DROP.mass_kg, PAPER_DROP.height_m, b.grip_travel_m,
                                         STATIC_OVER_KINETIC_MAX)
        worst = max(worst, drop_c / pour_c)
        parts.append(f"{name}: drop slip-out needs C <= {drop_c:.2f} N, first pour slip at "
                     f"{first_slip_ml:g} ml implies C = {pour_c:.2f} N")
    text = ("; ".join(parts) + f" (C <= r[(M+m)g + mgh/d] with r = {STATIC_OVER_KINETIC_MAX:g} static/sliding, "
            "no impact loss; C = (M + rho V)g + rho Q sqrt(2 g h_jet)).")
    if simulate:
        from ..sim.calibration import drop_fall_capacity  # deferred: heavy (numba kernels)

        kw = None if plant is None else plant.rig_kwargs()
        sim = drop_fall_capacity(bottles["TR"], rig_kwargs=kw, iterations=8)
        text += (f" The simulated plant agrees (open loop, sim.calibration.drop_fall_capacity): a 10 g drop "
                 f"ends in complete slippage of TR only below a capacity of {sim['capacity_g']:.0f} g, while "
                 f"its pour-calibrated grasp holds {sim['bottle_capacity_g']:.0f} g.")
    return Contradiction("static capacity: drop slip-outs vs the first pour slip",
                         text + " The same 0.8 N grasp cannot be both: a 10 g drop cannot end in complete "
                         "slippage of a grasp that holds 200 ml.", worst < 1.0)


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


def _paper_rows() -> list[dict[str, Any]]:
    cells: dict[tuple, dict[str, Any]] = {}
    for (e, metric, b, m), v in PAPER.items():
        if v.mean is not None:
            row = cells.setdefault((e, b, m), {"experiment": e, "bottle": b, "method": m,
                                               "response_ms": math.nan, "total_ms": math.nan})
            row[metric] = v.mean
    return list(cells.values())


def _own_table() -> list[Contradiction]:
    ci = ClaimInput(_paper_rows())
    out = []
    for c in CLAIMS:
        if c.number in (3, 5, 7, 8, 9):   # the claims the paper's table of means can judge
            verdict, numbers = c.judge(ci)
            if verdict == FAILS:
                out.append(Contradiction(f"claim {c.number} on the paper's own table",
                                         f"{c.text}: fails on the paper's means ({numbers})", True))
    return out


def contradictions(first_slip_ml: float = 200.0, *, plant: Any = None, simulate: bool = True
                   ) -> list[Contradiction]:
    """Where the paper's numbers contradict each other (docs/method.md section 4.1), computed.

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
    return [_capacity_contradiction(first_slip_ml, plant, simulate), _identical_totals(), _window_sd(), *_own_table()]


def contradictions_markdown(items: Sequence[Contradiction]) -> str:
    """The contradictions as a markdown list (reported, not chased).

    Examples
    --------
    >>> contradictions_markdown([Contradiction("a", "b", True)])
    '- **a** (inconsistent): b'
    """
    return "\n".join(f"- **{c.topic}** ({'inconsistent' if c.inconsistent else 'consistent'}): {c.finding}"
                     for c in items)
