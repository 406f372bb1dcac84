"""What a study's plants say: claim fractions with confidence intervals, sensitivity, figures, study.md.

* :func:`plant_table` - one record per plant: its constants, its error and
  each claim's verdict.
* :func:`claim_fractions` - per claim, the study's verdict (one of the six
  classes of :mod:`slipreflex.analysis.claims`) with its reason, the
  fraction of plants where it holds with a 95 % Wilson score interval
  (``scipy.stats.binomtest``) and the count of every class (denominator: the
  plants that ran without error and were not rejected for an observed first
  slip outside the paper's band). Claims 1-2 are judged on every plant's
  scans pooled.
* :func:`sensitivity` - which constants decide each claim. For every design:
  Spearman's rank correlation between each constant and the claim holding
  (1) or failing (0), over the plants where it was testable, with its
  p-value; it needs no particular design and any N, and a rank measure fits a
  yes/no outcome of constants with log-uniform ranges. For the ``saltelli``
  design, also SALib's first-order and total Sobol' indices of the same
  indicator (every other verdict and errors count as 0).
* :func:`write_outputs` - results.parquet / results.csv, plants.csv,
  claims.csv, sensitivity.csv, figures and study.md from a
  :class:`~slipreflex.study.StudyRun`.

Examples
--------
>>> [round(x, 4) for x in wilson(8, 10)]
[0.4902, 0.9433]
"""

from __future__ import annotations

import csv
import math
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis.claims import (
    CLAIMS,
    CLAIMS_CSV_COLUMNS,
    DEPENDS_PLANT,
    FAILING,
    FAILS_DEFINITION,
    FAILS_PAPER,
    FAILS_PLANT,
    HOLDS,
    NOT_DECIDABLE,
    UNRESOLVED,
    VERDICTS,
    ClaimInput,
    proportion_interval,
)
from ..files.paths import new_file
from .design import varying
from .refine import ratio_estimate
from .runner import _arrow_table

__all__ = ["wilson", "plant_table", "pooled_scan", "claim_fractions", "refinement", "deciders", "reaches", "FDR",
           "sensitivity", "top_constants", "write_outputs",
           "study_markdown", "CLAIMS_COLUMNS", "SENSITIVITY_COLUMNS", "Z95"]

#: Normal quantile of the 95 % intervals.
Z95: float = 1.959963984540054
#: Columns of claims.csv: the claims table's (value: the fraction of plants where the claim holds, low/high
#: its Wilson interval), then the plants and the count of each verdict.
CLAIMS_COLUMNS: tuple[str, ...] = (*CLAIMS_CSV_COLUMNS[:-1], "plants", "errors", "rejected", "decided_by",
                                   *(v.replace("-", "_") for v in VERDICTS))
#: False-discovery rate of the "decided by" column (Benjamini-Hochberg over every constant x claim).
FDR: float = 0.05
#: The claims read off the characterization scan (no bottle, no hand, no method reading reaches them).
SCAN_CLAIMS: tuple[int, ...] = (1, 2)
#: Which claims a reading of the paper can reach (the rest reach none).
READING_REACH: dict[str, tuple[int, ...]] = {
    "method.swt_persist": (6, 7, 9),
    "method.rest_k": (5, 6, 7, 9, 11),
    "judge.cutoff_ms": (3, 5, 6, 7, 8, 9, 10, 11),
    "judge.time_tol_ms": (8,),
    "judge.near_ml": (6,),
}


def reaches(constant: Any, claim: int) -> bool:
    """Whether an uncertain constant can change a claim's quantity at all.

    The scan claims see only the slip sensor (a scan has no bottle, hand or water); a
    reading of the paper reaches only the claims that use it; every physical constant
    of the rig can reach every trial claim.

    Examples
    --------
    >>> from slipreflex.sim.uncertain import UNCERTAIN
    >>> reaches(UNCERTAIN["wall_stiffness"], 1), reaches(UNCERTAIN["wall_stiffness"], 5)
    (False, True)
    >>> reaches(UNCERTAIN["near_volume"], 6), reaches(UNCERTAIN["near_volume"], 8)
    (True, False)
    """
    targets = tuple(getattr(constant, "targets", ()))
    readings = [t for t in targets if t.split(".")[0] in ("method", "judge")]
    if readings:
        return any(claim in READING_REACH.get(t, ()) for t in readings)
    if claim in SCAN_CLAIMS:
        return any(t.startswith("slip_sensor.") for t in targets)
    return True
#: Columns of sensitivity.csv.
SENSITIVITY_COLUMNS: tuple[str, ...] = ("claim", "constant", "n", "spearman_rho", "spearman_p", "bh_q",
                                        "reaches", "sobol_s1", "sobol_s1_conf", "sobol_st", "sobol_st_conf", "rank")


def wilson(k: int, n: int) -> tuple[float, float]:
    """Wilson score interval (95 %) of a binomial proportion ``k / n`` (NaN, NaN for ``n == 0``).

    ``scipy.stats.binomtest(k, n).proportion_ci(method="wilson")``.

    Examples
    --------
    >>> lo, hi = wilson(0, 20)
    >>> lo, round(hi, 3)
    (0.0, 0.161)
    """
    return proportion_interval(k, n)[1:]


def plant_table(parts: Mapping[int, tuple[dict, list]]) -> list[dict[str, Any]]:
    """One record per plant: ``plant``, its constants, calibration, ``error``, ``claim_N`` and ``reason_N``.

    Examples
    --------
    >>> plant_table({0: ({"values": {"a": 1.0}, "error": "", "claims": [[1, "holds", "r"]]}, [])})
    [{'plant': 0, 'a': 1.0, 'error': '', 'claim_1': 'holds', 'reason_1': 'r'}]
    """
    out = []
    for i in sorted(parts):
        meta = parts[i][0]
        rec = {"plant": i, **meta["values"], **meta.get("calibration", {}), "error": meta["error"]}
        for n, v, why in meta["claims"]:
            rec.update({f"claim_{n}": v, f"reason_{n}": why})
        out.append(rec)
    return out


def pooled_scan(parts: Mapping[int, tuple[dict, list]]):
    """Every plant's scans as one :class:`~slipreflex.sim.scan.ScanEnsemble` (None without scans).

    Examples
    --------
    >>> pooled_scan({0: ({"scan": {}}, [])}) is None
    True
    """
    from ..sim.scan import ScanEnsemble  # deferred: heavy (llvmlite, numba, scipy)

    scans = [parts[i][0].get("scan") or {} for i in sorted(parts)]
    scans = [x for x in scans if x]
    if not scans:
        return None
    cols = {k: np.concatenate([np.asarray(x[k]) for x in scans]) for k in scans[0]}
    return ScanEnsemble(step_mm=1.0 / 333.3333333333333, **cols)


def _study_verdict(claim: Any, verdicts: list[str], reasons: list[str], deciders: str = "") -> tuple[str, str]:
    """The study's class of a claim from its plants' classes (and the reason).

    The same class on most plants for a reason no plant changes (the method's equations,
    the paper's numbers, nothing to judge): that class. Otherwise: holds on every plant,
    holds; fails on every plant, fails on this plant; holds on some plants and fails on
    others, depends on the plant (the fraction, and the constants that decide it); the
    rest (plants whose own trials do not decide it), unresolved.
    """
    if not verdicts:
        return NOT_DECIDABLE, "no plant ran"
    top = max(VERDICTS, key=verdicts.count)
    k, n = verdicts.count(HOLDS), len(verdicts)
    failing = sum(v in FAILING for v in verdicts)
    share = f"{verdicts.count(top)} of {n} plants"
    if top in (FAILS_DEFINITION, FAILS_PAPER, NOT_DECIDABLE):   # the equations or the paper: not the plant
        why = max(set(r for v, r in zip(verdicts, reasons) if v == top), key=reasons.count)
        return top, f"{share}: {why}"
    f, lo, hi = proportion_interval(k, n)
    text = f"holds on {k} of {n} plants ({100 * f:.0f} %, Wilson {100 * lo:.0f}-{100 * hi:.0f} %)"
    decided = f"; decided by {deciders}" if deciders else "; no constant passes the false-discovery control"
    if k == n:
        return HOLDS, text
    if failing == n:
        return FAILS_PLANT, f"fails on every one of the {n} plants"
    if k and failing:
        return DEPENDS_PLANT, f"{text}, fails on {failing}{decided}"
    return UNRESOLVED, (f"{text}, fails on {failing}; on the other {n - k - failing} the plant's own trials do not "
                        "decide it (more --trials would)")


def deciders(sens: Sequence[Mapping[str, Any]], claim: int, k: int = 3) -> str:
    """The constants that decide ``claim``: Benjamini-Hochberg q below :data:`FDR`, reaching the claim.

    Examples
    --------
    >>> deciders([{"claim": 5, "constant": "a", "spearman_rho": 0.5, "bh_q": 0.01, "reaches": True},
    ...           {"claim": 5, "constant": "b", "spearman_rho": 0.4, "bh_q": 0.2, "reaches": True}], 5)
    'a (rho +0.50, q 0.01)'
    """
    rows = [r for r in sens if r["claim"] == claim and r.get("reaches") and r.get("bh_q") == r.get("bh_q")
            and r["bh_q"] < FDR]
    rows.sort(key=lambda r: (r["bh_q"], r["constant"]))
    return ", ".join(f"{r['constant']} (rho {r['spearman_rho']:+.2f}, q {r['bh_q']:.2g})" for r in rows[:k])


def claim_fractions(plants: Sequence[Mapping[str, Any]], scan: Any = None,
                    sens: Sequence[Mapping[str, Any]] = (), refined: Any = None) -> list[dict[str, Any]]:
    """Per claim: the study's class and reason, the fraction of plants where it holds (Wilson), class counts.

    Plants with an error, or rejected for an observed first slip outside the paper's band,
    are counted apart. ``scan``: the pooled scans (:func:`pooled_scan`) judge claims 1-2.
    ``sens``: the sensitivity rows (:func:`sensitivity`) that name what decides a claim
    that depends on the plant.
    ``refined``: a refined study's second stage, ``(strata, weights, n_candidates)`` with
    ``strata`` mapping each second-stage plant to its stratum; ``value``, ``low`` and ``high``
    are then the two-phase stratified estimate over those plants and its interval
    (:func:`slipreflex.study.refine.ratio_estimate`), the class counts stay over every plant.

    Examples
    --------
    >>> rows = claim_fractions([{"error": "", "claim_3": "holds"}, {"error": "", "claim_3": "fails-plant"}])
    >>> rows[2]["holds"], rows[2]["value"], rows[2]["verdict"]
    (1, 0.5, 'depends-plant')
    """

    ok = [p for p in plants if not p.get("error") and not p.get("rejected")]
    order = {x: i for i, x in enumerate(VERDICTS)}
    out = []
    for c in CLAIMS:
        v = [p.get(f"claim_{c.number}", NOT_DECIDABLE) for p in ok]
        why = [str(p.get(f"reason_{c.number}", "")) for p in ok]
        k = v.count(HOLDS)
        frac, lo, hi = proportion_interval(k, len(v)) if refined is None else _refined(plants, c.number, refined)
        dec = deciders(sens, c.number)
        verdict, reason = _study_verdict(c, v, why, dec)
        criterion, qualifier = "the class on every plant; holds on some and fails on others: depends on the plant", ""
        if c.number in SCAN_CLAIMS and scan is not None:
            judged = c.judge(ClaimInput([], scan))
            d = min([p for p in judged if p.primary] or judged, key=lambda p: order[p.verdict])
            verdict, reason, criterion, qualifier = (d.verdict, f"{len(scan)} scans pooled over the plants: "
                                                     f"{d.reason}", d.criterion, d.qualifier)
        out.append({"claim": c.number, "text": c.text, "where": c.where, "verdict": verdict, "qualifier": qualifier,
                    "reason": reason, "value": frac if v else float("nan"), "criterion": criterion, "low": lo,
                    "high": hi, "plants": len(v), "errors": sum(bool(p.get("error")) for p in plants),
                    "rejected": sum(bool(p.get("rejected")) and not p.get("error") for p in plants),
                    "decided_by": dec, **{x.replace("-", "_"): v.count(x) for x in VERDICTS}})
    return out


def _refined(plants: Sequence[Mapping[str, Any]], claim: int, refined: Any) -> tuple[float, float, float]:
    """The two-phase stratified estimate of where ``claim`` holds, over the second-stage plants."""
    strata, weights, n_candidates = refined
    second = [p for p in plants if int(p["plant"]) in strata]
    accepted = [not p.get("error") and not p.get("rejected") for p in second]
    holds = [a and p.get(f"claim_{claim}") == HOLDS for a, p in zip(accepted, second)]
    est, _, lo, hi = ratio_estimate(holds, accepted, [strata[int(p["plant"])] for p in second], weights,
                                    n_candidates)
    return est, lo, hi


def _sobol(plants: Sequence[Mapping[str, Any]], names: list[str], table: Mapping, claim: int,
           seed: int) -> dict[str, tuple[float, float, float, float]]:
    from SALib.analyze import sobol  # deferred: optional extra (study: SALib)

    d = len(names)
    if not names or len(plants) % (d + 2):
        return {}
    y = np.array([1.0 if p.get(f"claim_{claim}") == HOLDS else 0.0 for p in plants])
    if y.std() == 0:
        return {}
    problem = {"num_vars": d, "names": names, "bounds": [[0.0, 1.0]] * d}

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        si = sobol.analyze(problem, y, calc_second_order=False, seed=seed % 2**32)
    return {k: (float(si["S1"][i]), float(si["S1_conf"][i]), float(si["ST"][i]), float(si["ST_conf"][i]))
            for i, k in enumerate(names)}


def sensitivity(plants: Sequence[Mapping[str, Any]], table: Mapping, *, design: str = "sobol",
                seed: int = 0) -> list[dict[str, Any]]:
    """Which constants decide each claim (see the module notes); rank 1 matters most.

    Examples
    --------
    >>> from slipreflex.sim.uncertain import UNCERTAIN
    >>> ps = [{"error": "", "hand_latency": x, "claim_8": "holds" if x < 0.02 else "fails-plant"}
    ...       for x in np.linspace(0.005, 0.03, 12)]
    >>> top = [r for r in sensitivity(ps, UNCERTAIN) if r["claim"] == 8 and r["rank"] == 1][0]
    >>> top["constant"], top["spearman_rho"] < -0.8
    ('hand_latency', True)
    """
    from scipy.stats import spearmanr  # deferred: heavy (scipy.stats)

    names = [k for k in varying(table) if all(k in p for p in plants)]
    ok = [p for p in plants if not p.get("error") and not p.get("rejected")]
    out = []
    for c in CLAIMS:
        testable = [p for p in ok if p.get(f"claim_{c.number}") in (HOLDS, FAILS_PLANT, UNRESOLVED, DEPENDS_PLANT)]
        y = np.array([p[f"claim_{c.number}"] == HOLDS for p in testable], dtype=float)
        sob = _sobol(plants, names, table, c.number, seed) if design == "saltelli" and len(ok) == len(plants) \
            else {}
        rows = []
        for k in names:
            x = np.array([p[k] for p in testable], dtype=float)
            rho, pv = (float("nan"), float("nan"))
            if len(y) > 2 and y.std() > 0 and x.std() > 0:
                res: Any = spearmanr(x, y)   # a SignificanceResult (scipy's stubs do not say so)
                rho, pv = float(res.statistic), float(res.pvalue)
            s = sob.get(k, (float("nan"),) * 4)
            rows.append({"claim": c.number, "constant": k, "n": len(testable), "spearman_rho": rho,
                         "spearman_p": pv, "bh_q": float("nan"), "reaches": reaches(table[k], c.number),
                         "sobol_s1": s[0], "sobol_s1_conf": s[1], "sobol_st": s[2],
                         "sobol_st_conf": s[3]})
        key = (lambda r: -r["sobol_st"]) if sob else (lambda r: -abs(r["spearman_rho"]))
        ranked = sorted(rows, key=lambda r: (math.isnan(key(r)), key(r) if not math.isnan(key(r)) else 0,
                                            r["constant"]))
        for i, r in enumerate(ranked):
            r["rank"] = i + 1 if not math.isnan(key(r)) else 0
        out += sorted(ranked, key=lambda r: names.index(r["constant"]))
    _false_discovery(out)
    return out


def _false_discovery(rows: list[dict[str, Any]]) -> None:
    """Fill ``bh_q``: Benjamini-Hochberg over every (constant, claim) the constant can reach.

    ``scipy.stats.false_discovery_control``; a constant that cannot reach a claim gets no
    q and never counts among the tests.
    """
    from scipy.stats import false_discovery_control  # deferred: heavy (scipy.stats)

    tested = [r for r in rows if r["reaches"] and r["spearman_p"] == r["spearman_p"]]
    if not tested:
        return
    q = false_discovery_control(np.array([r["spearman_p"] for r in tested]), method="bh")
    for r, v in zip(tested, q):
        r["bh_q"] = float(v)


def top_constants(sens: Sequence[Mapping[str, Any]], claim: int, k: int = 2) -> list[str]:
    """The ``k`` constants that matter most for ``claim`` (fewer when fewer are ranked).

    Examples
    --------
    >>> top_constants([{"claim": 1, "constant": "a", "rank": 2}, {"claim": 1, "constant": "b", "rank": 1}], 1)
    ['b', 'a']
    """
    ranked = sorted((r for r in sens if r["claim"] == claim and r["rank"] > 0), key=lambda r: r["rank"])
    return [r["constant"] for r in ranked[:k]]


def _cell(v: Any) -> str:
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    if v is None:
        return ""
    return str(v)


def _write_csv(path: Path, rows: Sequence[Mapping[str, Any]], columns: Sequence[str]) -> Path:

    with new_file(path, "w", replace=True) as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(columns)
        for r in rows:
            w.writerow([_cell(r.get(c)) for c in columns])
    return path


def _columns(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    cols: list[str] = []
    seen = set()
    for r in rows:
        for k in r:
            if k not in seen:
                seen.add(k)
                cols.append(k)
    return cols


_COLORS = {HOLDS: "#2ca02c", "fails-definition": "#7f0000", "fails-paper": "#ff7f0e", FAILS_PLANT: "#d62728",
           DEPENDS_PLANT: "#9467bd", UNRESOLVED: "#1f77b4", NOT_DECIDABLE: "0.75", "error": "black"}


def _plot_claim(plants, claim: Any, xy: list[str], table: Mapping, path: Path) -> Path:
    import matplotlib  # deferred: heavy (matplotlib)

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # deferred: heavy (matplotlib)

    fig, ax = plt.subplots(figsize=(5.5, 4.2), constrained_layout=True)
    for verdict, color in _COLORS.items():
        sel = [p for p in plants if (("error" if p.get("error") else p.get(f"claim_{claim.number}")) == verdict)]
        if sel:
            x = [p[xy[0]] for p in sel]
            y = [p[xy[1]] if len(xy) > 1 else 0.0 for p in sel]
            ax.scatter(x, y, s=28, c=color, marker="x" if verdict == "error" else "o",
                       label=f"{verdict} ({len(sel)})", edgecolors="none" if verdict != "error" else None)
    for axis, name in zip("xy", xy):
        c = table[name]
        getattr(ax, f"set_{axis}label")(f"{name} ({c.unit})")
        if c.distribution == "loguniform":
            from matplotlib import ticker  # deferred: heavy (matplotlib)

            getattr(ax, f"set_{axis}scale")("log")
            a = getattr(ax, f"{axis}axis")
            a.set_major_locator(ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
            a.set_major_formatter(ticker.FormatStrFormatter("%g"))
            a.set_minor_formatter(ticker.NullFormatter())
    ax.set_title(f"claim {claim.number}: {claim.text}", fontsize=8, wrap=True)
    ax.legend(fontsize=7, loc="best")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def _plot_fractions(fractions: Sequence[Mapping[str, Any]], path: Path) -> Path:
    import matplotlib  # deferred: heavy (matplotlib)

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # deferred: heavy (matplotlib)

    fig, ax = plt.subplots(figsize=(8.5, 4.2), constrained_layout=True)
    n = [r["claim"] for r in fractions]
    bottom = np.zeros(len(n))
    for v in VERDICTS:
        share = np.array([r[v.replace("-", "_")] / r["plants"] if r["plants"] else np.nan for r in fractions]) * 100
        ax.bar(n, share, bottom=bottom, color=_COLORS[v], label=v)
        bottom += np.nan_to_num(share)
    f = np.array([r["value"] for r in fractions], dtype=float) * 100
    lo = np.array([r["low"] for r in fractions], dtype=float) * 100
    hi = np.array([r["high"] for r in fractions], dtype=float) * 100
    ax.errorbar(n, f, yerr=[np.maximum(np.nan_to_num(f - lo), 0), np.maximum(np.nan_to_num(hi - f), 0)], fmt="none",
                ecolor="black", capsize=3, label="holds: 95 % Wilson interval")
    ax.set(xticks=n, xlabel="claim", ylabel="% of plants", ylim=(0, 100),
           title="Where the paper's claims hold across plausible plants")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def write_outputs(run: Any, *, figures: bool = True, command: str | None = None) -> dict[str, Path]:
    """Write the combined results and the map of a study run into ``run.out``.

    Returns
    -------
    dict
        Paths by name: results_parquet, results_csv, plants, claims, sensitivity, study_md,
        and one per figure.

    Examples
    --------
    >>> import tempfile
    >>> from slipreflex.study import StudyConfig, run_study
    >>> cfg = StudyConfig(plants=2, trials=1, bottles=("TX",), methods=("dath",), experiments=("drop",),
    ...                   calibrate=False, scan=False)
    >>> paths = write_outputs(run_study(cfg, tempfile.mkdtemp(), workers=0, progress=False), figures=False)
    >>> sorted(paths)
    ['claims', 'plants', 'results_csv', 'results_parquet', 'sensitivity', 'study_md']
    """
    import pyarrow.parquet as pq  # deferred: optional extra (study: pyarrow)


    out = Path(run.out)
    rows = [r for i in sorted(run.parts) for r in run.parts[i][1]]
    paths: dict[str, Path] = {}
    paths["results_parquet"] = out / "results.parquet"
    pq.write_table(_arrow_table(rows), paths["results_parquet"])
    paths["results_csv"] = _write_csv(out / "results.csv", rows, _columns(rows))
    plants = plant_table(run.parts)
    paths["plants"] = _write_csv(out / "plants.csv", plants, _columns(plants))
    table = run.config.table
    sens = sensitivity(plants, table, design=run.config.design, seed=run.config.seed)
    paths["sensitivity"] = _write_csv(out / "sensitivity.csv", sens, SENSITIVITY_COLUMNS)
    fractions = claim_fractions(plants, pooled_scan(run.parts), sens, refinement(run))
    paths["claims"] = _write_csv(out / "claims.csv", fractions, CLAIMS_COLUMNS)
    figs: list[tuple[str, str]] = []
    if figures:
        fig_dir = out / "figures"
        fig_dir.mkdir(exist_ok=True)
        paths["fractions.png"] = _plot_fractions(fractions, fig_dir / "fractions.png")
        figs.append(("Every claim's holding fraction", "figures/fractions.png"))
        for c in CLAIMS:
            xy = top_constants(sens, c.number) or varying(table)[:2]
            if xy:
                name = f"claim_{c.number:02d}.png"
                paths[name] = _plot_claim(plants, c, xy, table, fig_dir / name)
                figs.append((f"Claim {c.number} over {' and '.join(xy)}", f"figures/{name}"))
    paths["study_md"] = out / "study.md"
    paths["study_md"].write_text(study_markdown(run, plants, fractions, sens, figs, command))
    return paths


def refinement(run: Any) -> Any:
    """``claim_fractions``' ``refined`` argument for a finished refined study (None otherwise).

    Examples
    --------
    >>> from slipreflex.study import StudyConfig, StudyRun
    >>> refinement(StudyRun(StudyConfig(plants=1), Path("o"), {}, [], 0.0, "serial")) is None
    True
    """
    cfg = run.config
    if not cfg.refine or not run.complete:
        return None
    plan = cfg.refine_plan(run.parts)
    strata = {cfg.plants + j: int(h) for j, h in enumerate(plan.strata)}
    return strata, plan.weights, plan.n_candidates


def _pct(x: float) -> str:
    return "-" if x != x else f"{100 * x:.0f}%"


def study_markdown(run: Any, plants: Sequence[Mapping[str, Any]], fractions: Sequence[Mapping[str, Any]],
                   sens: Sequence[Mapping[str, Any]], figures: Sequence[tuple[str, str]],
                   command: str | None = None) -> str:
    """study.md: what the map says about each of the paper's conclusions, computed from the run.

    Examples
    --------
    >>> from slipreflex.study import StudyConfig, StudyRun
    >>> run = StudyRun(StudyConfig(plants=1), Path("o"), {}, [], 0.0, "serial")
    >>> study_markdown(run, [], claim_fractions([]), [], []).startswith("# slipreflex study")
    True
    """
    cfg = run.config
    names = varying(cfg.table)
    errors = [p for p in plants if p.get("error")]
    lines = ["# slipreflex study: where the paper's claims hold", ""]
    if command:
        lines += [f"Command: `{command}`", ""]
    lines += [f"{len(plants)} plants ({cfg.design} design, seed {cfg.seed}) over {len(names)} uncertain "
              f"constants; on each: {cfg.trials} trial(s) x bottles {', '.join(cfg.bottles)} x experiments "
              f"{', '.join(cfg.experiments)} x methods {', '.join(cfg.methods)} = {cfg.trials_per_plant} "
              "closed-loop trials, the same trial seeds on every plant; pads calibrated to the paper's "
              f"open-loop first slip as the accelerometer observes it: {'yes' if cfg.calibrate else 'no'}; scans: "
              + (f"{cfg.scan_seeds} texture seeds of its own per plant" if cfg.scan else "none") + ". "
              f"{len(errors)} plant(s) raised an error (in plants.csv); "
              f"{sum(bool(p.get('rejected')) for p in plants)} rejected: their calibrated observed first slip "
              "left the paper's band (counted apart).", ""]
    lines += _calibration_lines(plants, cfg.table) if cfg.calibrate else []
    if cfg.refine:
        lines += [f"Refined: the first {cfg.plants} plants (the pilot) drew the strata, {cfg.refine} more were "
                  "sampled within them; a claim's holds and interval are the two-phase stratified estimate over "
                  "those (slipreflex.study.refine), its class counts are over every plant.", ""]
    lines += ["## Claims", "",
              "Class: the study's (fails-definition, fails-paper and not-decidable when most plants say so, for "
              "a reason no plant changes; otherwise holds on every plant: holds; fails on every plant: "
              "fails-plant; holds on some and fails on others: depends-plant; the rest unresolved; claims 1-2 on "
              "every plant's scans pooled). Holds: % of the plants that ran (and were not rejected) where the "
              "claim holds. Decided by: the constants whose Spearman correlation with the claim holding passes "
              f"Benjamini-Hochberg at {100 * FDR:g} % over every constant and claim it can reach (sensitivity.csv"
              + ("; SALib's total Sobol' indices beside it" if cfg.design == "saltelli" else "") + ").", "",
              "| # | claim | verdict | holds | 95 % interval | plants by verdict | decided by |",
              "|---|---|---|---|---|---|---|"]
    for r in fractions:
        dec = r.get("decided_by") or "-"
        by = ", ".join(f"{r[v.replace('-', '_')]} {v}" for v in VERDICTS if r[v.replace("-", "_")])
        cls = r["verdict"] + (f" ({r['qualifier']})" if r.get("qualifier") else "")
        lines.append(f"| {r['claim']} | {r['text']} | **{cls}** | {_pct(r['value'])} | "
                     f"{_pct(r['low'])}-{_pct(r['high'])} | {by or '-'} | {dec} |")
    lines += ["", "## What the map says", ""] + [f"- {s}" for s in _verdict_lines(fractions)] + [""]
    lines += ["## Uncertain constants", "", "| constant | unit | range | distribution |", "|---|---|---|---|"]
    for k, c in cfg.table.items():
        rng = f"{c.low:g}" if c.fixed else f"{c.low:g} .. {c.high:g}"
        lines.append(f"| {k} | {c.unit} | {rng} | {'fixed' if c.fixed else c.distribution} |")
    lines += [""]
    if figures:
        lines += ["## Figures", ""]
        for cap, rel in figures:
            lines += [f"![{cap}]({rel})", "", f"*{cap}*", ""]
    return "\n".join(lines)


def _calibration_lines(plants: Sequence[Mapping[str, Any]], table: Mapping) -> list[str]:
    """What the open-loop calibration could not do: plants whose first slip jumps over their target.

    Examples
    --------
    >>> from slipreflex.sim.uncertain import UNCERTAIN
    >>> _calibration_lines([{"error": "", "calibration_note": "", "first_slip_ml": 190.0}], UNCERTAIN)
    []
    >>> p = {"error": "", "calibration_note": "TR jumps", "first_slip_ml": 190.0, "calibrated_first_slip_ml_TR": 181.0}
    >>> "1 plant(s): no pad friction" in _calibration_lines([p], UNCERTAIN)[0]
    True
    """
    edge = [p for p in plants if p.get("calibration_note")]
    failed = [p for p in plants if "jumps from" in str(p.get("error", ""))]
    if not edge and not failed:
        return []
    c = table["first_slip_ml"]
    off = [abs(v - p["first_slip_ml"]) for p in edge for k, v in p.items()
           if k.startswith("calibrated_first_slip_ml_") and v == v]
    text = ("Calibration: the open-loop first pour slip grows in steps with the pads' mu_s (the bottle slips "
            "grossly only when all three contacts slide, and the middle finger's cuff sticks and slips in its "
            "own cycle as the water comes in, so the first slip can start only at one of the cuff's slips); "
            "where a step jumps over the plant's drawn target volume no pad friction meets it.")
    if edge:
        text += (f" {len(edge)} plant(s): no pad friction meets the target; calibrated to the nearest reachable "
                 f"volume within the paper's 'about 200 ml' ({c.low:g}-{c.high:g} ml), at most "
                 f"{max(off, default=0.0):.0f} ml from the target (calibrated_first_slip_ml_* in plants.csv).")
    if failed:
        text += (f" {len(failed)} plant(s): no reachable first slip lies in {c.low:g}-{c.high:g} ml, so the "
                 "paper's open-loop fact cannot be met on them; they are recorded as errors.")
    return [text, ""]


def _verdict_lines(fractions: Sequence[Mapping[str, Any]]) -> list[str]:
    return [f"Claim {r['claim']} ({r['text']}): **{r['verdict']}**: {r['reason']}." for r in fractions]
