"""Low-pass stage: 2nd-order Butterworth, causal, started at steady state (docs/method.md section 1.1).

The filter is designed by scipy (``butter(2, cutoff, fs=fs, output="sos")``) and run
in second-order sections in scipy's ``sosfilt`` arithmetic; its state starts at the
steady state of the first sample (``sosfilt_zi(sos) * r_1``), so a constant input
gives a constant output from the first sample on.

Examples
--------
>>> import numpy as np
>>> y = lowpass(np.full(5, 0.4))
>>> bool(np.allclose(y, 0.4))
True
"""

from __future__ import annotations

import math

import numpy as np

from ...core.hardware import DAQ_FS
from ._checks import as_samples
from ._shared import _design
from .params import FilterParams

__all__ = ["design_lowpass", "lowpass", "LowPass"]



def design_lowpass(fs: float = DAQ_FS, cutoff: float = 10.0) -> np.ndarray:
    """Second-order sections of the chain's low-pass filter.

    Parameters
    ----------
    fs : float
        Sampling rate (Hz).
    cutoff : float
        Cutoff frequency (Hz), below fs / 2.

    Returns
    -------
    numpy.ndarray
        A fresh ``(1, 6)`` array of sections as scipy returns them.

    Examples
    --------
    >>> design_lowpass(333.0, 10.0).shape
    (1, 6)
    """
    p = FilterParams(fs=fs, cutoff=cutoff)
    return _design(p.fs, p.cutoff)[0].copy()


def lowpass(raw, fs: float = DAQ_FS, cutoff: float = 10.0) -> np.ndarray:
    """Filter a whole recording of raw slip-sensor volts.

    Parameters
    ----------
    raw : array_like of float
        Raw samples r_1 .. r_K (volts); NaN or inf raises ValueError naming the index.
    fs : float
        Sampling rate (Hz).
    cutoff : float
        Cutoff frequency (Hz).

    Returns
    -------
    numpy.ndarray
        Filtered samples x_1 .. x_K, identical to feeding :class:`LowPass`
        one sample at a time.

    Examples
    --------
    >>> import numpy as np
    >>> x = lowpass(np.r_[np.zeros(50), np.ones(100)], fs=333.0, cutoff=10.0)
    >>> round(float(x[-1]), 3)
    1.0
    """
    p = FilterParams(fs=fs, cutoff=cutoff)
    r = as_samples("raw", raw)
    out = np.empty_like(r)
    if r.size:
        from ._kernels import lowpass_kernel  # deferred: heavy (numba kernels)

        sos, zi = _design(p.fs, p.cutoff)
        lowpass_kernel(r, sos, zi * r[0], out)
    return out


class LowPass:
    """Streaming low-pass filter: one raw sample in, one filtered sample out.

    Parameters
    ----------
    fs : float
        Sampling rate (Hz).
    cutoff : float
        Cutoff frequency (Hz).
    enabled : bool
        False passes samples through unchanged.

    Examples
    --------
    >>> f = LowPass(fs=333.0, cutoff=10.0)
    >>> round(f.step(0.5), 12), round(f.step(0.5), 12)   # steady state from the first sample
    (0.5, 0.5)
    >>> f.reset()
    """

    __slots__ = ("params", "_sections", "_zi0", "_zi", "_started")

    def __init__(self, fs: float = DAQ_FS, cutoff: float = 10.0, enabled: bool = True) -> None:
        self.params = FilterParams(fs=fs, cutoff=cutoff, enabled=enabled)
        sos, zi = _design(self.params.fs, self.params.cutoff)
        self._sections = [tuple(float(c) for c in row) for row in sos]
        self._zi0 = [tuple(float(c) for c in row) for row in zi]
        self.reset()

    def reset(self) -> None:
        """Forget all past input; the next sample sets the steady state again."""
        self._zi: list[list[float]] = []
        self._started = False

    def step(self, raw: float) -> float:
        """Filter one sample (volts) and return the filtered value.

        Parameters
        ----------
        raw : float
            Must be finite; the composed :class:`~slipreflex.SlipReflex` skips
            NaN samples before they reach this stage.

        Returns
        -------
        float
        """
        if not self.params.enabled:
            return raw
        x = float(raw)
        if not self._started:
            if not math.isfinite(x):
                raise ValueError(f"LowPass.step: sample must be finite, got {x!r}")
            self._zi = [[z0 * x, z1 * x] for z0, z1 in self._zi0]
            self._started = True
        for (b0, b1, b2, _a0, a1, a2), zi in zip(self._sections, self._zi):
            y = b0 * x + zi[0]
            zi[0] = b1 * x - a1 * y + zi[1]
            zi[1] = b2 * x - a2 * y
            x = y
        return x
