"""Monotonic PI controller on spike counts (paper Eq. 5-9, docs/method.md section 1.4).

Per window: ``h += v``; ``PI = P0 + Kp v + Ki h``; the command is the running
maximum of PI, clipped to [lo, hi], so it never decreases. After
``reset_after`` zero-count windows in a row, P0 becomes the current position
(the caller's measured middle-finger position, or the last command) and the
integral restarts; the running maximum is kept.

Examples
--------
>>> mpi([0, 2, 1, 0]).tolist()
[0.0, 20.0, 20.0, 20.0]
"""

from __future__ import annotations

import numpy as np

from ...core.errors import DataError
from ...core.hardware import FINGER_MAX, FINGER_MIN
from ._checks import as_vector
from ._shared import _clip
from .params import MPIParams

__all__ = ["mpi", "MPIController"]


def mpi(v, p0: float = 0.0, kp: float = 5.0, ki: float = 5.0, reset_after: int | None = 10,
        lo: float = float(FINGER_MIN), hi: float = float(FINGER_MAX)) -> np.ndarray:
    """Finger commands for a whole sequence of window counts.

    Parameters
    ----------
    v : array_like of float
        Spike counts v_z (finite, >= 0).
    p0 : float
        Initial finger position P0.
    kp, ki : float
        Gains (the paper uses 5 and 5).
    reset_after : int or None
        Zero windows in a row after which P0 := last command and h := 0;
        None never resets.
    lo, hi : float
        Saturation range (finger positions 0 .. 500).

    Returns
    -------
    numpy.ndarray of float
        One command u_z per window, identical to :class:`MPIController`.

    Examples
    --------
    >>> mpi([100, 100]).tolist()   # saturates at 500
    [500.0, 500.0]
    """
    p = MPIParams(p0=p0, kp=kp, ki=ki, reset_after=reset_after, lo=lo, hi=hi)
    counts = as_vector("v", v, np.float64)
    bad = ~(np.isfinite(counts) & (counts >= 0))
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(f"v[{i}] is {counts[i]!r}: counts must be finite and >= 0")
    out = np.empty_like(counts)
    if counts.size:
        from ._kernels import mpi_kernel  # deferred: heavy (numba kernels)

        reset_after = -1 if p.reset_after is None else p.reset_after
        mpi_kernel(counts, p.p0, _clip(p.p0, p.lo, p.hi), p.kp, p.ki, reset_after, p.lo, p.hi, out)
    return out


class MPIController:
    """Streaming MPI controller: one window count in, one finger command out.

    Examples
    --------
    >>> c = MPIController(p0=100.0)
    >>> c.step(3), c.step(0)
    (130.0, 130.0)
    >>> for _ in range(9): _ = c.step(0)     # 10 zero windows: reset
    >>> c.p_base, c.integral
    (130.0, 0.0)
    """

    __slots__ = ("params", "p_base", "integral", "command", "zero_windows")

    def __init__(self, p0: float = 0.0, kp: float = 5.0, ki: float = 5.0, reset_after: int | None = 10,
                 lo: float = float(FINGER_MIN), hi: float = float(FINGER_MAX)) -> None:
        self.params = MPIParams(p0=p0, kp=kp, ki=ki, reset_after=reset_after, lo=lo, hi=hi)
        self.reset()

    def reset(self) -> None:
        """Restore P0 = p0, h = 0 and the command to clip(p0)."""
        p = self.params
        self.p_base = p.p0
        self.integral = 0.0
        self.command = _clip(p.p0, p.lo, p.hi)
        self.zero_windows = 0

    def step(self, v: float, position: float | None = None) -> float:
        """Return the command for window count ``v``.

        Parameters
        ----------
        v : float
            Spike count of the window (>= 0).
        position : float, optional
            Measured middle-finger position, used as P0 if this window resets
            the controller; the last command otherwise.
        """
        p = self.params
        v = float(v)
        h = self.integral + v
        pi = self.p_base + p.kp * v + p.ki * h
        m = pi if pi > self.command else self.command
        m = _clip(m, p.lo, p.hi)
        self.command = m
        self.integral = h
        self.zero_windows = self.zero_windows + 1 if v == 0.0 else 0
        if self.zero_windows == p.reset_after:
            self.p_base = m if position is None else float(position)
            self.integral = 0.0
            self.zero_windows = 0
        return m
