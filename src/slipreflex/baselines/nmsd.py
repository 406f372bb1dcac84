"""NMSD: neuromimetic slip detection after Osborn et al. (shared SPEC section 2).

The comparison method of the paper's section II-E, on the 4 x 4 tactile array
sampled at 260 Hz. For every taxel the force derivative is taken,
``d_k = (f_k - f_(k-1)) * fs`` (N/s), and slip is a *fast change of the
derivative*: the statistic is ``s_k = d_k - d_(k-1)`` (N/s per sample), defined
from the third frame on (0 before). A taxel is over threshold when
``|s_k| > threshold``; a *detection* is a sample at which any taxel is over
threshold while none was at the previous sample (a rising edge of the ORed
signal), so one burst of fast change counts once and a slip that keeps
shaking the taxels keeps producing detections. Every detection adds 45 ms of
finger closing (:mod:`slipreflex.baselines.closing`).

The threshold is not a per-bottle tuning knob: :func:`slipreflex.baselines.rest_threshold`
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

from ..hardware import FINGER_MAX, FINGER_MIN, NMSD_FS, TACTILE_SHAPE
from ..validation import number, set_field
from ._validate import as_frames, frame_shape
from .closing import CLOSE_S, ClosingParams, closing_commands
from .shell import TactileReflex

__all__ = ["NMSDParams", "NMSD", "NMSDDetector", "nmsd_statistic", "nmsd_detections", "nmsd_commands",
           "nmsd_rest_statistic"]


@dataclass(frozen=True, slots=True)
class NMSDParams:
    """Parameters of the NMSD reflex.

    Parameters
    ----------
    threshold : float
        Threshold on ``|d_k - d_(k-1)|`` in N/s (> 0); derive it with
        :func:`slipreflex.baselines.rest_threshold`.
    speed : float
        Hand closing speed in finger units per second (> 0).
    fs : float
        Tactile sampling rate (Hz); 260 Hz in the paper.
    close_s : float
        Closing time per detection (s); 45 ms in the paper.
    p0, lo, hi : float
        Initial target and target saturation (finger units).
    shape : tuple of int
        Shape of one tactile frame: (rows, cols) or (channels,); the 4 x 4
        array by default.

    Examples
    --------
    >>> NMSDParams(threshold=40.0, speed=500.0).fs
    260.0
    """

    threshold: float
    speed: float
    fs: float = NMSD_FS
    close_s: float = CLOSE_S
    p0: float = 0.0
    lo: float = float(FINGER_MIN)
    hi: float = float(FINGER_MAX)
    shape: tuple[int, ...] = TACTILE_SHAPE

    def __post_init__(self) -> None:
        set_field(self, "threshold", number("threshold", self.threshold, lo=0.0, lo_open=True))
        set_field(self, "fs", number("fs", self.fs, lo=0.0, lo_open=True))
        set_field(self, "shape", frame_shape("shape", self.shape))
        self.closing  # validates speed, close_s, p0, lo, hi

    @property
    def closing(self) -> ClosingParams:
        """The closing-rule parameters at this method's rate.

        Examples
        --------
        >>> NMSDParams(threshold=1.0, speed=520.0).closing.samples_per_close
        12
        """
        return ClosingParams(fs=self.fs, speed=self.speed, close_s=self.close_s,
                             p0=self.p0, lo=self.lo, hi=self.hi)


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

    What :func:`slipreflex.baselines.rest_threshold` measures the spread of.

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
    over = (np.abs(s) > threshold).reshape(len(s), -1).any(axis=1)
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


class NMSDDetector:
    """NMSD's per-frame detector: change of the force derivative, rising edges over threshold.

    Examples
    --------
    >>> import numpy as np
    >>> d = NMSDDetector(fs=260.0, threshold=50.0)
    >>> [d.update(np.full(16, v))[2] for v in (0.0, 0.0, 0.0, -1.0)]
    [False, False, False, True]
    """

    def __init__(self, fs: float, threshold: float) -> None:
        self.fs, self.threshold = fs, threshold
        self._prev: np.ndarray | None = None
        self._prev_d: np.ndarray | None = None
        self._over = False

    def update(self, f: np.ndarray) -> tuple[float, bool, bool]:
        """One flat frame in; (largest ``|s_k|``, detection, detection).

        Examples
        --------
        >>> import numpy as np
        >>> NMSDDetector(fs=1.0, threshold=1.0).update(np.zeros(2))
        (0.0, False, False)
        """
        s = 0.0
        if self._prev is not None:
            d = (f - self._prev) * self.fs
            if self._prev_d is not None:
                s = float(np.max(np.abs(d - self._prev_d)))
            self._prev_d = d
        self._prev = f
        over = s > self.threshold
        event = over and not self._over
        self._over = over
        return s, event, event


class NMSD(TactileReflex):
    """Streaming NMSD reflex (implements :class:`slipreflex.interfaces.Reflex`).

    The shared :class:`~slipreflex.baselines.shell.TactileReflex` shell with
    :class:`NMSDDetector`; every detection adds ``close_s`` of closing.

    Parameters
    ----------
    params : NMSDParams, optional
        Parameters; or give them as keywords (unknown keywords are an error).

    Attributes
    ----------
    name : str
        ``"nmsd"``.
    input_kind : str
        ``"tactile"``.
    fs : float
        Rate at which :meth:`step` must be called (260 Hz by default).
    last_statistic : float
        Largest ``|s_k|`` over the taxels at the last step.
    last_event : bool
        Whether the last step was a detection.
    detections : int
        Detections since the last reset.
    closing_s : float
        Total closing time generated since the last reset (s).

    Examples
    --------
    >>> import numpy as np
    >>> from slipreflex.interfaces import Reflex
    >>> r = NMSD(threshold=50.0, speed=520.0)
    >>> isinstance(r, Reflex), r.name, r.input_kind, r.fs
    (True, 'nmsd', 'tactile', 260.0)
    >>> r.step(np.zeros((4, 4)), position=100.0) is None
    True
    """

    name = "nmsd"
    params_class = NMSDParams
    mode = "events"

    def _detector(self) -> NMSDDetector:
        return NMSDDetector(self.params.fs, self.params.threshold)
