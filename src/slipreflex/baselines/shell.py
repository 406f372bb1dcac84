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
from typing import Any, ClassVar, Protocol

import numpy as np

from ..validation import resolve_params
from ._validate import as_frame
from .closing import Closer, TriggerMode

__all__ = ["Detector", "TactileReflex"]


class Detector(Protocol):
    """What a tactile method computes on each frame.

    ``update(frame)`` takes one finite flat frame (float64, one value per taxel)
    and returns ``(statistic, trigger, event)``: the largest statistic over the
    taxels, the detector output the closing rule reads (a detection for
    ``"events"`` mode, the ON/OFF signal for ``"hold"``), and whether a new
    detection started.

    Examples
    --------
    >>> from slipreflex.baselines.nmsd import NMSDDetector
    >>> d = NMSDDetector(fs=10.0, threshold=1.0)
    >>> [d.update(np.array([x]))[2] for x in (0.0, 0.0, 1.0)]
    [False, False, True]
    """

    def update(self, frame: np.ndarray) -> tuple[float, bool, bool]: ...


class TactileReflex(ABC):
    """Streaming tactile reflex: frames in, closing-ramp targets out (a Reflex).

    Subclasses set :attr:`name`, :attr:`params_class` (a frozen dataclass with
    ``threshold``, ``fs``, ``shape`` and a ``closing`` property), :attr:`mode`,
    and :meth:`_detector`.

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
        The last step started a detection.
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
        self.last_trigger = False
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
        self.last_statistic, self.last_trigger, self.last_event = self._det.update(f)
        self.detections += self.last_event
        self._closer.feed(self.last_trigger, self.mode)
        return self._closer.step(position)
