"""The registry of experiments: one specification per experiment, in one place.

An experiment is what happens to the grasped bottle in a trial and how the trial is read:
what perturbs the rig and when (:attr:`ExperimentSpec.perturbation`, its load time and the
delay before it can make the bottle slip), what counts as a slip event (one onset, or
every onset a segmentation of the whole load finds), whether the load itself is recorded,
and what the figures and the report show (a title, a zoom, the paper's figure it is like).
``reproduce``, its analysis, the figures and the report read only these specifications,
so an experiment registered here runs everywhere without touching them.

The paper's two experiments, the sudden load (``drop``) and the gradual load (``pour``),
are the first registrations; their functions live with the run (:mod:`slipreflex.reproduce.experiments`)
and are named here by entry point, so this registry imports nothing above it. Check a new
one with :func:`slipreflex.testing.check_experiment`.

Examples
--------
>>> names()[:2]
('drop', 'pour')
>>> get("pour").slip_events, get("drop").records_load
('segmented', False)
>>> from slipreflex.reproduce.experiments import ReproduceConfig
>>> register(ExperimentSpec(name="heavy-drop", title="sudden heavy load",
...     perturbation=EntryPoint(f"{_PAPER_EXPERIMENTS}:drop_perturbation"),
...     describe=EntryPoint(f"{_PAPER_EXPERIMENTS}:describe_drop")))
>>> "heavy-drop" in names(), seed_branch("heavy-drop")
(True, 3)
>>> unregister("heavy-drop")
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from .errors import ParameterError
from .registry import EntryPoint, Registry
from .validation import choice

__all__ = ["ExperimentSpec", "EXPERIMENTS", "register", "unregister", "get", "names", "seed_branch", "EntryPoint",
           "SLIP_EVENTS", "CALIBRATION_BRANCH"]

#: How a trial's slip events are found: one onset after the perturbation ("single"), or
#: every onset a segmentation of the whole load finds ("segmented").
SLIP_EVENTS: tuple[str, ...] = ("single", "segmented")
#: The seed branch of the threshold calibration (after the paper's two experiments); a later
#: registration takes the branches after it, so the paper's seeds never move.
CALIBRATION_BRANCH: int = 2
_NAME = re.compile(r"^[a-z][a-z0-9_-]*$")


def _no_time(_: Any) -> float:
    return 0.0


@dataclass(frozen=True)
class ExperimentSpec:
    """One experiment: what perturbs the rig, what counts as a slip, what the outputs show.

    Parameters
    ----------
    name : str
        Registry name (lower case; what ``--experiments`` and results.csv say).
    title : str
        A few words for tables and captions ("sudden load").
    perturbation : callable
        ``perturbation(config)``: what :meth:`slipreflex.sim.Rig.perturb` applies in a trial
        of the run ``config`` (a :class:`slipreflex.reproduce.experiments.ReproduceConfig`).
    describe : callable
        ``describe(perturbation)``: the perturbation in words, for figure titles and notes
        ("10 g from 2 cm"), so an overridden load is named as run.
    load_s : callable
        ``load_s(perturbation)``: how long the load goes on (s; default 0, a sudden load).
        A trial records the rest, the load and ``after_s``.
    settle_s : callable
        ``settle_s(perturbation)``: how long after it starts the load can first make the
        bottle slip (s; default 0); slip events are looked for from then on.
    slip_events : {"single", "segmented"}
        One onset after the perturbation, or every onset over the whole load.
    records_load : bool
        The trial's load trace (the simulator's ``water_ml``) is analysed and drawn.
    zoom_s : (float, float) or None
        A trial figure's time axis around the perturbation (s before, s after); None: the
        whole trial.
    paper : callable or None
        ``paper()``: the paper's perturbation, when this is one of the paper's experiments
        (the report then compares with the paper only when the run's perturbation is it).
    paper_figures : mapping of str to str
        The paper's figure each plot is like ("trial", "response", "total").

    Examples
    --------
    >>> get("drop").title
    'sudden load'
    """

    name: str
    title: str
    perturbation: Callable[[Any], Any]
    describe: Callable[[Any], str]
    load_s: Callable[[Any], float] = _no_time
    settle_s: Callable[[Any], float] = _no_time
    slip_events: Literal["single", "segmented"] = "single"
    records_load: bool = False
    zoom_s: tuple[float, float] | None = None
    paper: Callable[[], Any] | None = None
    paper_figures: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not _NAME.match(self.name):
            raise ParameterError(f"ExperimentSpec.name must be lower case letters, digits, '-' or '_', "
                                 f"got {self.name!r}")
        if not isinstance(self.title, str) or not self.title.strip():
            raise ParameterError(f"ExperimentSpec.title must be a non-empty str, got {self.title!r}")
        for name in ("perturbation", "describe", "load_s", "settle_s"):
            if not callable(getattr(self, name)):
                raise ParameterError(f"ExperimentSpec.{name} must be callable, got {getattr(self, name)!r}")
        if self.paper is not None and not callable(self.paper):
            raise ParameterError(f"ExperimentSpec.paper must be callable or None, got {self.paper!r}")
        choice("slip_events", self.slip_events, SLIP_EVENTS)
        if self.zoom_s is not None:
            lo, hi = (float(v) for v in self.zoom_s)
            if not (math.isfinite(lo) and math.isfinite(hi) and lo >= 0 and hi > 0):
                raise ParameterError(f"ExperimentSpec.zoom_s must be (s before >= 0, s after > 0), got {self.zoom_s!r}")
            object.__setattr__(self, "zoom_s", (lo, hi))
        object.__setattr__(self, "records_load", bool(self.records_load))
        object.__setattr__(self, "paper_figures", dict(self.paper_figures))


#: The paper's experiments, which cannot be unregistered.
_PAPER = ("drop", "pour")
#: The experiment registry (registration order is the seed-branch order); the functions below read it.
EXPERIMENTS: Registry[ExperimentSpec] = Registry("experiment", ExperimentSpec, protected=_PAPER,
                                                 group="slipreflex.experiments")


def register(spec: ExperimentSpec, *, replace: bool = False) -> None:
    """Add an experiment (an existing name is an error unless ``replace``).

    Examples
    --------
    >>> register(get("drop"))
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: experiment 'drop' is already registered (pass replace=True)
    """
    EXPERIMENTS.register(spec, replace=replace)


def unregister(name: str) -> None:
    """Remove an experiment (the paper's two cannot be removed).

    Examples
    --------
    >>> unregister("drop")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: experiment 'drop' is built in and cannot be unregistered
    """
    EXPERIMENTS.unregister(name)


def get(name: str) -> ExperimentSpec:
    """The specification of experiment ``name``.

    Examples
    --------
    >>> get("shake")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: experiment: unknown 'shake' (known: drop, pour)
    """
    return EXPERIMENTS.get(name)


def names() -> tuple[str, ...]:
    """The registered experiments, in registration order (the paper's first).

    Examples
    --------
    >>> names()
    ('drop', 'pour')
    """
    return EXPERIMENTS.names()


def seed_branch(name: str) -> int:
    """The branch of the master seed an experiment's trials draw from.

    The paper's experiments take branches 0 and 1 and the threshold calibration branch 2
    (:data:`CALIBRATION_BRANCH`); the k-th later registration takes branch 2 + k, so
    registering an experiment never changes another's seeds.

    Examples
    --------
    >>> seed_branch("drop"), seed_branch("pour")
    (0, 1)
    """
    i = EXPERIMENTS.names().index(get(name).name)
    return i if i < CALIBRATION_BRANCH else i + 1


#: Where the paper's two experiments are implemented (named by entry point: the registry sits below them).
_PAPER_EXPERIMENTS = "slipreflex.reproduce.paper_experiments"

# the paper's experiments, in its order (drop: Figs. 10-14; pour: Figs. 15-17)
register(ExperimentSpec(
    name="drop", title="sudden load", perturbation=EntryPoint(f"{_PAPER_EXPERIMENTS}:drop_perturbation"),
    describe=EntryPoint(f"{_PAPER_EXPERIMENTS}:describe_drop"), slip_events="single", zoom_s=(0.3, 1.5),
    paper=EntryPoint(f"{_PAPER_EXPERIMENTS}:paper_drop"),
    paper_figures={"trial": "Figs. 10-12", "response": "Fig. 13", "total": "Fig. 14"}))
register(ExperimentSpec(
    name="pour", title="gradual load", perturbation=EntryPoint(f"{_PAPER_EXPERIMENTS}:pour_perturbation"),
    describe=EntryPoint(f"{_PAPER_EXPERIMENTS}:describe_pour"),
    load_s=EntryPoint(f"{_PAPER_EXPERIMENTS}:pour_load_s"),
    settle_s=EntryPoint(f"{_PAPER_EXPERIMENTS}:pour_settle_s"), slip_events="segmented", records_load=True,
    paper=EntryPoint(f"{_PAPER_EXPERIMENTS}:paper_pour"),
    paper_figures={"trial": "Fig. 15", "response": "Fig. 16", "total": "Fig. 17"}))
