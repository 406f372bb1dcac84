"""Detectors on recorded, labelled slip data: ``slipreflex benchmark`` (docs/benchmark.md).

* :mod:`~slipreflex.benchmark.trials` - the recorded-trial format (one CSV per trial, ``t``,
  channels, ``slip`` or ``# trial-label``, ``# layout``) and its bounded reader;
* :mod:`~slipreflex.benchmark.sweep` - every detector at every threshold of a grid in the
  data's units, alarms as episodes, the label tolerance; the energy statistic;
* :mod:`~slipreflex.benchmark.learned` - the learned baseline (scikit-learn, the ``learn`` extra);
* :mod:`~slipreflex.benchmark.protocol` - folds by trial, the operating point chosen on
  training trials, intervals, the chance line, curves and their bootstrap areas;
* :mod:`~slipreflex.benchmark.evaluate` - all of it over a data set (the command's default);
* :mod:`~slipreflex.benchmark.optable` - ``operating_points.csv``, its table, ``curves.png``;
* :mod:`~slipreflex.benchmark.scoring` - onset, detection, latency and false alarms of one
  method on one trial;
* :mod:`~slipreflex.benchmark.run` - every registered method that applies, on every trial,
  each with its threshold from the data before the onset (``--protocol rest-k``);
* :mod:`~slipreflex.benchmark.report` - ``benchmark.csv``, the per-method summary, figures;
* :mod:`~slipreflex.benchmark.vs_sim` - the simulated tactile array held against the data.

The shipped data set (:func:`shipped_dataset`): 7 trials of a Franka gripper moving a box
with two XELA uSkin 4 x 4 x 3 patches at about 60 Hz, 3 with labelled slip (MIT licence;
its folder holds the licence and a provenance note).

Examples
--------
>>> trials = read_folder(shipped_dataset())
>>> [round(tr.fs) for tr in trials][:3], trials[0].layout.shape
([60, 60, 60], (2, 4, 4, 3))
"""

from __future__ import annotations

from pathlib import Path

from .run import BenchmarkConfig, MethodRun, Skipped, run_benchmark, run_trial
from .scoring import Score, score
from .trials import Layout, RecordedTrial, read_folder, read_trial

__all__ = ["shipped_dataset", "read_folder", "read_trial", "Layout", "RecordedTrial", "Score", "score",
           "BenchmarkConfig", "MethodRun", "Skipped", "run_benchmark", "run_trial", "SHIPPED"]

#: Name of the data set shipped with the package.
SHIPPED: str = "imanlab-slip"


def shipped_dataset() -> Path:
    """The folder of the data set shipped with the package.

    Examples
    --------
    >>> (shipped_dataset() / "LICENSE").is_file()
    True
    """
    return Path(__file__).resolve().parent.parent / "data" / "datasets" / SHIPPED
