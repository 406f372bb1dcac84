"""The NMSD closing rule, turned into finger position targets (docs/method.md section 2).

Osborn et al.'s reflex closes the fingers for a fixed time on every slip
detection (45 ms in the paper); each further detection while the fingers are
still closing adds another 45 ms. A position-controlled hand cannot be told
"close for 45 ms", so :class:`Closer` turns closing time into a ramp of
position targets: on every sample spent closing, the target advances by
``speed / fs`` finger units, where ``speed`` is the hand's closing speed
(finger units per second, from the simulated hand's documented constant). The
hand then follows the ramp at its own speed, i.e. it closes for as long as the
rule says. The total closing time generated is ``closing_samples / fs``.

Two trigger modes share the rule:

* ``"events"`` (NMSD): every detection adds ``close_s`` of closing;
* ``"hold"`` (SWT-SD, whose detector gives an ON/OFF signal): while ON, a new
  ``close_s`` quantum starts whenever the previous one has run out, so the
  fingers close while ON and for at most ``close_s`` after it ends.

Examples
--------
>>> c = Closer(ClosingParams(fs=100.0, speed=1000.0, close_s=0.03))
>>> c.trigger()
>>> [c.step() for _ in range(4)]
[10.0, 20.0, 30.0, None]
>>> c.closing_samples
3
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from ...core._slots import slot
from ...core.errors import ParameterError
from ...core.hardware import FINGER_MAX, FINGER_MIN
from ...core.validation import instance, number, set_field
from . import _layout as _L
from ._layout import init_state, pack_closing

__all__ = ["CLOSE_S", "ClosingParams", "Closer", "closing_commands"]

#: Closing time per detection in the paper's NMSD implementation (s).
CLOSE_S: float = 0.045

TriggerMode = Literal["events", "hold"]


@dataclass(frozen=True, slots=True)
class ClosingParams:
    """Parameters of the closing rule.

    Parameters
    ----------
    fs : float
        Rate (Hz) at which :meth:`Closer.step` is called (> 0).
    speed : float
        Closing speed of the hand in finger units per second (> 0).
    close_s : float
        Closing time added by one detection (s, > 0); 45 ms in the paper.
    p0 : float
        Initial target used when no measured position is supplied.
    lo, hi : float
        Saturation of the targets (finger range).

    Examples
    --------
    >>> ClosingParams(fs=260.0, speed=500.0).samples_per_close
    12
    >>> ClosingParams(fs=260.0, speed=0.0)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: speed must be a finite number > 0, got 0.0
    """

    fs: float
    speed: float
    close_s: float = CLOSE_S
    p0: float = 0.0
    lo: float = float(FINGER_MIN)
    hi: float = float(FINGER_MAX)

    def __post_init__(self) -> None:
        set_field(self, "fs", number("fs", self.fs, lo=0.0, lo_open=True))
        set_field(self, "speed", number("speed", self.speed, lo=0.0, lo_open=True))
        set_field(self, "close_s", number("close_s", self.close_s, lo=0.0, lo_open=True))
        set_field(self, "p0", number("p0", self.p0))
        set_field(self, "lo", number("lo", self.lo))
        set_field(self, "hi", number("hi", self.hi))
        if self.hi < self.lo:
            raise ParameterError(f"hi must be >= lo, got lo={self.lo!r}, hi={self.hi!r}")

    @property
    def samples_per_close(self) -> int:
        """Closing samples added by one detection: ``round(close_s * fs)``, at least 1."""
        return max(1, int(round(self.close_s * self.fs)))

    @property
    def step_size(self) -> float:
        """Target increment per closing sample (finger units): ``speed / fs``."""
        return self.speed / self.fs


class Closer:
    """Streaming closing rule: detections in, a ramp of position targets out.

    Its state is a float64 vector and every call runs a compiled kernel of
    :mod:`slipreflex.methods.baselines._kernels`, the same arithmetic NMSD's and
    SWT-SD's compiled step and :func:`closing_commands` run.

    Parameters
    ----------
    params : ClosingParams
        The rule's parameters.

    Attributes
    ----------
    target : float
        The current position target.
    remaining : int
        Closing samples still to run.
    closing_samples : int
        Closing samples generated since the last reset (total closing time
        is ``closing_samples / fs``).
    triggers : int
        Number of closing quanta started since the last reset.

    Examples
    --------
    >>> c = Closer(ClosingParams(fs=10.0, speed=100.0, close_s=0.2))
    >>> c.trigger(); c.trigger()
    >>> [c.step(position=50.0) for _ in range(5)]
    [60.0, 70.0, 80.0, 90.0, None]
    """

    def __init__(self, params: ClosingParams) -> None:

        self.params = instance("params", params, ClosingParams)
        _load_kernels()
        self._P = pack_closing(self.params)
        self._S0 = init_state(self._P)
        self._S = self._S0.copy()

    def reset(self) -> None:
        """Restore the initial state (target ``p0``, nothing to close).

        Examples
        --------
        >>> c = Closer(ClosingParams(fs=10.0, speed=100.0)); c.trigger(); c.reset(); c.remaining
        0
        """
        self._S[:] = self._S0

    target = slot(_L.S_TARGET, float, "The current position target.")
    remaining = slot(_L.S_REMAINING, int, "Closing samples still to run.")
    closing_samples = slot(_L.S_CLOSING, int, "Closing samples generated since the last reset.")
    triggers = slot(_L.S_TRIGGERS, int, "Closing quanta started since the last reset.")

    @property
    def closing(self) -> bool:
        """True while closing samples remain.

        Examples
        --------
        >>> Closer(ClosingParams(fs=10.0, speed=100.0)).closing
        False
        """
        return self.remaining > 0

    def trigger(self) -> None:
        """Add one closing quantum (``close_s``) to the time still to close.

        Examples
        --------
        >>> c = Closer(ClosingParams(fs=100.0, speed=100.0, close_s=0.05)); c.trigger(); c.remaining
        5
        """
        _K.closer_feed(self._S, self._P, True, False)

    def feed(self, trig: bool, mode: TriggerMode = "events") -> None:
        """Apply one sample's detector output according to the trigger ``mode``.

        ``"events"``: a True adds a quantum; ``"hold"``: a True starts a quantum
        only when the previous one has run out.

        Examples
        --------
        >>> c = Closer(ClosingParams(fs=100.0, speed=100.0, close_s=0.05))
        >>> c.feed(True, "hold"); c.feed(True, "hold"); c.remaining
        5
        """
        _K.closer_feed(self._S, self._P, bool(trig), _hold(mode))

    def step(self, position: float | None = None) -> float | None:
        """Advance one sample; return the new target, or None when it does not change.

        Parameters
        ----------
        position : float, optional
            The hand's measured position; when a closing episode starts, the
            ramp starts from ``max(target, position)`` so it never commands a
            position behind the fingers. None or NaN: unknown.

        Examples
        --------
        >>> c = Closer(ClosingParams(fs=100.0, speed=100.0, close_s=0.01))
        >>> c.step(), c.trigger(), c.step(position=200.0)
        (None, None, 201.0)
        """
        u = _K.closer_step(self._S, self._P, math.nan if position is None else float(position))
        return None if u != u else u


def _hold(mode: str) -> bool:
    """True for the "hold" trigger mode; a mode that is neither is refused."""
    if mode not in ("events", "hold"):
        raise ParameterError(f"mode must be 'events' or 'hold', got {mode!r}")
    return mode == "hold"


_K: Any = None  # slipreflex.methods.baselines._kernels, imported with the first Closer or tactile reflex


def _load_kernels():
    """Import the compiled kernels (numba) once, on first use; return the module."""
    global _K
    if _K is None:
        from . import _kernels  # deferred: heavy (numba kernels)

        _K = _kernels
    return _K


def closing_commands(triggers, params: ClosingParams, *, mode: TriggerMode = "events",
                     positions=None) -> np.ndarray:
    """Batch closing rule: per-sample triggers in, per-sample targets out.

    Parameters
    ----------
    triggers : array_like of bool, shape (K,)
        Detections (``mode="events"``) or the ON/OFF signal (``mode="hold"``).
    params : ClosingParams
        The rule's parameters.
    mode : {"events", "hold"}
        How triggers start closing quanta (see the module docstring).
    positions : array_like of float, shape (K,), optional
        Measured hand positions (NaN where unknown).

    Returns
    -------
    numpy.ndarray of float, shape (K,)
        The new target at each sample, NaN where the target does not change.

    Examples
    --------
    >>> p = ClosingParams(fs=100.0, speed=100.0, close_s=0.02)
    >>> closing_commands([True, False, False, True, True], p).tolist()
    [1.0, 2.0, nan, 3.0, 4.0]
    """
    trig = np.asarray(triggers, dtype=bool)
    if trig.ndim != 1:
        raise ParameterError(f"triggers must be one-dimensional, got shape {trig.shape}")
    hold = _hold(mode)
    params = instance("params", params, ClosingParams)
    pos = np.full(trig.shape, np.nan) if positions is None else np.asarray(positions, dtype=np.float64)
    if pos.shape != trig.shape:
        raise ParameterError(f"positions must have shape {trig.shape}, got {pos.shape}")

    P = pack_closing(params)
    out = np.empty(trig.shape)
    _load_kernels().closing_kernel(trig, np.ascontiguousarray(pos), hold, init_state(P), P, out)
    return out
