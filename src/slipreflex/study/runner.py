"""Run a study: every plant of the design through the reproduce grid, on Dask or in this process.

One *plant* is one draw of the uncertain constants. :func:`run_plant`
builds it (:func:`slipreflex.sim.uncertain.plant_from_values`), calibrates
its pads so the open-loop first pour slip, as the accelerometer recipe observes it, comes at
its drawn volume (the paper's "about 200 ml")
(:func:`slipreflex.sim.calibration.calibrate_bottle`, per bottle), runs the
reproduce grid on it (same master seed for every plant: every plant faces
the same trials, so plants differ by physics only) and the characterization
scans with its slip sensor (its own texture seeds), and judges the paper's
claims (:func:`slipreflex.analysis.claims.judge`). A plant whose calibrated
observed first slip leaves the paper's band is rejected (counted apart, no
trials). It never raises: an error is recorded with the plant.

:func:`run_study` sends the plants to a ``dask.distributed`` cluster (a
``LocalCluster`` of single-threaded worker processes by default, or the
scheduler at ``scheduler``), or runs them here with ``workers=0``. Each
finished plant is written at once, by this process, as one Parquet part
(``parts/plant-NNNNNN.parquet``, written to a temporary name and renamed, so
a part is whole or absent); its metadata holds the study's fingerprint, the
plant's error and its claim verdicts. A run with the same arguments skips
the plants whose parts exist, so a killed study resumes and ends with the
same bits. Workers need no shared file system: results travel back to the
client.

Examples
--------
>>> cfg = StudyConfig(plants=2, trials=1, bottles=("TX",), methods=("dath",), experiments=("drop",),
...                   calibrate=False)
>>> len(cfg.plant_values()), cfg.trials_per_plant
(2, 1)
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import logging
import os
import signal
import sys
import time
import traceback
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from .. import __version__, methods
from ..analysis.claims import CLAIMS, judge
from ..core.errors import ParameterError
from ..core.validation import within
from ..files.interrupts import signals_ignored
from ..files.paths import new_file
from ..files.progress import Progress
from ..reproduce.experiments import BOTTLE_NAMES, DEFAULT_SEED, EXPERIMENTS, ReproduceConfig, run_trial
from ..reproduce.thresholds import calibrate
from .cluster import SCHEDULER_TIMEOUT_S, _client, _main_thread, probe_scheduler
from .design import DESIGNS, draw_design, unit_design, values_at, varying
from .refine import make_plan

__all__ = ["StudyConfig", "PlantOutcome", "run_plant", "run_study", "StudyRun", "PARTS_DIR", "STUDY_SCAN_BASE",
           "scan_seed_base", "read_parts", "part_path", "DEFAULT_PLANTS", "DEFAULT_TRIALS", "probe_scheduler",
           "SCHEDULER_TIMEOUT_S"]

#: Plants of the default study (a power of two keeps the Sobol' design balanced; see docs/study.md).
DEFAULT_PLANTS: int = 64
#: Trials per bottle, experiment and method on each plant of the default study.
DEFAULT_TRIALS: int = 1
#: Sub-directory of ``--out`` holding one Parquet part per finished plant.
PARTS_DIR: str = "parts"
_META_KEY = b"slipreflex.study"
#: Rig seeds of each plant's open-loop calibration (one seed: a third of the cost of the
#: reproduce default's three; the calibration's seed-to-seed spread is a few ml). A plant
#: whose one-seed calibration fails is calibrated again with the default's seeds.
CALIBRATION_SEEDS: tuple[int, ...] = (0,)


def _stepping_default() -> str:
    """This process's stepping (the environment's, or adaptive), checked."""

    from ..sim.rig import default_stepping  # deferred: heavy (numba kernels)

    return default_stepping()


def _grid_defaults() -> tuple:
    """The reproduce defaults: every bottle, the paper's methods, both experiments, the master seed."""

    return BOTTLE_NAMES, methods.names(paper=True), EXPERIMENTS, DEFAULT_SEED


@dataclass(frozen=True)
class StudyConfig:
    """Everything that decides a study's rows (not where or how fast it runs).

    Parameters
    ----------
    plants : int
        Plants asked for (``saltelli`` rounds up).
    design : {"sobol", "lhs", "saltelli"}
    trials : int
        Trials per bottle, experiment and method on each plant.
    bottles, methods, experiments : tuple of str
        The reproduce grid on each plant (methods: names of :mod:`slipreflex.methods`).
    seed : int
        Seeds the design and is the reproduce master seed of every plant.
    ranges : str or Path, optional
        A TOML file narrowing, widening or fixing constants
        (:func:`slipreflex.sim.uncertain.load_ranges`).
    calibrate : bool
        Calibrate each plant's pad friction to the paper's open-loop first slip (200 ml).
    scan : bool
        Run each plant's characterization scans (claims 1-2).
    scan_seeds : int
        Texture seeds of each plant's scans (its own seeds: :func:`scan_seed_base`); the
        study judges claims 1-2 on all plants' scans pooled (``plants x scan_seeds`` draws).
    stepping : {"adaptive", "fixed"}
        The simulator's stepping (:data:`slipreflex.sim.rig.STEPPINGS`; default: this process's,
        ``SLIPREFLEX_STEPPING`` or adaptive). Every plant runs with it wherever it runs (a remote
        worker's own environment does not decide), and it is part of the fingerprint.
    refine : int
        Second-stage plants (``--refine``; 0: none): after the ``plants`` pilot, plants where a
        claim's class changes between neighbours, and a two-phase stratified estimate of each
        claim's holding fraction (:mod:`slipreflex.study.refine`; ``design="sobol"`` only).

    Examples
    --------
    >>> StudyConfig(design="grid")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: design: unknown 'grid' (known: sobol, lhs, saltelli)
    """

    plants: int = DEFAULT_PLANTS
    design: str = "sobol"
    trials: int = DEFAULT_TRIALS
    bottles: tuple[str, ...] = field(default_factory=lambda: _grid_defaults()[0])
    methods: tuple[str, ...] = field(default_factory=lambda: _grid_defaults()[1])
    experiments: tuple[str, ...] = field(default_factory=lambda: _grid_defaults()[2])
    seed: int = field(default_factory=lambda: _grid_defaults()[3])
    ranges: str | None = None
    calibrate: bool = True
    scan: bool = True
    scan_seeds: int = 4
    stepping: str = field(default_factory=lambda: _stepping_default())
    refine: int = 0
    _table: Any = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        from ..sim.rig import STEPPINGS  # deferred: heavy (numba kernels)
        from ..sim.uncertain import UNCERTAIN, load_ranges  # deferred: heavy (numba kernels)

        if self.design not in DESIGNS:
            raise ParameterError(f"design: unknown {self.design!r} (known: {', '.join(DESIGNS)})")
        if self.stepping not in STEPPINGS:
            raise ParameterError(f"stepping: unknown {self.stepping!r} (known: {', '.join(STEPPINGS)})")

        object.__setattr__(self, "plants", within("plants", self.plants))
        if isinstance(self.refine, bool) or not isinstance(self.refine, int) or self.refine < 0:
            raise ParameterError(f"refine must be an integer >= 0, got {self.refine!r}")
        if self.refine and self.design != "sobol":
            raise ParameterError(f"refine: needs design 'sobol' (the refinement continues its sequence), "
                                 f"got {self.design!r}")
        if self.refine:
            within("plants", self.plants + self.refine, "--plants + --refine")
        if isinstance(self.scan_seeds, bool) or not isinstance(self.scan_seeds, int) or self.scan_seeds < 1:
            raise ParameterError(f"scan_seeds must be an integer >= 1, got {self.scan_seeds!r}")
        if self.ranges is not None:
            object.__setattr__(self, "ranges", str(self.ranges))
        table = UNCERTAIN if self.ranges is None else load_ranges(self.ranges)
        object.__setattr__(self, "_table", dict(table))
        self.reproduce_config()   # validates the grid before any work

    @property
    def table(self) -> dict:
        """The uncertain constants of this study (name -> UncertainConstant).

        Examples
        --------
        >>> "hand_latency" in StudyConfig(plants=1).table
        True
        """
        return self._table

    def reproduce_config(self, plant: Any = None):
        """The reproduce grid run on each plant.

        Examples
        --------
        >>> StudyConfig(plants=1, trials=2).reproduce_config().trials
        2
        """

        return ReproduceConfig(trials=self.trials, bottles=tuple(self.bottles), methods=tuple(self.methods),
                               experiments=tuple(self.experiments), seed=self.seed, plant=plant,
                               **({} if plant is None else plant.method_options()))

    @property
    def trials_per_plant(self) -> int:
        """Closed-loop trials run on each plant.

        Examples
        --------
        >>> StudyConfig(plants=1, trials=2, bottles=("TR",), methods=("dath",)).trials_per_plant
        4
        """
        return len(self.reproduce_config().cells())

    def plant_values(self) -> list[dict[str, float]]:
        """Every plant's constants, in plant order (reproducible from :attr:`seed`).

        Examples
        --------
        >>> StudyConfig(plants=3).plant_values() == StudyConfig(plants=3).plant_values()
        True
        """
        return draw_design(self.table, self.plants, self.design, self.seed)

    def fingerprint(self) -> str:
        """A hash of everything that decides the rows (the grid, the design, the table, the package).

        Examples
        --------
        >>> StudyConfig(plants=2).fingerprint() != StudyConfig(plants=3).fingerprint()
        True
        """

        rc = self.reproduce_config()
        doc = {"version": __version__, "plants": self.plants, "design": self.design, "seed": self.seed,
               "calibrate": self.calibrate, "scan": self.scan, "scan_seeds": self.scan_seeds,
               "stepping": self.stepping,
               "grid": {f.name: repr(getattr(rc, f.name)) for f in dataclasses.fields(rc) if f.name != "plant"},
               "table": {k: [c.low, c.high, c.nominal, c.distribution] for k, c in self.table.items()}}
        if self.refine:   # absent when 0: an unrefined study keeps the fingerprint it always had
            doc["refine"] = self.refine
        return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()[:20]

    def to_dict(self) -> dict[str, Any]:
        """The arguments, as study.json records them.

        Examples
        --------
        >>> StudyConfig(plants=1).to_dict()["plants"]
        1
        """
        return {f.name: (list(v) if isinstance(v := getattr(self, f.name), tuple) else v)
                for f in dataclasses.fields(self) if f.init and (f.name != "refine" or self.refine)}

    def refine_plan(self, parts: Mapping[int, tuple[dict, list]]):
        """The second stage, decided by the pilot's parts (every pilot plant must be finished).

        Returns
        -------
        slipreflex.study.refine.RefinePlan

        Examples
        --------
        >>> cfg = StudyConfig(plants=4, refine=4)
        >>> parts = {i: ({"error": "", "claims": [[2, "holds" if i % 2 else "unresolved", ""]]}, [])
        ...          for i in range(4)}
        >>> len(cfg.refine_plan(parts).points)
        4
        """

        missing = [i for i in range(self.plants) if i not in parts]
        if missing:
            raise ParameterError(f"refine: pilot plants {missing[:5]} not finished")
        holds = np.zeros((self.plants, len(CLAIMS)), dtype=bool)
        col = {c.number: j for j, c in enumerate(CLAIMS)}
        for i in range(self.plants):
            meta = parts[i][0]
            if meta.get("error") or (meta.get("calibration") or {}).get("rejected"):
                continue
            for num, verdict, *_ in meta.get("claims", []):
                holds[i, col[int(num)]] = verdict == "holds"
        pilot = unit_design("sobol", self.plants, len(varying(self.table)), self.seed)
        return make_plan(pilot, holds, self.refine, self.seed)

    def refine_values(self, parts: Mapping[int, tuple[dict, list]]) -> dict[int, dict[str, float]]:
        """The second stage's plants by index (``plants`` onwards), decided by the pilot's parts.

        Examples
        --------
        >>> StudyConfig(plants=2).refine_values({})
        {}
        """
        if not self.refine:
            return {}
        vals = values_at(self.table, self.refine_plan(parts).points)
        return {self.plants + j: v for j, v in enumerate(vals)}


@dataclass(frozen=True)
class PlantOutcome:
    """What one plant produced.

    Attributes
    ----------
    plant : int
        Its index in the study's design.
    values : dict
        Its uncertain constants.
    rows : list of dict
        One per trial and slip (constants and calibration as columns); empty on error.
    claims : list of (int, str, str)
        (claim number, verdict, reason); empty on error or when the plant was rejected.
    error : str
        ``""``, or the exception (type and message) that stopped the plant.
    trials : int
        Closed-loop trials it ran.
    calibration : dict
        What its calibration found (calibrated ``mu_s``, observed and true first
        slip per bottle, the calibration's note, ``rejected``: why its observed
        first slip leaves the paper's band, or ``""``); empty without calibration.
    scan : dict
        Its scan ensemble's numbers (:class:`~slipreflex.sim.scan.ScanEnsemble` fields as
        lists); empty without scans.

    Examples
    --------
    >>> PlantOutcome(0, {}, [], [], "ValueError: x", 0).error
    'ValueError: x'
    """

    plant: int
    values: dict
    rows: list
    claims: list
    error: str
    trials: int
    calibration: dict = field(default_factory=dict)
    scan: dict = field(default_factory=dict)


#: First texture seed of the study's scans; plant ``i`` scans seeds ``base + i * scan_seeds`` onwards.
STUDY_SCAN_BASE: int = 1_000_000_000


def scan_seed_base(index: int, config: StudyConfig) -> int:
    """First texture seed of plant ``index``'s scans: every plant gets its own.

    Examples
    --------
    >>> cfg = StudyConfig(plants=2)
    >>> scan_seed_base(1, cfg) - scan_seed_base(0, cfg) == cfg.scan_seeds
    True
    """
    return STUDY_SCAN_BASE + int(index) * config.scan_seeds


def _calibrated(plant: Any, table: Mapping) -> tuple[Any, dict[str, Any]]:
    """The plant with its pads calibrated to its open-loop first slip, and what the calibration found.

    One seed first; where the first slip jumps over the target (see
    :func:`~slipreflex.sim.calibration.calibrate_bottle`), the reproduce
    default's seeds (averaged), whose steps are finer; where the target is
    still inside a jump, the nearest edge whose volume lies in the table's
    ``first_slip_ml`` range (the paper's "about 200 ml") is taken. Columns:
    ``calibrated_mu_s_<bottle>``, ``calibrated_first_slip_ml_<bottle>`` and
    ``calibration_note`` (``""``, or the jumps the calibration fell back on).
    """

    from ..sim.calibration import CALIBRATION_SEEDS as DEFAULT_SEEDS  # deferred: heavy (numba kernels)
    from ..sim.calibration import calibrate_bottle  # deferred: heavy (numba kernels)

    c = table["first_slip_ml"]
    kw = plant.rig_kwargs()
    cals = {}
    memo: dict = {}   # the bottles' shared open-loop pours (TR and DK differ only in their surface)
    for name, bottle in plant.bottles.items():
        try:
            cals[name] = calibrate_bottle(bottle, plant.first_slip_ml, rig_kwargs=kw, seeds=CALIBRATION_SEEDS,
                                          memo=memo)
        except ParameterError:
            try:
                cals[name] = calibrate_bottle(bottle, plant.first_slip_ml, rig_kwargs=kw, seeds=DEFAULT_SEEDS,
                                              band_ml=(c.low, c.high), memo=memo)
            except ParameterError as err:   # no friction meets the paper's observed fact: counted apart
                return plant, {"calibration_note": "", "rejected": f"{err}"}
    plant = replace(plant, bottles=MappingProxyType({n: k.bottle for n, k in cals.items()}))
    extra: dict[str, Any] = {f"calibrated_mu_s_{n}": float(k.mu_s) for n, k in cals.items()}
    extra.update({f"calibrated_first_slip_ml_{n}": float(k.first_slip_ml) for n, k in cals.items()})
    extra.update({f"true_first_slip_ml_{n}": float(k.true_first_slip_ml) for n, k in cals.items()})
    extra["calibration_note"] = "; ".join(k.note for k in cals.values() if k.note)
    out = [f"{n} {k.first_slip_ml:.0f} ml" for n, k in cals.items() if not c.low <= k.first_slip_ml <= c.high]
    extra["rejected"] = (f"observed first slip outside the paper's {c.low:g}-{c.high:g} ml: " + ", ".join(out)
                         if out else "")
    return plant, extra


def run_plant(index: int, values: Mapping[str, float], config: StudyConfig) -> PlantOutcome:
    """Build, calibrate and run one plant; judge the claims. Never raises.

    Examples
    --------
    >>> cfg = StudyConfig(plants=1, trials=1, bottles=("TX",), methods=("dath",), experiments=("drop",),
    ...                   calibrate=False, scan=False)
    >>> out = run_plant(0, cfg.plant_values()[0], cfg)
    >>> out.error, len(out.rows), out.claims[2][1]
    ('', 1, 'not-decidable')
    """

    from ..sim.rig import stepping  # deferred: heavy (numba kernels)

    with stepping(config.stepping):
        return _run_plant(index, values, config)


def _run_plant(index: int, values: Mapping[str, float], config: StudyConfig) -> PlantOutcome:
    from ..sim.scan import scan_ensemble  # deferred: heavy (llvmlite, numba, scipy)
    from ..sim.uncertain import plant_from_values  # deferred: heavy (numba kernels)

    values = {k: float(v) for k, v in values.items()}
    try:
        plant = plant_from_values(values, table=config.table)
        extra: dict[str, Any] = {}
        if config.calibrate:
            plant, extra = _calibrated(plant, config.table)
            if extra["rejected"]:    # counted apart: it contradicts the paper's open-loop fact
                return PlantOutcome(index, values, [{"plant": index, **values, **extra, "error": ""}], [], "", 0,
                                    extra)
        rc = config.reproduce_config(plant)

        thresholds = calibrate(rc) if set(rc.methods) & set(methods.calibrated()) else {}
        rows = []
        for cell in rc.cells():
            rows += run_trial(cell, rc, thresholds)[0]
        ens = scan_ensemble(config.scan_seeds, base=scan_seed_base(index, config),
                            sensor=plant.slip_sensor) if config.scan else None
        judged = judge(rows, ens, plant)
        verdicts = [(r.number, r.verdict, r.reason) for r in judged]
        out_rows = [{"plant": index, **values, **extra, "error": "", **dict(r)} for r in rows]
        scan = {} if ens is None else {k: np.asarray(getattr(ens, k)).tolist() for k in _SCAN_FIELDS}
        return PlantOutcome(index, values, out_rows, verdicts, "", len(rc.cells()), extra, scan)
    except Exception as err:   # a plant that raises is recorded, the study goes on
        last = traceback.extract_tb(err.__traceback__)[-1]
        msg = f"{type(err).__name__}: {err} ({Path(last.filename).name}:{last.lineno})"
        return PlantOutcome(index, values, [{"plant": index, **values, "error": msg}], [], msg, 0)


_SCAN_FIELDS = ("seeds", "white_lo", "white_hi", "black_lo", "black_hi", "fixed_gap", "dath_gap", "fixed_spikes",
                "dath_spikes")


def part_path(out: Path, index: int) -> Path:
    """Where plant ``index``'s Parquet part lives.

    Examples
    --------
    >>> part_path(Path("o"), 7).name
    'plant-000007.parquet'
    """
    return Path(out) / PARTS_DIR / f"plant-{index:06d}.parquet"


def _arrow_table(rows: Sequence[Mapping[str, Any]]):
    import pyarrow as pa  # deferred: optional extra (study: pyarrow)

    cols: list[str] = []
    for r in rows:
        cols += [k for k in r if k not in cols]
    return pa.Table.from_pydict({c: [r.get(c) for r in rows] for c in cols})


def write_part(out: Path, outcome: PlantOutcome, fingerprint: str) -> Path:
    """Write one plant's rows and verdicts as a Parquet part (temporary name, then rename)."""
    import pyarrow.parquet as pq  # deferred: optional extra (study: pyarrow)

    table = _arrow_table(outcome.rows)
    meta = {"fingerprint": fingerprint, "plant": outcome.plant, "error": outcome.error,
            "claims": outcome.claims, "trials": outcome.trials, "values": outcome.values,
            "calibration": outcome.calibration, "scan": outcome.scan}
    table = table.replace_schema_metadata({_META_KEY: json.dumps(meta).encode()})
    path = part_path(out, outcome.plant)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    pq.write_table(table, tmp)
    os.replace(tmp, path)
    return path


def read_parts(out: Path, fingerprint: str | None = None) -> dict[int, tuple[dict, list[dict]]]:
    """Finished plants in ``out``: index -> (metadata, rows); parts of another study are left out.

    Examples
    --------
    >>> read_parts(Path("/nonexistent"))
    {}
    """
    import pyarrow.parquet as pq  # deferred: optional extra (study: pyarrow)

    found = {}
    for p in sorted((Path(out) / PARTS_DIR).glob("plant-*.parquet")):
        try:
            t = pq.read_table(p)
            meta = json.loads(t.schema.metadata[_META_KEY])
        except Exception:   # a part cut short is not a finished plant
            continue
        if fingerprint is None or meta.get("fingerprint") == fingerprint:
            found[int(meta["plant"])] = (meta, t.to_pylist())
    return found


@dataclass
class StudyRun:
    """A finished (or interrupted) study: the plants' outcomes as read back from the parts.

    Attributes
    ----------
    config : StudyConfig
    out : Path
    parts : dict
        Plant index -> (metadata, rows).
    computed : list of int
        Plants computed by this run (the rest were resumed).
    wall_s : float
    workers : str
        Where it ran ("serial", "LocalCluster(2)", the scheduler address).

    Examples
    --------
    >>> StudyRun(StudyConfig(plants=1), Path("o"), {}, [], 0.0, "serial").complete
    False
    """

    config: StudyConfig
    out: Path
    parts: dict
    computed: list
    wall_s: float
    workers: str

    @property
    def complete(self) -> bool:
        """Every plant of the design has a part.

        Examples
        --------
        >>> StudyRun(StudyConfig(plants=1), Path("o"), {0: ({}, [])}, [], 0.0, "serial").complete
        True
        """
        return len(self.parts) == len(self.config.plant_values()) + self.config.refine


class _Progress:
    """Plants and trials done: two bars on a terminal, a line per tenth of the plants in a log."""

    def __init__(self, plants: int, trials: int, done: int, enabled: bool):

        self.trials = trials
        self.plants = Progress(plants, desc="plants", unit="plant", enabled=enabled)
        tty = enabled and sys.stderr.isatty()
        self.trial_bar = Progress(plants * trials, desc="trials", unit="trial", enabled=tty)
        if done:
            self.plants.update(done)
            self.trial_bar.update(done * trials)

    def update(self, trials: int) -> None:
        self.plants.update()
        self.trial_bar.update(self.trials)

    def close(self) -> None:
        self.plants.close()
        self.trial_bar.close()


#: Options of ``slipreflex study`` by StudyConfig field, for the message naming what differs.
_OPTIONS = {"plants": "--plants", "design": "--design", "trials": "--trials", "bottles": "--bottles",
            "methods": "--methods", "experiments": "--experiments", "seed": "--seed", "ranges": "--ranges",
            "calibrate": "--no-calibration", "scan": "scan", "stepping": "SLIPREFLEX_STEPPING"}


def _differences(old: Mapping[str, Any], config: StudyConfig) -> list[str]:
    """What differs between the study recorded in study.json and ``config``, as options."""

    new = config.to_dict()
    was = old.get("config", {}) if isinstance(old.get("config"), dict) else {}

    def show(v: Any) -> str:
        return ",".join(map(str, v)) if isinstance(v, list) else str(v)

    out = [f"{_OPTIONS.get(k, k)} {show(new[k])} (the study there: {show(was.get(k))})"
           for k in new if k in was and was[k] != new[k]]
    if not out and old.get("version") not in (None, __version__):
        out.append(f"the slipreflex version {__version__} (the study there: {old.get('version')})")
    if not out and new.get("ranges"):
        out.append(f"the content of --ranges {new['ranges']} (same name, other constants)")
    return out or ["the study's constants (its fingerprint)"]


def _check_out(out: Path, config: StudyConfig) -> bool:
    """Refuse an --out that holds another study (before any work), naming the arguments that
    differ; record this one. True if this call created study.json (a failed start removes it)."""

    meta = out / "study.json"
    fp = config.fingerprint()
    created = not os.path.lexists(meta)
    if not created:
        try:
            old = json.loads(meta.read_text())
        except (OSError, ValueError):
            old = {}
        old = old if isinstance(old, dict) else {}
        if old.get("fingerprint") != fp:
            raise ParameterError(f"--out {out}: holds another study; this one differs in "
                                 + "; ".join(_differences(old, config))
                                 + ". Give the same arguments to resume it, or another --out")
        return False
    try:
        out.mkdir(parents=True, exist_ok=True)

        with new_file(meta, replace=True) as fh:
            fh.write(json.dumps({"fingerprint": fp, "version": __version__, "config": config.to_dict()},
                                indent=1, sort_keys=True) + "\n")
    except OSError as err:
        raise ParameterError(f"--out {out}: cannot write: {err.strerror}") from None
    return True


def run_study(config: StudyConfig, out: str | Path, *, workers: int | None = None, scheduler: str | None = None,
              progress: bool = True, on_plant: Callable[[PlantOutcome], None] | None = None,
              dashboard: str | None = None) -> StudyRun:
    """Run every plant not yet finished in ``out``; write one Parquet part per plant as it finishes.

    Parameters
    ----------
    config : StudyConfig
    out : str or Path
        Output directory (parts, study.json; :func:`slipreflex.study.write_outputs` adds the rest).
    workers : int, optional
        Local Dask worker processes (default: the machine's cores); 0 runs the
        plants in this process, without Dask.
    scheduler : str, optional
        ``tcp://HOST:PORT`` of a running Dask scheduler (overrides ``workers``).
    progress : bool
        Progress on stderr.
    on_plant : callable, optional
        Called with each plant's outcome after its part is written.
    dashboard : str, optional
        ``HOST:PORT`` for the local cluster's Dask dashboard (default: none; it has no
        authentication, so keep it on 127.0.0.1).

    Returns
    -------
    StudyRun

    Examples
    --------
    >>> import tempfile
    >>> cfg = StudyConfig(plants=2, trials=1, bottles=("TX",), methods=("dath",), experiments=("drop",),
    ...                   calibrate=False, scan=False)
    >>> run = run_study(cfg, tempfile.mkdtemp(), workers=0, progress=False)
    >>> sorted(run.parts), run.computed
    ([0, 1], [0, 1])
    """
    out = Path(out)
    if workers is not None and workers < 0:
        raise ParameterError(f"--workers must be >= 0, got {workers}")
    if workers is not None:

        if workers != 0:
            within("jobs", workers, "--workers")
    out_existed = os.path.isdir(out)
    created = _check_out(out, config)
    t0 = time.perf_counter()
    fp = config.fingerprint()
    plants = dict(enumerate(config.plant_values()))
    have = set(read_parts(out, fp))
    bar = _Progress(len(plants) + config.refine, config.trials_per_plant, len(have), progress)
    computed: list[int] = []

    def finished(o: PlantOutcome) -> None:
        write_part(out, o, fp)
        computed.append(o.plant)
        bar.update(o.trials)
        if on_plant:
            on_plant(o)

    where = "serial"

    def stage(values: Mapping[int, dict]) -> None:
        nonlocal where
        todo = [i for i in sorted(values) if i not in have]
        if todo and session is not None:
            where = _run_dask(todo, values, config, session, finished, fp)
        else:
            for i in todo:
                finished(run_plant(i, values[i], config))

    # one client (and local cluster) for the pilot and the refinement, started when a stage needs it
    session = _DaskSession(workers, scheduler, dashboard) if (workers != 0 or scheduler) else None
    try:
        stage(plants)
        if config.refine:   # the second stage is decided by the finished pilot
            stage(config.refine_values(read_parts(out, fp)))
    except BaseException:
        if created and not computed and not have:   # a failed start leaves no lock on --out
            (out / "study.json").unlink(missing_ok=True)
            if not out_existed:      # the folder this run made, if it is still empty
                for folder in (out / PARTS_DIR, out):
                    with contextlib.suppress(OSError):
                        folder.rmdir()
        raise
    finally:
        if session is not None:
            session.close()
        bar.close()
    return StudyRun(config, out, read_parts(out, fp), computed, time.perf_counter() - t0, where)


#: Loggers hushed after a Ctrl-C (their shutdown messages are expected, not news).
_QUIET_LOGGERS: tuple[str, ...] = ("distributed", "tornado", "asyncio")
#: Seconds the client and the local cluster get to close after a Ctrl-C.
_STOP_CLOSE_S: float = 3.0


class _DaskSession:
    """The Dask client (and local cluster) of one run: started on first use, shared by its stages, closed once."""

    def __init__(self, workers: int | None, scheduler: str | None, dashboard: str | None):
        self._args = (workers, scheduler, dashboard)
        self.client: Any = None
        self.cluster: Any = None
        self.where = ""
        self.stopped = False   # a Ctrl-C: the close is short and may be abandoned

    def start(self) -> Any:
        if self.client is None:
            self.client, self.cluster, self.where = _client(*self._args)
        return self.client

    def close(self) -> None:
        if self.client is None:
            return
        client, cluster, self.client, self.cluster = self.client, self.cluster, None, None
        with signals_ignored():
            # after a stop, a close that takes long is abandoned: the workers are this process's
            # children and end with it
            with contextlib.suppress(Exception) if self.stopped else contextlib.nullcontext():
                client.close(timeout=_STOP_CLOSE_S if self.stopped else None)
                if cluster is not None:
                    cluster.close(timeout=_STOP_CLOSE_S if self.stopped else None)


def _run_dask(todo: list[int], plants: Mapping[int, dict], config: StudyConfig, session: _DaskSession,
              finished: Callable[[PlantOutcome], None], fp: str) -> str:

    from dask.distributed import as_completed  # deferred: optional extra (study: dask)


    client = session.start()
    futures = []
    quiet = [logging.getLogger(n) for n in _QUIET_LOGGERS]
    levels = [q.level for q in quiet]

    def hush(signum: int, frame: Any) -> None:
        # A stop is quick and quiet: Dask's shutdown chatter (cancelled tasks, closed streams,
        # killed workers) is not the user's business; the caller prints one line. The loggers
        # are hushed here, before the interrupt reaches Dask's event loop.
        for q in quiet:
            q.setLevel(logging.CRITICAL)
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGINT, hush) if _main_thread() else None
    stopped = False
    try:
        futures = [client.submit(run_plant, i, plants[i], config, key=f"slipreflex-study-{fp}-{i}", pure=False)
                   for i in todo]
        for fut in as_completed(futures):
            finished(fut.result())
            fut.release()
    except KeyboardInterrupt:
        stopped = session.stopped = True
        for q in quiet:
            q.setLevel(logging.CRITICAL)
        raise
    finally:
        with signals_ignored():
            if old is not None:
                signal.signal(signal.SIGINT, old)
            for f in futures:
                f.cancel()
            if stopped:   # closed at once, still hushed (the caller's close is then a no-op)
                session.close()
        if not stopped:  # after a stop the event loop may still report closed streams: stay hushed
            for q, lv in zip(quiet, levels):
                q.setLevel(lv)
    return session.where
