"""The chain's methods as the registry builds them (:mod:`slipreflex.methods` names these by entry point).

Examples
--------
>>> from slipreflex.methods import MethodContext
>>> build_chain({"dath": True}, "dath", 120.0, MethodContext()).params.p0
120.0
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ...core import hardware as hw
from .. import Detections, MethodContext
from .reflex import SlipReflex, run_chain

__all__ = ["build_chain", "build_preset", "chain_detections"]


def build_chain(chain_params: Mapping[str, Any], name: str, p0: float, context: MethodContext,
                **params: Any) -> SlipReflex:
    """A :class:`SlipReflex` with ``chain_params``, the caller's ``params`` over them, named ``name``.

    Examples
    --------
    >>> build_chain({"n": 8}, "n8", 100.0, MethodContext()).name
    'n8'
    """
    reflex = SlipReflex(**{"fs": hw.DAQ_FS, **chain_params, **params, "p0": p0})
    reflex.name = name
    return reflex


def build_preset(preset: str, name: str, fixed: Mapping[str, Any], p0: float, context: MethodContext,
                 **params: Any) -> SlipReflex:
    """A :class:`SlipReflex` from a preset with ``fixed`` parameters, the caller's ``params`` over them.

    Examples
    --------
    >>> build_preset("dath-event", "dath-event", {}, 100.0, MethodContext()).name
    'dath-event'
    """
    reflex = SlipReflex.from_preset(preset, fs=params.pop("fs", hw.DAQ_FS), **{**fixed, **params, "p0": p0})
    reflex.name = name
    return reflex


def chain_detections(reflex: Any, volts: np.ndarray) -> Detections:
    """What a trial figure draws for a chain method: the filtered signal and the spikes.

    Examples
    --------
    >>> chain_detections(SlipReflex(), np.full(64, 0.4)).event_label
    'events (spikes)'
    """
    res = run_chain(volts, reflex.params)
    return Detections(res.filtered, f"slip sensor, {reflex.params.cutoff:g} Hz low-pass (V)",
                      np.asarray(res.events, dtype=bool), "events (spikes)")
