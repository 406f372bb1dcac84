"""results.csv, summary.csv, the terminal table and report.md (one definition of each).

Rows are :class:`~slipreflex.analysis.trial.TrialRow` objects or dicts with the same keys
(a results.csv read back); no data-frame library is needed. The prose of report.md (the
run's setup, the figure captions, the discussion) is here too, every number in it read from
its one definition.

Examples
--------
>>> rows = [{"experiment": "drop", "bottle": "TR", "method": "dath", "trial": i,
...          "response_ms": 50.0 + i, "total_ms": 300.0, "success": i < 2,
...          "onset_error_ms": 3.0, "n_events": 1} for i in range(3)]
>>> s = summarize(rows)[0]
>>> s["response_mean_ms"], s["response_n"], round(s["trial_success_rate"], 3)
(51.0, 3, 0.667)
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import experiment_specs, methods
from .. import hardware as hw
from ..baselines import CLOSE_S
from ..baselines.swt import SWT_LEVEL
from ..chain import ReflexParams
from ..csvfiles import cell_bool, cell_float
from ..methods import label as _label
from ..paths import new_file
from .claims import claims_section
from .onset import OnsetParams
from .paper import BOTTLE_ORDER, EXPERIMENTS, PAPER, PAPER_NOTES, PAPER_SUCCESS, paper_value
from .trial import MAX_RESPONSE_S, RESULT_COLUMNS, TrialRow

__all__ = ["SUMMARY_COLUMNS", "summarize", "void", "void_notice", "NOT_COMPARED", "write_csv", "read_csv",
           "terminal_table",
           "comparison_markdown", "success_markdown", "onset_markdown", "pour_slips_markdown",
           "differences",
           "report_markdown", "fmt_mean_sd", "group_key_order", "setup_lines", "discussion_text",
           "trial_caption", "zoom_caption", "bars_caption", "SUCCESS_CAPTION", "GRIP_CAPTION", "paper_figure"]

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


# --- the prose of report.md: the run's setup, the figure captions, the discussion -------------
#
# Every number here is read from its one definition (the run's configuration, the method
# registry, the hardware constants, the analysis parameters, the paper's table), so the text
# follows --rest-k, --swt-persist, --drop-mass, --pour-volume and the rest.

def paper_figure(experiment: str, plot: str) -> str:
    """The paper's figure a plot of ``experiment`` is like ("" when the paper has none).

    Examples
    --------
    >>> paper_figure("pour", "total"), paper_figure("pour", "zoom")
    ('Fig. 17', '')
    """
    return experiment_specs.get(experiment).paper_figures.get(plot, "")


def _like_paper(experiment: str, plot: str) -> str:
    fig = paper_figure(experiment, plot)
    return f" (like the paper's {fig})" if fig else ""


def _finite(x: Any) -> bool:
    return x is not None and not (isinstance(x, float) and math.isnan(x))


def _median(values: Iterable[float]) -> float:
    v = [float(x) for x in values if _finite(x)]
    return float(np.median(v)) if v else float("nan")


def _and_join(words: Sequence[str]) -> str:
    return " and ".join(words) if len(words) <= 2 else ", ".join(words[:-1]) + " and " + words[-1]


def _window_ms() -> float:
    """One MPI window of the paper's chain (ms): N samples at the DAQ's rate."""

    return 1e3 * hw.WINDOW_N / hw.DAQ_FS


def _paper_success(experiment: str, method: str) -> str:
    return PAPER_SUCCESS.get((experiment, "all", method), "not reported")


def trial_caption(experiment: str, bottle: str, method: str) -> str:
    """Caption of one example trial's figure.

    Examples
    --------
    >>> trial_caption("drop", "TR", "dath")[:38]
    'One drop trial, bottle TR, method DATH'
    """
    return (f"One {experiment} trial, bottle {bottle}, method {_label(method)}{_like_paper(experiment, 'trial')}: "
            "I onset, II first response, III last change")


def zoom_caption(bottle: str, method: str, experiment: str) -> str:
    """Caption of the zoom on an example trial's slips.

    Examples
    --------
    >>> zoom_caption("DK", "dath", "pour")
    'The same pour trial zoomed on its slips, every axis scaled to the zoom (DK, DATH)'
    """
    return (f"The same {experiment} trial zoomed on its slips, every axis scaled to the zoom "
            f"({bottle}, {_label(method)})")


def bars_caption(experiment: str, metric: str) -> str:
    """Caption of a bar chart of ``metric`` ("response" or "total").

    Examples
    --------
    >>> bars_caption("pour", "total").startswith("Total controller time, pour (like the paper's Fig. 17)")
    True
    """
    what = "Response" if metric == "response" else "Total controller"
    return f"{what} time, {experiment}{_like_paper(experiment, metric)}; diamonds: the paper"


#: Caption of the success chart.
SUCCESS_CAPTION: str = ("Success per trial (bars) and per slip event (dots): the slip suppressed before the "
                        "bottle slipped out")
#: Caption of the grip-without-slip chart.
GRIP_CAPTION: str = ("Grip added without slip: how far the hand closed (finger units, mean ± sd per trial) "
                     "while no true slip was under way; a pre-emptive squeeze the response times do not show")


def setup_lines(result: Any, command: str | None = None) -> list[str]:
    """Bullet lines describing a run (a :class:`slipreflex.experiments.ReproduceResult`).

    Examples
    --------
    >>> from slipreflex.experiments import ReproduceConfig, ReproduceResult
    >>> r = ReproduceResult(ReproduceConfig(trials=1, rest_k=4), [], [], {"nmsd": 10.0, "swt": 0.02},
    ...                     {}, 3.0, 2)
    >>> [s for s in setup_lines(r) if "threshold" in s][0][:48]
    'NMSD threshold 10 N/s, SWT-SD threshold 0.02 N: '
    >>> "4 sd" in " ".join(setup_lines(r))
    True
    """

    c = result.config
    lines = [f"command: `{command}`"] if command else []
    lines += [
        f"grid: {c.trials} trials x bottles {', '.join(c.bottles)} x experiments "
        f"{', '.join(c.experiments)} x methods {', '.join(c.methods)} "
        f"= {c.trials * len(c.bottles) * len(c.experiments) * len(c.methods)} trials, "
        f"{len(result.rows)} result rows (slip events)",
        f"master seed {c.seed}; trial seeds spawned per experiment, bottle and trial "
        "(numpy SeedSequence), " + ("each method its own (independent seeds)" if getattr(c, "independent_seeds", False)
                                    else "shared by every method (paired comparison)")
        + ("; each trial's placement, grip height and friction vary from its seed (sim.variations)"
           if getattr(c, "variations", False) else "; every repeat is the nominal plant"),
        f"drop: {c.drop.mass_kg * 1e3:g} g from {c.drop.height_m * 1e2:g} cm above the opening; "
        f"pour: {c.pour.volume_ml:g} ml at {c.pour.rate_l_min:g} L/min ({c.pour.duration_s:.0f} s)",
        f"protocol: grasp to {getattr(c, 'grasp_force_n', hw.CONTACT_FORCE_N):g} N, "
        "settle (simulator's grasp routine), "
        f"{c.rest_s:g} s of rest recorded, perturbation, {c.after_s:g} s after it ends",
        _chain_line(),
    ]
    lines += _plant_lines(c)
    if result.thresholds:
        lines.append(_threshold_line(result.thresholds, c))
    return lines + _analysis_lines(c) + [
        f"wall time {result.wall_s:.1f} s on {result.jobs} worker process(es) "
        f"({os.cpu_count()} cores), calibration {result.calibration_wall_s:.1f} s"]


def _plant_lines(c: Any) -> list[str]:
    """The plant's open-loop first slip and contact friction, computed for the run's bottles."""
    from ..sim import BOTTLES  # deferred: heavy (numba kernels)
    from ..sim.calibration import plant_lines  # deferred: heavy (numba kernels)

    names = [b for b in c.bottles if b in BOTTLES]
    return plant_lines([BOTTLES[b] for b in names], getattr(c, "grasp_force_n", hw.CONTACT_FORCE_N)) if names else []


def _chain_line() -> str:

    rp = ReflexParams()
    return (f"{_label(methods.FIXED)} / {_label(methods.DATH)}: the paper's chain (theta0 = "
            f"{rp.threshold:g} V, D = {rp.dath_samples}, N = {rp.n}, Kp = {rp.kp:g}, Ki = {rp.ki:g}, "
            f"reset after {rp.reset_after} zero windows) at the DAQ's {hw.DAQ_FS:.2f} Hz")


def _threshold_line(thresholds: dict[str, float], c: Any) -> str:
    swt_fs = methods.get(methods.SWT).fs
    parts = [f"{_label(m)} threshold {v:.3g} {methods.get(m).threshold_unit}".rstrip()
             for m, v in thresholds.items()]
    return (", ".join(parts) + f": {c.rest_k:g} sd of each method's own statistic on "
            f"{c.calibration_s:g} s rest recordings of all three bottles (pooled), the same for every "
            f"bottle; SWT-SD persistence {c.swt_persist} samples ({1e3 * c.swt_persist / swt_fs:.0f} ms) "
            "after the crossing")


def _analysis_lines(c: Any) -> list[str]:
    from ..sim import BOTTLES  # deferred: heavy (numba kernels)

    op = OnsetParams()
    travel = sorted({c.bottle(b).grip_travel_m if hasattr(c, "bottle") else BOTTLES[b].grip_travel_m
                     for b in c.bottles})
    return [
        f"onset: paper's recipe with k = {op.k:g} sd over the first {op.baseline_s * 1e3:.0f} ms; slip "
        f"episodes must peak at {op.peak_factor:g}x the threshold; responses later than "
        f"{MAX_RESPONSE_S:g} s are not responses",
        "success: the bottle had not slipped out completely by the end of the slip's window; "
        "slipped out = the simulator's *fallen out*, the bottle has slid its grip travel ("
        + ", ".join(f"{x * 1e2:g} cm" for x in travel)
        + ") below where it was grasped, the fingertips reach the shoulder and lose contact",
    ]


class _Rows:
    """The rows of a run with the selections the discussion needs."""

    def __init__(self, result: Any) -> None:

        # rows read back from results.csv are dicts of strings: type them once
        self.rows = [r if isinstance(r, TrialRow) else TrialRow.from_dict(r) for r in result.rows if not void(r)]
        self.summary, self.config = result.summary, result.config

    def sel(self, **kw: Any) -> list[Any]:
        return [r for r in self.rows if all(r[k] == v for k, v in kw.items())]

    @staticmethod
    def pct(sub: Sequence[Any], pred: Any) -> str:
        return f"{100 * sum(1 for r in sub if pred(r)) / len(sub):.0f}% of {len(sub)}" if sub else "n/a"


def discussion_text(result: Any) -> list[str]:
    """Why our numbers differ from the paper's, with the figures computed from this run.

    Every number in the text comes from the run (its rows and configuration) or from
    its one definition in the package.

    Examples
    --------
    >>> from slipreflex.experiments import ReproduceConfig, ReproduceResult
    >>> discussion_text(ReproduceResult(ReproduceConfig(trials=1), [], [], {}, {}, 0.0, 1))[0][:2]
    '**'
    """
    d = _Rows(result)
    parts = (_simulated_rig(d), _onset_paragraph(d), _fixed_vs_dath(d), _bottles_paragraph(d),
             _total_paragraph(d), _tactile_paragraph(d), _pour_slips_paragraph(d), _success_paragraph(d))
    return [p for p in parts if p]


def _simulated_rig(d: _Rows) -> str:
    cal = _and_join([f"{_label(m)}'s" for m in methods.calibrated() if m in d.config.methods])
    return ("**Simulated rig, not the paper's rig.** Every number here comes from the simulator "
            "(`slipreflex.sim`, docs/simulator.md): friction, pad compliance, hand speed and latency, "
            "sensor noise and the bottles' surfaces are physical estimates, not fits to the paper's "
            "results, and nothing in the simulator or in the methods was tuned to bring our numbers "
            "closer to the paper's (the only thresholds derived from data are "
            f"{cal or 'those of the calibrated methods'}, by their one rule). Absolute times are "
            "therefore not expected to match; what can carry over is the ordering of methods and bottles.")


def _onset_paragraph(d: _Rows) -> str:
    parts, late_pours = [], 0
    for e in experiment_specs.names():
        err = np.array([r.onset_error_ms for r in d.sel(experiment=e) if _finite(r.onset_error_ms)])
        if err.size:
            late = int((err > LATE_ONSET_MS).sum())
            late_pours += late if experiment_specs.get(e).slip_events == "segmented" else 0
            parts.append(f"{e}: median absolute error {np.median(np.abs(err)):.1f} ms, largest "
                         f"{np.abs(err).max():.0f} ms, {late} of {err.size} found more than "
                         f"{LATE_ONSET_MS:.0f} ms after the true onset")
    if not parts:
        return ""
    text = ("**Onset estimate.** The paper's accelerometer recipe against the simulator's true onsets "
            f"(the contacts' stick to slip): {'; '.join(parts)}.")
    if late_pours:
        text += (" A pour's slip under rate-and-state friction creeps before it accelerates, and the "
                 "accelerometer's envelope crosses its rest threshold only once it does: those onsets, and "
                 "the response times measured from them, start late.")
    return text + (" On the real rig the IMU is taped to a flexible bottle and feels the mass or the water "
                   "before the grasp gives way, so the paper's onsets, and its response times, carry more "
                   "spread than ours.")


#: An accelerometer onset this much (ms) after the simulator's true onset is called late in the report.
LATE_ONSET_MS: float = 100.0


def _fixed_vs_dath(d: _Rows) -> str:
    F, D = methods.FIXED, methods.DATH
    pairs: dict[tuple, dict[str, float]] = {}
    for r in d.rows:
        if r.method in (F, D) and _finite(r.response_ms):
            pairs.setdefault((r.experiment, r.bottle, r.trial, r.event), {})[r.method] = r.response_ms
    both = [v for v in pairs.values() if len(v) == 2]
    if not both:
        return ""
    same = sum(1 for v in both if abs(v[F] - v[D]) < 1e-6)
    return (f"**Fixed threshold vs DATH response.** In {same} of {len(both)} paired slips "
            "(same seed, same bottle) the two chains responded at exactly the same time. That "
            "follows from the method (docs/method.md section 1.2): DATH changes the threshold only after the first "
            "spike, and the MPI raises the command at the end of the first window holding a spike, "
            "so on the same input the first response cannot differ. The paper's fixed and DATH "
            "trials were separate physical runs, so their response times differ by trial-to-trial "
            "variation (and by how soon the first spike comes on each run). DATH differs from the "
            "fixed threshold in what follows the first spike: more spikes, a larger and longer "
            "command rise.")


def _bottles_paragraph(d: _Rows) -> str:
    by = {(x["experiment"], x["bottle"], x["method"]): x for x in d.summary}
    parts, tx_first = [], False
    for e in EXPERIMENTS:
        vals = {b: by[(e, b, methods.DATH)]["response_mean_ms"] for b in BOTTLE_ORDER
                if (e, b, methods.DATH) in by}
        vals = {b: v for b, v in vals.items() if _finite(v)}
        if len(vals) >= 2:
            order = sorted(vals, key=lambda b: vals[b])
            tx_first = tx_first or order[0] == "TX"
            parts.append(f"{e}: " + ", ".join(f"{b} {vals[b]:.0f} ms" for b in order) + " (paper: "
                         + ", ".join(f"{b} {p.mean:g} ms" for b in order
                                     if (p := paper_value(e, "response_ms", b, methods.DATH)) is not None
                                     and p.mean is not None) + ")")
    if not parts:
        return ""
    para = "**Bottles.** DATH's mean response by bottle, fastest first: " + "; ".join(parts) + "."
    if tx_first:
        para += (" As in the paper, the textured TX bottle is answered fastest. In the simulator "
                 "its surface makes the slip sensor fluctuate most; on the smooth transparent and "
                 "dark surfaces the sensor moves by only a few ADC steps over several millimetres "
                 "of sliding (see the zoomed DK pour figure), so the first spike, and with it the "
                 "first MPI response, comes later, and DATH cannot act before that first spike.")
    return para


def _paper_chain_totals() -> tuple[float, float]:
    """Smallest and largest mean total of the paper's chains (fixed, DATH), ms."""
    v = [p.mean for (e, metric, b, m), p in PAPER.items()
         if metric == "total_ms" and m in (methods.FIXED, methods.DATH) and p.mean is not None]
    return min(v), max(v)


def _total_paragraph(d: _Rows) -> str:

    drops = [r for r in d.sel(experiment="drop") if _finite(r.true_slip_ms)]
    chain = [r for r in d.rows if r.method in (methods.FIXED, methods.DATH) and r.n_increases > 0]
    if not (drops and chain):
        return ""
    w, (lo, hi) = _window_ms(), _paper_chain_totals()
    return (f"**Total controller time.** In the simulator a drop makes the bottle slide "
            f"{_median(r.true_slip_mm for r in drops):.1f} mm in "
            f"{_median(r.true_slip_ms for r in drops):.0f} ms (medians) before the pads stick "
            f"again. The fixed and DATH chains see spikes for only a few {w:.0f} ms windows (median "
            f"{_median(r.n_increases for r in chain):.0f} command increases per slip), so the "
            f"first-to-last change of the MPI command is a small multiple of {w:.0f} ms, far below the "
            f"paper's {lo:.0f}-{hi:.0f} ms: the paper's bottles kept creeping and vibrating for hundreds "
            "of milliseconds and its sensor kept seeing motion. For NMSD and SWT-SD the total is the "
            f"closing time generated, {CLOSE_S * 1e3:.0f} ms per detection, and short slips give few "
            "detections.")


def _tactile_paragraph(d: _Rows) -> str:

    tactile = {m for m in methods.names() if methods.get(m).input_kind == "tactile"}
    tac = [r for r in d.rows if r.method in tactile and r.n_events > 0]
    if not tac:
        return ""
    missed = "; ".join(
        f"{_label(m)} missed {_Rows.pct(sub, lambda r: not _finite(r.response_ms))} {e} slips"
        for m in methods.names() for e in EXPERIMENTS
        if (sub := [r for r in tac if r.method == m and r.experiment == e]))
    shape = " x ".join(map(str, hw.TACTILE_SHAPE))
    persist_ms = 1e3 * d.config.swt_persist / methods.get(methods.SWT).fs
    persistence = (f"SWT-SD needs the level-{SWT_LEVEL} detail to stay over threshold for {persist_ms:.0f} ms "
                   "after the crossing, so a slip that is over sooner, like the simulated drops, cannot "
                   "trigger it. " if d.config.swt_persist else
                   f"SWT-SD decides at the crossing of the level-{SWT_LEVEL} detail, whose 21 ms window "
                   "already holds the change that follows (docs/method.md section 2.1). ")
    return (f"**NMSD and SWT-SD.** Both read the index fingertip's {shape} array with thresholds from "
            f"one rule ({d.config.rest_k:g} sd of the method's statistic at rest, the same for every "
            f"bottle). {missed} (no command within {MAX_RESPONSE_S:g} s of the onset). {persistence}The paper "
            "gives no thresholds, wavelet or persistence rule for either method, so their absolute "
            "numbers depend on these choices (documented in docs/reproduce.md) more than on anything "
            "else.")


def _pour_slips_paragraph(d: _Rows) -> str:
    pour_trials = {(r.bottle, r.method, r.trial): r.n_events for r in d.sel(experiment="pour")}
    if not pour_trials:
        return ""
    two = sum(1 for n in pour_trials.values() if n >= 2)
    kept = [r for r in d.sel(experiment="pour") if r.method in (methods.FIXED, methods.DATH)
            and r.n_events > 0 and r.success]
    vol = _median(r.load_at_onset for r in d.sel(experiment="pour", event=0) if r.n_events > 0)
    para = (f"**Slips per pour.** {two} of {len(pour_trials)} pour trials showed two or more "
            f"slips (paper: two in most trials, near 200 and 400 ml); the first came at a median "
            f"{vol:.0f} ml.")
    if kept and 2 * two < len(pour_trials):
        para += _stiff_grasp_sentence(kept)
    return para


def _stiff_grasp_sentence(kept: Sequence[Any]) -> str:
    from ..sim import BOTTLES, HandParams  # deferred: heavy (numba kernels)

    hp = HandParams()
    k_n = 1.0 / (1.0 / hp.pad_normal_stiffness_n_m + 1.0 / hp.finger_stiffness_n_m
                 + 1.0 / BOTTLES["TR"].wall_stiffness_n_m)
    per_unit = k_n * hp.travel_per_unit_m
    return (" After the first slip the MPI raised the fingers by a median "
            f"{_median(r.rise for r in kept):.0f} position units in the trials that kept the "
            f"bottle; in the simulator a unit adds about {per_unit:.2f} N per contact (pad, finger "
            f"and wall springs in series over {hp.travel_per_unit_m * 1e3:.1f} mm per unit), a "
            f"grip several times the {hw.CONTACT_FORCE_N:.1f} N of the grasp, which holds the rest of "
            "the water without another slip. The paper's MPI added \"just enough force\" for the "
            "first slip and the bottle slipped again as the water rose: the simulated grasp is "
            "stiffer than the real one.")


def _success_paragraph(d: _Rows) -> str:
    text = ["**Success.**"]
    drop_rows, pour_rows = d.sel(experiment="drop"), d.sel(experiment="pour")
    if drop_rows:
        text.append(f"The bottle stayed in the grasp in {_Rows.pct(drop_rows, lambda r: r.success)} drop "
                    f"rows (paper: {_paper_success('drop', methods.DATH)} with DATH, "
                    f"{_paper_success('drop', methods.FIXED)} with the fixed threshold).")
        if all(r.success for r in drop_rows):
            text.append(f"The simulated {d.config.drop.mass_kg * 1e3:g} g drop is a small, short slip "
                        "that stops by itself once the landing transient has passed, so no method "
                        "loses a bottle to it and the drop cannot separate the methods by success.")
    if pour_rows:
        ran = [m for m in methods.names() if d.sel(experiment="pour", method=m)]
        per = ", ".join(f"{_label(m)} {_Rows.pct(d.sel(experiment='pour', method=m), lambda r: r.success)}"
                        for m in ran)
        text.append(f"In the pours: {per} (paper: {_paper_success('pour', methods.DATH)} with DATH).")
    falls = [1e3 * (r.fell_out_s - r.onset_s) for r in d.rows
             if r.fell_out and _finite(r.onset_s) and r.fell_out_s >= r.onset_s]
    if falls:
        text.append(
            "A pour's slip starts at the friction limit and accelerates (kinetic friction is below "
            f"static): a bottle that fell was gone a median {_median(falls):.0f} ms after the onset. "
            "The paper's bottles slipped more gently.")
    if pour_rows:
        text += _pour_response_sentences(d)
    return " ".join(text)


def _pour_response_sentences(d: _Rows) -> list[str]:

    ran = [m for m in methods.names() if d.sel(experiment="pour", method=m)]
    med = {m: _median(r.response_ms for r in d.sel(experiment="pour", method=m)) for m in ran}
    resp = ", ".join(f"{_label(m)} " + (f"{med[m]:.0f} ms" if _finite(med[m]) else "none (never responded)")
                     for m in ran)
    out = [f"Median pour response: {resp}."]
    mpi = [med[m] for m in (methods.DATH, methods.FIXED) if m in med and _finite(med[m])]
    if methods.NMSD in med and _finite(med[methods.NMSD]) and mpi and med[methods.NMSD] < min(mpi):
        out.append(f"NMSD commands on the very sample that detects ({hw.NMSD_FS:g} Hz) and keeps closing at "
                   f"the hand's full speed, while the MPI raises the command only at the end of a "
                   f"{_window_ms():.0f} ms window, to P0 + Kp v + Ki h, so against a fast slip the paper's "
                   "controller is at a disadvantage in the simulator.")
    pre = {m: sum(1 for r in d.sel(experiment="pour", method=m) if r.n_events == 0 and r.n_increases > 0)
           for m in ran}
    if any(pre.values()):
        out.append("Trials in which the command rose although the accelerometer never showed a "
                   "slip (the grip was raised on small motions and no slip followed): "
                   + ", ".join(f"{_label(m)} {n}" for m, n in pre.items() if n) + ".")
    return out
