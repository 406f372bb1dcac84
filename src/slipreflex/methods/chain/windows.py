"""Spike counts in non-overlapping windows of N samples (paper Eq. 3, docs/method.md section 1.3).

Windows are aligned to the first sample of the stream; an unfinished tail
window is not emitted.

Examples
--------
>>> import numpy as np
>>> count_windows(np.array([1, 0, 1, 1, 0, 1, 1]), n=3).tolist()
[2, 2]
"""

from __future__ import annotations

import numpy as np

from ...core.errors import DataError
from ...core.hardware import WINDOW_N
from ._checks import as_vector
from .params import WindowParams

__all__ = ["count_windows", "WindowCounter"]


def count_windows(events, n: int = WINDOW_N) -> np.ndarray:
    """Count spikes in each complete window of ``n`` samples.

    Parameters
    ----------
    events : array_like of bool or {0, 1}
        y_k for every sample.
    n : int
        Window length in samples (>= 1); 16 samples is 48 ms at 333.33 Hz.

    Returns
    -------
    numpy.ndarray of int64
        v_z for the floor(K / n) complete windows.

    Examples
    --------
    >>> count_windows([True] * 40).tolist()
    [16, 16]
    """
    p = WindowParams(n=n)
    y = as_vector("events", events)
    if y.dtype != np.bool_:
        bad = ~np.isin(y, (0, 1))
        if bad.any():
            i = int(np.argmax(bad))
            raise DataError(f"events[{i}] is {y[i]!r}: events must be 0/1 or bool")
    full = (y.size // p.n) * p.n
    return y[:full].astype(np.int64).reshape(-1, p.n).sum(axis=1)


class WindowCounter:
    """Streaming window counter: one event in, a count out on window completion.

    Examples
    --------
    >>> wc = WindowCounter(n=2)
    >>> [wc.step(e) for e in (True, True, False)]
    [None, 2, None]
    """

    __slots__ = ("params", "_n", "_count", "_filled")

    def __init__(self, n: int = WINDOW_N) -> None:
        self.params = WindowParams(n=n)
        self._n = self.params.n
        self.reset()

    def reset(self) -> None:
        """Start a new window at the next sample."""
        self._count = 0
        self._filled = 0

    def step(self, event: bool) -> int | None:
        """Add one sample's event; return v_z when it completes the window, else None."""
        if event:
            self._count += 1
        self._filled += 1
        if self._filled == self._n:
            v = self._count
            self._count = 0
            self._filled = 0
            return v
        return None
