"""The paper's per-slip metrics on recorded streams (docs/method.md section 4).

All times are in seconds on the recording's clock.

* **Response time** (:func:`response_time`): from the slip onset to the first
  *increase* of the commanded finger position inside the slip's window. It can
  be negative when the controller moved before the accelerometer crossed its
  threshold (we keep the sign; the paper's numbers are all positive).
* **Controller activity** (:func:`controller_activity`): the increases of the
  commanded position that belong to the slip: from the first increase in the
  window, every further increase closer than ``gap`` (default
  ``ACTIVITY_GAP_S`` = 0.5 s, about the MPI's 10-window reset horizon) to the
  previous one. Its **span** (first to last change) is the paper's *total
  controller time* for the fixed and DATH chains. For NMSD and SWT-SD the paper
  reports the *total closing time generated*; their command is a ramp with one
  increase per closing sample, so it is ``n_increases / fs`` of the method.
* **Success** (:func:`suppressed`): the slip was suppressed before the object
  slipped out completely, i.e. the object had not fallen out of the grasp by
  the end of the slip's window.

Examples
--------
>>> import numpy as np
>>> cmd_t = np.array([0.10, 1.05, 1.10, 1.15, 1.20])
>>> cmd_v = np.array([100., 100., 110., 125., 125.])
>>> response_time(1.0, cmd_t, cmd_v, window=(0.9, 3.0))
0.1
>>> a = controller_activity(cmd_t, cmd_v, window=(0.9, 3.0))
>>> round(a.span, 3), a.n_increases
(0.05, 2)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.errors import DataError, ParameterError

__all__ = ["ACTIVITY_GAP_S", "Activity", "increases", "response_time", "controller_activity",
           "suppressed", "grip_without_slip"]

#: Largest pause (s) between two command increases of the same slip.
ACTIVITY_GAP_S: float = 0.5


def _commands(cmd_t, cmd_v) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(cmd_t, dtype=np.float64).ravel()
    v = np.asarray(cmd_v, dtype=np.float64).ravel()
    if t.shape != v.shape:
        raise DataError(f"command times and values differ in length: {t.size} != {v.size}")
    if t.size and not (np.isfinite(t).all() and np.isfinite(v).all()):
        raise DataError("command stream holds non-finite values")
    if t.size > 1 and (np.diff(t) < 0).any():
        raise DataError("command times must not decrease")
    return t, v


def _window(window) -> tuple[float, float]:
    lo, hi = float(window[0]), float(window[1])
    if math.isnan(lo) or math.isnan(hi) or not hi > lo:
        raise ParameterError(f"window must be (start, end) with end > start, got {window}")
    return lo, hi


def increases(cmd_t, cmd_v, *, base: float | None = None) -> np.ndarray:
    """Indices of commands that raise the commanded position above the previous one.

    Parameters
    ----------
    cmd_t, cmd_v : array_like
        Command times (s) and values (finger units), in time order.
    base : float, optional
        The command in force before the first one (e.g. the grasp position);
        without it the first command is not counted as an increase.

    Returns
    -------
    numpy.ndarray of int

    Examples
    --------
    >>> increases([0, 1, 2, 3], [5., 5., 7., 6.], base=4.0).tolist()
    [0, 2]
    """
    _, v = _commands(cmd_t, cmd_v)
    if v.size == 0:
        return np.zeros(0, dtype=np.int64)
    prev = np.concatenate(([np.inf if base is None else base], v[:-1]))
    return np.flatnonzero(v > prev)


def response_time(onset: float, cmd_t, cmd_v, *, window: tuple[float, float],
                  base: float | None = None) -> float:
    """Time from ``onset`` to the first command increase inside ``window``.

    Returns NaN when the onset is NaN or no increase falls in the window.

    Examples
    --------
    >>> response_time(2.0, [1.0, 2.06], [10., 12.], window=(1.5, 4.0))
    0.06
    >>> response_time(float("nan"), [2.06], [12.], window=(1.5, 4.0), base=10.0)
    nan
    """
    lo, hi = _window(window)
    t, _ = _commands(cmd_t, cmd_v)
    if math.isnan(onset):
        return float("nan")
    inc = increases(cmd_t, cmd_v, base=base)
    inc = inc[(t[inc] >= lo) & (t[inc] < hi)]
    if inc.size == 0:
        return float("nan")
    return round(float(t[inc[0]] - onset), 12)


@dataclass(frozen=True, slots=True)
class Activity:
    """The command increases that belong to one slip.

    Attributes
    ----------
    first, last : float
        Times of the first and last increase (NaN when there is none).
    n_increases : int
        Number of increases.
    rise : float
        Total increase of the commanded position (finger units).

    Examples
    --------
    >>> a = Activity(first=1.0, last=1.3, n_increases=4, rise=20.0)
    >>> a.span, a.closing_time(fs=40.0)
    (0.3, 0.1)
    """

    first: float
    last: float
    n_increases: int
    rise: float

    @property
    def span(self) -> float:
        """First to last change (s): the paper's total controller time.

        NaN when the slip had no response.

        Examples
        --------
        >>> import math
        >>> math.isnan(Activity(float("nan"), float("nan"), 0, 0.0).span)
        True
        """
        return round(self.last - self.first, 12)

    def closing_time(self, fs: float) -> float:
        """Closing time generated by a ramp with one increase per sample at ``fs`` (s).

        Examples
        --------
        >>> Activity(1.0, 1.1, 26, 40.0).closing_time(260.0)
        0.1
        """
        return self.n_increases / fs if self.n_increases else float("nan")


def controller_activity(cmd_t, cmd_v, *, window: tuple[float, float], base: float | None = None,
                        gap: float = ACTIVITY_GAP_S) -> Activity:
    """The slip's command increases: from the first in ``window``, while pauses are <= ``gap``.

    Examples
    --------
    >>> a = controller_activity([1.0, 1.1, 1.2, 2.5], [1., 2., 3., 4.], window=(0.5, 3.0), base=0.0)
    >>> a.first, a.last, a.n_increases, a.rise
    (1.0, 1.2, 3, 3.0)
    """
    lo, hi = _window(window)
    if not gap > 0:
        raise ParameterError(f"gap must be > 0, got {gap}")
    t, v = _commands(cmd_t, cmd_v)
    inc = increases(cmd_t, cmd_v, base=base)
    inc = inc[(t[inc] >= lo) & (t[inc] < hi)]
    if inc.size == 0:
        return Activity(float("nan"), float("nan"), 0, 0.0)
    ti = t[inc]
    breaks = np.flatnonzero(np.diff(ti) > gap)
    n = int(breaks[0] + 1) if breaks.size else int(inc.size)
    keep = inc[:n]
    prev = np.concatenate(([np.inf if base is None else base], v[:-1]))
    rise = float(np.sum(v[keep] - prev[keep]))
    return Activity(float(t[keep[0]]), float(t[keep[-1]]), n, rise)


def suppressed(fell_out_time: float | None, window_end: float) -> bool:
    """Whether the slip was suppressed: the object had not fallen out by ``window_end``.

    Examples
    --------
    >>> suppressed(None, 5.0), suppressed(4.2, 5.0), suppressed(6.0, 5.0)
    (True, False, True)
    """
    if fell_out_time is None or math.isnan(fell_out_time):
        return True
    return bool(fell_out_time >= window_end)


def grip_without_slip(cmd_t, cmd_v, base: float, slips: Any) -> float:
    """How far the commanded position rose (finger units) while no true slip was under way.

    ``slips`` are the simulator's slip episodes (``onset``, ``end``; an open one lasts to
    the end); ``base`` is the command in force before the first (the grasp position).
    A reflex that squeezes at a knock, before any slip, shows here and not in its
    response times.

    Examples
    --------
    >>> from types import SimpleNamespace as E
    >>> grip_without_slip([1.0, 2.0, 3.0], [150.0, 170.0, 175.0], 148.0, [E(onset=1.9, end=2.5)])
    7.0
    """
    t = np.asarray(cmd_t, dtype=float)
    v = np.asarray(cmd_v, dtype=float)
    if t.size == 0:
        return 0.0
    rise = np.maximum(np.diff(np.concatenate(([base], v))), 0.0)
    during = np.zeros(t.size, dtype=bool)
    for ev in slips:
        end = math.inf if ev.end is None else ev.end
        during |= (t >= ev.onset) & (t <= end)
    return float(rise[~during].sum())
