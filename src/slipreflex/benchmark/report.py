"""What ``slipreflex benchmark`` writes: ``benchmark.csv``, ``summary.csv``, the table, figures.

Examples
--------
>>> import tempfile, pathlib
>>> from slipreflex.benchmark import read_folder, shipped_dataset, run_benchmark, BenchmarkConfig
>>> runs, _ = run_benchmark(read_folder(shipped_dataset())[:1], BenchmarkConfig(methods=("fixed",), rates=("data",)))
>>> out = pathlib.Path(tempfile.mkdtemp())
>>> write_runs(runs, out / "benchmark.csv").read_text().splitlines()[0].split(",")[:6]
['trial', 'method', 'rate', 'fs_hz', 'threshold', 'slips']
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import methods as registry
from ..files.csvfiles import write_columns
from .run import MethodRun, reduce_channels

__all__ = ["RUN_COLUMNS", "SUMMARY_COLUMNS", "write_runs", "summarize", "write_summary", "format_table",
           "markdown_table", "plot_trial_runs"]

RUN_COLUMNS: tuple[str, ...] = ("trial", "method", "rate", "fs_hz", "threshold", "slips", "onset_t",
                                "detection_t", "latency_ms", "false_alarms", "scored_s",
                                "false_alarm_rate_per_min", "detections")
SUMMARY_COLUMNS: tuple[str, ...] = ("method", "label", "rate", "fs_hz", "slip_trials", "detected",
                                    "detection_rate", "median_latency_ms", "control_trials",
                                    "control_false_alarms", "control_minutes", "false_alarms_per_min",
                                    "pre_onset_false_alarms", "same_detections_as")


def _r(x: float, nd: int = 4) -> float:
    return round(float(x), nd) if math.isfinite(x) else float("nan")


def write_runs(runs: Sequence[MethodRun], path: str | Path) -> Path:
    """``benchmark.csv``: one row per trial, method and rate (:data:`RUN_COLUMNS`).

    Examples
    --------
    >>> write_runs([], __import__("tempfile").mkdtemp() + "/b.csv").read_text()
    'trial,method,rate,fs_hz,threshold,slips,onset_t,detection_t,latency_ms,false_alarms,scored_s,false_alarm_rate_per_min,detections\\n'
    """
    cols: dict[str, list[Any]] = {c: [] for c in RUN_COLUMNS}
    for r in runs:
        s = r.score
        for c, v in zip(RUN_COLUMNS, (r.trial, r.method, r.rate, _r(r.fs, 3), float(f"{r.threshold:.6g}"),
                                      int(s.slips), _r(s.onset_t), _r(s.detection_t), _r(s.latency_ms, 1),
                                      s.false_alarms, _r(s.scored_s), _r(s.false_alarm_rate_per_min, 1),
                                      s.detections)):
            cols[c].append(v)
    path = Path(path)
    write_columns(path, cols)
    return path


def summarize(runs: Sequence[MethodRun]) -> list[dict[str, Any]]:
    """Per method and rate: detection rate on slip trials, median latency, false alarms on the controls.

    ``same_detections_as`` names an earlier method (same rate) whose detections are the same on
    every trial (a variant that changes only the controller or the hand rule).

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset, run_benchmark, BenchmarkConfig
    >>> runs, _ = run_benchmark(read_folder(shipped_dataset()), BenchmarkConfig(methods=("dath", "dath-event"),
    ...                                                                          rates=("data",)))
    >>> [(s["method"], s["slip_trials"], s["control_trials"], s["same_detections_as"]) for s in summarize(runs)]
    [('dath', 3, 4, ''), ('dath-event', 3, 4, 'dath')]
    """
    keys: list[tuple[str, str]] = []
    for r in runs:
        if (r.method, r.rate) not in keys:
            keys.append((r.method, r.rate))
    out = []
    for m, rate in keys:
        rs = [r for r in runs if r.method == m and r.rate == rate]
        slip = [r.score for r in rs if r.score.slips]
        ctrl = [r.score for r in rs if not r.score.slips]
        lat = [s.latency_ms for s in slip if s.detected]
        fa = sum(s.false_alarms for s in ctrl)
        minutes = sum(s.scored_s for s in ctrl) / 60.0
        same = ""
        for m2, rate2 in keys[:keys.index((m, rate))]:
            if rate2 != rate:
                continue
            other = {r.trial: r.detections for r in runs if r.method == m2 and r.rate == rate}
            if all(r.trial in other and np.array_equal(r.detections, other[r.trial]) for r in rs):
                same = m2
                break
        out.append({
            "method": m, "label": registry.label(m), "rate": rate,
            "fs_hz": _r(float(np.median([r.fs for r in rs])), 1),
            "slip_trials": len(slip), "detected": sum(s.detected for s in slip),
            "detection_rate": _r(sum(s.detected for s in slip) / len(slip), 3) if slip else float("nan"),
            "median_latency_ms": _r(float(np.median(lat)), 1) if lat else float("nan"),
            "control_trials": len(ctrl), "control_false_alarms": fa, "control_minutes": _r(minutes, 3),
            "false_alarms_per_min": _r(fa / minutes, 1) if minutes > 0 else float("nan"),
            "pre_onset_false_alarms": sum(s.false_alarms for s in slip),
            "same_detections_as": same,
        })
    return out


def write_summary(summary: Sequence[dict[str, Any]], path: str | Path) -> Path:
    """``summary.csv`` (:data:`SUMMARY_COLUMNS`).

    Examples
    --------
    >>> write_summary([], __import__("tempfile").mkdtemp() + "/s.csv").read_text().startswith("method,label,rate")
    True
    """
    path = Path(path)
    write_columns(path, {c: [s[c] for s in summary] for c in SUMMARY_COLUMNS})
    return path


def _fmt(v: Any, nd: int = 0) -> str:
    if isinstance(v, float):
        return "-" if not math.isfinite(v) else f"{v:.{nd}f}"
    return str(v)


def _rows(summary: Sequence[dict[str, Any]]) -> list[list[str]]:
    rows = []
    for s in summary:
        rate = "data" if s["rate"] == "data" else "resampled"
        rows.append([s["label"], f"{s['fs_hz']:.0f} Hz ({rate})", f"{s['detected']}/{s['slip_trials']}",
                     _fmt(s["median_latency_ms"]), _fmt(s["false_alarms_per_min"]),
                     str(s["pre_onset_false_alarms"]), registry.label(s["same_detections_as"])
                     if s["same_detections_as"] else ""])
    return rows


_HEAD = ["method", "rate", "slips detected", "median latency (ms)", "false alarms/min (controls)",
         "false alarms before onset", "same detections as"]


def format_table(summary: Sequence[dict[str, Any]]) -> str:
    """The summary as a plain-text table (what the command prints).

    Examples
    --------
    >>> s = [{"label": "DATH", "rate": "data", "fs_hz": 59.8, "detected": 2, "slip_trials": 3,
    ...       "median_latency_ms": 12.0, "false_alarms_per_min": 150.0, "pre_onset_false_alarms": 4,
    ...       "same_detections_as": ""}]
    >>> print(format_table(s).splitlines()[2])
    DATH    60 Hz (data)  2/3             12                   150                          4
    """
    rows = [_HEAD, *_rows(summary)]
    w = [max(len(r[i]) for r in rows) for i in range(len(_HEAD))]
    lines = ["  ".join(c.ljust(w[i]) for i, c in enumerate(r)).rstrip() for r in rows]
    lines.insert(1, "  ".join("-" * x for x in w))
    return "\n".join(lines)


def markdown_table(summary: Sequence[dict[str, Any]]) -> str:
    """The summary as a Markdown table (README, docs/benchmark.md).

    Examples
    --------
    >>> s = [{"label": "NMSD", "rate": "method", "fs_hz": 260.0, "detected": 1, "slip_trials": 3,
    ...       "median_latency_ms": float("nan"), "false_alarms_per_min": 300.0, "pre_onset_false_alarms": 2,
    ...       "same_detections_as": ""}]
    >>> markdown_table(s).splitlines()[2]
    '| NMSD | 260 Hz (resampled) | 1/3 | - | 300 | 2 |  |'
    """
    rows = _rows(summary)
    out = ["| " + " | ".join(_HEAD) + " |", "|" + "|".join("---" for _ in _HEAD) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(out)


def _plt():
    import matplotlib  # deferred: heavy (matplotlib)

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt  # deferred: heavy (matplotlib)

    return plt


def _shade(ax, t: np.ndarray, slip: np.ndarray, cal_end: float) -> None:
    on = np.asarray(slip) != 0
    edges = np.flatnonzero(np.diff(np.r_[0, on.astype(int), 0]))
    for a, b in zip(edges[::2], edges[1::2]):
        ax.axvspan(t[a], t[min(b, len(t) - 1)], color="#d62728", alpha=0.12, lw=0)
    ax.axvspan(t[0], cal_end, color="0.85", alpha=0.5, lw=0)


def _raster(ax, runs: Sequence[MethodRun], rows: list[str], same: dict) -> None:
    """One row of detection ticks per method and rate, a dot at the first detection during the slip."""
    for i, key in enumerate(rows):
        r = next(r for r in runs if r.key == key)
        y = len(rows) - 1 - i
        color = registry.get(r.method).color
        ax.vlines(r.t[r.detections], y - 0.35, y + 0.35, color=color, lw=0.9)
        if r.score.detected:
            ax.plot([r.score.detection_t], [y], "o", color=color, ms=5, mec="k", mew=0.6)
    labels = []
    for key in reversed(rows):
        r = next(r for r in runs if r.key == key)
        twins = sorted(set(same.get(key, [])))
        labels.append(f"{r.label} @ {r.fs:.0f} Hz" + ("" if r.rate == "data" else " (resampled)")
                      + (f"\n= {', '.join(twins)}" if twins else ""))
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(labels, fontsize=7)
    ax.set_ylim(-0.6, len(rows) - 0.4)


def plot_trial_runs(trial, runs: Sequence[MethodRun], path: str | Path, *, calibration_s: float,
                    reduction: str) -> Path:
    """One trial: its taxels, the chain's channel, and every method's detections against the label.

    Top: the normal component of every taxel (change since the first sample; one colour per
    array). Middle: the channel the chain methods read. Bottom: one row per method and rate,
    a tick per detection, a dot at the first detection during the labelled slip. The
    labelled slip is shaded red, the calibration span grey.

    Examples
    --------
    >>> import tempfile
    >>> from slipreflex.benchmark import read_folder, shipped_dataset, run_trial, BenchmarkConfig
    >>> tr = read_folder(shipped_dataset())[-1]
    >>> runs = run_trial(tr, BenchmarkConfig(methods=("dath", "nmsd"), rates=("data",)))
    >>> plot_trial_runs(tr, runs, tempfile.mkdtemp() + "/t.png", calibration_s=1.0,
    ...                 reduction="z-sum").stat().st_size > 10_000
    True
    """

    plt = _plt()
    t = trial.t
    cal_end = float(t[0] + calibration_s)
    rows, same = [], {}
    for key in dict.fromkeys(r.key for r in runs):
        r = next(r for r in runs if r.key == key)
        twin = next((k for k in rows if k.endswith("@" + r.rate)
                     and np.array_equal(next(q for q in runs if q.key == k).detections, r.detections)), None)
        if twin is None:
            rows.append(key)
        else:
            same.setdefault(twin, []).append(r.label)
    fig = plt.figure(figsize=(11, 4.2 + 0.3 * len(rows)))
    gs = fig.add_gridspec(3, 1, height_ratios=[2.2, 1.6, 0.32 * len(rows) + 0.6], hspace=0.12)
    ax0 = fig.add_subplot(gs[0])
    ax1 = fig.add_subplot(gs[1], sharex=ax0)
    ax2 = fig.add_subplot(gs[2], sharex=ax0)
    if trial.layout is not None:
        z = trial.normal_frames().reshape(len(t), trial.layout.arrays, -1)
        z = z - z[0]
        for a in range(z.shape[1]):
            ax0.plot(t, z[:, a, :], lw=0.6, color=f"C{a}", alpha=0.7)
            normal = trial.layout.components[trial.layout.normal]
            ax0.plot([], [], color=f"C{a}", label=f"array {a + 1}: normal ({normal}) per taxel")
        ax0.set_ylabel("change (channel units)")
    else:
        ch = trial.channels - trial.channels[0]
        ax0.plot(t, ch, lw=0.7)
        ax0.set_ylabel("channels - first value")
    _shade(ax0, t, trial.slip, cal_end)
    ax0.axvspan(0, 0, color="#d62728", alpha=0.12, label="labelled slip")
    ax0.axvspan(0, 0, color="0.85", alpha=0.5, label="calibration span")
    ax0.legend(loc="upper left", fontsize=7, ncol=2, framealpha=0.8)
    onset = trial.onset_t
    kind = "slip" if onset is not None else "control, no slip"
    ax0.set_title(f"{trial.name} ({kind}): {len(t)} samples at {trial.fs:.1f} Hz", fontsize=10)
    for name, x in reduce_channels(trial, reduction)[:4]:
        ax1.plot(t, x, lw=0.9, color="k", label=f"chain input: {name}")
    _shade(ax1, t, trial.slip, cal_end)
    ax1.set_ylabel("chain input")
    ax1.legend(loc="upper left", fontsize=7)
    _raster(ax2, runs, rows, same)
    _shade(ax2, t, trial.slip, cal_end)
    ax2.set_xlabel("time (s)")
    ax2.set_title("detections (tick), first detection during the labelled slip (dot); "
                  "'= X': X detects the same", fontsize=8, loc="left")
    for ax in (ax0, ax1):
        ax.tick_params(labelbottom=False)
        ax.grid(alpha=0.25)
    if onset is not None:
        for ax in (ax0, ax1, ax2):
            ax.axvline(onset, color="#d62728", lw=0.8, ls="--")
    ax2.set_xlim(t[0], t[-1])
    path = Path(path)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path
