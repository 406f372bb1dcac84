"""Scoring one method's detections on one labelled trial (docs/benchmark.md, "Scoring").

Definitions, with ``t`` the trial's times, ``slip`` its label and ``t_cal`` the end of the
calibration span (the threshold was set from the samples before it):

* **onset** ``onset_t``: the time of the first sample labelled 1 (none for a control);
  the labelled slip lasts to the last sample of that first run of 1s (``slip_end_t``).
* **detection** ``detection_t``: the first detection at a sample with
  ``onset_t <= t <= slip_end_t``; none if the method stays silent while the slip is
  labelled. ``latency_ms = 1000 (detection_t - onset_t)``.
* **false alarms**: detections with ``t_cal <= t < onset_t`` (a slip trial) or
  ``t >= t_cal`` (a control); the scored time is ``onset_t - t_cal`` or ``t[-1] - t_cal``,
  and ``false_alarm_rate_per_min = 60 false_alarms / scored time``. Detections inside the
  calibration span are not scored (the threshold was fitted there), nor those after the onset.

Examples
--------
>>> import numpy as np
>>> t = np.arange(10) / 10
>>> slip = np.array([0, 0, 0, 0, 0, 0, 1, 1, 0, 0])
>>> det = np.zeros(10, bool); det[[1, 3, 7, 9]] = True
>>> s = score(t, slip, det, calibration_end=0.2)
>>> s.onset_t, s.detection_t, round(s.latency_ms, 6), s.false_alarms, round(s.false_alarm_rate_per_min, 6)
(0.6, 0.7, 100.0, 1, 150.0)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import DataError

__all__ = ["Score", "score"]


@dataclass(frozen=True)
class Score:
    """One method on one trial.

    Attributes
    ----------
    slips : bool
        The trial has a labelled slip.
    onset_t, slip_end_t : float
        First labelled slip sample and the end of its run (NaN for a control).
    detection_t, latency_ms : float
        First detection during the labelled slip and its delay after the onset (NaN: missed
        or a control).
    false_alarms : int
        Detections in the scored span before the onset (the whole scored span of a control).
    scored_s : float
        Length of that span (s).
    false_alarm_rate_per_min : float
        ``60 * false_alarms / scored_s`` (NaN when ``scored_s`` is 0).
    detections : int
        All detections in the trial, calibration span included.

    Examples
    --------
    >>> Score(False, np.nan, np.nan, np.nan, np.nan, 2, 30.0, 4.0, 3).detected
    False
    """

    slips: bool
    onset_t: float
    slip_end_t: float
    detection_t: float
    latency_ms: float
    false_alarms: int
    scored_s: float
    false_alarm_rate_per_min: float
    detections: int

    @property
    def detected(self) -> bool:
        """A slip trial whose slip the method detected."""
        return self.slips and bool(np.isfinite(self.detection_t))


def score(t, slip, detections, *, calibration_end: float) -> Score:
    """Score a detection sequence against the label (the definitions are in the module docstring).

    Parameters
    ----------
    t : array_like, shape (K,)
        Sample times (s), increasing.
    slip : array_like of 0/1, shape (K,)
        The label.
    detections : array_like of bool, shape (K,)
        True at each sample where the method detected slip.
    calibration_end : float
        End of the calibration span (s); must not be after the onset.

    Returns
    -------
    Score

    Raises
    ------
    DataError
        Arrays of different lengths, or a calibration span that reaches past the onset.

    Examples
    --------
    >>> import numpy as np
    >>> s = score(np.arange(5.0), np.zeros(5), np.array([0, 1, 0, 1, 1], bool), calibration_end=2.0)
    >>> s.false_alarms, s.scored_s, s.false_alarm_rate_per_min, s.detections
    (2, 2.0, 60.0, 3)
    """
    t = np.asarray(t, dtype=float)
    slip = np.asarray(slip) != 0
    det = np.asarray(detections, dtype=bool)
    if not (t.shape == slip.shape == det.shape) or t.ndim != 1:
        raise DataError(f"score: t, slip and detections differ in shape: {t.shape}, {slip.shape}, {det.shape}")
    nan = float("nan")
    on = np.flatnonzero(slip)
    if on.size:
        first = int(on[0])
        after = np.flatnonzero(~slip[first:])
        last = first + (int(after[0]) if after.size else len(t) - first) - 1
        onset_t, end_t = float(t[first]), float(t[last])
        if calibration_end > onset_t:
            raise DataError(f"calibration span ends at {calibration_end:g} s, after the slip onset at {onset_t:g} s")
        hits = np.flatnonzero(det[first:last + 1])
        detection_t = float(t[first + hits[0]]) if hits.size else nan
        latency = 1000.0 * (detection_t - onset_t) if hits.size else nan
        scored = (t >= calibration_end) & (t < onset_t)
        span = onset_t - calibration_end
    else:
        onset_t = end_t = detection_t = latency = nan
        scored = t >= calibration_end
        span = float(t[-1]) - calibration_end
    fa = int(np.count_nonzero(det & scored))
    rate = 60.0 * fa / span if span > 0 else nan
    return Score(bool(on.size), onset_t, end_t, detection_t, latency, fa, max(span, 0.0), rate,
                 int(np.count_nonzero(det)))
