"""The reflex shell NMSD and SWT-SD share: a detector object plus the closing rule.

A tactile method differs from another only in its *detector*: what it
computes on each frame and when that means slip. :class:`TactileReflex` does
the rest once: it checks each frame against the method's frame shape, feeds
the detector, hands its trigger to the :class:`~slipreflex.baselines.Closer`
in the method's trigger mode, keeps the diagnostics of the
:class:`~slipreflex.interfaces.Reflex` protocol, and resets everything. A
method is a parameter class, a detector class and three class attributes.

Examples
--------
>>> import numpy as np
>>> from slipreflex.baselines import NMSD
>>> r = NMSD(threshold=50.0, speed=520.0, shape=(3,))       # a 3-channel sensor
>>> [r.step(np.full(3, v)) is not None for v in (0.0, 0.0, 0.0, -1.0)]
[False, False, False, True]
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

import numpy as np

from ..hardware import FINGER_MAX, FINGER_MIN, NMSD_FS, TACTILE_SHAPE
from ..validation import number, resolve_params, set_field
from ._validate import as_frame, frame_shape
from .closing import CLOSE_S, Closer, ClosingParams, TriggerMode

__all__ = ["TactileParams", "Detector", "TactileReflex"]


@dataclass(frozen=True, slots=True)
class TactileParams:
    """Parameters every tactile method has: its threshold, rate, frame shape and closing rule.

    A method's parameter class derives from this one, sets its own default
    ``fs`` and adds its own fields (checked in its ``__post_init__`` after
    calling this one's).

    Parameters
    ----------
    threshold : float
        Threshold on the method's statistic (> 0); derive it with
        :func:`slipreflex.baselines.rest_threshold`.
    speed : float
        Hand closing speed in finger units per second (> 0).
    fs : float
        Tactile sampling rate (Hz).
    close_s : float
        Closing time per detection (s); 45 ms in the paper.
    p0, lo, hi : float
        Initial target and target saturation (finger units).
    shape : tuple of int
        Shape of one tactile frame: (rows, cols) or (channels,); the 4 x 4
        array by default.

    Examples
    --------
    >>> TactileParams(threshold=1.0, speed=260.0, fs=260.0, shape=(8,)).closing.step_size
    1.0
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
        >>> TactileParams(threshold=1.0, speed=520.0).closing.samples_per_close
        12
        """
        return ClosingParams(fs=self.fs, speed=self.speed, close_s=self.close_s,
                             p0=self.p0, lo=self.lo, hi=self.hi)


class Detector(Protocol):
    """What a tactile method computes on each frame.

    ``update(frame)`` takes one finite flat frame (float64, one value per taxel)
    and returns ``(statistic, level)``: the largest statistic over the taxels,
    and whether the method sees slip on this frame. The shell makes a
    detection of every rising edge of ``level``; the closing rule reads the
    detections (``"events"`` mode) or ``level`` itself (``"hold"`` mode).

    Examples
    --------
    >>> from slipreflex.baselines.nmsd import NMSDDetector
    >>> d = NMSDDetector(fs=10.0, threshold=1.0)
    >>> [d.update(np.array([x]))[1] for x in (0.0, 0.0, 1.0)]
    [False, False, True]
    """

    def update(self, frame: np.ndarray) -> tuple[float, bool]: ...


class TactileReflex(ABC):
    """Streaming tactile reflex: frames in, closing-ramp targets out (a Reflex).

    Subclasses set :attr:`name`, :attr:`params_class` (a :class:`TactileParams`),
    :attr:`mode`, and :meth:`_detector`.

    Parameters
    ----------
    params : params_class, optional
        Parameters; or give them as keywords, or both (keywords override; see
        :func:`slipreflex.validation.resolve_params`).

    Attributes
    ----------
    fs : float
        Rate at which :meth:`step` must be called.
    last_statistic : float
        Largest statistic over the taxels at the last step.
    last_event : bool
        The last step started a detection (a rising edge of the detector's level).
    last_level : bool
        The detector's level at the last step (slip seen on this frame).
    last_filtered, last_threshold, last_count
        The :class:`~slipreflex.interfaces.Reflex` diagnostics: NaN (no
        filtered scalar), the threshold, None (no windows).
    detections : int
        Detections since the last reset.

    Examples
    --------
    >>> from slipreflex.baselines import SWTSD
    >>> isinstance(SWTSD(threshold=0.1, speed=380.0), TactileReflex)
    True
    """

    name: ClassVar[str]
    params_class: ClassVar[type]
    mode: ClassVar[TriggerMode]
    input_kind: ClassVar[str] = "tactile"

    def __init__(self, params: Any = None, **kwargs: Any) -> None:
        self.params = resolve_params(self.params_class, params, kwargs)
        self.fs = self.params.fs
        self._closer = Closer(self.params.closing)
        self.reset()

    @abstractmethod
    def _detector(self) -> Detector:
        """A fresh detector for this method's parameters."""

    def reset(self) -> None:
        """Restore the initial state.

        Examples
        --------
        >>> from slipreflex.baselines import NMSD
        >>> r = NMSD(threshold=1.0, speed=100.0); r.reset(); r.detections
        0
        """
        self._det = self._detector()
        self._closer.reset()
        self.last_statistic = 0.0
        self.last_event = False
        self.last_level = False
        self.last_filtered = math.nan
        self.last_threshold = float(self.params.threshold)
        self.last_count: int | None = None
        self.detections = 0

    @property
    def closing_s(self) -> float:
        """Total closing time generated since the last reset (s).

        Examples
        --------
        >>> from slipreflex.baselines import NMSD
        >>> NMSD(threshold=1.0, speed=100.0).closing_s
        0.0
        """
        return self._closer.closing_samples / self.fs

    @property
    def closing(self) -> bool:
        """True while the fingers are being told to close.

        Examples
        --------
        >>> from slipreflex.baselines import NMSD
        >>> NMSD(threshold=1.0, speed=100.0).closing
        False
        """
        return self._closer.closing

    def step(self, frame, position: float | None = None) -> float | None:
        """Take one frame of the method's shape; return a new finger target or None.

        A frame that is not finite or not of the method's shape is refused with
        :class:`~slipreflex.errors.DataError` before anything changes.

        Examples
        --------
        >>> import numpy as np
        >>> from slipreflex.baselines import NMSD
        >>> r = NMSD(threshold=50.0, speed=520.0)
        >>> out = [r.step(np.full((4, 4), v)) for v in (0.0, 0.0, 0.0, -1.0)]
        >>> out[-1], r.last_event
        (2.0, True)
        """
        f = as_frame("frame", frame, self.params.shape)
        self.last_statistic, level = self._det.update(f)
        self.last_event = level and not self.last_level
        self.last_level = level
        self.detections += self.last_event
        self._closer.feed(self.last_event if self.mode == "events" else level, self.mode)
        return self._closer.step(position)
