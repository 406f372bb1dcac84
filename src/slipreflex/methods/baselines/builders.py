"""NMSD and SWT-SD as the registry builds them (:mod:`slipreflex.methods` names these by entry point).

Examples
--------
>>> from slipreflex.methods import MethodContext
>>> build_nmsd(100.0, MethodContext(thresholds={"nmsd": 40.0}, speed=500.0, method="nmsd")).params.threshold
40.0
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...core.errors import ParameterError
from .. import Detections, MethodContext
from .nmsd import NMSD, nmsd_detections
from .swt import SWTSD, swt_on

__all__ = ["build_nmsd", "build_swt", "nmsd_method_detections", "swt_method_detections"]

_FORCE_LABEL = "index tactile array, total force (N)"


def _tactile_kwargs(context: MethodContext, params: dict[str, Any]) -> dict[str, Any]:
    """Threshold and speed from the context unless the caller gave them."""
    if "threshold" not in params:
        if context.threshold is None:
            raise ParameterError(f"{context.method} needs a threshold: pass threshold=... or a context "
                                 "with calibrated thresholds (slipreflex.reproduce.experiments.calibrate)")
        params["threshold"] = context.threshold
    if "speed" not in params:
        params["speed"] = context.closing_speed()
    return params


def build_nmsd(p0: float, context: MethodContext, **params: Any) -> NMSD:
    """An :class:`NMSD` with the context's calibrated threshold and closing speed.

    Examples
    --------
    >>> build_nmsd(0.0, MethodContext(speed=500.0), threshold=30.0).params.speed
    500.0
    """
    return NMSD(p0=p0, **_tactile_kwargs(context, params))


def build_swt(p0: float, context: MethodContext, **params: Any) -> SWTSD:
    """An :class:`SWTSD` with the context's threshold, closing speed and ``swt_persist`` option.

    Examples
    --------
    >>> build_swt(0.0, MethodContext(speed=500.0, options={"swt_persist": 3}), threshold=0.1).params.persist
    3
    """
    if "persist" not in params and context.options.get("swt_persist") is not None:
        params["persist"] = context.options["swt_persist"]
    return SWTSD(p0=p0, **_tactile_kwargs(context, params))


def _total_force(frames: np.ndarray) -> np.ndarray:
    return np.asarray(frames, dtype=float).reshape(len(frames), -1).sum(axis=1)


def nmsd_method_detections(reflex: Any, frames: np.ndarray) -> Detections:
    """What a trial figure draws for NMSD: the total force and the detections.

    Examples
    --------
    >>> r = build_nmsd(0.0, MethodContext(speed=500.0), threshold=30.0)
    >>> nmsd_method_detections(r, np.zeros((5, 4, 4))).events.tolist()
    [False, False, False, False, False]
    """
    det = nmsd_detections(frames, reflex.fs, threshold=reflex.params.threshold)
    return Detections(_total_force(frames), _FORCE_LABEL, det, "NMSD detections")


def swt_method_detections(reflex: Any, frames: np.ndarray) -> Detections:
    """What a trial figure draws for SWT-SD: the total force and where each ON stretch starts.

    Examples
    --------
    >>> r = build_swt(0.0, MethodContext(speed=500.0), threshold=0.1)
    >>> swt_method_detections(r, np.zeros((5, 4, 4))).event_label
    'SWT-SD ON starts'
    """
    on = swt_on(frames, threshold=reflex.params.threshold, persist=reflex.params.persist)
    starts = on & ~np.concatenate(([False], on[:-1]))
    return Detections(_total_force(frames), _FORCE_LABEL, starts, "SWT-SD ON starts")
