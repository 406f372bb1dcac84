"""Every detector at every threshold of a grid, in the data's units (docs/benchmark.md, "Protocol").

A *detector* is one method at one rate, ready to run on one trial at any threshold
(:func:`prepare`): the registered methods (each with its threshold parameter set to the
value, nothing else changed), and two baselines that need no registered method:

* ``energy``: the energy of the sample-to-sample change of every channel read, summed over
  channels and over a causal window of :data:`ENERGY_WINDOW_S`; a detection is a rising
  edge of "energy over the threshold" (the threshold in squared channel units);
* ``learned``: a small classifier on windowed features (:mod:`slipreflex.benchmark.learned`),
  fitted on the training trials of each fold only; its statistic is the slip probability.

Its alarms are *episodes*: detections closer than the refractory gap are one alarm
(:func:`episode_starts`). On a trial with an onset, with tolerance ``tol``, the detection
window is ``[onset - tol, end of the labelled slip + tol]``; a detection there is a hit
(latency from the labelled onset, negative when it leads the label); an episode that starts
before the window is a false alarm, and the time before the window is the trial's negative
time. A control is negative time throughout. Time in alarm: the part of the negative time
within one refractory gap after a detection. A trial-level set (``# trial-label``)
asks only whether the trial alarmed at all.

Examples
--------
>>> t = np.arange(10) / 10
>>> episode_starts(t[[1, 2, 3, 7]], 0.15).tolist()
[0.1, 0.7]
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import methods as registry
from ..core.errors import DataError
from ..methods.baselines import rest_statistic
from ..methods.chain import run_chain
from .run import _quantum, _scaled, _trial_reflex, reduce_channels, to_rate
from .trials import RecordedTrial

__all__ = ["Sweep", "Detector", "prepare", "sweep", "grid", "episode_starts", "alarm_time", "score_at",
           "channel_inputs", "energy_statistic", "AGGREGATIONS", "BASELINES", "ENERGY", "LEARNED",
           "ENERGY_WINDOW_S", "GRID_POINTS", "GRID_DECADES"]

ENERGY, LEARNED = "energy", "learned"
#: The two baselines beside the registered methods.
BASELINES: tuple[str, ...] = (ENERGY, LEARNED)
#: How channels without a layout become what a chain method reads: each its own with the same
#: threshold and an alarm on any counting, their sum, or the length of the vector of their changes.
AGGREGATIONS: tuple[str, ...] = ("any", "sum", "magnitude")
#: The energy baseline's window (s): about the 48 ms x 2 of the paper's chain window, long enough
#: to hold several samples at 60 Hz (6), short against the shortest labelled slip (0.3 s).
ENERGY_WINDOW_S: float = 0.1
#: Thresholds per sweep and the decades they span below the largest value the statistic reaches:
#: 10 per decade (26 % apart), down to where every method fires on the noise.
GRID_POINTS, GRID_DECADES = 41, 4


@dataclass(frozen=True)
class Detector:
    """One method at one rate on one trial, runnable at any threshold.

    Attributes
    ----------
    method, rate : str
    t : numpy.ndarray
        Times of its samples (s).
    fs : float
        The rate it runs at (Hz).
    top : float
        A threshold at or above anything its statistic reaches on this trial.
    run : callable
        ``run(threshold) -> bool array`` over ``t``: its detections.

    Examples
    --------
    >>> d = Detector("x", "data", np.arange(3.0), 1.0, 2.0, lambda thr: np.array([0.0, 3.0, 1.0]) > thr)
    >>> d.run(2.0).tolist()
    [False, True, False]
    """

    method: str
    rate: str
    t: np.ndarray
    fs: float
    top: float
    run: Callable[[float], np.ndarray]


@dataclass(frozen=True)
class Sweep:
    """One detector on one trial at every threshold of its grid (arrays of the grid's length).

    Attributes
    ----------
    trial : str
    positive : bool
        The trial slips (a labelled onset, or its trial label).
    thresholds : numpy.ndarray
    hit : numpy.ndarray of bool
        Onset trials: a detection in the detection window; trial-level: any detection.
    latency_ms : numpy.ndarray
        First detection in the window after the labelled onset (NaN: none, or no onset).
    false_alarms : numpy.ndarray of int
        Episodes starting in the negative time.
    negative_s : float
        Negative time (s).
    alarm_s : numpy.ndarray
        Negative time in alarm (s).
    window_s : float
        Length of the detection window (NaN without an onset).

    Examples
    --------
    >>> s = Sweep("a", False, np.array([1.0]), np.array([False]), np.array([np.nan]), np.array([2]),
    ...           30.0, np.array([0.5]), np.nan)
    >>> float(s.false_alarms[0] * 60 / s.negative_s)
    4.0
    """

    trial: str
    positive: bool
    thresholds: np.ndarray
    hit: np.ndarray
    latency_ms: np.ndarray
    false_alarms: np.ndarray
    negative_s: float
    alarm_s: np.ndarray
    window_s: float


def episode_starts(det_t: np.ndarray, gap: float) -> np.ndarray:
    """Times of the first detection of each episode (detections closer than ``gap`` s merged).

    Examples
    --------
    >>> episode_starts(np.array([0.0, 0.2, 0.5, 0.6]), 0.25).tolist()
    [0.0, 0.5]
    """
    det_t = np.asarray(det_t, float)
    if not det_t.size:
        return det_t
    return det_t[np.r_[True, np.diff(det_t) > gap]]


def alarm_time(det_t: np.ndarray, gap: float, lo: float, hi: float) -> float:
    """Length of ``[lo, hi)`` within ``gap`` s after some detection (s).

    Examples
    --------
    >>> round(alarm_time(np.array([0.0, 0.1, 1.0]), 0.25, 0.0, 2.0), 6)
    0.6
    """
    d = np.asarray(det_t, float)
    d = d[(d + gap > lo) & (d < hi)]
    if not d.size or hi <= lo:
        return 0.0
    starts, ends = np.maximum(d, lo), np.minimum(d + gap, hi)
    total, cur_s, cur_e = 0.0, starts[0], ends[0]
    for s, e in zip(starts[1:], ends[1:]):
        if s > cur_e:
            total += cur_e - cur_s
            cur_s = s
        cur_e = max(cur_e, e)
    return float(total + cur_e - cur_s)


def _slip_window(trial: RecordedTrial) -> tuple[float, float] | None:
    """Labelled onset and the end of its first run of slip samples, or None."""
    on = np.flatnonzero(trial.slip)
    if not on.size:
        return None
    first = int(on[0])
    after = np.flatnonzero(trial.slip[first:] == 0)
    last = first + (int(after[0]) if after.size else len(trial.t) - first) - 1
    return float(trial.t[first]), float(trial.t[last])


def score_at(trial: RecordedTrial, t: np.ndarray, events: np.ndarray, *, refractory_s: float,
             tolerance_s: float) -> tuple[bool, float, int, float, float, float]:
    """One trial at one threshold: ``(hit, latency_ms, false_alarms, negative_s, alarm_s, window_s)``.

    Examples
    --------
    >>> from slipreflex.benchmark.trials import RecordedTrial
    >>> from pathlib import Path
    >>> t = np.arange(20) / 10
    >>> tr = RecordedTrial("x", Path("x.csv"), t, np.zeros((20, 1)), ("a",), (t >= 1.5).astype(np.int8), None)
    >>> ev = np.isin(np.arange(20), [2, 3, 9, 15])
    >>> hit, lat, fa, neg, alarm, win = score_at(tr, t, ev, refractory_s=0.25, tolerance_s=0.1)
    >>> hit, round(lat, 6), fa, round(neg, 6), round(alarm, 6), round(win, 6)
    (True, 0.0, 2, 1.4, 0.6, 0.5)
    """
    det_t = t[np.asarray(events, bool)]
    t0, t1 = float(t[0]), float(t[-1])
    nan = float("nan")
    if trial.trial_label is not None:
        neg = 0.0 if trial.trial_label else t1 - t0
        fa = 0 if trial.trial_label else len(episode_starts(det_t, refractory_s))
        return bool(det_t.size), nan, fa, neg, alarm_time(det_t, refractory_s, t0, t0 + neg), nan
    win = _slip_window(trial)
    if win is None:
        starts = episode_starts(det_t, refractory_s)
        return False, nan, len(starts), t1 - t0, alarm_time(det_t, refractory_s, t0, t1), nan
    lo, hi = max(t0, win[0] - tolerance_s), min(t1, win[1] + tolerance_s)
    inside = det_t[(det_t >= lo) & (det_t <= hi)]
    starts = episode_starts(det_t, refractory_s)
    fa = int(np.count_nonzero(starts < lo))
    lat = 1000.0 * (float(inside[0]) - win[0]) if inside.size else nan
    return bool(inside.size), lat, fa, lo - t0, alarm_time(det_t, refractory_s, t0, lo), hi - lo


def sweep(det: Detector, trial: RecordedTrial, thresholds: np.ndarray, *, refractory_s: float,
          tolerance_s: float) -> Sweep:
    """Score ``det`` on ``trial`` at every threshold.

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> tr = read_folder(shipped_dataset())[-1]
    >>> d = prepare(ENERGY, tr, "data")
    >>> s = sweep(d, tr, grid(d.top), refractory_s=0.25, tolerance_s=0.1)
    >>> bool(s.hit[20]), bool(s.hit[-1]), int(s.false_alarms[-1])
    (True, False, 0)
    """
    rows = [score_at(trial, det.t, det.run(float(thr)), refractory_s=refractory_s, tolerance_s=tolerance_s)
            for thr in thresholds]
    hit, lat, fa, neg, alarm, win = zip(*rows)
    return Sweep(trial.name, trial.positive, np.asarray(thresholds, float), np.array(hit, bool),
                 np.array(lat, float), np.array(fa, int), float(neg[0]), np.array(alarm, float), float(win[0]))


def grid(top: float, points: int = GRID_POINTS, decades: float = GRID_DECADES) -> np.ndarray:
    """Thresholds from ``top / 10**decades`` to ``top``, evenly spaced in log.

    Examples
    --------
    >>> grid(100.0, 3, 2).tolist()
    [1.0, 10.0, 100.0]
    """
    top = float(top) if top > 0 else 1.0
    return np.geomspace(top / 10.0 ** decades, top, points)


def channel_inputs(trial: RecordedTrial, reduction: str, aggregate: str) -> list[tuple[str, np.ndarray]]:
    """What a chain method reads: a layout's reduction, or the channels aggregated (:data:`AGGREGATIONS`).

    Examples
    --------
    >>> from pathlib import Path
    >>> t = np.arange(3.0)
    >>> tr = RecordedTrial("x", Path("x.csv"), t, np.array([[0, 0], [3, 4], [3, 4.0]]), ("a", "b"),
    ...                    np.zeros(3, np.int8), None)
    >>> [(n, x.tolist()) for n, x in channel_inputs(tr, "z-sum", "magnitude")]
    [('magnitude of 2 channels', [0.0, 5.0, 5.0])]
    """
    chans = reduce_channels(trial, reduction)
    if trial.layout is not None or aggregate == "any" or len(chans) == 1:
        return chans
    x = np.stack([c for _, c in chans], axis=1)
    if aggregate == "sum":
        return [(f"sum of {len(chans)} channels", x.sum(axis=1))]
    return [(f"magnitude of {len(chans)} channels", np.linalg.norm(x, axis=1))]


def energy_statistic(x: np.ndarray, fs: float, window_s: float = ENERGY_WINDOW_S) -> np.ndarray:
    """Energy of the sample-to-sample change of ``x`` (K, C), summed over channels and a causal window.

    Examples
    --------
    >>> energy_statistic(np.array([[0.0], [1.0], [1.0], [1.0], [3.0]]), fs=10.0, window_s=0.2).tolist()
    [0.0, 1.0, 1.0, 0.0, 4.0]
    """
    x = np.asarray(x, float).reshape(len(x), -1)
    e = np.r_[0.0, (np.diff(x, axis=0) ** 2).sum(axis=1)]
    w = max(1, int(round(window_s * fs)))
    c = np.r_[0.0, np.cumsum(e)]
    return c[1:] - c[np.maximum(np.arange(1, len(c)) - w, 0)]


def rising(stat: np.ndarray, threshold: float) -> np.ndarray:
    """Rising edges of ``stat > threshold`` (the first sample of each run above).

    Examples
    --------
    >>> rising(np.array([0, 2, 3, 0, 5.0]), 1.0).tolist()
    [False, True, False, False, True]
    """
    over = np.asarray(stat) > threshold
    return over & ~np.r_[False, over[:-1]]


def _at_rate(trial: RecordedTrial, x: np.ndarray, fs_method: float, rate: str):
    if rate == "data":
        return trial.t, x, trial.fs
    return to_rate(trial.t, x, fs_method)


def _chain(name: str, trial: RecordedTrial, rate: str, reduction: str, aggregate: str) -> Detector:
    spec = registry.get(name)
    base = _trial_reflex(name)
    detect = spec.detections
    assert detect is not None
    runs: list[tuple[np.ndarray, dict[str, Any]]] = []
    top = 0.0
    for _, x in channel_inputs(trial, reduction, aggregate):
        step = _quantum(x)
        t, x, fs = _at_rate(trial, x, spec.fs, rate)
        over: dict[str, Any] = {"fs": fs, **(_scaled(base, spec.fs, fs) if rate == "data" else {})}
        if base.params.dath_floor > 0:
            over["dath_floor"] = step or base.params.dath_floor
        filtered = run_chain(x, dataclasses.replace(base.params, **over)).filtered
        top = max(top, 1.05 * float(np.ptp(filtered)))
        runs.append((x, over))

    def run(threshold: float) -> np.ndarray:
        return np.logical_or.reduce([detect(registry.make(name, **over, threshold=threshold), x).events
                                     for x, over in runs])

    return Detector(name, rate, t, fs, top, run)


def _tactile(name: str, trial: RecordedTrial, rate: str) -> Detector:
    spec = registry.get(name)
    base = _trial_reflex(name)
    detect = spec.detections
    assert detect is not None
    frames = trial.normal_frames()
    t, frames, fs = _at_rate(trial, frames - frames[0], spec.fs, rate)
    over = _scaled(base, spec.fs, fs) if rate == "data" else {}
    top = 1.05 * float(np.max(np.abs(rest_statistic(frames, name, fs)), initial=0.0))

    def run(threshold: float) -> np.ndarray:
        reflex = registry.make(name, context=registry.MethodContext(speed=1.0), fs=fs, threshold=threshold, **over)
        return np.asarray(detect(reflex, frames).events, bool)

    return Detector(name, rate, t, fs, top, run)


def statistic_detector(name: str, rate: str, t: np.ndarray, fs: float, stat: np.ndarray) -> Detector:
    """A detector whose detections are the rising edges of ``stat`` over the threshold.

    Examples
    --------
    >>> d = statistic_detector("s", "data", np.arange(3.0), 1.0, np.array([0.0, 2.0, 0.0]))
    >>> d.run(1.0).tolist(), d.top
    ([False, True, False], 2.0)
    """
    stat = np.asarray(stat, float)
    return Detector(name, rate, t, fs, float(np.max(stat, initial=0.0)), lambda thr: rising(stat, thr))


def prepare(name: str, trial: RecordedTrial, rate: str, *, reduction: str = "z-sum",
            aggregate: str = "any") -> Detector:
    """Method ``name`` (registered, or :data:`ENERGY`) on ``trial`` at ``rate``.

    Raises
    ------
    DataError
        ``energy`` resampled (it has no rate of its own).

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> d = prepare("nmsd", read_folder(shipped_dataset())[0], "data")
    >>> int(d.run(d.top).sum()), int(d.run(d.top / 100).sum()) > 0
    (0, True)
    """
    if name == ENERGY:
        if rate != "data":
            raise DataError("energy runs at the data's rate only")
        return statistic_detector(ENERGY, rate, trial.t, trial.fs, energy_statistic(trial.channels, trial.fs))
    if registry.get(name).input_kind == "slip":
        return _chain(name, trial, rate, reduction, aggregate)
    return _tactile(name, trial, rate)


def sweeps_of(dets: Sequence[Detector], trials: Sequence[RecordedTrial], thresholds: np.ndarray, *,
              refractory_s: float, tolerance_s: float) -> list[Sweep]:
    """:func:`sweep` of each detector on its trial (same order).

    Examples
    --------
    >>> sweeps_of([], [], np.ones(1), refractory_s=0.25, tolerance_s=0.1)
    []
    """
    return [sweep(d, tr, thresholds, refractory_s=refractory_s, tolerance_s=tolerance_s)
            for d, tr in zip(dets, trials)]
