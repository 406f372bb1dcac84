"""Event encoder: FA-I-like spikes by send-on-delta, fixed threshold or DATH (docs/method.md section 1.2).

For every filtered sample x_k the encoder accumulates the difference to the
previous sample (paper Eq. 1), fires when ``|acc| > theta`` (Eq. 2, strictly
greater) and resets the accumulator. With DATH on, the first spike fired under
theta0 sets ``theta = max(|x_k - x_(k-1)|, floor)`` (Eq. 4) for the next D
samples; spikes during that time do not re-arm it; sample k+D+1 is compared
against theta0 again.

Two options let the accumulator forget (docs/method.md, "Variants"): a periodic
reset every ``acc_reset`` samples (the authors' rig code) and an exponential
leak with a time constant of ``acc_leak`` samples. Both are off by default.

Examples
--------
>>> import numpy as np
>>> encode(np.array([0.0, 0.005, 0.010, 0.010]), threshold=0.008).tolist()
[False, False, True, False]
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ._checks import as_samples
from .params import DEFAULT_THRESHOLD, EncoderParams

__all__ = ["encode", "encode_trace", "EncoderTrace", "EventEncoder", "dath_update"]


class EncoderTrace(NamedTuple):
    """Per-sample internals of the encoder, for plots like the paper's Fig. 6-9.

    Attributes
    ----------
    events : numpy.ndarray of bool
        y_k.
    accumulator : numpy.ndarray of float
        The accumulator compared with the threshold at sample k (before its reset).
    threshold : numpy.ndarray of float
        The threshold in force at sample k.
    """

    events: np.ndarray
    accumulator: np.ndarray
    threshold: np.ndarray


def encode_trace(x, threshold: float = DEFAULT_THRESHOLD, dath: bool = False, dath_samples: int = 16,
                 x0: float | None = None, dath_floor: float = 0.0, acc_reset: int | None = None,
                 acc_leak: float | None = None) -> EncoderTrace:
    """Encode filtered samples and return events with accumulator and threshold.

    Parameters are those of :func:`encode`.

    Returns
    -------
    EncoderTrace

    Examples
    --------
    >>> import numpy as np
    >>> tr = encode_trace(np.array([0.0, 0.01, 0.011, 0.0111]), dath=True)
    >>> tr.events.tolist(), tr.threshold.round(4).tolist()
    ([False, True, False, False], [0.008, 0.008, 0.01, 0.01])
    """
    p = EncoderParams(threshold=threshold, dath=dath, dath_samples=dath_samples, x0=x0,
                      dath_floor=dath_floor, acc_reset=acc_reset, acc_leak=acc_leak)
    xs = as_samples("x", x)
    k = xs.size
    events = np.zeros(k, dtype=np.bool_)
    acc = np.empty(k)
    theta = np.empty(k)
    if k:
        from ._kernels import encode_kernel  # deferred: heavy (numba kernels)

        prev = xs[0] if p.x0 is None else p.x0
        encode_kernel(xs, prev, p.threshold, p.dath, p.dath_samples, p.dath_floor, p.acc_reset or 0,
                      p.leak_factor, p.acc_leak is not None, events, acc, theta)
    return EncoderTrace(events, acc, theta)


def encode(x, threshold: float = DEFAULT_THRESHOLD, dath: bool = False, dath_samples: int = 16,
           x0: float | None = None, dath_floor: float = 0.0, acc_reset: int | None = None,
           acc_leak: float | None = None) -> np.ndarray:
    """Turn filtered slip-sensor samples into spikes (one bool per sample).

    Parameters
    ----------
    x : array_like of float
        Filtered samples (volts); NaN or inf raises ValueError naming the index.
    threshold : float
        Base threshold theta0 (V), >= 0. The paper uses 0.008 V (2 LSB).
    dath : bool
        Use the Dynamic Adaptive Threshold.
    dath_samples : int
        DATH duration D (samples).
    x0 : float or None
        Initial reference; None uses the first sample; 0.0 is the paper's literal start.
    dath_floor : float
        Lower bound of the DATH threshold (V).
    acc_reset : int or None
        Clear the accumulator every this many samples (None: never, the paper).
    acc_leak : float or None
        Time constant of the accumulator's exponential leak, in samples (None:
        no leak, the paper): ``acc = acc * exp(-1 / acc_leak) + d``.

    Returns
    -------
    numpy.ndarray of bool
        y_k for every sample, identical to :class:`EventEncoder` step by step.

    Examples
    --------
    >>> import numpy as np
    >>> encode(np.full(4, 0.4), x0=0.0).tolist()   # the paper's start-up spike
    [True, False, False, False]
    >>> drift = np.arange(12) * 0.001              # 1 mV per sample, never 8 mV at once
    >>> int(encode(drift).sum()), int(encode(drift, acc_reset=5).sum())
    (1, 0)
    """
    return encode_trace(x, threshold, dath, dath_samples, x0, dath_floor, acc_reset, acc_leak).events


class EventEncoder:
    """Streaming event encoder: one filtered sample in, one bool out.

    Parameters are those of :func:`encode`. After each :meth:`step`,
    ``last_threshold`` holds the threshold that sample was compared against and
    ``last_accumulator`` the accumulator before its reset.

    Examples
    --------
    >>> enc = EventEncoder(threshold=0.008, dath=True)
    >>> [enc.step(v) for v in (0.0, 0.01, 0.011)]
    [False, True, False]
    >>> round(enc.threshold, 4)   # DATH active: |0.01 - 0.0|
    0.01
    """

    __slots__ = ("params", "_prev", "acc", "threshold", "remaining", "clock", "last_threshold",
                 "last_accumulator", "_leak")

    def __init__(self, threshold: float = DEFAULT_THRESHOLD, dath: bool = False, dath_samples: int = 16,
                 x0: float | None = None, dath_floor: float = 0.0, acc_reset: int | None = None,
                 acc_leak: float | None = None) -> None:
        self.params = EncoderParams(threshold=threshold, dath=dath, dath_samples=dath_samples, x0=x0,
                                    dath_floor=dath_floor, acc_reset=acc_reset, acc_leak=acc_leak)
        self._leak = self.params.leak_factor
        self.reset()

    def reset(self) -> None:
        """Restore the initial state (reference x0 or the next sample)."""
        self._prev: float | None = self.params.x0
        self.acc = 0.0
        self.threshold = self.params.threshold
        self.remaining = 0
        self.clock = 0
        self.last_threshold = self.params.threshold
        self.last_accumulator = 0.0

    def step(self, x: float) -> bool:
        """Encode one filtered sample; returns True on a spike."""
        x = float(x)
        prev = x if self._prev is None else self._prev
        d = x - prev
        p = self.params
        acc = self.acc * self._leak + d if p.acc_leak is not None else self.acc + d
        theta = self.threshold
        self.last_threshold = theta
        self.last_accumulator = acc
        event = abs(acc) > theta
        if event:
            acc = 0.0
        if p.acc_reset is not None:
            self.clock += 1
            if self.clock >= p.acc_reset:
                self.clock = 0
                acc = 0.0
        self.acc = acc
        if p.dath:
            self.remaining, self.threshold = dath_update(self.remaining, self.threshold, event, d, p.threshold,
                                                         p.dath_floor, p.dath_samples)
        self._prev = x
        return event


def dath_update(remaining: int, threshold, event: bool, d, rest, floor, samples: int) -> tuple:
    """One sample of the DATH rule (Eq. 4): (samples it still holds, threshold for the next sample).

    While ``remaining`` > 0 the raised threshold holds and counts down, back to ``rest``
    (theta0) when it reaches 0; otherwise a spike (``event``) raises it to
    ``max(|d|, floor)`` for ``samples`` samples. Only comparisons: the same rule runs on
    floats (:class:`EventEncoder`) and on the board's Q16 integers
    (:class:`slipreflex.methods.board.BoardReflex`).

    Examples
    --------
    >>> dath_update(0, 0.008, True, 0.03, 0.008, 0.0, 16)
    (16, 0.03)
    >>> dath_update(1, 0.03, False, 0.0, 0.008, 0.0, 16)
    (0, 0.008)
    """
    if remaining > 0:
        remaining -= 1
        return remaining, (rest if remaining == 0 else threshold)
    if event:
        ad = abs(d)
        return samples, (ad if ad > floor else floor)
    return remaining, threshold
