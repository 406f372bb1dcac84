"""The reflex shell NMSD and SWT-SD share: one compiled step over a state vector.

A tactile method differs from another only in its *detector*: what it
computes on each frame and when that means slip. Both detectors, the rising
edge and the closing rule (:class:`~slipreflex.methods.baselines.Closer`'s arithmetic)
are one compiled function, ``tactile_step(S, P, frame, position)``
(:mod:`slipreflex.methods.baselines._kernels`, layout in
:mod:`slipreflex.methods.baselines._layout`). :class:`TactileReflex` holds the
parameter vector ``P`` and the state vector ``S``, checks each frame against
the method's frame shape before calling the step, reads the diagnostics of the
:class:`~slipreflex.core.interfaces.Reflex` protocol out of ``S``, and resets it in
place. :meth:`TactileReflex.compiled` hands the step and the live vectors to a
compiled closed loop, which then advances the very state the object holds. A
method is a parameter class and four class attributes.

Examples
--------
>>> import numpy as np
>>> from slipreflex.methods.baselines import NMSD
>>> r = NMSD(threshold=50.0, speed=520.0, shape=(3,))       # a 3-channel sensor
>>> [r.step(np.full(3, v)) is not None for v in (0.0, 0.0, 0.0, -1.0)]
[False, False, False, True]
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ...core._slots import slot
from ...core.hardware import FINGER_MAX, FINGER_MIN, NMSD_FS, TACTILE_SHAPE
from ...core.validation import number, resolve_params, set_field
from . import _layout as _L
from . import closing as _closing
from ._validate import as_frame, frame_shape
from .closing import CLOSE_S, ClosingParams, TriggerMode, _load_kernels

if TYPE_CHECKING:
    from ...core.interfaces import InputKind

__all__ = ["TactileParams", "TactileReflex"]


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
        :func:`slipreflex.methods.baselines.rest_threshold`.
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
        _ = self.closing  # validates speed, close_s, p0, lo, hi

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


class TactileReflex(ABC):
    """Streaming tactile reflex: frames in, closing-ramp targets out (a Reflex).

    Subclasses set :attr:`name`, :attr:`params_class` (a :class:`TactileParams`),
    :attr:`mode`, :attr:`kind` (which detector of the compiled step) and
    :meth:`_weights`.

    Parameters
    ----------
    params : params_class, optional
        Parameters; or give them as keywords, or both (keywords override; see
        :func:`slipreflex.core.validation.resolve_params`).

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
        The :class:`~slipreflex.core.interfaces.Reflex` diagnostics: NaN (no
        filtered scalar), the threshold, None (no windows).
    detections : int
        Detections since the last reset.

    Examples
    --------
    >>> from slipreflex.methods.baselines import SWTSD
    >>> isinstance(SWTSD(threshold=0.1, speed=380.0), TactileReflex)
    True
    """

    name: str
    params_class: ClassVar[type]
    mode: ClassVar[TriggerMode]
    kind: ClassVar[float]
    input_kind: InputKind = "tactile"

    def __init__(self, params: Any = None, **kwargs: Any) -> None:
        self.params = resolve_params(self.params_class, params, kwargs)
        self.fs = self.params.fs
        self._P = _L.pack_params(self.params, self.kind, self.mode == "hold", self._weights())
        self._S0 = _L.init_state(self._P)
        self._S = self._S0.copy()
        _load_kernels()

    @abstractmethod
    def _weights(self) -> np.ndarray:
        """The detector's window weights, oldest sample first (empty for a detector without)."""

    def reset(self) -> None:
        """Restore the initial state, in place (a compiled loop holding ``S`` sees it).

        Examples
        --------
        >>> from slipreflex.methods.baselines import NMSD
        >>> r = NMSD(threshold=1.0, speed=100.0); r.reset(); r.detections
        0
        """
        self._S[:] = self._S0

    last_statistic = slot(_L.S_STAT, float, "Largest statistic over the taxels at the last step.")
    last_event = slot(_L.S_EVENT, bool, "The last step started a detection.")
    last_level = slot(_L.S_LEVEL, bool, "The detector's level at the last step.")
    detections = slot(_L.S_DETECTIONS, int, "Detections since the last reset.")
    last_filtered = math.nan
    last_count = None

    @property
    def last_threshold(self) -> float:
        """The detection threshold (the method's statistic is compared with it)."""
        return float(self.params.threshold)

    @property
    def closing_s(self) -> float:
        """Total closing time generated since the last reset (s).

        Examples
        --------
        >>> from slipreflex.methods.baselines import NMSD
        >>> NMSD(threshold=1.0, speed=100.0).closing_s
        0.0
        """
        return float(self._S[_L.S_CLOSING]) / self.fs

    @property
    def closing(self) -> bool:
        """True while the fingers are being told to close.

        Examples
        --------
        >>> from slipreflex.methods.baselines import NMSD
        >>> NMSD(threshold=1.0, speed=100.0).closing
        False
        """
        return bool(self._S[_L.S_REMAINING] > 0.0)

    @property
    def probe_slots(self) -> dict[str, int]:
        """The slots of the state vector a closed loop records after every frame (what it computed).

        ``stat`` the frame's largest statistic, ``event`` 1 at a detection (rising edge),
        ``level`` 1 while over the threshold, ``target`` the closing rule's target.

        Examples
        --------
        >>> from slipreflex.methods.baselines import NMSD
        >>> sorted(NMSD(threshold=1.0, speed=500.0).probe_slots)
        ['event', 'level', 'stat', 'target']
        """
        return {"stat": _L.S_STAT, "event": _L.S_EVENT, "level": _L.S_LEVEL, "target": _L.S_TARGET}

    def compiled(self) -> tuple[Any, np.ndarray, np.ndarray]:
        """The compiled step and the live state: ``(tactile_step, S, P)``.

        ``tactile_step(S, P, frame, position) -> float`` takes the frame's taxels
        as a flat float64 array (row-major) and the measured slip-finger position
        (NaN unknown) and returns the new target, or NaN; called from numba code
        on this ``S``, it advances this object (``step`` goes on from there, and
        ``reset`` restores ``S`` in place). A non-finite frame changes nothing.

        Examples
        --------
        >>> import numpy as np
        >>> from slipreflex.methods.baselines import NMSD
        >>> r = NMSD(threshold=50.0, speed=520.0)
        >>> step, S, P = r.compiled()
        >>> [step(S, P, np.full(16, v), np.nan) for v in (0.0, 0.0, 0.0, -1.0)][-1], r.detections
        (2.0, 1)
        """
        return _load_kernels().tactile_step, self._S, self._P

    def step(self, frame, position: float | None = None) -> float | None:
        """Take one frame of the method's shape; return a new finger target or None.

        A frame that is not finite or not of the method's shape is refused with
        :class:`~slipreflex.core.errors.DataError` before anything changes.

        Examples
        --------
        >>> import numpy as np
        >>> from slipreflex.methods.baselines import NMSD
        >>> r = NMSD(threshold=50.0, speed=520.0)
        >>> out = [r.step(np.full((4, 4), v)) for v in (0.0, 0.0, 0.0, -1.0)]
        >>> out[-1], r.last_event
        (2.0, True)
        """
        f = as_frame("frame", frame, self.params.shape)
        u = _closing._K.tactile_step(self._S, self._P, f, _NAN if position is None else float(position))
        return None if u != u else u


_NAN = math.nan
