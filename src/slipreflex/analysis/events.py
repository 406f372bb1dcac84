"""Segmenting an induction interval into slip events (pours: every slip is its own event).

A pour makes the bottle slip several times (the paper: near 200 ml and near
400 ml). The paper analysed "all slips individually, as if they belonged to a
separate trial". We segment with the same accelerometer envelope, threshold and
episodes as the onset detector (:func:`slipreflex.analysis.onset.episodes`:
runs above threshold inside the induction interval that peak at three times
the threshold or more); episodes closer than ``merge_s`` (default
``MERGE_S`` = 1 s) are one slip. Each slip's onset is the
first above-threshold sample of its episode, and its *window* (where its
controller response is looked for) runs from ``lead_s`` before the onset to
``lead_s`` before the next slip's onset (or the end of the recording).

Examples
--------
>>> import numpy as np
>>> t = np.arange(0, 10, 0.01)
>>> env = np.zeros_like(t); env[(t > 2) & (t < 2.3)] = 1; env[(t > 6) & (t < 6.2)] = 1
>>> [(round(e.onset, 2), round(e.window[1], 2)) for e in segment_events(t, env, 0.3, (1.0, 9.0))]
[(2.01, 5.91), (6.01, 10.0)]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import DataError
from .onset import OnsetParams, accel_envelope, episodes, rest_threshold_of, select_axis

__all__ = ["MERGE_S", "LEAD_S", "SlipEvent", "segment_events", "first_pour_slip"]

#: Above-threshold episodes closer than this (s) belong to one slip.
MERGE_S: float = 1.0
#: A slip's window starts this long (s) before its onset.
LEAD_S: float = 0.1


@dataclass(frozen=True, slots=True)
class SlipEvent:
    """One slip found in the accelerometer.

    Attributes
    ----------
    onset : float
        Onset time (s).
    end : float
        Last above-threshold time of the slip (s).
    window : (float, float)
        Where the controller's response to this slip is looked for (s).

    Examples
    --------
    >>> SlipEvent(1.0, 1.2, (0.9, 3.0)).duration
    0.2
    """

    onset: float
    end: float
    window: tuple[float, float]

    @property
    def duration(self) -> float:
        """Above-threshold duration (s).

        Examples
        --------
        >>> SlipEvent(2.0, 2.5, (1.9, 4.0)).duration
        0.5
        """
        return round(self.end - self.onset, 12)


def segment_events(t, envelope, threshold: float, interval: tuple[float, float], *,
                   merge_s: float = MERGE_S, lead_s: float = LEAD_S,
                   t_end: float | None = None, params=None) -> list[SlipEvent]:
    """Split the above-threshold samples inside ``interval`` into slip events.

    Parameters
    ----------
    t, envelope : array_like, shape (K,)
        Times (s) and the rectified, filtered accelerometer.
    threshold : float
        Envelope threshold (from the rest period).
    interval : (float, float)
        Induction interval (s): candidates outside are ignored.
    merge_s, lead_s : float
        See the module docstring.
    t_end : float, optional
        End of the last window (default: just after the last sample).
    params : OnsetParams, optional
        Episode rules (``join_s``, ``peak_factor``).

    Returns
    -------
    list of SlipEvent, in time order (empty when nothing crossed).

    Examples
    --------
    >>> import numpy as np
    >>> segment_events(np.arange(5.0), np.zeros(5), 1.0, (0.0, 4.0))
    []
    """
    t = np.asarray(t, dtype=np.float64)
    env = np.asarray(envelope, dtype=np.float64)
    if t.shape != env.shape or t.ndim != 1:
        raise DataError(f"times and envelope must be 1-D of equal length, got {t.shape}, {env.shape}")

    lo, hi = float(interval[0]), float(interval[1])
    eps = episodes(t, env, threshold, (lo, hi), params)
    if not eps:
        return []
    groups: list[list[int]] = [[eps[0][0], eps[0][1]]]
    for i0, i1 in eps[1:]:
        if t[i0] - t[groups[-1][1]] > merge_s:
            groups.append([i0, i1])
        else:
            groups[-1][1] = i1
    end_all = float(t[-1] + (t[-1] - t[-2] if t.size > 1 else 0.0)) if t_end is None else float(t_end)
    onsets = [float(t[g[0]]) for g in groups]
    out = []
    for i, (_, i1) in enumerate(groups):
        w0 = max(lo, onsets[i] - lead_s)
        w1 = onsets[i + 1] - lead_s if i + 1 < len(onsets) else end_all
        out.append(SlipEvent(onsets[i], float(t[i1]), (w0, w1)))
    return out


def first_pour_slip(t, accel, volume_ml, window: tuple[float, float], params=None) -> tuple[float, float]:
    """(onset s, volume ml at it) of a pour recording's first slip, as a pour trial is analysed (NaN if none).

    The axis, envelope and rest threshold of :func:`slipreflex.analysis.onset.detect_onset`, the
    episodes segmented into slips as :func:`segment_events` does for a pour; the
    volume is ``volume_ml`` (the flow sensor's) at the first slip's onset. The open-loop
    calibration of the simulated plant calls it (``slipreflex.sim.calibration``).

    Examples
    --------
    >>> t = np.arange(0, 6, 1 / 333.0)
    >>> acc = np.random.default_rng(0).normal(0, 0.002, (t.size, 3))
    >>> acc[t >= 4.0, 2] += 0.05
    >>> on, ml = first_pour_slip(t, acc, 10.0 * t, (1.0, 5.9))
    >>> bool(4.0 <= on < 4.03), bool(40.0 <= ml < 40.3)
    (True, True)
    """

    p = params or OnsetParams()
    t = np.asarray(t, dtype=float)
    lo, hi = float(window[0]), float(window[1])
    if t.size < 8 or hi <= lo:
        return float("nan"), float("nan")
    a = np.asarray(accel, dtype=float)
    axis = select_axis(t, a, (lo, hi), baseline_s=p.baseline_s)
    env = accel_envelope(t, a[:, axis], p)
    found = segment_events(t, env, rest_threshold_of(t, env, p), (lo, hi), params=p)
    if not found:
        return float("nan"), float("nan")
    on = found[0].onset
    return on, float(np.interp(on, t, np.asarray(volume_ml, dtype=float)))
