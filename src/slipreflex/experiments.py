"""The paper's experiments on the simulated rig: protocol, trial grid, parallel runs.

One *trial* (SPEC 4): build the rig for a bottle with the trial's seed, grasp
to 0.8 N and settle, record ``rest_s`` of the bottle at rest, then apply the
perturbation (the sudden 10 g drop, or the 500 ml pour at 1 L/min) while the
method's reflex runs in closed loop, and record every stream until
``after_s`` after the perturbation has ended. The recording is analysed with
:func:`slipreflex.analysis.analyse_trial` into one row per slip event.

Seeds come from one master seed through :class:`numpy.random.SeedSequence`
spawning: ``SeedSequence(master).spawn(len(EXPERIMENTS))[e].spawn(len(BOTTLES))[b]
.spawn(k + 1)[k]`` for trial ``k`` (keys by the canonical position of the
experiment and bottle, so a trial's seed does not depend on which subset is
run). All four methods of a trial index share the seed: they face the same
bottle texture, sensor noise and flow-sensor unit (a paired comparison). The
calibration recordings of the threshold rule have their own branch of the
master seed.

The comparison methods' thresholds come from one rule
(:func:`slipreflex.baselines.rest_threshold`): a calibration recording of the
rig at rest, for every built-in bottle, pooled; one threshold per method for
every bottle and trial.

Examples
--------
>>> cfg = ReproduceConfig(trials=2, bottles=("TX",), methods=("dath",), experiments=("drop",))
>>> len(cfg.cells())
2
>>> trial_seed(cfg.seed, "drop", "TX", 0) == trial_seed(cfg.seed, "drop", "TX", 0)
True
"""

from __future__ import annotations

import dataclasses
import math
import os
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from . import methods
from .analysis.paper import BOTTLE_ORDER
from .analysis.paper import EXPERIMENTS as PAPER_EXPERIMENTS
from .analysis.trial import RESULT_COLUMNS, TrialRow
from .baselines.calibration import REST_K
from .baselines.swt import SWT_WINDOW
from .errors import ParameterError
from .validation import choices, integer, positive, set_field

__all__ = [
    "METHODS", "EXPERIMENTS", "BOTTLE_NAMES", "DEFAULT_SEED", "ReproduceConfig", "Cell",
    "trial_seed", "calibration_seed", "closing_speed", "calibrate", "make_reflex", "run_trial",
    "ReproduceResult", "run_reproduce", "write_outputs", "method_context",
    "RESULTS_CSV_COLUMNS", "LANDING_S",
]

#: The paper's methods, in the one method order of :mod:`slipreflex.methods` (run by default;
#: any registered method may be chosen).
METHODS: tuple[str, ...] = methods.names(paper=True)
#: Experiments: sudden load and gradual load (the paper's, from :mod:`slipreflex.analysis.paper`).
EXPERIMENTS: tuple[str, ...] = PAPER_EXPERIMENTS
#: The paper's bottles (keys of ``slipreflex.sim.BOTTLES``), in the canonical order used for seeds.
BOTTLE_NAMES: tuple[str, ...] = BOTTLE_ORDER
#: The master seed of the default reproduction (the paper's publication date).
DEFAULT_SEED: int = 20191215
#: Columns of results.csv: the fields of :class:`slipreflex.analysis.TrialRow`.
RESULTS_CSV_COLUMNS: tuple[str, ...] = RESULT_COLUMNS


@dataclass(frozen=True)
class ReproduceConfig:
    """Everything that defines a reproduction run (every count and parameter overridable).

    Parameters
    ----------
    trials : int
        Trials per bottle, experiment and method (paper: 10).
    bottles, methods, experiments : tuple of str
        Subsets of :data:`BOTTLE_NAMES`, :data:`METHODS`, :data:`EXPERIMENTS`.
    seed : int
        Master seed.
    drop_mass_kg, drop_height_m : float or None
        The sudden load (None: the simulator's ``PAPER_DROP``, 10 g from 2 cm).
    pour_rate_l_min, pour_volume_ml : float or None
        The gradual load (None: ``PAPER_POUR``, 500 ml at 1 L/min).
    rest_s : float
        Recorded rest before the perturbation (s); its first 200 ms set the
        onset threshold.
    after_s : float
        Recording after the drop / after the pour ends (s).
    calibration_s : float
        Length of each at-rest calibration recording of the threshold rule (s).
    rest_k : float
        Standard deviations of the at-rest statistic in the NMSD / SWT-SD
        thresholds (the rule's k, default ``REST_K`` = 5); for sensitivity
        studies, the same for every bottle.
    swt_persist : int
        SWT-SD persistence after the crossing (samples, default ``SWT_WINDOW``,
        8 samples = 21 ms at 380 Hz).

    Examples
    --------
    >>> ReproduceConfig().trials, ReproduceConfig().methods
    (10, ('dath', 'fixed', 'nmsd', 'swt'))
    >>> ReproduceConfig(bottles=("XX",))
    Traceback (most recent call last):
    ...
    slipreflex.errors.ParameterError: bottles: unknown 'XX' (known: TR, DK, TX)
    """

    trials: int = 10
    bottles: tuple[str, ...] = BOTTLE_NAMES
    methods: tuple[str, ...] = METHODS
    experiments: tuple[str, ...] = EXPERIMENTS
    seed: int = DEFAULT_SEED
    drop_mass_kg: float | None = None
    drop_height_m: float | None = None
    pour_rate_l_min: float | None = None
    pour_volume_ml: float | None = None
    rest_s: float = 0.5
    after_s: float = 2.0
    calibration_s: float = 2.0
    rest_k: float = REST_K
    swt_persist: int = SWT_WINDOW

    def __post_init__(self) -> None:
        set_field(self, "trials", integer("trials", self.trials, lo=1))
        set_field(self, "seed", integer("seed", self.seed, lo=0))
        for name, known in (("bottles", BOTTLE_NAMES), ("experiments", EXPERIMENTS)):
            set_field(self, name, choices(name, getattr(self, name), known))
        set_field(self, "methods", choices("methods", self.methods, methods.names(), any_case=True))
        for name in ("rest_s", "after_s", "calibration_s", "rest_k"):
            set_field(self, name, positive(name, getattr(self, name)))
        set_field(self, "swt_persist", integer("swt_persist", self.swt_persist, lo=0))
        if self.rest_s < 0.25:
            raise ParameterError(f"rest_s must be >= 0.25 s (200 ms of rest set the onset threshold), "
                                 f"got {self.rest_s!r}")
        self.drop  # validates the drop and pour through the simulator's own classes
        self.pour

    @property
    def drop(self):
        """The sudden load as a :class:`slipreflex.sim.Drop`.

        Examples
        --------
        >>> ReproduceConfig(drop_mass_kg=0.02).drop.mass_kg
        0.02
        """
        from .sim import PAPER_DROP

        return dataclasses.replace(
            PAPER_DROP,
            mass_kg=PAPER_DROP.mass_kg if self.drop_mass_kg is None else self.drop_mass_kg,
            height_m=PAPER_DROP.height_m if self.drop_height_m is None else self.drop_height_m)

    @property
    def pour(self):
        """The gradual load as a :class:`slipreflex.sim.Pour`.

        Examples
        --------
        >>> round(ReproduceConfig(pour_volume_ml=100).pour.duration_s, 1)
        6.0
        """
        from .sim import PAPER_POUR

        return dataclasses.replace(
            PAPER_POUR,
            rate_l_min=PAPER_POUR.rate_l_min if self.pour_rate_l_min is None else self.pour_rate_l_min,
            volume_ml=PAPER_POUR.volume_ml if self.pour_volume_ml is None else self.pour_volume_ml)

    def duration(self, experiment: str) -> float:
        """Closed-loop recording length (s) of one trial of ``experiment``.

        Examples
        --------
        >>> ReproduceConfig().duration("drop")
        2.5
        """
        load = 0.0 if experiment == "drop" else self.pour.duration_s
        return self.rest_s + load + self.after_s

    def cells(self) -> list["Cell"]:
        """Every trial to run, longest first (pours before drops) for load balance.

        Examples
        --------
        >>> [c.experiment for c in ReproduceConfig(trials=1, bottles=("TR",), methods=("dath",)).cells()]
        ['pour', 'drop']
        """
        out = []
        for e in sorted(self.experiments, key=lambda x: x != "pour"):
            for b in self.bottles:
                for k in range(self.trials):
                    seed = trial_seed(self.seed, e, b, k)
                    for m in self.methods:
                        out.append(Cell(e, b, m, k, seed))
        return out


@dataclass(frozen=True)
class Cell:
    """One trial of the grid.

    Examples
    --------
    >>> Cell("drop", "TR", "dath", 0, 123).key
    ('drop', 'TR', 'dath', 0)
    """

    experiment: str
    bottle: str
    method: str
    trial: int
    seed: int

    @property
    def key(self) -> tuple[str, str, str, int]:
        """(experiment, bottle, method, trial).

        Examples
        --------
        >>> Cell("pour", "DK", "nmsd", 3, 1).key[2]
        'nmsd'
        """
        return (self.experiment, self.bottle, self.method, self.trial)


def trial_seed(master: int, experiment: str, bottle: str, trial: int) -> int:
    """The rig seed of one trial, spawned from the master seed (shared by all methods).

    ``SeedSequence(master).spawn(2)[e].spawn(3)[b].spawn(trial + 1)[trial]``,
    with ``e`` and ``b`` the canonical positions of the experiment and bottle;
    returned as a 63-bit integer (what results.csv records).

    Examples
    --------
    >>> trial_seed(1, "drop", "TR", 0) != trial_seed(1, "drop", "TR", 1)
    True
    >>> trial_seed(1, "pour", "TX", 2) == trial_seed(1, "pour", "TX", 2)
    True
    """
    e = EXPERIMENTS.index(experiment)
    b = BOTTLE_NAMES.index(bottle)
    ss = np.random.SeedSequence(master).spawn(len(EXPERIMENTS))[e].spawn(len(BOTTLE_NAMES))[b]
    child = ss.spawn(trial + 1)[trial]
    return int(child.generate_state(2, dtype=np.uint64)[0] >> np.uint64(1))


def calibration_seed(master: int, bottle: str) -> int:
    """Seed of the at-rest calibration recording of ``bottle`` (its own branch of the master).

    Examples
    --------
    >>> calibration_seed(1, "TR") != trial_seed(1, "drop", "TR", 0)
    True
    """
    ss = np.random.SeedSequence(master).spawn(len(EXPERIMENTS) + 1)[len(EXPERIMENTS)]
    child = ss.spawn(len(BOTTLE_NAMES))[BOTTLE_NAMES.index(bottle)]
    return int(child.generate_state(2, dtype=np.uint64)[0] >> np.uint64(1))


def closing_speed() -> float:
    """The simulated hand's closing speed (units/s): ``slipreflex.sim.HandParams().speed_units_s``.

    Examples
    --------
    >>> closing_speed() > 0
    True
    """
    return methods.MethodContext().closing_speed()


def calibrate(config: ReproduceConfig) -> dict[str, float]:
    """Thresholds of the calibrated methods by the one rule (k sd of the statistic at rest).

    For every built-in bottle (always all three, whatever ``config.bottles``
    says), grasp with the bottle's calibration seed and record the index
    tactile array at rest for ``calibration_s`` at the rate of every method
    with a rest statistic (:func:`slipreflex.methods.calibrated`, in the
    method order: NMSD's 260 Hz, then SWT-SD's 380 Hz); pool the recordings of
    each method and apply :func:`slipreflex.baselines.rest_threshold`'s rule.

    Returns
    -------
    dict
        Threshold by method name, e.g. ``{"nmsd": N/s, "swt": N}``.

    Examples
    --------
    >>> th = calibrate(ReproduceConfig(calibration_s=0.5))
    >>> sorted(th), th["nmsd"] > 0 and th["swt"] > 0
    (['nmsd', 'swt'], True)
    """
    from .baselines import rest_statistic
    from .sim import Rig, simulate_open_loop

    specs = [methods.get(m) for m in methods.calibrated()]
    stats: dict[str, list[np.ndarray]] = {s.name: [] for s in specs}
    for b in BOTTLE_NAMES:
        rig = Rig(b, seed=calibration_seed(config.seed, b))
        rig.grasp()
        for spec in specs:
            tr = simulate_open_loop(rig, config.calibration_s, tactile_fs=spec.fs)
            stats[spec.name].append(rest_statistic(tr.tactile, spec.rest_statistic, spec.fs))
    out = {}
    for method, parts in stats.items():
        sd = float(np.std(np.concatenate(parts)))
        if not sd > 0:
            raise ParameterError(f"calibration: the simulated tactile array has no noise at rest; "
                                 f"cannot derive a {method} threshold")
        out[method] = float(config.rest_k) * sd
    return out


def method_context(config: ReproduceConfig, thresholds: dict[str, float]) -> methods.MethodContext:
    """What every method of a run is built with: thresholds, the simulated hand's speed, options.

    Examples
    --------
    >>> method_context(ReproduceConfig(swt_persist=4), {}).options["swt_persist"]
    4
    """
    return methods.MethodContext(thresholds=dict(thresholds), speed=closing_speed(),
                                 options={"swt_persist": config.swt_persist})


def make_reflex(method: str, *, p0: float, thresholds: dict[str, float], swt_persist: int | None = None):
    """The reflex of ``method``, starting from finger position ``p0`` (via :func:`slipreflex.methods.make`).

    Examples
    --------
    >>> make_reflex("dath", p0=200.0, thresholds={}).name
    'dath'
    >>> make_reflex("swt", p0=200.0, thresholds={"swt": 0.02}).fs
    380.0
    """
    ctx = methods.MethodContext(thresholds=dict(thresholds), speed=closing_speed(),
                                options={"swt_persist": swt_persist})
    return methods.make(method, p0=p0, context=ctx)


def _plot_data(cell: Cell, spec: methods.MethodSpec, tr, reflex, rows, t_pert: float):
    """The streams of one trial for :func:`slipreflex.analysis.figures.plot_trial`."""
    from .analysis.figures import TrialPlot
    from .analysis.onset import OnsetParams, accel_envelope

    axis = rows[0].axis
    env = accel_envelope(tr.t, tr.accel[:, axis], OnsetParams())
    sensor_t, x = (tr.t, tr.volts) if spec.input_kind == "slip" else (tr.tactile_t, tr.tactile)
    det = spec.detections(reflex, x) if spec.detections is not None else None
    pour = cell.experiment == "pour"
    xlim = None if pour else (t_pert - 0.3, min(tr.t_end, t_pert + 1.5))
    axes = "xyz"
    return TrialPlot(
        title=f"{cell.experiment} {cell.bottle} {cell.method} (trial {cell.trial}, seed {cell.seed})",
        accel_t=tr.t, accel=tr.accel[:, axis], accel_label=f"accelerometer ({axes[axis]} axis)",
        envelope=env, threshold=float("nan"), sensor_t=None if det is None else sensor_t,
        sensor=None if det is None else det.sensor,
        sensor_label="" if det is None else det.sensor_label,
        event_t=None if det is None else sensor_t[det.events],
        event_label="" if det is None else det.event_label, cmd_t=tr.cmd_t, cmd_v=tr.cmd_value,
        load_t=tr.t if pour else None, load=tr.water_ml if pour else None,
        onsets=[r.onset_s for r in rows], responses=[r.onset_s + r.response_ms / 1e3 for r in rows],
        lasts=[r.last_change_s for r in rows], true_onsets=[r.true_onset_s for r in rows],
        xlim=xlim)


def run_trial(cell: Cell, config: ReproduceConfig, thresholds: dict[str, float], *,
              keep_plot: bool = False, spec: methods.MethodSpec | None = None):
    """Run and analyse one trial: grasp, rest, perturb, closed loop, metrics.

    ``spec`` is the method's specification (default: the registry's entry for
    ``cell.method``; a worker process gets it passed, so a method registered
    only in the parent process runs too).

    Returns
    -------
    (list of TrialRow, TrialPlot or None)
        The trial's rows (one per slip event) and, if asked, its plot data.

    Examples
    --------
    >>> cfg = ReproduceConfig(trials=1)
    >>> cell = Cell("drop", "TX", "dath", 0, trial_seed(cfg.seed, "drop", "TX", 0))
    >>> rows, _ = run_trial(cell, cfg, {})
    >>> rows[0].n_events, rows[0].success
    (1, True)
    """
    from .analysis.trial import TrialStreams, analyse_trial
    from .hardware import SLIP_FINGER
    from .sim import Rig, run_closed_loop

    rig = Rig(cell.bottle, seed=cell.seed)
    grasp = rig.grasp()
    p0 = float(round(grasp.positions[SLIP_FINGER]))
    spec = spec or methods.get(cell.method)
    reflex = spec.build(p0, dataclasses.replace(method_context(config, thresholds), method=spec.name))
    t_pert = rig.t + config.rest_s
    load = config.drop if cell.experiment == "drop" else config.pour
    rig.perturb(load, at=t_pert)
    tr = run_closed_loop(rig, reflex, config.duration(cell.experiment))
    load_s = 0.0 if cell.experiment == "drop" else config.pour.duration_s
    fall = float("nan") if tr.fall_time is None else float(tr.fall_time)
    pour = cell.experiment == "pour"
    # a pour induces slip once the water has landed; the jet's landing knock is not a slip
    start = t_pert + (_jet_fall_s(config.pour) + LANDING_S if pour else 0.0)
    streams = TrialStreams(
        experiment=cell.experiment, method=cell.method, bottle=cell.bottle, seed=cell.seed,
        trial=cell.trial, accel_t=tr.t, accel=tr.accel, cmd_t=tr.cmd_t, cmd_v=tr.cmd_value,
        base_command=p0, induction=(start, t_pert + load_s + config.after_s), t_end=tr.t_end,
        fell_out_time=fall, true_onsets=[e.onset for e in tr.slip_events], method_fs=float(reflex.fs),
        ramp=spec.ramp,
        load_t=tr.t if pour else None, load=tr.water_ml if pour else None,
        threshold=thresholds.get(cell.method, float(getattr(getattr(reflex, "params", None),
                                                             "threshold", float("nan")))))
    truth = {round(e.onset, 9): e for e in tr.slip_events}
    rows = []
    for r in analyse_trial(streams):
        ev = truth.get(round(r.true_onset_s, 9)) if not math.isnan(r.true_onset_s) else None
        # the simulator's slip episode: how long it slid (NaN while open / fallen) and how far
        rows.append(dataclasses.replace(
            r, grasp_position=p0, grasp_force_n=float(grasp.force_n), perturbation_s=t_pert,
            true_slip_ms=float("nan") if ev is None or ev.end is None else 1e3 * (ev.end - ev.onset),
            true_slip_mm=float("nan") if ev is None else 1e3 * ev.distance))
    plot = _plot_data(cell, spec, tr, reflex, rows, t_pert) if keep_plot else None
    return rows, plot


#: After the poured water lands, its knock (~30 ms in the simulator) is over by this time (s).
LANDING_S: float = 0.1


def _jet_fall_s(pour) -> float:
    """Fall time (s) of the poured water from the spout to the bottle."""
    from . import hardware as hw

    return math.sqrt(2.0 * pour.fall_height_m / hw.GRAVITY)


def _run_cell(cell: Cell, config: ReproduceConfig, thresholds: dict[str, float], keep_plot: bool,
              spec: methods.MethodSpec):
    return cell, run_trial(cell, config, thresholds, keep_plot=keep_plot, spec=spec)


@dataclass
class ReproduceResult:
    """Everything a reproduction produced.

    Attributes
    ----------
    config : ReproduceConfig
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

    Examples
    --------
    >>> ReproduceResult(ReproduceConfig(), [], [], {}, {}, 0.0, 1).rows
    []
    """

    config: ReproduceConfig
    rows: list[TrialRow]
    summary: list[dict[str, Any]]
    thresholds: dict[str, float]
    plots: dict[tuple, Any]
    wall_s: float
    jobs: int
    calibration_wall_s: float = 0.0


def _order(row: TrialRow) -> tuple:
    return (EXPERIMENTS.index(row.experiment), BOTTLE_NAMES.index(row.bottle),
            methods.names().index(row.method), row.trial, row.event)


def run_reproduce(config: ReproduceConfig | None = None, *, jobs: int | None = None,
                  progress: bool = True, plots: bool = True,
                  on_done: Callable[[Cell], None] | None = None) -> ReproduceResult:
    """Run the whole grid of trials in parallel and summarize it.

    Parameters
    ----------
    config : ReproduceConfig, optional
        The run (default: the paper's 10 x 3 x 2 x 4 grid).
    jobs : int, optional
        Worker processes (default: the machine's cores); 1 runs in this process.
    progress : bool
        Show a tqdm progress bar on stderr.
    plots : bool
        Keep the example trials' plot data (one per bottle and experiment).
    on_done : callable, optional
        Called with each finished cell.

    Returns
    -------
    ReproduceResult

    Examples
    --------
    >>> cfg = ReproduceConfig(trials=1, bottles=("TR",), methods=("fixed", "dath"),
    ...                       experiments=("drop",))
    >>> res = run_reproduce(cfg, jobs=1, progress=False, plots=False)
    >>> [(r.method, r.n_events) for r in res.rows]
    [('dath', 1), ('fixed', 1)]
    """
    from tqdm import tqdm

    from .analysis.report import summarize

    config = config or ReproduceConfig()
    jobs = int(jobs or os.cpu_count() or 1)
    if jobs < 1:
        raise ParameterError(f"jobs must be >= 1, got {jobs}")
    t0 = time.perf_counter()
    thresholds = calibrate(config) if set(config.methods) & set(methods.calibrated()) else {}
    specs = {m: methods.get(m) for m in config.methods}
    t_cal = time.perf_counter() - t0
    cells = config.cells()
    plot_method = methods.DATH if methods.DATH in config.methods else config.methods[0]
    want = {c.key for c in cells if plots and c.trial == 0 and c.method == plot_method}
    done: dict[tuple, tuple] = {}
    bar = tqdm(total=len(cells), file=sys.stderr, disable=not progress, desc="trials", unit="trial",
               dynamic_ncols=True)
    try:
        if jobs == 1:
            for c in cells:
                _, res = _run_cell(c, config, thresholds, c.key in want, specs[c.method])
                done[c.key] = res
                bar.update()
                if on_done:
                    on_done(c)
        else:
            with ProcessPoolExecutor(max_workers=jobs) as ex:
                futs = [ex.submit(_run_cell, c, config, thresholds, c.key in want, specs[c.method])
                        for c in cells]
                for f in as_completed(futs):
                    c, res = f.result()
                    done[c.key] = res
                    bar.update()
                    if on_done:
                        on_done(c)
    finally:
        bar.close()
    rows = sorted((r for c in cells for r in done[c.key][0]), key=_order)
    plot_data = {c.key: done[c.key][1] for c in cells if done[c.key][1] is not None}
    return ReproduceResult(config, rows, summarize(rows), thresholds, plot_data,
                           time.perf_counter() - t0, jobs, calibration_wall_s=t_cal)


def write_outputs(result: ReproduceResult, out_dir: str | Path, *, command: str | None = None,
                  discussion: Sequence[str] | None = None) -> dict[str, Path]:
    """Write results.csv, summary.csv, the figures and report.md into ``out_dir``.

    The report's prose (setup, captions, discussion) comes from
    :mod:`slipreflex.analysis.report`.

    Returns
    -------
    dict
        Paths by name ("results", "summary", "report", and one per figure).

    Examples
    --------
    >>> import tempfile
    >>> cfg = ReproduceConfig(trials=1, bottles=("TX",), methods=("dath",), experiments=("drop",))
    >>> res = run_reproduce(cfg, jobs=1, progress=False)
    >>> paths = write_outputs(res, tempfile.mkdtemp())
    >>> sorted(p for p in paths if not p.endswith(".png"))
    ['report', 'results', 'summary']
    """
    from .analysis import report as R

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"results": R.write_csv(out / "results.csv", result.rows, RESULTS_CSV_COLUMNS),
             "summary": R.write_csv(out / "summary.csv", result.summary, R.SUMMARY_COLUMNS)}
    figs = _write_figures(result, out, paths)
    md = R.report_markdown(summary=result.summary, rows=result.rows, figures=figs,
                           setup=R.setup_lines(result, command),
                           discussion=list(discussion) if discussion is not None else R.discussion_text(result))
    paths["report"] = out / "report.md"
    paths["report"].write_text(md)
    return paths


def _write_figures(result: ReproduceResult, out: Path, paths: dict[str, Path]) -> list[tuple[str, str]]:
    """Draw the example trials, bar charts and success chart; (caption, relative path) of each."""
    from .analysis import figures as F
    from .analysis import report as R

    figs: list[tuple[str, str]] = []
    fig_dir = out / "figures"
    for key in sorted(result.plots, key=lambda k: (EXPERIMENTS.index(k[0]), BOTTLE_NAMES.index(k[1]))):
        e, b, m, _ = key
        name = f"trial_{e}_{b}_{m}.png"
        paths[name] = F.plot_trial(result.plots[key], fig_dir / name)
        figs.append((R.trial_caption(e, b, m), f"figures/{name}"))
        ons = [x for x in result.plots[key].onsets if x == x]
        if e == "pour" and ons:
            zname = f"trial_{e}_{b}_{m}_zoom.png"
            zoom = dataclasses.replace(result.plots[key], xlim=(ons[0] - 0.3, ons[0] + 1.0),
                                       title=result.plots[key].title + ", around the first slip")
            paths[zname] = F.plot_trial(zoom, fig_dir / zname)
            figs.append((R.zoom_caption(b, m), f"figures/{zname}"))
    for e in result.config.experiments:
        for metric in ("response", "total"):
            name = f"bars_{e}_{metric}.png"
            paths[name] = F.bar_chart(result.summary, e, metric, fig_dir / name)
            figs.append((R.bars_caption(e, metric), f"figures/{name}"))
    paths["success.png"] = F.success_chart(result.summary, fig_dir / "success.png")
    figs.append((R.SUCCESS_CAPTION, "figures/success.png"))
    return figs
