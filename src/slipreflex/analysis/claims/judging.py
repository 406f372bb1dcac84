"""The judging of each of the paper's claims, part by part, and the registry :data:`CLAIMS`.

Each judge reads a :class:`~slipreflex.analysis.claims.verdicts.ClaimInput` and returns the
claim's parts; :data:`CLAIMS` holds the paper's eleven sentences, where they are, and their
judges. Re-exported by :mod:`slipreflex.analysis.claims`.

Examples
--------
>>> [c.number for c in CLAIMS][:3]
[1, 2, 3]
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from ...methods import DATH, FIXED, NMSD, SWT
from ...methods import label as _label
from ...methods import names as method_names
from ..paper import BOTTLE_ORDER, EXPERIMENTS, PAPER
from ..stats import (
    FRACTION,
    INDEX,
    MEAN,
    MEAN_DIFF,
    RATIO,
    Sample,
    cluster_interval,
    km_median,
    newcombe_interval,
    rank_p,
    wilson_interval,
)
from .drop import DROP_ASSUMPTIONS, drop_bounds
from .verdicts import (
    BOOTSTRAP_SEED,
    CALIBRATED_INPUT,
    CENTRAL,
    CONFIDENCE,
    FAILS_DEFINITION,
    FAILS_PAPER,
    FAILS_PLANT,
    HOLDS,
    INF,
    LENGTH_TOL_MM,
    MOST,
    NOT_DECIDABLE,
    TOLERANCES,
    UNDER_MS,
    UNRESOLVED,
    VERDICTS,
    VOLT_TOL,
    Claim,
    ClaimInput,
    ClaimResult,
    Part,
    _ci,
    _count,
    _f,
    _get,
    _num,
    about_rate_band,
    median_interval,
)

__all__ = ["CLAIMS", "tilt_and_taper"]


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
    from ...sim import BOTTLES  # deferred: heavy (numba kernels)

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


