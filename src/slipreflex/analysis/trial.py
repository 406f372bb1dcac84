"""From one trial's recorded streams to the paper's metrics, one row per slip event.

:class:`TrialStreams` holds only what the analysis needs (accelerometer,
commanded finger position, induction interval, the simulator's truth), so the
analysis runs the same on a simulated trial, a recording, or hand-built arrays.
:func:`analyse_trial` applies the paper's recipe:

* **drop**: one slip; onset = first accelerometer candidate inside the
  induction interval (:func:`~slipreflex.analysis.onset.detect_onset`); its
  window runs from the start of the induction interval to the end of the trial.
* **pour**: every slip is its own event
  (:func:`~slipreflex.analysis.events.segment_events` on the same envelope and
  threshold); each event has its own window.

For each event: response time, controller activity (span and, for the
tactile methods, the closing time), the paper's *total* (span for fixed/DATH,
closing time for NMSD/SWT-SD), success, and the simulator's true onset with
the error of the accelerometer estimate against it.

Examples
--------
>>> import numpy as np
>>> fs = 333.0
>>> t = np.arange(int(3 * fs)) / fs
>>> acc = np.random.default_rng(0).normal(0, 0.002, (t.size, 3)); acc[:, 2] += 1
>>> acc[t >= 1.5, 1] += 0.1
>>> s = TrialStreams(experiment="drop", method="dath", bottle="TR", seed=1, trial=0,
...                  accel_t=t, accel=acc, cmd_t=[1.56, 1.60, 1.70], cmd_v=[210., 230., 240.],
...                  base_command=200.0, induction=(1.2, 2.2), t_end=3.0,
...                  fell_out_time=float("nan"), true_onsets=[1.49], method_fs=333.0)
>>> row = analyse_trial(s)[0]
>>> round(row["response_ms"]), round(row["total_ms"]), row["success"]
(58, 140, True)
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import methods
from ..core import experiment_specs
from ..core.errors import ParameterError
from .events import LEAD_S, MERGE_S, segment_events
from .metrics import ACTIVITY_GAP_S, controller_activity, response_time, suppressed
from .onset import OnsetParams, accel_envelope, detect_onset, rest_threshold_of, select_axis

__all__ = ["TrialRow", "TrialStreams", "analyse_trial", "RESULT_COLUMNS", "MAX_RESPONSE_S",
           "true_onset_for", "EARLY_DETECTION_S"]

#: A command increase later than this after the onset (s) is not a response to that slip.
MAX_RESPONSE_S: float = 1.0

_NAN = float("nan")


@dataclass(frozen=True)
class TrialRow(Mapping):
    """One slip event of one trial: a row of results.csv, typed, one meaning per field.

    :func:`analyse_trial` fills the analysis fields; the experiment runner adds
    the trial's grasp and the simulator's truth (NaN when unknown, e.g. on
    hardware). Rows read back from a CSV file (:meth:`from_dict`) have the
    same types as rows just computed. A row is also a read-only mapping of its
    fields (``row["name"]``, ``dict(row)``), so code written for the CSV's dicts reads it.

    Attributes
    ----------
    experiment, bottle, method : str
    trial, seed, event : int
        Trial index, the trial's seed, and the event's index within the trial.
    n_events, n_true_slips : int
        Slips the accelerometer found in the trial, and slips the simulator had.
    onset_s, true_onset_s, onset_error_ms : float
        Accelerometer onset, the simulator's true onset, estimate minus truth.
    axis : int
        Accelerometer axis used (0, 1, 2).
    response_ms, total_ms : float
        The paper's response time and total controller time (NaN: no response).
    span_ms, closing_ms : float
        First-to-last command change, and the closing time generated (ramp methods).
    n_increases : int
        Command increases in the event's window.
    rise : float
        How far the command rose in the window (finger units).
    first_change_s, last_change_s : float
        First and last command change in the window.
    success, fell_out : bool
        Slip suppressed before the object slipped out; the object fell out at all.
    fell_out_s : float
        When it fell out (NaN if it never did).
    window_start_s, window_end_s : float
        The event's analysis window.
    load_at_onset : float
        The load signal at the onset (poured ml), NaN without one.
    threshold : float
        The method's detection threshold (reported only).
    grasp_position, grasp_force_n, perturbation_s : float
        The trial's grasp (slip-finger position, force) and when the load was applied.
    true_slip_ms, true_slip_mm : float
        How long and how far the simulator's slip episode slid.
    fell_before_load : bool
        The object left the grasp before the perturbation: the trial tested the grasp, not
        the method, and is reported apart (void), never scored.
    grip_without_slip : float
        How far the hand closed in the trial (finger units) while no true slip was under
        way (simulator truth; NaN on hardware): the same on every row of the trial.

    Examples
    --------
    >>> r = TrialRow(experiment="drop", bottle="TR", method="dath", trial=0, seed=1, event=0,
    ...              n_events=1, success=True)
    >>> r.success, r["method"], math.isnan(r.response_ms)
    (True, 'dath', True)
    >>> TrialRow.from_dict({**r.as_dict(), "success": "False", "trial": "3"}).trial
    3
    """

    experiment: str
    bottle: str
    method: str
    trial: int
    seed: int
    event: int
    n_events: int
    n_true_slips: int = 0
    onset_s: float = _NAN
    true_onset_s: float = _NAN
    onset_error_ms: float = _NAN
    axis: int = 0
    response_ms: float = _NAN
    total_ms: float = _NAN
    span_ms: float = _NAN
    closing_ms: float = _NAN
    n_increases: int = 0
    rise: float = 0.0
    first_change_s: float = _NAN
    last_change_s: float = _NAN
    success: bool = False
    fell_out: bool = False
    fell_out_s: float = _NAN
    window_start_s: float = _NAN
    window_end_s: float = _NAN
    load_at_onset: float = _NAN
    threshold: float = _NAN
    grasp_position: float = _NAN
    grasp_force_n: float = _NAN
    perturbation_s: float = _NAN
    true_slip_ms: float = _NAN
    true_slip_mm: float = _NAN
    fell_before_load: bool = False
    grip_without_slip: float = _NAN

    def __getitem__(self, name: str) -> Any:
        if not isinstance(name, str) or name not in _FIELDS:
            raise KeyError(name)
        return getattr(self, name)

    def __iter__(self):
        return (f.name for f in dataclasses.fields(self))

    def __len__(self) -> int:
        return len(dataclasses.fields(self))

    def as_dict(self) -> dict[str, Any]:
        """The row as a dict in column order.

        Examples
        --------
        >>> list(TrialRow("drop", "TR", "dath", 0, 1, 0, 1).as_dict())[:3]
        ['experiment', 'bottle', 'method']
        """
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrialRow:
        """A row from a dict, e.g. a results.csv line (strings parsed; "" is NaN; unknown keys ignored).

        Examples
        --------
        >>> TrialRow.from_dict({"experiment": "pour", "bottle": "DK", "method": "nmsd", "trial": "2",
        ...                     "seed": "9", "event": "0", "n_events": "1", "success": "True",
        ...                     "response_ms": ""}).success
        True
        """
        kw = {}
        for f in dataclasses.fields(cls):
            if f.name in data:
                kw[f.name] = _parse(f.name, str(f.type), data[f.name])
        return cls(**kw)


def _parse(name: str, kind: str, value: Any) -> Any:
    if not isinstance(value, str):
        return value
    text = value.strip()
    if kind == "bool":
        if text not in ("True", "False"):
            raise ParameterError(f"{name}: expected True or False, got {value!r}")
        return text == "True"
    if kind == "int":
        return int(text)
    if kind == "float":
        return float(text) if text else _NAN
    return value


#: Columns of results.csv, in order (one definition: the fields of :class:`TrialRow`).
RESULT_COLUMNS: tuple[str, ...] = tuple(f.name for f in dataclasses.fields(TrialRow))
_FIELDS = frozenset(RESULT_COLUMNS)


@dataclass(frozen=True)
class TrialStreams:
    """What the analysis needs from one trial.

    Parameters
    ----------
    experiment : str
        A registered experiment (:mod:`slipreflex.core.experiment_specs`).
    method, bottle : str
    seed, trial : int
        The trial's seed and index (reported, not used).
    accel_t, accel : array_like
        Accelerometer times (s) and (K, 3) values (g); the first 200 ms are rest.
    cmd_t, cmd_v : array_like
        Times (s) and values of the commands the reflex issued.
    base_command : float
        The command in force before the reflex's first one (the grasp position).
    induction : (float, float)
        Interval (s) where slip was induced.
    t_end : float
        End of the recording (s).
    fell_out_time : float
        When the object fell out of the grasp (s), NaN if it never did.
    true_onsets : array_like
        The simulator's true slip onsets (s); empty when unknown.
    method_fs : float
        The reflex's rate (Hz), for the closing time of ramp methods.
    load_t, load : array_like, optional
        A load signal (e.g. poured volume in ml) to report at each onset.
    threshold : float
        The reflex's detection threshold (reported only).
    ramp : bool or None
        Whether the method's command is a closing ramp, so its *total* is the
        closing time it generated (NMSD, SWT-SD); None reads it from the
        method's specification (:mod:`slipreflex.methods`), False for a method
        that is not registered.

    Examples
    --------
    >>> TrialStreams(experiment="drop", method="nmsd", bottle="DK", seed=0, trial=0,
    ...              accel_t=[0, 1], accel=[[0, 0, 1], [0, 0, 1]], cmd_t=[], cmd_v=[],
    ...              base_command=0.0, induction=(0.5, 1.0), t_end=1.0,
    ...              fell_out_time=float("nan"), true_onsets=[], method_fs=260.0).ramp
    True
    """

    experiment: str
    method: str
    bottle: str
    seed: int
    trial: int
    accel_t: Any
    accel: Any
    cmd_t: Any
    cmd_v: Any
    base_command: float
    induction: tuple[float, float]
    t_end: float
    fell_out_time: float
    true_onsets: Any
    method_fs: float
    load_t: Any = None
    load: Any = None
    threshold: float = float("nan")
    ramp: bool | None = None

    def __post_init__(self) -> None:
        experiment_specs.get(self.experiment)   # a registered experiment (else a one-line error)
        if self.ramp is None:
            registered = self.method.casefold() in methods.names() if isinstance(self.method, str) else False
            object.__setattr__(self, "ramp", methods.get(self.method).ramp if registered else False)


#: A detected onset may come this much (s) before the simulator's own stick -> slip instant
#: and still be that slip's (the accelerometer feels the load step a few samples early).
EARLY_DETECTION_S: float = 0.1


def true_onset_for(truth: np.ndarray, onset: float, induced: float, hi: float) -> float:
    """The true onset of the slip a detected ``onset`` belongs to, NaN if none.

    The slip under way when it was detected: the last true onset after ``induced`` (when
    the perturbation could cause a slip) and at or before ``onset`` +
    :data:`EARLY_DETECTION_S`. A slow rate-and-state slip creeps for a second or more
    before its acceleration shows, so the truth may be far before the detection; a
    later slip never is (a nearest-in-time rule matched a creeping pour slip detected
    1.3 s late to the next slip, 12.6 s later). With no detection (NaN), the first true
    onset in [``induced``, ``hi``).

    Examples
    --------
    >>> truth = np.array([14.689, 28.568])
    >>> true_onset_for(truth, 15.963, 3.0, 30.5), true_onset_for(truth, 30.666, 3.0, 34.5)
    (14.689, 28.568)
    >>> true_onset_for(truth, 10.0, 3.0, 34.5)      # a detection before any slip: none
    nan
    """
    if math.isnan(onset):
        cand = truth[(truth >= induced) & (truth < hi)]
        return float(cand[0]) if cand.size else float("nan")
    cand = truth[(truth >= induced) & (truth <= onset + EARLY_DETECTION_S)]
    return float(cand[-1]) if cand.size else float("nan")


def _load_at(s: TrialStreams, t: float) -> float:
    if s.load_t is None or math.isnan(t):
        return float("nan")
    lt = np.asarray(s.load_t, dtype=float)
    lv = np.asarray(s.load, dtype=float)
    if lt.size == 0:
        return float("nan")
    return float(np.interp(t, lt, lv))


def analyse_trial(s: TrialStreams, onset_params: OnsetParams | None = None, *,
                  merge_s: float = MERGE_S, lead_s: float = LEAD_S,
                  gap: float = ACTIVITY_GAP_S,
                  max_response_s: float = MAX_RESPONSE_S) -> list[TrialRow]:
    """The paper's metrics for every slip event of one trial.

    The controller's response to a slip is its first command increase in the
    slip's window and no later than ``max_response_s`` after the onset;
    without one, response and total are NaN (the method did not react to that
    slip).

    Returns
    -------
    list of TrialRow
        One row per slip event; a trial
        in which the accelerometer found no slip gives one row with
        ``event = 0``, ``n_events = 0`` and NaN timings (success still says
        whether the object stayed in the grasp).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(0, 20, 1 / 333.0)
    >>> acc = np.random.default_rng(2).normal(0, 0.002, (t.size, 3))
    >>> for t0 in (6.0, 13.0):
    ...     acc[(t >= t0) & (t < t0 + 0.3), 0] += 0.05
    >>> s = TrialStreams(experiment="pour", method="nmsd", bottle="DK", seed=3, trial=1,
    ...                  accel_t=t, accel=acc, cmd_t=6.05 + np.arange(12) / 260.0,
    ...                  cmd_v=200 + np.arange(1, 13) * 2.0, base_command=200.0,
    ...                  induction=(1.0, 19.0), t_end=20.0, fell_out_time=float("nan"),
    ...                  true_onsets=[5.98, 12.99], method_fs=260.0)
    >>> rows = analyse_trial(s)
    >>> [r["event"] for r in rows], round(rows[0]["total_ms"], 1), bool(np.isnan(rows[1]["response_ms"]))
    ([0, 1], 46.2, True)
    """
    p = onset_params or OnsetParams()
    t = np.asarray(s.accel_t, dtype=float)
    acc = np.asarray(s.accel, dtype=float)
    cmd_t = np.asarray(s.cmd_t, dtype=float).ravel()
    cmd_v = np.asarray(s.cmd_v, dtype=float).ravel()
    truth = np.sort(np.asarray(s.true_onsets, dtype=float).ravel())
    lo, hi = float(s.induction[0]), float(s.induction[1])
    fell = float(s.fell_out_time)

    if experiment_specs.get(s.experiment).slip_events == "single":
        on = detect_onset(t, acc, (lo, hi), p)
        events = [(on.time, (lo, float(s.t_end)))]
        axis, thr = on.axis, on.threshold
    else:
        axis = select_axis(t, acc, (lo, hi), baseline_s=p.baseline_s)
        env = accel_envelope(t, acc[:, axis], p)
        thr = rest_threshold_of(t, env, p)
        found = segment_events(t, env, thr, (lo, hi), merge_s=merge_s, lead_s=lead_s,
                               t_end=float(s.t_end), params=p)
        events = [(e.onset, e.window) for e in found] or [(float("nan"), (lo, float(s.t_end)))]
    n_events = 0 if math.isnan(events[0][0]) else len(events)

    rows = []
    for i, (onset, window) in enumerate(events):
        first_by = window[1] if math.isnan(onset) else min(window[1], onset + max_response_s)
        resp = response_time(onset, cmd_t, cmd_v, window=(window[0], first_by), base=s.base_command)
        act = controller_activity(cmd_t, cmd_v, window=window, base=s.base_command, gap=gap)
        if act.n_increases and act.first >= first_by:
            act = controller_activity(cmd_t, cmd_v, window=(window[0], first_by),
                                      base=s.base_command, gap=gap)
        closing = act.closing_time(s.method_fs) if s.ramp else float("nan")
        total = closing if s.ramp else (act.span if act.n_increases else float("nan"))
        if math.isnan(onset):  # no slip found: activity is reported, but it is no slip's total
            total = float("nan")
        true_on = true_onset_for(truth, onset, lo, window[1])
        rows.append(TrialRow(
            experiment=s.experiment, bottle=s.bottle, method=s.method,
            trial=int(s.trial), seed=int(s.seed), event=i, n_events=n_events,
            n_true_slips=int(((truth >= lo) & (truth <= float(s.t_end))).sum()),
            onset_s=onset, true_onset_s=true_on, onset_error_ms=(onset - true_on) * 1e3,
            axis=int(axis), response_ms=resp * 1e3, total_ms=total * 1e3,
            span_ms=act.span * 1e3, closing_ms=closing * 1e3,
            n_increases=int(act.n_increases), rise=float(act.rise),
            first_change_s=act.first, last_change_s=act.last,
            success=bool(suppressed(fell, window[1])), fell_out=not math.isnan(fell), fell_out_s=fell,
            window_start_s=float(window[0]), window_end_s=float(window[1]),
            load_at_onset=_load_at(s, onset), threshold=float(s.threshold)))
    return rows
