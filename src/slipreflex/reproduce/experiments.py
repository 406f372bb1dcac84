"""The paper's experiments on the simulated rig: protocol, trial grid, parallel runs.

One *trial* (docs/method.md section 4): build the rig for a bottle with the trial's seed, grasp
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
(:func:`slipreflex.methods.baselines.rest_threshold`): a calibration recording of the
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
import functools
import itertools
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import methods
from ..analysis.metrics import grip_without_slip
from ..analysis.onset import OnsetParams
from ..analysis.outputs import ReproduceResult, trial_plot, write_outputs
from ..analysis.paper import BOTTLE_ORDER, bottle_key
from ..analysis.paper import EXPERIMENTS as PAPER_EXPERIMENTS
from ..analysis.trial import RESULT_COLUMNS, TrialStreams, analyse_trial
from ..core import experiment_specs
from ..core.errors import ParameterError
from ..core.hardware import CONTACT_FORCE_N, SLIP_FINGER
from ..core.validation import choices, flag, integer, set_field, within
from ..files.interrupts import Interrupted
from ..files.progress import Progress
from ..methods.baselines.calibration import REST_K
from ..methods.baselines.swt import SWT_PERSIST
from .grasping import check_run_grasp
from .grid import Cell, grid_result, run_cells
from .paper_experiments import LANDING_S
from .thresholds import calibrate, calibration_seed
from .warmup import STARTUP_S, TRIAL_SIM_SPEED, estimate_wall_s, warm_kernels  # noqa: F401  (public here too)

__all__ = [
    "METHODS", "EXPERIMENTS", "BOTTLE_NAMES", "DEFAULT_SEED", "ReproduceConfig", "Cell",
    "trial_seed", "calibration_seed", "estimate_wall_s", "TRIAL_SIM_SPEED", "grasp_seeds", "closing_speed", "calibrate",
    "run_trial",
    "ReproduceResult", "run_reproduce", "write_outputs", "method_context",
    "RESULTS_CSV_COLUMNS", "LANDING_S",
]

#: The paper's methods, in the one method order of :mod:`slipreflex.methods` (run by default;
#: any registered method may be chosen).
METHODS: tuple[str, ...] = methods.names(paper=True)
#: The experiments run by default: the paper's sudden and gradual load (any registered
#: experiment, :mod:`slipreflex.core.experiment_specs`, may be chosen).
EXPERIMENTS: tuple[str, ...] = PAPER_EXPERIMENTS
#: The paper's bottles (keys of ``slipreflex.sim.BOTTLES``), in the canonical order used for seeds.
BOTTLE_NAMES: tuple[str, ...] = BOTTLE_ORDER
#: The master seed of the default reproduction (the paper's publication date).
DEFAULT_SEED: int = 20191215
#: Columns of results.csv: the fields of :class:`slipreflex.analysis.TrialRow`.
RESULTS_CSV_COLUMNS: tuple[str, ...] = RESULT_COLUMNS


def _override(base: Any, **values: Any) -> Any:
    """``base`` with the fields given a value (not None) replaced."""
    return dataclasses.replace(base, **{k: v for k, v in values.items() if v is not None})


@dataclass(frozen=True)
class ReproduceConfig:
    """Everything that defines a reproduction run (every count and parameter overridable).

    Parameters
    ----------
    trials : int
        Trials per bottle, experiment and method (paper: 10; default 20, so that the claims'
        verdict classes do not hang on one master seed's draws: docs/reproduce.md).
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
        SWT-SD persistence after the crossing (samples, default ``SWT_PERSIST``,
        0: the "within-window" reading; 8 samples = 21 ms at 380 Hz is the
        "after-crossing" one, ``slipreflex.methods.baselines.swt.SWT_PERSISTENCE``).
    variations : bool
        Each trial's plant varies from its seed as real repeats do
        (:mod:`slipreflex.sim.variations`); False: every repeat is the nominal plant.
    independent_seeds : bool
        Give each method its own trial seeds (default False: the paired design,
        every method faces the same trials).
    grasp_force_n : float
        Force (N) at which the grasp routine stops closing (paper: 0.8 N). A
        force that cannot hold a bottle is an error before the first trial.
    plant : slipreflex.sim.uncertain.Plant, optional
        The simulated plant (parameter objects and bottles); None: the
        default plant. ``slipreflex study`` runs the grid on many plants, and
        ``--objects FILE.toml`` adds a file's bottles to the plant's.
    drop_object, pour_object : slipreflex.sim.Drop, slipreflex.sim.Pour, optional
        The sudden and gradual loads (None: the paper's, ``PAPER_DROP`` and
        ``PAPER_POUR``); ``drop_mass_kg`` and the others override their fields.

    Examples
    --------
    >>> ReproduceConfig().trials, ReproduceConfig().methods
    (20, ('dath', 'fixed', 'nmsd', 'swt'))
    >>> ReproduceConfig(bottles=("XX",))
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: bottles: unknown 'XX' (known: TR, DK, TX)
    """

    trials: int = 20
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
    swt_persist: int = SWT_PERSIST
    variations: bool = True
    independent_seeds: bool = False
    grasp_force_n: float = CONTACT_FORCE_N
    plant: Any = None
    drop_object: Any = None
    pour_object: Any = None

    def __post_init__(self) -> None:
        for name in ("variations", "independent_seeds"):
            set_field(self, name, flag(name, getattr(self, name)))
        set_field(self, "trials", within("trials", self.trials))
        set_field(self, "seed", integer("seed", self.seed, lo=0))
        known_bottles = tuple(self.plant.bottles) if self.plant is not None else BOTTLE_NAMES
        for name, known in (("bottles", known_bottles), ("experiments", experiment_specs.names())):
            set_field(self, name, choices(name, getattr(self, name), known))
        set_field(self, "methods", choices("methods", self.methods, methods.names(), any_case=True))
        for name in ("rest_s", "after_s", "calibration_s", "rest_k", "grasp_force_n", "swt_persist"):
            set_field(self, name, within(name, getattr(self, name)))

        need = OnsetParams().baseline_s + 0.05
        if self.rest_s < need:
            raise ParameterError(f"rest_s must be >= {need:g} s (the first {OnsetParams().baseline_s * 1e3:g} "
                                 f"ms of rest set the onset threshold), got {self.rest_s!r}")
        _ = self.drop, self.pour  # validates the drop and pour through the simulator's own classes

    @property
    def drop(self):
        """The sudden load as a :class:`slipreflex.sim.Drop`.

        Examples
        --------
        >>> ReproduceConfig(drop_mass_kg=0.02).drop.mass_kg
        0.02
        """
        from ..sim import PAPER_DROP  # deferred: heavy (numba kernels)

        return _override(self.drop_object or PAPER_DROP, mass_kg=self.drop_mass_kg, height_m=self.drop_height_m)

    @property
    def pour(self):
        """The gradual load as a :class:`slipreflex.sim.Pour`.

        Examples
        --------
        >>> round(ReproduceConfig(pour_volume_ml=100).pour.duration_s, 1)
        6.0
        """
        from ..sim import PAPER_POUR  # deferred: heavy (numba kernels)

        return _override(self.pour_object or PAPER_POUR, rate_l_min=self.pour_rate_l_min, volume_ml=self.pour_volume_ml)

    def bottle(self, name: str):
        """The :class:`slipreflex.sim.Bottle` called ``name`` in this run's plant.

        Examples
        --------
        >>> ReproduceConfig().bottle("TX").name
        'TX'
        """
        from ..sim import BOTTLES  # deferred: heavy (numba kernels)

        return (self.plant.bottles if self.plant is not None else BOTTLES)[name]

    def duration(self, experiment: str) -> float:
        """Closed-loop recording length (s) of one trial of ``experiment``.

        Examples
        --------
        >>> ReproduceConfig().duration("drop")
        2.5
        """
        exp = experiment_specs.get(experiment)
        return self.rest_s + exp.load_s(exp.perturbation(self)) + self.after_s

    def cells(self) -> list[Cell]:
        """Every trial to run, the longest experiments first (pours before drops) for load balance.

        Examples
        --------
        >>> [c.experiment for c in ReproduceConfig(trials=1, bottles=("TR",), methods=("dath",)).cells()]
        ['pour', 'drop']
        """
        out = []
        for e in sorted(self.experiments, key=lambda x: -self.duration(x)):
            for b in self.bottles:
                for k in range(self.trials):
                    seed = trial_seed(self.seed, e, b, k)
                    for m in self.methods:
                        own = trial_seed(self.seed, e, b, k, method=m) if self.independent_seeds else seed
                        out.append(Cell(e, b, m, k, own))
        return out


def trial_seed(master: int, experiment: str, bottle: str, trial: int, method: str | None = None) -> int:
    """The rig seed of one trial, spawned from the master seed (shared by all methods).

    ``SeedSequence(master).spawn(2)[e].spawn(3)[b].spawn(trial + 1)[trial]``,
    with ``e`` and ``b`` the canonical positions of the experiment and bottle;
    returned as a 63-bit integer (what results.csv records). With ``method``
    (the independent-seeds option) the trial's sequence is keyed further by
    the method's name, so each method gets its own trials.

    Examples
    --------
    >>> trial_seed(1, "drop", "TR", 0) != trial_seed(1, "drop", "TR", 1)
    True
    >>> trial_seed(1, "pour", "TX", 2) == trial_seed(1, "pour", "TX", 2)
    True
    """
    entropy, spawn_key, pool_size = _cell_sequence(master, experiment_specs.seed_branch(experiment),
                                                   bottle_key(bottle))
    # The child spawn(trial + 1)[trial] would make, built directly: the same bits in O(1),
    # so a grid's seeds take time linear in its trials (spawning them was quadratic).
    child = np.random.SeedSequence(entropy, spawn_key=(*spawn_key, trial), pool_size=pool_size)
    if method is not None:
        key = [int(c) for c in method.lower().encode()]
        child = np.random.SeedSequence([*child.generate_state(2), *key])
    return _seed63(child)


def grasp_seeds(config: ReproduceConfig, bottle: str) -> list[int]:
    """The trial seeds of ``bottle`` in a run, trial by trial (what its grasp check simulates).

    Examples
    --------
    >>> len(grasp_seeds(ReproduceConfig(trials=3), "TR"))
    6
    """
    return list(dict.fromkeys(trial_seed(config.seed, e, bottle, k) for k in range(config.trials)
                              for e in config.experiments))


@functools.lru_cache(maxsize=64)
def _cell_sequence(master: int, e: int, b: int) -> tuple[Any, tuple[int, ...], int]:
    """(entropy, spawn_key, pool_size) of ``SeedSequence(master).spawn(2)[e].spawn(3)[b]``.

    A bottle that is not the paper's (``b`` >= 3) gets the child with spawn key ``b``,
    built directly, so its seeds do not depend on which other bottles run.
    """
    root = np.random.SeedSequence(master)   # a registered experiment's branch, built directly
    parent = root.spawn(len(EXPERIMENTS))[e] if e < len(EXPERIMENTS) else np.random.SeedSequence(
        root.entropy, spawn_key=(e,), pool_size=root.pool_size)
    if b >= len(BOTTLE_NAMES):
        return parent.entropy, (*parent.spawn_key, b), parent.pool_size
    ss = parent.spawn(len(BOTTLE_NAMES))[b]
    return ss.entropy, tuple(ss.spawn_key), ss.pool_size


def _seed63(ss: np.random.SeedSequence) -> int:
    """A seed sequence as the 63-bit integer results.csv records."""
    return int(ss.generate_state(2, dtype=np.uint64)[0] >> np.uint64(1))


def closing_speed() -> float:
    """The simulated hand's closing speed (units/s): ``slipreflex.sim.HandParams().speed_units_s``.

    Examples
    --------
    >>> closing_speed() > 0
    True
    """
    return methods.MethodContext().closing_speed()


def method_context(config: ReproduceConfig, thresholds: dict[str, float]) -> methods.MethodContext:
    """What every method of a run is built with: thresholds, the simulated hand's speed, options.

    Examples
    --------
    >>> method_context(ReproduceConfig(swt_persist=4), {}).options["swt_persist"]
    4
    """
    speed = closing_speed() if config.plant is None else float(config.plant.hand.speed_units_s)
    return methods.MethodContext(thresholds=dict(thresholds), speed=speed,
                                 options={"swt_persist": config.swt_persist})


def _run_paired(cells: tuple[Cell, ...], config: ReproduceConfig, thresholds: dict[str, float],
                keep_plot: frozenset, specs: dict[str, methods.MethodSpec]) -> dict[Cell, tuple]:
    """run_trial for the methods of one trial seed, in one process (so one grasp, copied)."""
    return {c: run_trial(c, config, thresholds, keep_plot=c.key in keep_plot, spec=specs[c.method])
            for c in cells}


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
    from ..sim import run_closed_loop  # deferred: heavy (numba kernels)
    from ..sim.variations import VariationSpread, grasped_rig  # deferred: heavy (numba kernels)

    plant = {} if config.plant is None else {"rig_kwargs": config.plant.rig_kwargs(),
                                             "bottles": dict(config.plant.bottles)}
    rig, grasp = grasped_rig(cell.bottle, cell.seed, config.grasp_force_n,
                             spread=None if config.variations else VariationSpread.none(), **plant)
    p0 = float(round(grasp.positions[SLIP_FINGER]))
    spec = spec or methods.get(cell.method)
    reflex = spec.build(p0, dataclasses.replace(method_context(config, thresholds), method=spec.name))
    threshold = reflex.last_threshold          # the threshold it starts with, for results.csv
    t_pert = rig.t + config.rest_s
    exp = experiment_specs.get(cell.experiment)
    what = exp.perturbation(config)
    rig.perturb(what, at=t_pert)
    tr = run_closed_loop(rig, reflex, config.duration(cell.experiment))
    # slips are looked for from when the load can first cause one (a pour: once the water has landed)
    start = t_pert + exp.settle_s(what)
    end = t_pert + exp.load_s(what) + config.after_s
    streams = TrialStreams(
        experiment=cell.experiment, method=cell.method, bottle=cell.bottle, seed=cell.seed,
        trial=cell.trial, accel_t=tr.t, accel=tr.accel, cmd_t=tr.cmd_t, cmd_v=tr.cmd_value,
        base_command=p0, induction=(start, end), t_end=tr.t_end,
        fell_out_time=float("nan") if tr.fall_time is None else float(tr.fall_time),
        true_onsets=[e.onset for e in tr.slip_events], method_fs=float(reflex.fs), ramp=spec.ramp,
        load_t=tr.t if exp.records_load else None, load=tr.water_ml if exp.records_load else None,
        threshold=float("nan") if threshold is None else float(threshold))
    truth = {round(e.onset, 9): e for e in tr.slip_events}
    before = tr.fall_time is not None and tr.fall_time < t_pert      # fell in the grasp or the rest

    unslipped = grip_without_slip(tr.cmd_t, tr.cmd_value, p0, tr.slip_events)
    rows = [dataclasses.replace(r, grasp_position=p0, grasp_force_n=float(grasp.force_n),
                                perturbation_s=t_pert, fell_before_load=before, grip_without_slip=unslipped,
                                **_true_slip(truth.get(round(r.true_onset_s, 9))))
            for r in analyse_trial(streams)]
    plot = trial_plot(cell, spec, tr, reflex, rows, t_pert) if keep_plot else None
    return rows, plot


def _true_slip(ev: Any) -> dict[str, float]:
    """The simulator's slip episode: how long it slid (NaN while open / fallen) and how far."""
    return {"true_slip_ms": float("nan") if ev is None or ev.end is None else 1e3 * (ev.end - ev.onset),
            "true_slip_mm": float("nan") if ev is None else 1e3 * ev.distance}


def run_reproduce(config: ReproduceConfig | None = None, *, jobs: int | None = None,
                  progress: bool = True, plots: bool = True,
                  on_done: Callable[[Cell], None] | None = None) -> ReproduceResult:
    """Run the whole grid of trials in parallel and summarize it.

    Parameters
    ----------
    config : ReproduceConfig, optional
        The run (default: 20 trials x 3 bottles x 2 experiments x 4 methods; the paper ran 10).
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
    config = config or ReproduceConfig()
    jobs = int(jobs or os.cpu_count() or 1)
    if jobs < 1:
        raise ParameterError(f"jobs must be >= 1, got {jobs}")
    t0 = time.perf_counter()


    for b in config.bottles:                    # a grasp that cannot hold a bottle fails here, at once
        check_run_grasp(config, b, grasp_seeds(config, b))
    thresholds = calibrate(config) if set(config.methods) & set(methods.calibrated()) else {}
    specs = {m: methods.get(m) for m in config.methods}
    if jobs > 1:       # compiled here once: the forked workers inherit it (each compiled its own before)
        warm_kernels(config, method_context(config, thresholds), specs,
                     trial_seed(config.seed, config.experiments[0], config.bottles[0], 0))
    t_cal = time.perf_counter() - t0
    cells = config.cells()
    plot_method = methods.DATH if methods.DATH in config.methods else config.methods[0]
    # every bottle's first trial with DATH (the paper's Figs. 10-12, 15); NMSD's and SWT-SD's on the
    # first bottle, so their detections are seen too
    extra = {methods.NMSD, methods.SWT} & set(config.methods)
    want = {c.key for c in cells if plots and c.trial == 0
            and (c.method == plot_method or (c.method in extra and c.bottle == config.bottles[0]))}
    # the methods of one trial seed (consecutive cells) run in one call and share its grasp
    groups = [tuple(g) for _, g in itertools.groupby(cells, lambda c: (c.experiment, c.bottle, c.trial, c.seed))]
    calls = {g: functools.partial(_run_paired, g, config, thresholds, frozenset(want), specs) for g in groups}
    done: dict[tuple, dict] = {}

    def finished(group: tuple) -> None:
        bar.update(len(group))
        if on_done is not None:
            for c in group:
                on_done(c)

    with Progress(len(cells), desc="trials", unit="trial", enabled=progress) as bar:
        try:
            run_cells(calls, jobs, finished, done)
        except KeyboardInterrupt:
            partial = grid_result(config, cells, _by_cell(done), thresholds, t0, jobs, t_cal)
            raise Interrupted(partial, partial.partial_note) from None
    return grid_result(config, cells, _by_cell(done), thresholds, t0, jobs, t_cal)


def _by_cell(done: dict[tuple, dict]) -> dict[Cell, tuple]:
    return {c: r for results in done.values() for c, r in results.items()}

