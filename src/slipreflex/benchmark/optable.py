"""What the operating-point benchmark writes: ``operating_points.csv``, its table, ``curves.png``.

Examples
--------
>>> from slipreflex.benchmark.evaluate import Evaluation
>>> from slipreflex.benchmark.protocol import ProtocolConfig
>>> ev = Evaluation("onset", [], [], {}, {}, ProtocolConfig(), "leave-one-trial-out", "1 channel")
>>> format_points(ev).splitlines()[0].startswith("protocol: leave-one-trial-out")
True
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import methods as registry
from ..files.csvfiles import write_columns
from .evaluate import Evaluation
from .protocol import ALARM_WARNING, OperatingPoint
from .report import _plt
from .sweep import BASELINES

__all__ = ["POINT_COLUMNS", "write_points", "format_points", "markdown_points", "plot_curves", "label"]

POINT_COLUMNS: tuple[str, ...] = (
    "method", "rate", "kind", "threshold_median", "threshold_min", "threshold_max", "fixed", "slip_trials",
    "detected", "detected_lo", "detected_hi", "median_latency_ms", "false_alarms", "negative_min",
    "false_alarms_per_min", "fa_lo", "fa_hi", "alarm_fraction", "chance_detected", "chance_latency_ms",
    "trials", "correct", "accuracy_lo", "accuracy_hi", "area", "area_lo", "area_hi")


def label(method: str) -> str:
    """A method's label (the baselines' own names).

    Examples
    --------
    >>> label("energy"), label("swt")
    ('energy', 'SWT-SD')
    """
    return method if method in BASELINES else registry.label(method)


def _r(x: float, nd: int = 4) -> float:
    return round(float(x), nd) if math.isfinite(x) else float("nan")


def write_points(ev: Evaluation, path: str | Path) -> Path:
    """``operating_points.csv``: one row per method and rate (:data:`POINT_COLUMNS`).

    Examples
    --------
    >>> from slipreflex.benchmark.protocol import ProtocolConfig
    >>> ev = Evaluation("onset", [], [], {}, {}, ProtocolConfig(), "", "")
    >>> write_points(ev, __import__("tempfile").mkdtemp() + "/p.csv").read_text().split(",")[0]
    'method'
    """
    cols: dict[str, list[Any]] = {c: [] for c in POINT_COLUMNS}
    for p in ev.points:
        thr = np.asarray(p.thresholds)
        vals = (p.method, p.rate, p.kind, float(f"{np.median(thr):.6g}"), float(f"{thr.min():.6g}"),
                float(f"{thr.max():.6g}"), int(p.method in ev.fixed), p.slip_trials, p.detected,
                _r(p.detected_ci[0]), _r(p.detected_ci[1]), _r(p.median_latency_ms, 1), p.false_alarms,
                _r(p.negative_min), _r(p.fa_per_min, 2), _r(p.fa_ci[0], 2), _r(p.fa_ci[1], 2),
                _r(p.alarm_fraction), _r(p.chance_detected, 3), _r(p.chance_latency_ms, 1), p.trials, p.correct,
                _r(p.accuracy_ci[0]), _r(p.accuracy_ci[1]), _r(p.area), _r(p.area_ci[0]), _r(p.area_ci[1]))
        for c, v in zip(POINT_COLUMNS, vals):
            cols[c].append(v)
    path = Path(path)
    write_columns(path, cols)
    return path


def _f(v: float, nd: int = 0) -> str:
    return "-" if not math.isfinite(v) else f"{v:.{nd}f}"


def _ci(lo: float, hi: float, nd: int = 2) -> str:
    return "" if not (math.isfinite(lo) and math.isfinite(hi)) else f" [{lo:.{nd}f}, {hi:.{nd}f}]"


def _threshold(p: OperatingPoint, fixed: bool) -> str:
    thr = np.asarray(p.thresholds)
    mid = f"{np.median(thr):.3g}"
    if fixed:
        return f"{mid} (given)"
    return mid if thr.min() == thr.max() else f"{mid} ({thr.min():.3g}-{thr.max():.3g})"


def _onset_rows(ev: Evaluation) -> tuple[list[str], list[list[str]]]:
    head = ["method", "rate", "threshold (data units)", "slips detected [95% CI]", "median latency ms",
            "false alarms/min [95% CI]", "in alarm", "chance: detected, latency ms", "curve area [95% CI]"]
    rows = []
    for p in ev.points:
        note = " (!)" if math.isfinite(p.alarm_fraction) and p.alarm_fraction > ALARM_WARNING else ""
        rows.append([label(p.method), p.rate, _threshold(p, p.method in ev.fixed),
                     f"{p.detected}/{p.slip_trials}{_ci(*p.detected_ci)}", _f(p.median_latency_ms),
                     f"{_f(p.fa_per_min, 1)}{_ci(*p.fa_ci, nd=1)}", f"{_f(100 * p.alarm_fraction)} %{note}",
                     f"{_f(p.chance_detected, 1)}, {_f(p.chance_latency_ms)}", f"{_f(p.area, 2)}{_ci(*p.area_ci)}"])
    return head, rows


def _trial_rows(ev: Evaluation) -> tuple[list[str], list[list[str]]]:
    head = ["method", "rate", "threshold (data units)", "accuracy [95% CI]", "slip trials alarmed",
            "no-slip trials alarmed", "AUC [95% CI]"]
    rows = []
    for p in ev.points:
        acc = p.correct / p.trials if p.trials else math.nan
        rows.append([label(p.method), p.rate, _threshold(p, p.method in ev.fixed),
                     f"{_f(100 * acc)} %{_ci(100 * p.accuracy_ci[0], 100 * p.accuracy_ci[1], nd=0)}",
                     f"{p.detected}/{p.slip_trials}", f"{p.negatives_alarmed}/{p.trials - p.slip_trials}",
                     f"{_f(p.area, 2)}{_ci(*p.area_ci)}"])
    return head, rows


def _notes(ev: Evaluation) -> list[str]:
    c = ev.protocol
    lines = [f"protocol: {ev.split}; " + (
        f"each method's threshold chosen on the training trials for at most {c.fa_per_min:g} false alarms "
        f"per minute; alarms within {c.refractory_s:g} s are one episode; label tolerance {c.tolerance_s:g} s"
        if ev.kind == "onset" else
        "trial-level labels (no onset): classification, first alarm or none; threshold chosen for the best "
        "training accuracy"),
        f"channels: {ev.channels}"]
    if ev.fixed:
        lines.append("given thresholds (not chosen): " + ", ".join(f"{label(m)} {v:g}" for m, v in ev.fixed.items()))
    for key, twin in ev.same.items():
        m, rate = key.split("@")
        lines.append(f"{label(m)} ({rate}): the same scores as {label(twin.split('@')[0])} at every threshold "
                     "(not repeated)")
    for s in ev.skipped:
        lines.append(f"not run: {label(s.method)}: {s.reason}")
    if ev.kind == "onset":
        lines.append(f"chance: a Poisson alarm at the method's held-out false-alarm rate, in the same detection "
                     f"windows; (!) in alarm more than {100 * ALARM_WARNING:.0f} % of the negative time")
    return lines


def _text(head: list[str], rows: list[list[str]]) -> str:
    w = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]
    lines = ["  ".join(c.ljust(w[i]) for i, c in enumerate(r)).rstrip() for r in [head, *rows]]
    lines.insert(1, "  ".join("-" * x for x in w))
    return "\n".join(lines)


def format_points(ev: Evaluation) -> str:
    """The operating-point table as plain text, its protocol and notes first (what the command prints).

    Examples
    --------
    >>> from slipreflex.benchmark.protocol import ProtocolConfig
    >>> ev = Evaluation("trial", [], [], {}, {}, ProtocolConfig(), "leave-one-trial-out", "2 channels")
    >>> "classification" in format_points(ev)
    True
    """
    head, rows = (_onset_rows if ev.kind == "onset" else _trial_rows)(ev)
    return "\n".join(_notes(ev) + [_text(head, rows)])


def markdown_points(ev: Evaluation) -> str:
    """The operating-point table as Markdown (docs/benchmark.md, README).

    Examples
    --------
    >>> from slipreflex.benchmark.protocol import ProtocolConfig
    >>> ev = Evaluation("onset", [], [], {}, {}, ProtocolConfig(), "", "")
    >>> markdown_points(ev).splitlines()[0].startswith("| method | rate |")
    True
    """
    head, rows = (_onset_rows if ev.kind == "onset" else _trial_rows)(ev)
    out = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    return "\n".join(out + ["| " + " | ".join(r) + " |" for r in rows])


def plot_curves(ev: Evaluation, path: str | Path, *, title: str = "") -> Path:
    """Detection rate against false alarms per minute (or the ROC) per method, operating points marked.

    Examples
    --------
    >>> from slipreflex.benchmark.protocol import ProtocolConfig
    >>> ev = Evaluation("onset", [], [], {}, {}, ProtocolConfig(), "", "")
    >>> plot_curves(ev, __import__("tempfile").mkdtemp() + "/c.png").suffix
    '.png'
    """
    plt = _plt()
    rates = list(dict.fromkeys(p.rate for p in ev.points)) or ["data"]
    fig, axes = plt.subplots(1, len(rates), figsize=(6.5 * len(rates), 4.6), squeeze=False)
    for ax, rate in zip(axes[0], rates):
        for i, p in enumerate(q for q in ev.points if q.rate == rate):
            x, y = p.curve
            ok = np.isfinite(x) & np.isfinite(y)
            order = np.argsort(x[ok], kind="stable")
            color = f"C{i % 10}"
            ax.step(x[ok][order], np.maximum.accumulate(y[ok][order]) if order.size else y[ok], where="post",
                    color=color, lw=1.2, label=f"{label(p.method)} (area {_f(p.area, 2)})")
            px, py = p.point
            ax.plot([px], [py], "o", color=color, mec="k", ms=6)
        if ev.kind == "onset":
            ax.axvline(ev.protocol.fa_per_min, color="0.5", ls="--", lw=0.8, label="target false-alarm rate")
            ax.set_xlim(0, ev.protocol.fa_max_per_min)
            ax.set_xlabel("false alarms per minute (episodes, pooled negative time)")
            ax.set_ylabel("slips detected (fraction)")
        else:
            ax.plot([0, 1], [0, 1], color="0.6", ls=":", lw=0.8, label="chance")
            ax.set_xlabel("no-slip trials alarmed (fraction)")
            ax.set_ylabel("slip trials alarmed (fraction)")
        ax.set_ylim(-0.03, 1.03)
        ax.grid(alpha=0.3)
        ax.set_title(f"{title} ({rate} rate): dots are the held-out operating points", fontsize=9)
        ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def points_by_method(points: Sequence[OperatingPoint]) -> dict[str, OperatingPoint]:
    """``method@rate`` -> its point.

    Examples
    --------
    >>> points_by_method([])
    {}
    """
    return {f"{p.method}@{p.rate}": p for p in points}
