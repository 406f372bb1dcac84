"""NMSD: neuromimetic slip detection after Osborn et al. (docs/method.md section 2).

The comparison method of the paper's section II-E, on the 4 x 4 tactile array
sampled at 260 Hz. For every taxel the force derivative is taken,
``d_k = (f_k - f_(k-1)) * fs`` (N/s), and slip is a *fast change of the
derivative*: the statistic is ``s_k = d_k - d_(k-1)`` (N/s per sample), defined
from the third frame on (0 before). A taxel is over threshold when
``|s_k| > threshold``; a *detection* is a sample at which any taxel is over
threshold while none was at the previous sample (a rising edge of the ORed
signal), so one burst of fast change counts once and a slip that keeps
shaking the taxels keeps producing detections. Every detection adds 45 ms of
finger closing (:mod:`slipreflex.methods.baselines.closing`).

The threshold is not a per-bottle tuning knob: :func:`slipreflex.methods.baselines.rest_threshold`
derives it from a recording of the rig at rest (k standard deviations of
``s``).

Examples
--------
>>> import numpy as np
>>> frames = np.zeros((6, 4, 4)); frames[4:, 0, 0] = -0.5      # a sudden force drop
>>> nmsd_detections(frames, fs=260.0, threshold=50.0).tolist()
[False, False, False, False, True, False]
>>> r = NMSD(threshold=50.0, speed=500.0)
>>> [r.step(f) is not None for f in frames]
[False, False, False, False, True, True]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...core.hardware import NMSD_FS
from ...core.validation import number
from ._layout import KIND_NMSD
from ._validate import as_frames
from .closing import closing_commands
from .shell import TactileParams, TactileReflex

__all__ = ["NMSDParams", "NMSD", "nmsd_statistic", "nmsd_detections", "nmsd_commands",
           "nmsd_rest_statistic"]


@dataclass(frozen=True, slots=True)
class NMSDParams(TactileParams):
    """Parameters of the NMSD reflex (the fields of :class:`~slipreflex.methods.baselines.shell.TactileParams`).

    ``threshold`` is on ``|d_k - d_(k-1)|`` in N/s; ``fs`` is 260 Hz in the
    paper; ``close_s`` is the closing time per detection.

    Examples
    --------
    >>> p = NMSDParams(threshold=40.0, speed=520.0)
    >>> p.fs, p.closing.samples_per_close
    (260.0, 12)
    """

    fs: float = NMSD_FS


def nmsd_statistic(frames, fs: float = NMSD_FS) -> np.ndarray:
    """Change of the force derivative per taxel, ``s_k = d_k - d_(k-1)`` (N/s).

    Parameters
    ----------
    frames : array_like, shape (K, rows, cols) or (K, channels)
        Tactile forces (N) at ``fs``.
    fs : float
        Sampling rate (Hz).

    Returns
    -------
    numpy.ndarray, same shape as ``frames``
        The statistic; zero for the first two frames (no second difference yet).

    Examples
    --------
    >>> import numpy as np
    >>> f = np.zeros((4, 4, 4)); f[:, 1, 1] = [0.0, 0.0, 0.5, 1.5]
    >>> nmsd_statistic(f, fs=2.0)[:, 1, 1].tolist()
    [0.0, 0.0, 1.0, 1.0]
    """
    f = as_frames("frames", frames)
    fs = number("fs", fs, lo=0.0, lo_open=True)
    s = np.zeros_like(f)
    if len(f) >= 3:
        d = np.diff(f, axis=0) * fs
        s[2:] = np.diff(d, axis=0)
    return s


def nmsd_rest_statistic(frames, fs: float = NMSD_FS) -> np.ndarray:
    """NMSD's statistic on a rest recording, pooled over taxels, warm-up frames dropped.

    What :func:`slipreflex.methods.baselines.rest_threshold` measures the spread of.

    Examples
    --------
    >>> import numpy as np
    >>> nmsd_rest_statistic(np.zeros((10, 4, 4))).shape
    (128,)
    """
    return nmsd_statistic(frames, fs)[2:].ravel()


def nmsd_detections(frames, fs: float = NMSD_FS, *, threshold: float) -> np.ndarray:
    """Detections: rising edges of "any taxel has ``|s_k| > threshold``".

    Parameters
    ----------
    frames : array_like, shape (K, rows, cols) or (K, channels)
        Tactile forces (N).
    fs : float
        Sampling rate (Hz).
    threshold : float
        Threshold on ``|s_k|`` (N/s).

    Returns
    -------
    numpy.ndarray of bool, shape (K,)

    Examples
    --------
    >>> import numpy as np
    >>> f = np.zeros((5, 4, 4)); f[3:, 2, 3] = 1.0
    >>> nmsd_detections(f, fs=1.0, threshold=0.5).tolist()
    [False, False, False, True, False]
    """
    threshold = number("threshold", threshold, lo=0.0, lo_open=True)
    s = nmsd_statistic(frames, fs)
    over = np.asarray(np.asarray(np.abs(s) > threshold).reshape(len(s), -1).any(axis=1))
    prev = np.concatenate(([False], over[:-1]))
    return over & ~prev


def nmsd_commands(frames, params: NMSDParams, positions=None) -> np.ndarray:
    """Batch NMSD reflex: frames in, finger targets out (NaN where unchanged).

    Gives exactly what :class:`NMSD` returns sample by sample.

    Parameters
    ----------
    frames : array_like, shape (K, rows, cols) or (K, channels)
        Tactile forces (N) at ``params.fs``.
    params : NMSDParams
        The reflex parameters.
    positions : array_like, shape (K,), optional
        Measured hand positions fed with each frame (NaN where unknown).

    Returns
    -------
    numpy.ndarray of float, shape (K,)

    Examples
    --------
    >>> import numpy as np
    >>> f = np.zeros((6, 4, 4)); f[4:, 0, 0] = -1.0
    >>> p = NMSDParams(threshold=50.0, speed=260.0)
    >>> nmsd_commands(f, p).tolist()
    [nan, nan, nan, nan, 1.0, 2.0]
    """
    det = nmsd_detections(frames, params.fs, threshold=params.threshold)
    return closing_commands(det, params.closing, mode="events", positions=positions)


class NMSD(TactileReflex):
    """Streaming NMSD reflex (implements :class:`slipreflex.core.interfaces.Reflex`).

    The shared :class:`~slipreflex.methods.baselines.shell.TactileReflex` shell (its
    parameters, attributes, diagnostics and compiled step) with NMSD's
    detector: a detection is a rising edge of "any taxel over threshold"
    (:func:`nmsd_detections`), and every detection adds ``close_s`` of closing. ``name`` is ``"nmsd"``, ``fs`` 260 Hz
    by default, and ``last_statistic`` the largest ``|s_k|`` over the taxels.

    Examples
    --------
    >>> import numpy as np
    >>> from slipreflex.core.interfaces import Reflex
    >>> r = NMSD(threshold=50.0, speed=520.0)
    >>> isinstance(r, Reflex), r.name, r.input_kind, r.fs
    (True, 'nmsd', 'tactile', 260.0)
    >>> r.step(np.zeros((4, 4)), position=100.0) is None
    True
    """

    name = "nmsd"
    params_class = NMSDParams
    mode = "events"
    kind = KIND_NMSD

    def _weights(self) -> np.ndarray:
        return np.empty(0)
