"""Running a grid of trials: its cells, the worker pool, Ctrl-C, and the result over the finished trials.

:func:`slipreflex.reproduce.experiments.run_reproduce` plans the grid (its :class:`Cell` s, from
:meth:`~slipreflex.reproduce.experiments.ReproduceConfig.cells`, their seeds and thresholds) and
hands each trial to :func:`run_cells` as a call without arguments; :func:`grid_result`
turns the finished trials into a :class:`~slipreflex.analysis.outputs.ReproduceResult`,
rows in the one order (:func:`row_order`), whether every trial finished or an interrupt
stopped the run.

Examples
--------
>>> done = {}
>>> run_cells({"a": lambda: 1, "b": lambda: 2}, 1, lambda key: None, done)
>>> done
{'a': 1, 'b': 2}
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from typing import Any

from .. import methods
from ..analysis.outputs import ReproduceResult
from ..analysis.paper import bottle_key
from ..analysis.report import summarize
from ..core import experiment_specs
from ..files.interrupts import stop_pool, worker_signals

__all__ = ["Cell", "run_cells", "row_order", "grid_result"]


@dataclass(frozen=True)
class Cell:
    """One trial of the grid: experiment, bottle, method, trial index and the trial's seed.

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


def run_cells(calls: Mapping[Any, Callable[[], Any]], jobs: int,
              finished: Callable[[Any], Any], done: dict) -> None:
    """Run every call into ``done`` by its key: in this process for ``jobs == 1``, else on a pool.

    ``finished(key)`` is called as each call's result arrives. On Ctrl-C or SIGTERM
    (a :class:`KeyboardInterrupt`) queued calls are cancelled, running ones get
    :data:`~slipreflex.files.interrupts.GRACE_S` to finish, and the interrupt propagates with
    ``done`` holding every finished call. On a pool the calls must pickle (for example a
    :func:`functools.partial` of a module-level function).

    Examples
    --------
    >>> import functools
    >>> done = {}
    >>> run_cells({k: functools.partial(abs, -k) for k in range(3)}, 2, lambda key: None, done)
    >>> sorted(done.items())
    [(0, 0), (1, 1), (2, 2)]
    """
    if jobs == 1:
        for key, call in calls.items():
            done[key] = call()
            finished(key)
        return
    ex = ProcessPoolExecutor(max_workers=jobs, initializer=worker_signals)
    futures = {ex.submit(call): key for key, call in calls.items()}

    def collect(f) -> None:
        key = futures[f]
        if key not in done:
            done[key] = f.result()
            finished(key)

    try:
        for f in as_completed(futures):
            collect(f)
    except KeyboardInterrupt:
        stop_pool(ex, list(futures), collect)
        raise
    ex.shutdown()


def row_order(row: Any) -> tuple:
    """Sort key of results.csv: experiment, bottle (the paper's first), method, trial, event.

    Examples
    --------
    >>> from types import SimpleNamespace as R
    >>> rows = [R(experiment="drop", bottle="TX", method="dath", trial=0, event=0),
    ...         R(experiment="drop", bottle="TR", method="nmsd", trial=0, event=0)]
    >>> [r.bottle for r in sorted(rows, key=row_order)]
    ['TR', 'TX']
    """
    return (experiment_specs.names().index(row.experiment), bottle_key(row.bottle), row.bottle,
            methods.names().index(row.method), row.trial, row.event)


def grid_result(config: Any, cells: Sequence[Any], done: Mapping[Any, tuple], thresholds: dict[str, float],
                t0: float, jobs: int, t_cal: float) -> ReproduceResult:
    """The run's result over the finished cells (all of them unless interrupted).

    ``done`` maps a finished cell to what :func:`slipreflex.reproduce.experiments.run_trial`
    returned, (rows, plot data or None); ``t0`` is the run's start
    (:func:`time.perf_counter`), ``t_cal`` the calibration's wall time (s).

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> res = grid_result(ReproduceConfig(), ["a cell"], {}, {}, time.perf_counter(), 1, 0.0)
    >>> res.partial_note
    'interrupted after 0 of 1 trials'
    """

    fin = [c for c in cells if c in done]
    rows = sorted((r for c in fin for r in done[c][0]), key=row_order)
    plot_data = {c.key: done[c][1] for c in fin if done[c][1] is not None}
    return ReproduceResult(config, rows, summarize(rows), thresholds, plot_data,
                           time.perf_counter() - t0, jobs, calibration_wall_s=t_cal,
                           trials_planned=len(cells), trials_finished=len(fin))
