"""The learned baseline: a small classifier on windowed features, fitted on training trials only.

What a trained detector reaches on the same split as the hand-built ones. Per sample, from
causal windows ending at it (so it could run online):

* the log energy of the sample-to-sample change of every channel, over 0.1 s and 0.3 s;
* the change of the chain's input (the layout's reduction, or the channels aggregated)
  over 0.1 s, signed and absolute, and its sd over 0.3 s.

A logistic regression (scikit-learn, the ``learn`` extra) on the standardised features,
classes weighted by their frequency. Training samples: on a trial with an onset, those in
the first :data:`POSITIVE_S` of the labelled slip are slip, those before the detection
window (onset minus the tolerance) and every sample of a control are not; the rest (the
tolerance and the later slip) are left out. On a trial-level set every sample of a slip
trial is slip. The statistic is the predicted probability of slip; its threshold is chosen
as every other method's.

Examples
--------
>>> from slipreflex.benchmark import read_folder, shipped_dataset
>>> trials = read_folder(shipped_dataset())
>>> features(trials[0]).shape
(404, 5)
"""

from __future__ import annotations

import importlib.util
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..core.errors import DataError
from .sweep import channel_inputs, energy_statistic
from .trials import RecordedTrial

__all__ = ["features", "fit", "probability", "POSITIVE_S", "PROBABILITY_GRID", "available"]

#: Span after the labelled onset whose samples train as slip (s): the start of the slip is what a
#: detector must catch; later samples (a box already lost) would teach it something else.
POSITIVE_S: float = 0.25
#: Thresholds on the probability: 41 points evenly spaced in log-odds from -8 to 8.
PROBABILITY_GRID: np.ndarray = 1.0 / (1.0 + np.exp(-np.linspace(-8.0, 8.0, 41)))


def available() -> str | None:
    """None if scikit-learn is installed, else why the learned baseline cannot run.

    Examples
    --------
    >>> available() is None or "learn" in available()
    True
    """
    if importlib.util.find_spec("sklearn") is None:
        return "needs scikit-learn (pip install 'slipreflex[learn]')"
    return None


def _window_change(x: np.ndarray, w: int) -> np.ndarray:
    return x - x[np.maximum(np.arange(len(x)) - w, 0)]


def _moving_sd(x: np.ndarray, w: int) -> np.ndarray:
    c1, c2 = np.r_[0.0, np.cumsum(x)], np.r_[0.0, np.cumsum(x * x)]
    hi = np.arange(1, len(c1))
    lo = np.maximum(hi - w, 0)
    n = hi - lo
    m = (c1[hi] - c1[lo]) / n
    return np.sqrt(np.maximum((c2[hi] - c2[lo]) / n - m * m, 0.0))


def features(trial: RecordedTrial, *, reduction: str = "z-sum", aggregate: str = "sum") -> np.ndarray:
    """The per-sample features (K, 5) of one trial (the module docstring lists them).

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> f = features(read_folder(shipped_dataset())[-1])
    >>> bool(np.isfinite(f).all())
    True
    """
    fs = trial.fs
    short, long_ = max(1, int(round(0.1 * fs))), max(2, int(round(0.3 * fs)))
    x = channel_inputs(trial, reduction, "sum" if aggregate == "any" else aggregate)[0][1]
    dx = _window_change(x, short)
    return np.column_stack([np.log1p(energy_statistic(trial.channels, fs, 0.1)),
                            np.log1p(energy_statistic(trial.channels, fs, 0.3)),
                            dx, np.abs(dx), _moving_sd(x, long_)])


def _labels(trial: RecordedTrial, tolerance_s: float) -> np.ndarray:
    """Training label per sample: 1 slip, 0 not, -1 left out."""
    if trial.trial_label is not None:
        return np.full(len(trial.t), int(trial.trial_label))
    y = np.zeros(len(trial.t), int)
    onset = trial.onset_t
    if onset is None:
        return y
    y[trial.t >= onset - tolerance_s] = -1
    y[(trial.slip > 0) & (trial.t < onset + POSITIVE_S)] = 1
    return y


def fit(trials: Sequence[RecordedTrial], *, tolerance_s: float, seed: int = 1, reduction: str = "z-sum",
        aggregate: str = "sum") -> Any:
    """A standardising logistic regression fitted on the samples of ``trials``.

    Raises
    ------
    DataError
        When the training trials hold only one class.

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> trials = read_folder(shipped_dataset())
    >>> model = fit(trials[1:], tolerance_s=0.1)                    # doctest: +SKIP
    >>> probability(model, trials[0]).shape                          # doctest: +SKIP
    (404,)
    """
    from sklearn.linear_model import LogisticRegression  # deferred: optional extra (learn)
    from sklearn.pipeline import make_pipeline  # deferred: optional extra (learn)
    from sklearn.preprocessing import StandardScaler  # deferred: optional extra (learn)

    xs, ys = [], []
    for tr in trials:
        y = _labels(tr, tolerance_s)
        keep = y >= 0
        xs.append(features(tr, reduction=reduction, aggregate=aggregate)[keep])
        ys.append(y[keep])
    y = np.concatenate(ys)
    if len(np.unique(y)) < 2:
        raise DataError("the learned baseline's training trials hold one class only")
    model = make_pipeline(StandardScaler(), LogisticRegression(class_weight="balanced", max_iter=2000,
                                                               random_state=seed))
    model.fit(np.concatenate(xs), y)
    return model


def probability(model: Any, trial: RecordedTrial, *, reduction: str = "z-sum", aggregate: str = "sum") -> np.ndarray:
    """The fitted model's probability of slip at every sample of ``trial``.

    Examples
    --------
    >>> probability.__name__
    'probability'
    """
    return model.predict_proba(features(trial, reduction=reduction, aggregate=aggregate))[:, 1]
