"""The files a reproduction writes: results.csv, summary.csv, report.md and the figures.

:class:`ReproduceResult` holds what a run of the grid produced (made by
:func:`slipreflex.reproduce.experiments.run_reproduce`); :func:`write_outputs` writes it;
:func:`trial_plot` turns one simulated trial into the data of its figure, drawing the
method's detections the way its :class:`~slipreflex.methods.MethodSpec` says. The text
comes from :mod:`slipreflex.analysis.report`, the drawing from :mod:`slipreflex.analysis.figures`.

Examples
--------
>>> from slipreflex.reproduce.experiments import ReproduceConfig
>>> ReproduceResult(ReproduceConfig(), [], [], {}, {}, 0.0, 1).rows   # a run's rows (write_outputs: a whole run)
[]
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..core import experiment_specs
from ..files.interrupts import worker_signals
from ..methods import DATH
from . import figures as F
from .claims import judge_run, write_claims_csv, write_parts_csv
from .figures import TrialPlot
from .onset import OnsetParams, accel_envelope
from .paper import BOTTLE_ORDER
from .report import (
    GRIP_CAPTION,
    SUCCESS_CAPTION,
    SUMMARY_COLUMNS,
    bars_caption,
    discussion_text,
    report_markdown,
    setup_lines,
    terminal_table,
    trial_caption,
    void,
    write_csv,
    zoom_caption,
)
from .trial import RESULT_COLUMNS, TrialRow

__all__ = ["ReproduceResult", "write_outputs", "trial_plot", "paper_part", "not_the_papers", "trial_outcome",
           "scored", "zoom_window", "judged_claims", "replicates_note"]


@dataclass
class ReproduceResult:
    """Everything a reproduction produced.

    Attributes
    ----------
    config : slipreflex.reproduce.experiments.ReproduceConfig
    rows : list of TrialRow
        One per trial and slip event (the rows of results.csv).
    summary : list of dict
        Per experiment, bottle and method (columns of summary.csv).
    thresholds : dict
        The calibrated methods' thresholds, by method name.
    plots : dict
        Plot data of the example trials, by cell key.
    wall_s : float
        Wall time of the whole run (s).
    jobs : int
        Worker processes used.
    calibration_wall_s : float
        Wall time of the threshold calibration (s); the length of each
        calibration *recording* is ``config.calibration_s``.
    trials_planned, trials_finished : int
        Trials in the grid and trials finished: fewer when Ctrl-C or SIGTERM
        stopped the run (:class:`~slipreflex.files.interrupts.Interrupted` carries it).
    replicates : list of TrialRow
        Rows of the replicate grids run on derived master seeds for claims this run's
        trials left unresolved (``replicates.csv``; empty: none was needed).
    replicate_seeds : tuple of int
        Their master seeds, in order.

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> ReproduceResult(ReproduceConfig(), [], [], {}, {}, 0.0, 1).rows
    []
    """

    config: Any
    rows: list[TrialRow]
    summary: list[dict[str, Any]]
    thresholds: dict[str, float]
    plots: dict[tuple, Any]
    wall_s: float
    jobs: int
    calibration_wall_s: float = 0.0
    trials_planned: int = 0
    trials_finished: int = 0
    replicates: list[TrialRow] = field(default_factory=list)
    replicate_seeds: tuple[int, ...] = ()

    @property
    def partial_note(self) -> str:
        """``"interrupted after 87 of 240 trials"`` for a stopped run, else ``""``.

        Examples
        --------
        >>> from slipreflex.reproduce.experiments import ReproduceConfig
        >>> ReproduceResult(ReproduceConfig(), [], [], {}, {}, 0.0, 1, 0.0, 240, 87).partial_note
        'interrupted after 87 of 240 trials'
        """
        if self.trials_finished >= self.trials_planned:
            return ""
        return f"interrupted after {self.trials_finished} of {self.trials_planned} trials"


def write_outputs(result: ReproduceResult, out_dir: str | Path, *, command: str | None = None,
                  discussion: Sequence[str] | None = None, jobs: int | None = None) -> dict[str, Path]:
    """Write results.csv, summary.csv, the figures and report.md of a run into ``out_dir``.

    Parameters
    ----------
    result : ReproduceResult
    out_dir : str or Path
        Created if missing.
    command : str, optional
        The command line, quoted in report.md.
    discussion : sequence of str, optional
        Replaces the computed discussion paragraphs.
    jobs : int, optional
        Processes that draw the figures (default: the run's ``result.jobs``).

    Returns
    -------
    dict
        Paths by name ("results", "summary", "report", "claims" and "claim_parts" (the paper's claims
        judged, unless the run is partial or has none of the paper's cells), and one per figure).

    Examples
    --------
    >>> import tempfile
    >>> from slipreflex.reproduce.experiments import ReproduceConfig, run_reproduce
    >>> cfg = ReproduceConfig(trials=1, bottles=("TX",), methods=("dath",), experiments=("drop",))
    >>> res = run_reproduce(cfg, jobs=1, progress=False)
    >>> paths = write_outputs(res, tempfile.mkdtemp())
    >>> sorted(p for p in paths if not p.endswith(".png"))
    ['claim_parts', 'claims', 'report', 'results', 'summary']
    >>> sorted(paths)[:2]
    ['bars_drop_response.png', 'bars_drop_total.png']
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    partial = getattr(result, "partial_note", "")
    notes = [f"partial: {partial}"] if partial else []
    paths = {"results": write_csv(out / "results.csv", result.rows, RESULT_COLUMNS, notes=notes),
             "summary": write_csv(out / "summary.csv", result.summary, SUMMARY_COLUMNS, notes=notes)}
    # A stopped run is saved at once: its figures would take seconds the user did not give.
    figs = [] if partial else _write_figures(result, out, paths, result.jobs if jobs is None else jobs)
    notices = [f"Partial run: {partial}; the tables cover the finished trials only, "
               "and no figures were drawn nor claims judged."] if partial else []
    paper, others, notice = paper_part(result)
    notices += [notice] if notice else []
    note = replicates_note(result)
    notices += [note[:1].upper() + note[1:] + "."] if note else []

    if result.replicates:
        paths["replicates"] = write_csv(out / "replicates.csv", result.replicates, RESULT_COLUMNS,
                                        notes=[replicates_note(result)])
    claims = judged_claims(result)
    if claims:
        paths["claims"] = write_claims_csv(out / "claims.csv", claims)
        paths["claim_parts"] = write_parts_csv(out / "claim_parts.csv", claims)
    md = report_markdown(summary=paper.summary, rows=paper.rows, figures=figs,
                         setup=setup_lines(result, command), notices=notices,
                         discussion=list(discussion) if discussion is not None else discussion_text(paper),
                         claims=claims)
    if others:

        md += ("\n## Your objects (no paper values)\n\n```\n" + terminal_table(others) + "\n```\n")
    paths["report"] = out / "report.md"
    paths["report"].write_text(md)
    return paths


def judged_claims(result: ReproduceResult) -> list:
    """The paper's claims judged on a run: its scored paper rows, pooled with its replicates' rows.

    Empty for a partial run or one without any of the paper's cells.

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> judged_claims(ReproduceResult(ReproduceConfig(), [], [], {}, {}, 0.0, 1))
    []
    """
    paper = paper_part(result)[0]
    if result.partial_note or not paper.rows:
        return []
    pooled = scored(paper.rows) + scored(result.replicates)
    return judge_run(pooled, seed=result.config.seed, plant=result.config.plant)


def replicates_note(result: ReproduceResult) -> str:
    """One line on the replicate grids behind a run's claims ("" when none ran).

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> replicates_note(ReproduceResult(ReproduceConfig(), [], [], {}, {}, 0.0, 1))
    ''
    """
    if not result.replicate_seeds:
        return ""
    methods = sorted({str(getattr(r, "method", "")) for r in result.replicates})
    return (f"claims judged on this run pooled with {len(result.replicate_seeds)} replicate grid(s) of "
            f"{', '.join(methods)} on master seeds {', '.join(map(str, result.replicate_seeds))} "
            f"({len(result.replicates)} rows, replicates.csv): one run's trials left a claim unresolved")


def scored(rows: Sequence[Any]) -> list[Any]:
    """The rows a method is judged on: every row but those of void trials (object out before the load).

    Examples
    --------
    >>> scored([{"fell_before_load": True}, {"fell_before_load": False}])
    [{'fell_before_load': False}]
    """

    return [r for r in rows if not void(r)]


def not_the_papers(config: Any) -> list[str]:
    """What in a run is not the paper's: its own bottles, drop or pour (empty: all the paper's).

    ``config`` is a :class:`slipreflex.reproduce.experiments.ReproduceConfig`.

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> not_the_papers(ReproduceConfig())
    []
    >>> not_the_papers(ReproduceConfig(drop_mass_kg=0.02))
    ['drop (20 g from 2 cm)']
    """
    from ..sim import BOTTLES  # deferred: heavy (numba kernels)

    out = [f"bottle {b}" for b in config.bottles if b not in BOTTLES or config.bottle(b) != BOTTLES[b]]
    for e in config.experiments:
        exp = experiment_specs.get(e)
        what = exp.perturbation(config)
        if exp.paper is None or what != exp.paper():
            out.append(f"{e} ({exp.describe(what)})")
    return out


def paper_part(result: ReproduceResult) -> tuple[ReproduceResult, list[dict[str, Any]], str]:
    """The run restricted to the paper's bottles and loads, the other summary rows, and a notice.

    The report compares with the paper only the first part; the notice (empty when every
    object is the paper's) says so in the report's first lines.

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> res = ReproduceResult(ReproduceConfig(drop_mass_kg=0.02), [], [], {}, {}, 0.0, 1)
    >>> paper_part(res)[2][:50]
    "Not the paper's objects: drop (20 g from 2 cm). Th"
    """
    differ = not_the_papers(result.config)
    if not differ:
        return result, [], ""

    def comparable(r: Any) -> bool:            # the paper's bottle under the paper's load
        return f"bottle {r['bottle']}" not in differ and not any(d.startswith(r["experiment"]) for d in differ)

    keep = [s for s in result.summary if comparable(s)]
    others = [s for s in result.summary if not comparable(s)]
    rows = [r for r in result.rows if comparable(r)]
    notice = ("Not the paper's objects: " + ", ".join(differ) + ". The paper's numbers are compared "
              "only where the bottle and its load are the paper's"
              + ("" if keep else " (none in this run)") + "; the other results are at the end, "
              "under 'Your objects', and in results.csv.")
    return dataclasses.replace(result, rows=rows, summary=keep), others, notice


def _figure_tasks(result: ReproduceResult, fig_dir: Path) -> list[tuple[str, str, Any, tuple]]:
    """(file name, caption, drawing function, its arguments before the path) of every figure of a run."""

    tasks: list[tuple[str, str, Any, tuple]] = []
    order = experiment_specs.names()
    for key in sorted(result.plots, key=lambda k: (order.index(k[0]), BOTTLE_ORDER.index(k[1])
                                                   if k[1] in BOTTLE_ORDER else len(BOTTLE_ORDER), k[1])):
        e, b, m, _ = key
        plot = result.plots[key]
        tasks.append((f"trial_{e}_{b}_{m}.png", trial_caption(e, b, m), F.plot_trial, (plot,)))
        ons = [x for x in plot.onsets if x == x]
        if ons and (m == DATH or not any(k[2] == DATH for k in result.plots)):    # one zoom per figure set
            zoom = dataclasses.replace(plot, xlim=zoom_window(plot, e),
                                       title=plot.title + ", zoomed on its slips")
            tasks.append((f"trial_{e}_{b}_{m}_zoom.png", zoom_caption(b, m, e), F.plot_trial, (zoom,)))
    for e in result.config.experiments:
        exp = experiment_specs.get(e)
        what = f"{exp.title}, {exp.describe(exp.perturbation(result.config))}"
        for metric in ("response", "total"):
            tasks.append((f"bars_{e}_{metric}.png", bars_caption(e, metric),
                          functools.partial(F.bar_chart, what=what), (result.summary, e, metric)))
    tasks.append(("success.png", SUCCESS_CAPTION, F.success_chart, (result.summary,)))
    tasks.append(("grip_without_slip.png", GRIP_CAPTION, F.grip_chart, (result.summary,)))
    return tasks


#: A trial's zoom: from this long before its first onset (s) ...
ZOOM_BEFORE_S: float = 0.08
#: ... to this long after its last response (s), at least ``ZOOM_MIN_S`` wide; a drop's full
#: figure spans 1.8 s, its zoom about a quarter of it.
ZOOM_AFTER_S: float = 0.15
ZOOM_MIN_S: float = 0.3


def zoom_window(plot: Any, experiment: str) -> tuple[float, float]:
    """The time span of a trial's zoomed figure: the first onset to the slip's responses.

    A single-slip experiment (a drop) is zoomed on its onset and the reflex's first
    commands (a few windows); one with slips seconds apart (a pour's segmented events)
    on its first to last slip.

    Examples
    --------
    >>> from types import SimpleNamespace as P
    >>> zoom_window(P(onsets=[2.0], responses=[2.05]), "drop")
    (1.92, 2.22)
    """
    ons = [x for x in plot.onsets if x == x]
    resp = [x for x in plot.responses if x == x] or ons
    lo = min(ons) - ZOOM_BEFORE_S
    segmented = experiment_specs.get(experiment).slip_events == "segmented" if experiment in experiment_specs.names() \
        else False
    hi = (max(ons) + 0.7) if segmented and len(ons) > 1 else max(resp) + ZOOM_AFTER_S
    return round(lo, 9), round(max(hi, lo + ZOOM_MIN_S), 9)


def _draw(task: tuple[Any, tuple, Path]) -> Path:
    draw, args, path = task
    return draw(*args, path)


def _write_figures(result: ReproduceResult, out: Path, paths: dict[str, Path],
                   jobs: int = 1) -> list[tuple[str, str]]:
    """Draw the example trials, bar charts and success chart; (caption, relative path) of each.

    The figures are independent, so ``jobs`` > 1 draws them in that many processes (a
    figure costs a few tenths of a second, mostly matplotlib's text layout).
    """

    fig_dir = out / "figures"
    tasks = _figure_tasks(result, fig_dir)
    work = [(draw, args, fig_dir / name) for name, _, draw, args in tasks]
    jobs = max(1, min(int(jobs), len(work)))
    if jobs == 1:
        drawn = [_draw(w) for w in work]
    else:


        F._plt()                       # imported once here, so the forked workers start warm
        with ProcessPoolExecutor(max_workers=jobs, initializer=worker_signals) as ex:
            drawn = list(ex.map(_draw, work))
    for (name, _, _, _), path in zip(tasks, drawn):
        paths[name] = path
    return [(caption, f"figures/{name}") for name, caption, _, _ in tasks]


def trial_plot(cell: Any, spec: Any, tr: Any, reflex: Any, rows: Sequence[Any], t_pert: float):
    """What :func:`slipreflex.analysis.figures.plot_trial` draws of one simulated trial.

    Parameters
    ----------
    cell : slipreflex.reproduce.experiments.Cell
        The trial (experiment, bottle, method, index, seed).
    spec : slipreflex.methods.MethodSpec
        The method's specification: its input stream and how its detections are drawn.
    tr : slipreflex.sim.loop.SimTrace
        The closed-loop recording.
    reflex : Reflex
        The reflex that ran (its parameters draw the detections).
    rows : sequence of TrialRow
        The trial's analysed rows (onsets, responses, last changes).
    t_pert : float
        When the load was applied (s).

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig, Cell, run_trial, trial_seed
    >>> cfg = ReproduceConfig(trials=1, after_s=0.5)
    >>> cell = Cell("drop", "TX", "nmsd", 0, trial_seed(cfg.seed, "drop", "TX", 0))
    >>> _, plot = run_trial(cell, cfg, {"nmsd": 15.0}, keep_plot=True)
    >>> plot.event_label, plot.sensor.shape == plot.sensor_t.shape
    ('NMSD detections the reflex computed', True)
    """
    from ..sim.loop import reflex_log  # deferred: heavy (numba kernels)

    axis = rows[0].axis
    env = accel_envelope(tr.t, tr.accel[:, axis], OnsetParams())
    drawn = _drawn(spec, reflex, reflex_log(tr))
    exp = experiment_specs.get(cell.experiment)
    zoom = exp.zoom_s
    xlim = None if zoom is None else (t_pert - zoom[0], min(tr.t_end, t_pert + zoom[1]))
    axes = "xyz"
    return TrialPlot(
        title=f"{cell.experiment} {cell.bottle} {cell.method} (trial {cell.trial}, seed {cell.seed})",
        accel_t=tr.t, accel=tr.accel[:, axis], accel_label=f"accelerometer ({axes[axis]} axis)",
        envelope=env, threshold=float("nan"), cmd_t=tr.cmd_t, cmd_v=tr.cmd_value,
        load_t=tr.t if exp.records_load else None, load=tr.water_ml if exp.records_load else None,
        onsets=[r.onset_s for r in rows], responses=[r.onset_s + r.response_ms / 1e3 for r in rows],
        lasts=[r.last_change_s for r in rows], true_onsets=[r.true_onset_s for r in rows],
        load_at_onsets=[r.load_at_onset for r in rows],
        xlim=xlim, outcome=trial_outcome(rows, tr.fall_time), **drawn)


def _drawn(spec: Any, reflex: Any, log: dict | None) -> dict[str, Any]:
    """The sensor, detection and window-count panels from what the loop's reflex recorded.

    Nothing is recomputed: a reflex that recorded nothing (no ``probe_slots``) leaves the
    panels empty, labelled so.
    """
    if log is None:
        return {"sensor_label": f"{spec.label}: the reflex recorded nothing to draw",
                "event_label": "detections (not recorded)"}
    t = log["t"]
    if spec.input_kind == "slip":
        counts = log["count"] >= 0
        return {"sensor_t": t, "sensor": log["x"],
                "sensor_label": f"slip sensor as the reflex filtered it, {reflex.params.cutoff:g} Hz low-pass (V)",
                "event_t": t[log["event"] > 0], "event_label": "spikes the reflex computed",
                "counts_t": t[counts], "counts": log["count"][counts],
                "sensor_threshold": float("nan")}
    unit = getattr(spec, "threshold_unit", "")
    return {"sensor_t": t, "sensor": log["stat"],
            "sensor_label": f"{spec.label} statistic the reflex computed ({unit}), threshold dotted",
            "sensor_threshold": float(reflex.params.threshold),
            "event_t": t[log["event"] > 0], "event_label": f"{spec.label} detections the reflex computed"}


def trial_outcome(rows: Sequence[Any], fall_time: float | None) -> str:
    """What happened in a trial, for its figure's title: slips found, caught or not, a fall.

    Examples
    --------
    >>> from types import SimpleNamespace as R
    >>> trial_outcome([R(n_events=1, onset_s=2.66, response_ms=71.0, success=True)], None)
    'slip at 2.66 s, detected and caught (response 71 ms)'
    >>> trial_outcome([R(n_events=0, onset_s=float("nan"), response_ms=float("nan"), success=True)], None)
    'no slip found'
    >>> trial_outcome([R(n_events=1, onset_s=14.6, response_ms=float("nan"), success=False)], 14.9)
    'slip at 14.60 s, no response; fell out at 14.90 s'
    """
    fell = "" if fall_time is None else f"fell out at {float(fall_time):.2f} s"
    found = [r for r in rows if r.n_events > 0 and r.onset_s == r.onset_s]
    if not found:
        return "no slip found" + (f"; {fell}" if fell else "")
    parts = []
    for r in found:
        if r.response_ms != r.response_ms:
            parts.append(f"slip at {r.onset_s:.2f} s, no response")
        else:
            how = "detected and caught" if r.success else "detected, not caught"
            parts.append(f"slip at {r.onset_s:.2f} s, {how} (response {r.response_ms:.0f} ms)")
    return "; ".join(parts + ([fell] if fell else []))
