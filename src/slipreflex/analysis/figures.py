"""Figures like the paper's (matplotlib with the Agg backend, imported lazily).

* :func:`plot_trial` - one trial, like Figs. 10-12 (drop) and 15 (pour):
  accelerometer, filtered sensor, events, commanded position (and poured
  volume for a pour), with the onset (I), the first response (II) and the last
  change (III) marked.
* :func:`bar_chart` - mean and sd per bottle and method, like Figs. 13, 14,
  16 and 17, with the paper's values drawn beside ours.
* :func:`success_chart` - success per trial and per slip event, per bottle and method.
* :func:`grip_chart` - how far the hand closed without a true slip under way.

Examples
--------
>>> import os, tempfile
>>> s = [{"experiment": "drop", "bottle": "TR", "method": "dath", "response_mean_ms": 50.0,
...       "response_sd_ms": 5.0, "response_n": 10, "trial_success_rate": 0.8, "trial_success_n": 10}]
>>> p = bar_chart(s, "drop", "response", os.path.join(tempfile.mkdtemp(), "b.png"))
>>> p.stat().st_size > 1000
True
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import methods as _registry
from ..core import experiment_specs
from ..core.errors import ParameterError
from .paper import BOTTLE_ORDER, PAPER_SUCCESS, paper_value

__all__ = ["TrialPlot", "plot_trial", "bar_chart", "success_chart", "grip_chart", "check_figure_path"]


def _color(m: str) -> str:
    """A method's colour in every figure (its :class:`~slipreflex.methods.MethodSpec`), grey if unknown."""
    return _registry.get(m).color if m.casefold() in _registry.names() else "0.5"


def _plt():
    import matplotlib  # deferred: heavy (matplotlib)

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt  # deferred: heavy (matplotlib)

    return plt


@dataclass
class TrialPlot:
    """The streams of one trial to plot (times in s).

    Examples
    --------
    >>> TrialPlot(title="x", accel_t=[0, 1], accel=[0, 0]).title
    'x'
    """

    title: str
    accel_t: Any
    accel: Any
    accel_label: str = "accelerometer (g)"
    envelope: Any = None
    threshold: float = float("nan")
    sensor_t: Any = None
    sensor: Any = None
    sensor_label: str = "filtered sensor"
    event_t: Any = None
    event_label: str = "events"
    cmd_t: Any = None
    cmd_v: Any = None
    load_t: Any = None
    load: Any = None
    load_label: str = "volume (ml)"
    counts_t: Any = None
    counts: Any = None
    sensor_threshold: float = float("nan")
    load_at_onsets: Sequence[float] = ()
    onsets: Sequence[float] = ()
    responses: Sequence[float] = ()
    lasts: Sequence[float] = ()
    true_onsets: Sequence[float] = ()
    xlim: tuple[float, float] | None = None
    notes: dict = field(default_factory=dict)
    outcome: str = ""


def check_figure_path(path: str | Path, option: str) -> None:
    """Refuse, before any work, a figure path whose suffix matplotlib cannot write.

    Raises :class:`~slipreflex.core.errors.ParameterError` naming the option and the formats.

    Examples
    --------
    >>> check_figure_path("out/cal.png", "--figure")
    >>> check_figure_path("out/cal.toml", "--figure")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: --figure out/cal.toml: matplotlib cannot write '.toml' (one of: ..., ...
    """
    from matplotlib.backend_bases import FigureCanvasBase  # deferred: heavy (matplotlib)

    kinds = sorted(FigureCanvasBase.get_supported_filetypes())   # a class method: no figure made or closed
    suffix = Path(path).suffix.lower().lstrip(".")
    if suffix not in kinds:
        shown = ", ".join("." + k for k in kinds)
        raise ParameterError(f"{option} {path}: matplotlib cannot write '.{suffix}' (one of: {shown})")


def _save(plt, fig, path: str | Path, layout: bool = True) -> Path:
    """Lay out (unless done), write (creating the folder) and close one figure; the path written."""
    crop = False
    if layout:
        with warnings.catch_warnings():
            warnings.filterwarnings("error", "Tight layout not applied", UserWarning)
            try:
                fig.tight_layout()
            except UserWarning:  # a legend beside the axes wider than the margins: crop to what is drawn instead
                crop = True
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, bbox_inches="tight" if crop else None)
    plt.close(fig)
    return path


def _mark(ax, times: Sequence[float], color: str, label: str | None, style: str = "--") -> None:
    first = True
    for x in times:
        if x is not None and not math.isnan(x):
            ax.axvline(x, color=color, ls=style, lw=0.9, label=label if first else None)
            first = False


def plot_trial(p: TrialPlot, path: str | Path) -> Path:
    """Draw one trial as the paper's Figs. 10-12 / 15 and save it as PNG.

    Examples
    --------
    >>> import os, tempfile, numpy as np
    >>> t = np.linspace(0, 2, 600)
    >>> tp = TrialPlot(title="demo", accel_t=t, accel=np.sin(9 * t), sensor_t=t, sensor=t,
    ...                event_t=[1.0, 1.1], cmd_t=[1.05, 1.2], cmd_v=[200, 220], onsets=[0.98],
    ...                responses=[1.05], lasts=[1.2])
    >>> plot_trial(tp, os.path.join(tempfile.mkdtemp(), "t.png")).suffix
    '.png'
    """
    plt = _plt()
    has_load = p.load_t is not None and len(p.load_t) > 0
    n = 4 + int(has_load)
    fig, axes = plt.subplots(n, 1, figsize=(7.5, 1.7 * n + 0.9), sharex=True)
    axes = list(axes)
    every = list(axes)
    letters = iter("ABCDE")
    ax_load = None
    if has_load:
        ax = ax_load = axes.pop(0)
        ax.plot(p.load_t, p.load, color="tab:cyan", lw=1)
        ax.set_ylabel(p.load_label, fontsize=8)
        ax.set_title(f"{next(letters)}) {p.load_label}, at each onset (I) and response (II)", loc="left",
                     fontsize=8, y=1.0)
        lt, lv = np.asarray(p.load_t, dtype=float), np.asarray(p.load, dtype=float)
        for on, resp in zip(p.onsets, p.responses):
            for x, mark, color in ((on, "o", "tab:red"), (resp, "s", "tab:green")):
                if x is not None and math.isfinite(x):
                    y = float(np.interp(x, lt, lv))
                    ax.plot([x], [y], mark, color=color, ms=3.5, transform=ax.transData)
                    if mark == "o":
                        ax.annotate(f"{y:.0f} ml", (x, y), xytext=(3, 3), textcoords="offset points",
                                    fontsize=6.5, color=color)
    ax_acc, ax_sen, ax_ev, ax_cmd = axes
    ax_acc.plot(p.accel_t, p.accel, color="0.4", lw=0.6, label="raw")
    if p.envelope is not None:
        ax2 = ax_acc.twinx()
        ax2.plot(p.accel_t, p.envelope, color="tab:purple", lw=0.9, label="rectified, 30 Hz")
        if not math.isnan(p.threshold):
            ax2.axhline(p.threshold, color="tab:purple", ls=":", lw=0.8)
        ax2.set_ylabel("envelope (g)", fontsize=7)
        ax2.tick_params(labelsize=7)
        every.append(ax2)
    ax_acc.set_ylabel("g", fontsize=8)
    ax_acc.set_title(f"{next(letters)}) {p.accel_label}", loc="left", fontsize=8, y=1.0)
    if p.sensor is not None:
        ax_sen.plot(p.sensor_t, p.sensor, color="tab:blue", lw=0.8)
        if not math.isnan(p.sensor_threshold):
            ax_sen.axhline(p.sensor_threshold, color="tab:blue", ls=":", lw=0.8)
    ax_sen.set_title(f"{next(letters)}) {p.sensor_label}", loc="left", fontsize=8, y=1.0)
    ev = np.asarray([] if p.event_t is None else p.event_t, dtype=float)
    if ev.size:
        ax_ev.vlines(ev, 0, 1, color="k", lw=0.7)
    ax_ev.set_yticks([])
    counted = ""
    if p.counts_t is not None and len(p.counts_t):
        ax_n = ax_ev.twinx()
        ax_n.step(p.counts_t, p.counts, where="pre", color="tab:orange", lw=0.8, label="window count")
        ax_n.set_ylabel("count", fontsize=7)
        ax_n.set_ylim(bottom=0, top=max(1.0, float(np.max(p.counts))) * 1.15)
        ax_n.tick_params(labelsize=7)
        every.append(ax_n)
        counted = ", spike count per window (orange)"
    ax_ev.set_title(f"{next(letters)}) {p.event_label} ({ev.size}){counted}", loc="left", fontsize=8, y=1.0)
    if p.cmd_t is not None and len(p.cmd_t):
        ax_cmd.step(p.cmd_t, p.cmd_v, where="post", color="tab:green", lw=1.0)
    ax_cmd.set_ylabel("position", fontsize=8)
    ax_cmd.set_title(f"{next(letters)}) commanded finger position", loc="left", fontsize=8, y=1.0)
    ax_cmd.set_xlabel("time (s)")
    for ax in (ax_acc, ax_sen, ax_ev, ax_cmd) + ((ax_load,) if ax_load is not None else ()):
        _mark(ax, p.onsets, "tab:red", "I onset" if ax is ax_acc else None)
        _mark(ax, p.responses, "tab:green", "II response" if ax is ax_acc else None)
        _mark(ax, p.lasts, "tab:olive", "III last change" if ax is ax_acc else None, ":")
        _mark(ax, p.true_onsets, "k", "true onset (sim)" if ax is ax_acc else None, "-.")
        ax.tick_params(labelsize=7)
    handles, labels = [], []
    for ax in every:
        h, lab = ax.get_legend_handles_labels()
        handles += h
        labels += lab
    # Below the axes, never over the data.
    fig.legend(handles, labels, fontsize=6.5, loc="lower center", ncol=min(6, max(1, len(labels))))
    if p.xlim:
        ax_cmd.set_xlim(*p.xlim)
        for ax in every:
            _fit_y(ax, p.xlim)
    fig.suptitle(p.title + (f"\n{p.outcome}" if p.outcome else ""), fontsize=9)
    _stack_layout(fig, n, title_lines=2 if p.outcome else 1)
    return _save(plt, fig, path, layout=False)


def _stack_layout(fig, n: int, title_lines: int) -> None:
    """Margins of ``n`` stacked panels in inches (tight_layout would measure every label: slow)."""
    w, h = fig.get_figwidth(), fig.get_figheight()
    top = 0.42 + 0.15 * title_lines            # the suptitle's lines, then the first panel's title
    fig.subplots_adjust(left=0.75 / w, right=1 - 0.62 / w, top=1 - top / h, bottom=0.72 / h,
                        hspace=0.3 / ((h - top - 0.72) / n - 0.3))


def _fit_y(ax, xlim: tuple[float, float]) -> None:
    """Scale the y axis to the data inside ``xlim`` (a zoom shows its own range, not the trial's)."""
    lo, hi = math.inf, -math.inf
    for line in ax.get_lines():
        if line.get_transform() != ax.transData:   # axvline / axhline markers, not data
            continue
        x, y = (np.asarray(v, dtype=float) for v in line.get_data())
        inside = (x >= xlim[0]) & (x <= xlim[1]) & np.isfinite(y)
        if x.size and inside.any():
            lo, hi = min(lo, float(y[inside].min())), max(hi, float(y[inside].max()))
    if math.isfinite(lo) and math.isfinite(hi):
        pad = 0.08 * (hi - lo) if hi > lo else max(abs(hi) * 0.05, 0.5)
        ax.set_ylim(lo - pad, hi + pad)


def _present(summary, experiment):
    rows = [s for s in summary if s["experiment"] == experiment]
    bottles = [b for b in BOTTLE_ORDER if any(s["bottle"] == b for s in rows)]
    methods = [m for m in _registry.names() if any(s["method"] == m for s in rows)]
    return {(s["bottle"], s["method"]): s for s in rows}, bottles, methods


def bar_chart(summary: Sequence[dict[str, Any]], experiment: str, metric: str,
              path: str | Path, what: str | None = None) -> Path:
    """Bars of ``metric`` ("response" or "total") with sd, ours beside the paper's.

    ``what`` names the load as run ("10 g dropped from 2 cm"; default: the experiment's
    title, :mod:`slipreflex.core.experiment_specs`).

    Our values are the filled bars; the paper's mean and sd, where it reports
    them, are black diamonds with error bars next to each bar.

    Examples
    --------
    >>> import os, tempfile
    >>> bar_chart([], "pour", "total", os.path.join(tempfile.mkdtemp(), "x.png")).exists()
    True
    """
    plt = _plt()
    by, bottles, methods = _present(summary, experiment)
    from matplotlib.lines import Line2D  # deferred: heavy (matplotlib)
    from matplotlib.patches import Patch  # deferred: heavy (matplotlib)

    fig, ax = plt.subplots(figsize=(7.8, 3.4))
    width = 0.8 / max(1, len(methods))
    handles = []
    for j, m in enumerate(methods):
        xs = np.arange(len(bottles)) + (j - (len(methods) - 1) / 2) * width
        mean = [by.get((b, m), {}).get(f"{metric}_mean_ms", np.nan) for b in bottles]
        sd = [by.get((b, m), {}).get(f"{metric}_sd_ms", np.nan) for b in bottles]
        ns = [by.get((b, m), {}).get(f"{metric}_n", "") for b in bottles]
        mean = np.array([float(x) for x in mean])
        sd = np.nan_to_num(np.array([float(x) for x in sd]))
        ok = np.isfinite(mean)
        below = np.minimum(sd, np.maximum(mean, 0.0))    # a time is never negative: clip at zero
        ax.bar(xs[ok], mean[ok], width * 0.9, yerr=[below[ok], sd[ok]], capsize=3, color=_color(m))
        for x, top, n in zip(xs[ok], (mean + sd)[ok], np.asarray(ns, dtype=object)[ok]):
            ax.text(x, top, f"n={n}", ha="center", va="bottom", fontsize=5.5)
        handles.append(Patch(color=_color(m), label=f"{_registry.label(m)} (ours)"))
        for x in xs[~ok]:
            ax.text(x, 0, "n/a", ha="center", va="bottom", fontsize=6, rotation=90)
        for x, b in zip(xs, bottles):
            pv = paper_value(experiment, f"{metric}_ms", b, m)
            if pv is not None and pv.mean is not None:
                psd = pv.sd or 0.0
                ax.errorbar(x + width * 0.25, pv.mean, yerr=[[min(psd, pv.mean)], [psd]], fmt="D", color="k",
                            ms=3.5, capsize=2, lw=0.8)
    handles.append(Line2D([], [], marker="D", color="k", ms=3.5, lw=0.8, label="paper (mean ± sd)"))
    ax.set_xticks(np.arange(len(bottles)))
    ax.set_xticklabels(bottles)
    label = "response time" if metric == "response" else "total controller time"
    what = what or f"{experiment}, {experiment_specs.get(experiment).title}"
    ax.set_ylabel(f"{label} (ms)")
    ax.set_title(f"{label.capitalize()}, {what} (bars: sd)", fontsize=9)
    ax.set_ylim(bottom=0)
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return _save(plt, fig, path)


def _paper_rate(experiment: str, bottle: str, method: str) -> tuple[float, str] | None:
    """The paper's stated success (percent, marker): "D" a value, "v" an upper bound."""

    text = PAPER_SUCCESS.get((experiment, bottle, method)) or PAPER_SUCCESS.get((experiment, "all", method))
    if not text:
        return None
    value = float("".join(ch for ch in text if ch.isdigit() or ch == ".") or "nan")
    return value, "v" if "under" in text else "D"


def success_chart(summary: Sequence[dict[str, Any]], path: str | Path) -> Path:
    """Success rate per experiment, bottle and method, the paper's stated rates beside ours.

    Bars: success per trial (every slip of the trial suppressed); white dots: success
    per slip event. The axis runs from 0 to 100 %; a rate of zero is drawn as a visible
    "0" at the base, a method not run as "n/a"; each bar says how many trials it counts.

    Examples
    --------
    >>> import os, tempfile
    >>> s = [{"experiment": "pour", "bottle": "DK", "method": "nmsd", "trial_success_rate": 1.0,
    ...       "event_success_rate": 0.5}]
    >>> success_chart(s, os.path.join(tempfile.mkdtemp(), "s.png")).exists()
    True
    """
    plt = _plt()
    from matplotlib.lines import Line2D  # deferred: heavy (matplotlib)
    from matplotlib.patches import Patch  # deferred: heavy (matplotlib)

    exps = [e for e in experiment_specs.names() if any(s["experiment"] == e for s in summary)]
    exps += sorted({s["experiment"] for s in summary} - set(exps))
    exps = exps or [experiment_specs.names()[0]]
    fig, axes = plt.subplots(1, len(exps), figsize=(4.4 * len(exps) + 1.6, 3.6), squeeze=False)
    shown: dict[str, Any] = {}
    for ax, e in zip(axes[0], exps):
        by, bottles, methods = _present(summary, e)
        width = 0.8 / max(1, len(methods))
        for j, m in enumerate(methods):
            xs = np.arange(len(bottles)) + (j - (len(methods) - 1) / 2) * width
            for x, b in zip(xs, bottles):
                row = by.get((b, m), {})
                rate = 100 * float(row.get("trial_success_rate", np.nan))
                n = row.get("trial_success_n")
                per_event = 100 * float(row.get("event_success_rate", np.nan))
                if np.isfinite(rate):
                    ax.bar(x, rate, width * 0.9, color=_color(m), edgecolor=_color(m), lw=1.2)
                    label = ("0" if rate == 0 else "") + (f"\n{n} trials" if n else "")
                    ax.text(x, max(rate, per_event if np.isfinite(per_event) else 0) + 2.5, label.strip(),
                            ha="center", va="bottom", fontsize=5.5)
                    if np.isfinite(per_event):
                        ax.plot(x, per_event, "o", mfc="white", mec="k", ms=4, zorder=6)
                        shown["o"] = True
                else:
                    ax.text(x, 1.5, "n/a", ha="center", va="bottom", fontsize=6, rotation=90)
                paper = _paper_rate(e, b, m)
                if paper is not None:
                    ax.plot(x, paper[0], paper[1], color="k", ms=4.5, zorder=5)
                    shown[paper[1]] = True
            shown.setdefault(m, True)
        ax.set_xticks(np.arange(len(bottles)))
        ax.set_xticklabels(bottles)
        ax.set_ylim(0, 118)
        ax.set_yticks([0, 20, 40, 60, 80, 100])
        ax.set_ylabel("success (%)")
        ax.set_title(f"Success, {e}: per trial (bars), per slip event (dots)", fontsize=8)
    handles: list[Any] = [Patch(color=_color(m), label=f"{_registry.label(m)}, per trial (ours)") for m in shown
                          if m not in ("D", "v", "o")]
    if "o" in shown:
        handles.append(Line2D([], [], ls="", marker="o", mfc="white", mec="k", ms=4, label="per slip event (ours)"))
    if "D" in shown:
        handles.append(Line2D([], [], ls="", marker="D", color="k", ms=4.5, label="paper, as stated"))
    if "v" in shown:
        handles.append(Line2D([], [], ls="", marker="v", color="k", ms=4.5, label="paper: under this"))
    fig.legend(handles=handles, fontsize=7, loc="center right")
    fig.tight_layout(rect=(0, 0, 1 - 1.5 / fig.get_figwidth(), 1))
    return _save(plt, fig, path, layout=False)


def grip_chart(summary: Sequence[dict[str, Any]], path: str | Path) -> Path:
    """The grip the reflex added without slip: per experiment, bottle and method, mean ± sd per trial.

    How far the hand closed (finger units) while the simulator had no true slip under
    way: a squeeze at a knock or at the water's landing, before any slip, that the
    response times and success rates do not show.

    Examples
    --------
    >>> import os, tempfile
    >>> s = [{"experiment": "pour", "bottle": "DK", "method": "dath", "grip_without_slip_mean": 350.0,
    ...       "grip_without_slip_sd": 20.0, "grip_without_slip_n": 3}]
    >>> grip_chart(s, os.path.join(tempfile.mkdtemp(), "g.png")).exists()
    True
    """
    plt = _plt()
    from matplotlib.patches import Patch  # deferred: heavy (matplotlib)

    exps = [e for e in ("drop", "pour") if any(s["experiment"] == e for s in summary)] or ["drop"]
    fig, axes = plt.subplots(1, len(exps), figsize=(4.4 * len(exps) + 1.6, 3.4), squeeze=False)
    shown: list[str] = []
    for ax, e in zip(axes[0], exps):
        by, bottles, methods = _present(summary, e)
        width = 0.8 / max(1, len(methods))
        for j, m in enumerate(methods):
            xs = np.arange(len(bottles)) + (j - (len(methods) - 1) / 2) * width
            mean = np.array([float(by.get((b, m), {}).get("grip_without_slip_mean", np.nan)) for b in bottles])
            sd = np.nan_to_num(np.array([float(by.get((b, m), {}).get("grip_without_slip_sd", np.nan))
                                         for b in bottles]))
            ok = np.isfinite(mean)
            ax.bar(xs[ok], mean[ok], width * 0.9, yerr=[np.minimum(sd, mean)[ok], sd[ok]], capsize=2,
                   color=_color(m))
            for x, v in zip(xs[ok], mean[ok]):
                ax.text(x, v, f"{v:.0f}", ha="center", va="bottom", fontsize=5.5)
            if m not in shown:
                shown.append(m)
        ax.set_xticks(np.arange(len(bottles)))
        ax.set_xticklabels(bottles)
        ax.set_ylim(bottom=0)
        ax.set_ylabel("finger units closed without slip")
        ax.set_title(f"Grip added without slip, {e} (mean ± sd per trial)", fontsize=8)
    fig.legend(handles=[Patch(color=_color(m), label=_registry.label(m)) for m in shown], fontsize=7,
               loc="center right")
    fig.tight_layout(rect=(0, 0, 1 - 1.3 / fig.get_figwidth(), 1))
    return _save(plt, fig, path, layout=False)
