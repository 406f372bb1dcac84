"""results.csv, summary.csv, the terminal table and report.md (one definition of each).

Rows are plain dicts with the keys of :data:`~slipreflex.analysis.trial.RESULT_COLUMNS`;
no data-frame library is needed.

Examples
--------
>>> rows = [{"experiment": "drop", "bottle": "TR", "method": "dath", "trial": i,
...          "response_ms": 50.0 + i, "total_ms": 300.0, "success": i < 2,
...          "onset_error_ms": 3.0, "n_events": 1} for i in range(3)]
>>> s = summarize(rows)[0]
>>> s["response_mean_ms"], s["response_n"], round(s["success_rate"], 3)
(51.0, 3, 0.667)
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import methods
from ..methods import label as _label
from .paper import BOTTLE_ORDER, EXPERIMENTS, PAPER_SUCCESS, paper_value
from .trial import RESULT_COLUMNS

__all__ = ["SUMMARY_COLUMNS", "summarize", "write_csv", "read_csv", "terminal_table",
           "comparison_markdown", "success_markdown", "onset_markdown", "pour_slips_markdown",
           "differences",
           "report_markdown", "fmt_mean_sd", "group_key_order"]

#: Columns of summary.csv, in order.
SUMMARY_COLUMNS: tuple[str, ...] = (
    "experiment", "bottle", "method", "n_trials", "n_rows", "n_events",
    "response_mean_ms", "response_sd_ms", "response_n",
    "total_mean_ms", "total_sd_ms", "total_n",
    "success_rate", "success_n",
    "onset_error_mean_ms", "onset_error_sd_ms", "onset_error_n",
    "paper_response_ms", "paper_total_ms",
)


def _num(x: Any) -> float:
    """A cell as float: "" (how write_csv stores NaN) and None are NaN."""
    return float("nan") if x is None or (isinstance(x, str) and not x.strip()) else float(x)


def _stats(values: Iterable[Any]) -> tuple[float, float, int]:
    v = np.array([_num(x) for x in values], dtype=float)
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
    return (idx(EXPERIMENTS, e), e, idx(BOTTLE_ORDER, b), b, idx(methods.names(), m), m)


def _table_methods(by: dict[tuple[str, str, str], Any]) -> list[str]:
    """Columns of a comparison table: the paper's methods, then any other method that ran."""
    ran = {k[2] for k in by}
    return (list(methods.names(paper=True)) + [m for m in methods.names() if m in ran
                                               and m not in methods.names(paper=True)]
            + sorted(ran - set(methods.names())))


def _truthy(x: Any) -> float:
    if isinstance(x, str):
        return 1.0 if x.strip().lower() in ("true", "1") else 0.0
    return float(bool(x))


def summarize(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Mean, sd (ddof 1) and n per experiment, bottle and method, plus success rate.

    Success rate is over all rows (slip events; a trial without a detected slip
    counts once). NaN timings (no onset, no response) are left out of the means
    and counted in ``n``.

    Examples
    --------
    >>> summarize([])
    []
    """
    groups: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r["experiment"], r["bottle"], r["method"]), []).append(r)
    out = []
    for key in sorted(groups, key=group_key_order):
        g = groups[key]
        e, b, m = key
        rm, rs, rn = _stats(r.get("response_ms", math.nan) for r in g)
        tm, ts, tn = _stats(r.get("total_ms", math.nan) for r in g)
        em, es, en = _stats(r.get("onset_error_ms", math.nan) for r in g)
        succ = [_truthy(r.get("success", False)) for r in g]
        pr, pt = paper_value(e, "response_ms", b, m), paper_value(e, "total_ms", b, m)
        out.append({
            "experiment": e, "bottle": b, "method": m,
            "n_trials": len({(r.get("trial"), r.get("seed")) for r in g}),
            "n_rows": len(g),
            "n_events": int(sum(1 for r in g if _num(r.get("n_events", 1)) > 0)),
            "response_mean_ms": rm, "response_sd_ms": rs, "response_n": rn,
            "total_mean_ms": tm, "total_sd_ms": ts, "total_n": tn,
            "success_rate": float(np.mean(succ)) if succ else float("nan"), "success_n": len(succ),
            "onset_error_mean_ms": em, "onset_error_sd_ms": es, "onset_error_n": en,
            "paper_response_ms": pr.text() if pr else "", "paper_total_ms": pt.text() if pt else "",
        })
    return out


def _cell(v: Any) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "True" if v else "False"
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(round(v, 6))
    return str(v)


def write_csv(path: str | Path, rows: Sequence[dict[str, Any]],
              columns: Sequence[str] = RESULT_COLUMNS) -> Path:
    """Write ``rows`` with exactly ``columns`` (NaN as an empty cell).

    Examples
    --------
    >>> import tempfile, os
    >>> p = write_csv(os.path.join(tempfile.mkdtemp(), "r.csv"), [{"a": 1.5, "b": float("nan")}], ["a", "b"])
    >>> p.read_text().splitlines()
    ['a,b', '1.5,']
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as fh:
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
        return list(csv.DictReader(fh))


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


def terminal_table(summary: Sequence[dict[str, Any]]) -> str:
    """A compact text table of the summary for the terminal.

    Examples
    --------
    >>> print(terminal_table([]))
    exp   bottle method  response ms (n)   total ms (n)      success
    """
    head = f"{'exp':5} {'bottle':6} {'method':7} {'response ms (n)':17} {'total ms (n)':17} success"
    lines = [head]
    for s in summary:
        lines.append(
            f"{s['experiment']:5} {s['bottle']:6} {_label(s['method']):7} "
            f"{fmt_mean_sd(s['response_mean_ms'], s['response_sd_ms'], s['response_n']):17} "
            f"{fmt_mean_sd(s['total_mean_ms'], s['total_sd_ms'], s['total_n']):17} "
            f"{100 * s['success_rate']:.0f}% of {s['success_n']}")
    return "\n".join(lines)


def comparison_markdown(summary: Sequence[dict[str, Any]]) -> str:
    """The paper's table beside ours, as markdown (one line per experiment, metric, bottle).

    Examples
    --------
    >>> print(comparison_markdown([]).splitlines()[0])
    | experiment, metric | bottle | DATH paper | DATH ours | fixed paper | fixed ours | NMSD paper | NMSD ours | SWT-SD paper | SWT-SD ours |
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
                                       s[f"{metric}_n"]) if s else "not run"
                    cells += [p.text() if p else "-", ours]
                lines.append(f"| {e}, {label} | {b} | " + " | ".join(cells) + " |")
    for e in exps:
        cells = []
        for m in order:
            pt = PAPER_SUCCESS.get((e, "all", m), "-")
            ours = [by[(e, b, m)] for b in bottles if (e, b, m) in by]
            if ours:
                n = sum(s["success_n"] for s in ours)
                rate = sum(s["success_rate"] * s["success_n"] for s in ours) / n if n else math.nan
                cells += [pt, f"{100 * rate:.0f}% of {n}"]
            else:
                cells += [pt, "not run"]
        lines.append(f"| {e}, success | all | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def success_markdown(summary: Sequence[dict[str, Any]]) -> str:
    """Success rates per experiment, bottle and method as a markdown table.

    Examples
    --------
    >>> print(success_markdown([{"experiment": "drop", "bottle": "TX", "method": "dath",
    ...                          "success_rate": 0.9, "success_n": 10}]).splitlines()[2])
    | drop | TX | 90% (10) | 90 % | not run | - | not run | - | not run | - |
    """
    by = {(s["experiment"], s["bottle"], s["method"]): s for s in summary}
    order = _table_methods(by)
    cols = " | ".join(f"{_label(m)} ours | paper" for m in order)
    lines = [f"| experiment | bottle | {cols} |", "|---|---|" + "---|" * (2 * len(order))]
    keys = sorted({(e, b) for e, b, _ in by}, key=lambda k: group_key_order((k[0], k[1], "")))
    for e, b in keys:
        cells = []
        for m in order:
            s = by.get((e, b, m))
            cells.append(f"{100 * s['success_rate']:.0f}% ({s['success_n']})" if s else "not run")
            cells.append(PAPER_SUCCESS.get((e, b, m), "-"))
        lines.append(f"| {e} | {b} | " + " | ".join(cells) + " |")
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
        groups.setdefault((r["experiment"], r["bottle"]), []).append(_num(r.get("onset_error_ms")))
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
    groups: dict[tuple[str, str], dict[tuple, list[dict[str, Any]]]] = {}
    for r in rows:
        if r["experiment"] != "pour":
            continue
        groups.setdefault((r["bottle"], r["method"]), {}).setdefault((r["trial"], r["seed"]), []).append(r)
    lines = ["| bottle | method | slips per trial (mean) | trials with 2+ slips | ml at 1st slip (median) "
             "| ml at 2nd slip (median) |", "|---|---|---|---|---|---|"]
    for (b, m) in sorted(groups, key=lambda k: group_key_order(("pour", k[0], k[1]))):
        trials = groups[(b, m)]
        n = [int(_num(rs[0].get("n_events", 0))) for rs in trials.values()]
        first = [_num(r.get("load_at_onset")) for rs in trials.values() for r in rs
                 if int(_num(r.get("event", 0))) == 0 and int(_num(r.get("n_events", 0))) > 0]
        second = [_num(r.get("load_at_onset")) for rs in trials.values() for r in rs
                  if int(_num(r.get("event", 0))) == 1]

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
            if abs(m - p.mean) > tolerance_sd * p.sd:
                out.append(f"{s['experiment']}, {metric}, {s['bottle']}, {_label(s['method'])}: "
                           f"ours {m:.0f} ms vs paper {p.text()} ms ({m - p.mean:+.0f} ms, "
                           f"{m / p.mean:.1f}x)")
    return out


def report_markdown(*, summary: Sequence[dict[str, Any]], rows: Sequence[dict[str, Any]],
                    figures: Sequence[tuple[str, str]], setup: Sequence[str],
                    discussion: Sequence[str]) -> str:
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

    Examples
    --------
    >>> md = report_markdown(summary=[], rows=[], figures=[("A bar chart", "fig.png")],
    ...                      setup=["seed 1"], discussion=["Because."])
    >>> "![A bar chart](fig.png)" in md and "- seed 1" in md
    True
    """
    from .paper import PAPER_NOTES

    lines = ["# slipreflex reproduce: the paper's experiments on the simulated rig", ""]
    lines += ["## Run", ""] + [f"- {s}" for s in setup] + [""]
    lines += ["## The paper's table beside ours", "",
              "Mean ± sd (n) in ms; *paper* columns are the paper's section III / SPEC 4 values, "
              "*ours* come from `results.csv` (one value per slip event). Response time: onset "
              "(accelerometer) to the first increase of the commanded finger position. Total: first "
              "to last change of the command for that slip (fixed, DATH) or the closing time the "
              "method generated (NMSD, SWT-SD).", "", comparison_markdown(summary), ""]
    lines += ["## Success (slip suppressed before the bottle slipped out)", "",
              success_markdown(summary), ""]
    lines += ["## Onset estimate vs the simulator's true onset", "",
              "Accelerometer onset minus the true onset of the slip (positive: the estimate is late).",
              "", onset_markdown(rows), ""]
    if any(r["experiment"] == "pour" for r in rows):
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
