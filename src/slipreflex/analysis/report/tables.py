"""summary.csv, results.csv, the terminal table and the Markdown tables and sections of report.md.

Rows are :class:`~slipreflex.analysis.trial.TrialRow` objects or dicts with the same keys
(a results.csv read back). Re-exported by :mod:`slipreflex.analysis.report`.

Examples
--------
>>> SUMMARY_COLUMNS[:3]
('experiment', 'bottle', 'method')
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ... import methods
from ...core import experiment_specs
from ...files.csvfiles import cell_bool, cell_float
from ...files.paths import new_file
from ...methods import label as _label
from ..claims import claims_section
from ..paper import BOTTLE_ORDER, EXPERIMENTS, PAPER_NOTES, PAPER_SUCCESS, paper_value
from ..trial import RESULT_COLUMNS

__all__ = [
    "SUMMARY_COLUMNS", "summarize", "void", "void_notice", "NOT_COMPARED", "write_csv", "read_csv", "terminal_table",
    "comparison_markdown", "success_markdown", "onset_markdown", "pour_slips_markdown", "differences",
    "report_markdown", "fmt_mean_sd", "group_key_order"
]


#: Columns of summary.csv, in order.
SUMMARY_COLUMNS: tuple[str, ...] = (
    "experiment", "bottle", "method", "n_trials", "n_rows", "n_events",
    "response_mean_ms", "response_sd_ms", "response_n",
    "total_mean_ms", "total_sd_ms", "total_n",
    "trial_success_rate", "trial_success_n", "event_success_rate", "event_success_n",
    "grip_without_slip_mean", "grip_without_slip_sd", "grip_without_slip_n",
    "onset_error_mean_ms", "onset_error_sd_ms", "onset_error_n",
    "paper_response_ms", "paper_total_ms", "n_void",
)


def _stats(values: Iterable[Any]) -> tuple[float, float, int]:
    v = np.array([cell_float(x) for x in values], dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return float("nan"), float("nan"), 0
    sd = float(np.std(v, ddof=1)) if v.size > 1 else float("nan")
    return float(np.mean(v)), sd, int(v.size)


def group_key_order(key: tuple[str, str, str]) -> tuple:
    """Sort key: experiments, bottles and methods in the paper's order.

    Examples
    --------
    >>> sorted([("pour", "TR", "nmsd"), ("drop", "TX", "dath")], key=group_key_order)[0]
    ('drop', 'TX', 'dath')
    """
    def idx(seq, x):
        return seq.index(x) if x in seq else len(seq)
    e, b, m = key
    return (idx(experiment_specs.names(), e), e, idx(BOTTLE_ORDER, b), b, idx(methods.names(), m), m)


def _table_methods(by: dict[tuple[str, str, str], Any]) -> list[str]:
    """Columns of a comparison table: the paper's methods, then any other method that ran."""
    ran = {k[2] for k in by}
    return (list(methods.names(paper=True)) + [m for m in methods.names() if m in ran
                                               and m not in methods.names(paper=True)]
            + sorted(ran - set(methods.names())))


def _count(x: Any) -> int:
    """A count cell as an int (a blank or NaN cell is 0)."""
    v = cell_float(x)
    return int(v) if v == v else 0


def _flag(x: Any) -> float:
    """A True/False cell (bool or its CSV text) as 1.0 / 0.0."""
    return float(cell_bool(x))


def void(row: Any) -> bool:
    """Whether a row's trial is void: the object left the grasp before the perturbation.

    Such a trial measures the grasp, not the method: it is reported apart (``n_void``)
    and never scored.

    Examples
    --------
    >>> void({"fell_before_load": "True"}), void({"fell_before_load": False}), void({})
    (True, False, False)
    """
    return bool(_flag(row.get("fell_before_load", False)))


def _trial_key(r: Any) -> tuple:
    return (str(r.get("trial")), str(r.get("seed")))


def summarize(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Mean, sd (ddof 1) and n per experiment, bottle and method, plus success per trial and per event.

    ``trial_success_rate``: the trials in which every slip was suppressed (the object
    stayed in the grasp), over the trials; ``event_success_rate``: the rows that
    succeeded, over all rows (slip events; a trial without a detected slip counts
    once). ``grip_without_slip``: per trial, how far the hand closed (finger units)
    while no true slip was under way (simulator truth; NaN on hardware). NaN timings
    (no onset, no response) are left out of the means and counted in ``n``. Void
    trials (the object fell out before the perturbation) are left out of everything
    and counted in ``n_void``.

    Examples
    --------
    >>> rows = [{"experiment": "drop", "bottle": "TR", "method": "dath", "trial": 0, "event": e,
    ...          "success": e == 0, "grip_without_slip": 12.0} for e in (0, 1)]
    >>> s = summarize(rows)[0]
    >>> s["trial_success_rate"], s["trial_success_n"], s["event_success_rate"], s["event_success_n"]
    (0.0, 1, 0.5, 2)
    >>> s["grip_without_slip_mean"], s["n_void"]
    (12.0, 0)
    """
    groups: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r["experiment"], r["bottle"], r["method"]), []).append(r)
    out = []
    for key in sorted(groups, key=group_key_order):
        everything = groups[key]
        g = [r for r in everything if not void(r)]
        e, b, m = key
        rm, rs, rn = _stats(r.get("response_ms", math.nan) for r in g)
        tm, ts, tn = _stats(r.get("total_ms", math.nan) for r in g)
        em, es, en = _stats(r.get("onset_error_ms", math.nan) for r in g)
        succ = [_flag(r.get("success", False)) for r in g]
        trials: dict[tuple, list[Any]] = {}
        for r in g:
            trials.setdefault(_trial_key(r), []).append(r)
        per_trial = [min(_flag(r.get("success", False)) for r in t) for t in trials.values()]
        gm, gs, gn = _stats(t[0].get("grip_without_slip", math.nan) for t in trials.values())
        pr, pt = paper_value(e, "response_ms", b, m), paper_value(e, "total_ms", b, m)
        out.append({
            "experiment": e, "bottle": b, "method": m,
            "n_trials": len(trials),
            "n_rows": len(g),
            "n_events": int(sum(1 for r in g if cell_float(r.get("n_events", 1)) > 0)),
            "response_mean_ms": rm, "response_sd_ms": rs, "response_n": rn,
            "total_mean_ms": tm, "total_sd_ms": ts, "total_n": tn,
            "trial_success_rate": float(np.mean(per_trial)) if per_trial else float("nan"),
            "trial_success_n": len(per_trial),
            "event_success_rate": float(np.mean(succ)) if succ else float("nan"), "event_success_n": len(succ),
            "grip_without_slip_mean": gm, "grip_without_slip_sd": gs, "grip_without_slip_n": gn,
            "onset_error_mean_ms": em, "onset_error_sd_ms": es, "onset_error_n": en,
            "paper_response_ms": pr.text() if pr else "", "paper_total_ms": pt.text() if pt else "",
            "n_void": len({_trial_key(r) for r in everything if void(r)}),
        })
    return out


def _pct(s: dict[str, Any], kind: str) -> str:
    """``"90% of 10"`` for a summary row's ``kind`` ("trial" or "event") success, ``"-"`` without one."""
    n = _count(s.get(f"{kind}_success_n", 0))
    return f"{100 * float(s[f'{kind}_success_rate']):.0f}% of {n}" if n else "-"


def void_notice(summary: Sequence[dict[str, Any]]) -> str:
    """The line that says which trials were void (object out before the perturbation), ``""`` if none.

    Examples
    --------
    >>> line = void_notice([{"experiment": "drop", "bottle": "JAR", "method": "dath", "n_void": 2, "n_trials": 8}])
    >>> line.startswith("Void trials (the object left the grasp before the perturbation"), line.split(": ")[1]
    (True, 'drop JAR DATH 2 of 10. A stronger --grasp-force holds it.')
    """
    parts = [f"{s['experiment']} {s['bottle']} {_label(s['method'])} {int(s['n_void'])} of "
             f"{int(s['n_void']) + int(s['n_trials'])}" for s in summary if _count(s.get("n_void", 0))]
    if not parts:
        return ""
    return ("Void trials (the object left the grasp before the perturbation, so no method was tested; "
            "not scored): " + ", ".join(parts) + ". A stronger --grasp-force holds it.")


def _cell(v: Any) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "True" if v else "False"
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(round(v, 6))
    return str(v)


def write_csv(path: str | Path, rows: Sequence[Any],
              columns: Sequence[str] = RESULT_COLUMNS, *, notes: Sequence[str] = ()) -> Path:
    """Write ``rows`` with exactly ``columns`` (NaN as an empty cell).

    ``notes`` come first, as ``# `` lines (a partial run says so there); :func:`read_csv`
    skips them.

    Examples
    --------
    >>> import tempfile, os
    >>> p = write_csv(os.path.join(tempfile.mkdtemp(), "r.csv"), [{"a": 1.5, "b": float("nan")}], ["a", "b"])
    >>> p.read_text().splitlines()
    ['a,b', '1.5,']
    """

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with new_file(path, "w", replace=True) as fh:
        fh.writelines(f"# {n}\n" for n in notes)
        w = csv.writer(fh)
        w.writerow(columns)
        for r in rows:
            w.writerow([_cell(r.get(c, "")) for c in columns])
    return path


def read_csv(path: str | Path) -> list[dict[str, str]]:
    """Read a CSV written by :func:`write_csv` into dicts of strings.

    Examples
    --------
    >>> import tempfile, os
    >>> p = write_csv(os.path.join(tempfile.mkdtemp(), "r.csv"), [{"a": 1}], ["a"])
    >>> read_csv(p)
    [{'a': '1'}]
    """
    with Path(path).open(newline="") as fh:
        return list(csv.DictReader(line for line in fh if not line.startswith("#")))


def fmt_mean_sd(mean: float, sd: float, n: int | None = None, digits: int = 0) -> str:
    """``"mean ± sd"`` (and ``" (n)"``), or ``"-"`` when there is no value.

    Examples
    --------
    >>> fmt_mean_sd(50.26, 6.4, 10), fmt_mean_sd(float("nan"), float("nan"), 0), fmt_mean_sd(-0.2, 1.0)
    ('50 ± 6 (10)', '-', '0 ± 1')
    """
    if n == 0 or mean is None or (isinstance(mean, float) and math.isnan(mean)):
        return "-"
    s = f"{round(mean, digits) + 0.0:.{digits}f}"   # + 0.0: no "-0"
    s += f" ± {sd:.{digits}f}" if sd == sd else ""
    return s + (f" ({n})" if n is not None else "")


def _answered(s: Mapping[str, Any]) -> str:
    """A cell's response as mean ± sd over the slips answered, and how many of its slips those were.

    A slip no response answered within the cutoff is a censored trial: the mean is over the
    answered ones, and the count says how many were not.

    Examples
    --------
    >>> _answered({"response_mean_ms": 62.0, "response_sd_ms": 21.0, "response_n": 12, "n_events": 20})
    '62 ± 21 (12 of 20)'
    """
    text = fmt_mean_sd(s["response_mean_ms"], s["response_sd_ms"])
    slips = s.get("n_events")
    return text if text == "-" else text + (f" ({s['response_n']} of {slips})" if slips else f" ({s['response_n']})")


def terminal_table(summary: Sequence[dict[str, Any]]) -> str:
    """A compact text table of the summary for the terminal.

    Examples
    --------
    >>> print(terminal_table([]))
    exp   bottle method  response ms (n of N)  total ms (n)      success/trial success/slip event grip w/o slip
    """
    w = max([7] + [len(_label(s["method"])) for s in summary])
    head = (f"{'exp':5} {'bottle':6} {'method':{w}} {'response ms (n of N)':21} {'total ms (n)':17} "
            f"{'success/trial':13} {'success/slip event':18} grip w/o slip")
    lines = [head]
    for s in summary:
        grip = s.get("grip_without_slip_mean", math.nan)
        lines.append(
            f"{s['experiment']:5} {s['bottle']:6} {_label(s['method']):{w}} "
            f"{_answered(s):21} "
            f"{fmt_mean_sd(s['total_mean_ms'], s['total_sd_ms'], s['total_n']):17} "
            f"{_pct(s, 'trial'):13} {_pct(s, 'event'):18} "
            + ("-" if not _finite(cell_float(grip)) else f"{float(grip):.0f} units"))
    notice = void_notice(summary)
    return "\n".join(lines + ([notice] if notice else []))


def comparison_markdown(summary: Sequence[dict[str, Any]]) -> str:
    """The paper's table beside ours, as markdown (one line per experiment, metric, bottle).

    Examples
    --------
    >>> comparison_markdown([]).splitlines()[0].split(" | ")[:5]
    ['| experiment, metric', 'bottle', 'DATH paper', 'DATH ours', 'fixed paper']
    """
    by = {(s["experiment"], s["bottle"], s["method"]): s for s in summary}
    order = _table_methods(by)
    cols = " | ".join(f"{_label(m)} paper | {_label(m)} ours" for m in order)
    lines = [f"| experiment, metric | bottle | {cols} |", "|---|---|" + "---|" * (2 * len(order))]
    exps = [e for e in EXPERIMENTS if any(k[0] == e for k in by)] or list(EXPERIMENTS)
    bottles = [b for b in BOTTLE_ORDER if any(k[1] == b for k in by)] or list(BOTTLE_ORDER)
    for e in exps:
        for metric, label in (("response", "response ms"), ("total", "total ms")):
            for b in bottles:
                cells = []
                for m in order:
                    p = paper_value(e, f"{metric}_ms", b, m)
                    s = by.get((e, b, m))
                    ours = fmt_mean_sd(s[f"{metric}_mean_ms"], s[f"{metric}_sd_ms"],
                                       s[f"{metric}_n"]) if s else NOT_COMPARED
                    cells += [p.text() if p else "-", ours]
                lines.append(f"| {e}, {label} | {b} | " + " | ".join(cells) + " |")
    for e in exps:
        cells = []
        for m in order:
            pt = PAPER_SUCCESS.get((e, "all", m), "-")
            ours = [by[(e, b, m)] for b in bottles if (e, b, m) in by]
            n = sum(s["event_success_n"] for s in ours)
            if n:
                rate = sum(s["event_success_rate"] * s["event_success_n"] for s in ours) / n
                cells += [pt, f"{100 * rate:.0f}% of {n} slip events"]
            else:
                cells += [pt, NOT_COMPARED]
        lines.append(f"| {e}, success | all | " + " | ".join(cells) + " |")
    return "\n".join(lines)


#: What a table cell says where this run has no comparable value: the method or bottle did not
#: run, or ran only with objects or loads that are not the paper's (those are under 'Your objects').
NOT_COMPARED: str = "no comparable run"


def success_markdown(summary: Sequence[dict[str, Any]]) -> str:
    """Success per trial and per slip event, and the grip added without slip, as a markdown table.

    Examples
    --------
    >>> print(success_markdown([{"experiment": "drop", "bottle": "TX", "method": "dath",
    ...                          "trial_success_rate": 0.9, "trial_success_n": 10, "event_success_rate": 0.9,
    ...                          "event_success_n": 10, "grip_without_slip_mean": 4.0}]).splitlines()[2])
    | drop | TX | DATH | 90% of 10 | 90% of 10 | 4 | 90 % |
    """
    lines = ["| experiment | bottle | method | success per trial | success per slip event | "
             "grip added without slip (units) | paper |", "|---|---|---|---|---|---|---|"]
    for s in sorted(summary, key=lambda s: group_key_order((s["experiment"], s["bottle"], s["method"]))):
        e, b, m = s["experiment"], s["bottle"], s["method"]
        grip = cell_float(s.get("grip_without_slip_mean", math.nan))
        lines.append(f"| {e} | {b} | {_label(m)} | {_pct(s, 'trial')} | {_pct(s, 'event')} | "
                     f"{'-' if math.isnan(grip) else format(grip, '.0f')} | {PAPER_SUCCESS.get((e, b, m), '-')} |")
    return "\n".join(lines)


def onset_markdown(rows: Sequence[dict[str, Any]]) -> str:
    """Accelerometer onset estimate vs the simulator's true onset, per experiment and bottle.

    Examples
    --------
    >>> r = [{"experiment": "drop", "bottle": "TR", "onset_error_ms": e} for e in (2.0, 4.0)]
    >>> print(onset_markdown(r).splitlines()[2])
    | drop | TR | 3.0 ± 1.4 (2) | 2.0 | 4.0 |
    """
    groups: dict[tuple[str, str], list[float]] = {}
    for r in rows:
        groups.setdefault((r["experiment"], r["bottle"]), []).append(cell_float(r.get("onset_error_ms")))
    lines = ["| experiment | bottle | error ms, mean ± sd (n) | min | max |", "|---|---|---|---|---|"]
    for (e, b) in sorted(groups, key=lambda k: group_key_order((k[0], k[1], ""))):
        v = np.array(groups[(e, b)], dtype=float)
        v = v[np.isfinite(v)]
        m, s, n = _stats(v)
        lo = f"{v.min():.1f}" if v.size else "-"
        hi = f"{v.max():.1f}" if v.size else "-"
        lines.append(f"| {e} | {b} | {fmt_mean_sd(m, s, n, 1)} | {lo} | {hi} |")
    return "\n".join(lines)


def pour_slips_markdown(rows: Sequence[dict[str, Any]]) -> str:
    """Slips per pour trial and the poured volume at each, per bottle and method.

    The paper: "two distinct slips were observed in most of the trials", near
    200 ml and near 400 ml.

    Examples
    --------
    >>> r = [{"experiment": "pour", "bottle": "DK", "method": "dath", "trial": 0, "seed": 1,
    ...       "event": e, "n_events": 2, "load_at_onset": v} for e, v in ((0, 190.0), (1, 410.0))]
    >>> print(pour_slips_markdown(r).splitlines()[2])
    | DK | DATH | 2.0 | 100% | 190 | 410 |
    """
    groups: dict[tuple[str, str, str], dict[tuple, list[dict[str, Any]]]] = {}
    for r in rows:
        if not experiment_specs.get(r["experiment"]).records_load:   # slips at a load: the pour's
            continue
        key = (r["experiment"], r["bottle"], r["method"])
        groups.setdefault(key, {}).setdefault((r["trial"], r["seed"]), []).append(r)
    lines = ["| bottle | method | slips per trial (mean) | trials with 2+ slips | ml at 1st slip (median) "
             "| ml at 2nd slip (median) |", "|---|---|---|---|---|---|"]
    for (e, b, m) in sorted(groups, key=group_key_order):
        trials = groups[(e, b, m)]
        n = [int(cell_float(rs[0].get("n_events", 0))) for rs in trials.values()]
        first = [cell_float(r.get("load_at_onset")) for rs in trials.values() for r in rs
                 if int(cell_float(r.get("event", 0))) == 0 and int(cell_float(r.get("n_events", 0))) > 0]
        second = [cell_float(r.get("load_at_onset")) for rs in trials.values() for r in rs
                  if int(cell_float(r.get("event", 0))) == 1]

        def med(v):
            v = [x for x in v if x == x]
            return f"{np.median(v):.0f}" if v else "-"
        lines.append(f"| {b} | {_label(m)} | {np.mean(n):.1f} | "
                     f"{100 * np.mean([k >= 2 for k in n]):.0f}% | {med(first)} | {med(second)} |")
    return "\n".join(lines)


def differences(summary: Sequence[dict[str, Any]], *, tolerance_sd: float = 2.0) -> list[str]:
    """Cells where our mean lies outside the paper's mean ± ``tolerance_sd`` x its sd.

    Examples
    --------
    >>> s = [{"experiment": "drop", "bottle": "TR", "method": "dath", "response_mean_ms": 120.0,
    ...       "response_sd_ms": 5.0, "response_n": 10, "total_mean_ms": 300.0,
    ...       "total_sd_ms": 50.0, "total_n": 10}]
    >>> differences(s)
    ['drop, response, TR, DATH: ours 120 ms vs paper 50 ± 6.48 ms (+70 ms, 2.4x)']
    """
    out = []
    for s in summary:
        for metric in ("response", "total"):
            p = paper_value(s["experiment"], f"{metric}_ms", s["bottle"], s["method"])
            if p is None or p.mean is None:
                continue
            m = float(s[f"{metric}_mean_ms"])
            if math.isnan(m):
                out.append(f"{s['experiment']}, {metric}, {s['bottle']}, "
                           f"{_label(s['method'])}: no value of ours (paper {p.text()} ms)")
                continue
            if p.sd is not None and abs(m - p.mean) > tolerance_sd * p.sd:
                out.append(f"{s['experiment']}, {metric}, {s['bottle']}, {_label(s['method'])}: "
                           f"ours {m:.0f} ms vs paper {p.text()} ms ({m - p.mean:+.0f} ms, "
                           f"{m / p.mean:.1f}x)")
    return out


def report_markdown(*, summary: Sequence[dict[str, Any]], rows: Sequence[Any],
                    figures: Sequence[tuple[str, str]], setup: Sequence[str],
                    discussion: Sequence[str], claims: Sequence[Any] = (),
                    notices: Sequence[str] = ()) -> str:
    """The whole report.md: the paper's table beside ours, success, onsets, figures, honesty.

    Parameters
    ----------
    summary, rows : sequence of dict
        From :func:`summarize` and the per-event rows.
    figures : sequence of (caption, relative path)
    setup : sequence of str
        Bullet lines describing the run (command, seeds, thresholds, timing).
    discussion : sequence of str
        Paragraphs on why our numbers differ where they do.
    claims : sequence of ClaimResult, optional
        The paper's claims judged on this run (:func:`slipreflex.analysis.claims.judge_run`);
        with them come the paper's self-contradictions.
    notices : sequence of str
        What a reader must know first (a partial run, objects that are not the
        paper's): bold lines right under the title.

    Examples
    --------
    >>> md = report_markdown(summary=[], rows=[], figures=[("A bar chart", "fig.png")],
    ...                      setup=["seed 1"], discussion=["Because."])
    >>> "![A bar chart](fig.png)" in md and "- seed 1" in md
    True
    """

    lines = ["# slipreflex reproduce: the paper's experiments on the simulated rig", ""]
    voided = void_notice(summary)
    lines += [line for n in [*notices, *([voided] if voided else [])] for line in (f"**{n}**", "")]
    lines += ["## Run", ""] + [f"- {s}" for s in setup] + [""]
    lines += ["## The paper's table beside ours", "",
              "Mean ± sd (n) in ms; *paper* columns are the paper's section III / docs/method.md section 4 values, "
              "*ours* come from `results.csv` (one value per slip event). Response time: onset "
              "(accelerometer) to the first increase of the commanded finger position. Total: first "
              "to last change of the command for that slip (fixed, DATH) or the closing time the "
              "method generated (NMSD, SWT-SD).", "", comparison_markdown(summary), ""]
    if claims:

        lines += claims_section(claims)
    lines += ["## Success (slip suppressed before the bottle slipped out)", "",
              "*Per trial*: the trials in which the bottle stayed in the grasp through every slip; "
              "*per slip event*: the slip events suppressed, over all slip events (a trial without a "
              "detected slip counts once). *Grip added without slip*: how far the hand closed (finger "
              "units, mean per trial) while no true slip was under way (the simulator's truth): a "
              "pre-emptive squeeze, e.g. at the water's landing, that the response times do not show.",
              "", success_markdown(summary), ""]
    lines += ["## Onset estimate vs the simulator's true onset", "",
              "Accelerometer onset minus the true onset of the slip (positive: the estimate is late).",
              "", onset_markdown(rows), ""]
    if any(experiment_specs.get(r["experiment"]).records_load for r in rows):
        lines += ["## Slips per pour", "",
                  "The paper saw two slips in most pours, near 200 ml and near 400 ml (volume from the "
                  "flow sensor at each accelerometer onset).", "", pour_slips_markdown(rows), ""]
    lines += ["## Figures", ""]
    for caption, rel in figures:
        lines += [f"![{caption}]({rel})", "", f"*{caption}*", ""]
    lines += ["## Where we differ from the paper, and why", ""]
    diffs = differences(summary)
    if diffs:
        lines += ["Cells where our mean is outside the paper's mean ± 2 sd:", ""]
        lines += [f"- {d}" for d in diffs] + [""]
    else:
        lines += ["Every reported cell of ours is within the paper's mean ± 2 sd.", ""]
    for para in discussion:
        lines += [para, ""]
    lines += ["## The paper's other claims", ""] + [f"- {n}" for n in PAPER_NOTES] + [""]
    return "\n".join(lines)


def _finite(x: Any) -> bool:
    return x is not None and not (isinstance(x, float) and math.isnan(x))


