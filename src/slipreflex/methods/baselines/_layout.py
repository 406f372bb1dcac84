"""The state-array layout of the compiled tactile step (an internal API, numpy only).

:func:`slipreflex.methods.baselines._kernels.tactile_step` runs one tactile frame through
NMSD's or SWT-SD's detector and the closing rule on two float64 vectors, like the
chain's ``chain_step`` (:mod:`slipreflex.methods.chain._layout`): ``P``, the parameters,
read only, made by :func:`pack_params`; and ``S``, the state, made by
:func:`init_state`. :class:`~slipreflex.methods.baselines.NMSD`,
:class:`~slipreflex.methods.baselines.SWTSD` and :class:`~slipreflex.methods.baselines.Closer`
are thin shells around one ``(S, P)`` pair; ``reset()`` is ``S[:] = init_state(P)``.
The closing rule's slots form the head of both vectors, so a :class:`Closer` alone
is the head only (:func:`pack_closing`).

Examples
--------
>>> from slipreflex.methods.baselines import SWTParams
>>> P = pack_params(SWTParams(threshold=0.1, speed=380.0, p0=120.0), KIND_SWT, True, np.ones(8))
>>> S = init_state(P)
>>> int(P[P_TAXELS]), int(P[P_SPC]), float(S[S_TARGET]), S.size == S_ARRAYS + 10 * 16
(16, 17, 120.0, True)
"""

from __future__ import annotations

import numpy as np

from ...core._slots import Layout

__all__ = ["pack_closing", "pack_params", "init_state"]

# P, the parameters (read only):
#   P_KIND        KIND_NMSD, KIND_SWT, or KIND_CLOSER (a Closer alone: no detector)
#   P_TAXELS      taxels T of a frame (frames are flat, row-major)
#   P_THRESHOLD   threshold on the method's statistic
#   P_FS          sampling rate (Hz; NMSD's derivative)
#   P_PERSIST     SWT-SD: samples the crossing must persist after the crossing sample
#   P_HOLD        1: the closing rule reads the detector's level ("hold"); 0: its rising edges ("events")
#   P_SPC         closing samples per quantum (ClosingParams.samples_per_close)
#   P_STEP        target increment per closing sample (ClosingParams.step_size)
#   P_LO, P_HI    target saturation
#   P_TARGET0     initial target clip(p0, lo, hi)
#   P_WINDOW      SWT-SD window W (0 for NMSD); then W weights from P_WEIGHTS, oldest sample first
#
# S, the state; reset() is S[:] = init_state(P):
#   S_FRAMES      frames taken since the reset
#   S_STAT, S_EVENT, S_LEVEL   the last frame's largest statistic, detection (rising edge), level
#   S_DETECTIONS  detections since the reset
#   S_TARGET, S_REMAINING, S_CLOSING, S_TRIGGERS, S_EPISODE   the closing rule: target, closing
#                 samples still to run, closing samples run, quanta started, samples into the episode
#   S_RING        SWT-SD: ring slot the next frame goes to
#   then from S_ARRAYS: NMSD the previous frame (T) and the previous derivative (T);
#                       SWT-SD the window ring (W rows of T), each taxel's over-threshold run (T)
#                       and each taxel's last coefficient c_k (T; 0 until the window is full).

# A Closer alone has no detector: its P leaves the detector's slots at 0 (pack_closing).
PARAMS = Layout("a tactile method's parameters P", """
    KIND TAXELS=0 THRESHOLD=0 FS=0 PERSIST=0 HOLD SPC STEP LO HI TARGET0 WINDOW=0""", prefix="P_")
(P_KIND, P_TAXELS, P_THRESHOLD, P_FS, P_PERSIST, P_HOLD, P_SPC, P_STEP, P_LO, P_HI, P_TARGET0,
 P_WINDOW) = PARAMS.slots
P_WEIGHTS = PARAMS.size   # then the SWT-SD window's W weights

STATE = Layout("a tactile method's state S", """
    FRAMES=0 STAT=0 EVENT=0 LEVEL=0 DETECTIONS=0 TARGET REMAINING=0 CLOSING=0 TRIGGERS=0
    EPISODE=0 RING=0""", prefix="S_")
(S_FRAMES, S_STAT, S_EVENT, S_LEVEL, S_DETECTIONS, S_TARGET, S_REMAINING, S_CLOSING, S_TRIGGERS,
 S_EPISODE, S_RING) = STATE.slots
S_ARRAYS = STATE.size     # then the detector's arrays

KIND_CLOSER, KIND_NMSD, KIND_SWT = -1.0, 0.0, 1.0


def pack_closing(closing, hold: bool = False) -> np.ndarray:
    """The head of ``P``: a :class:`~slipreflex.methods.baselines.ClosingParams` (a Closer's whole ``P``)."""
    head = PARAMS.new()
    head[P_KIND] = KIND_CLOSER
    head[P_HOLD] = float(hold)
    head[P_SPC] = closing.samples_per_close
    head[P_STEP] = closing.step_size
    head[P_LO] = closing.lo
    head[P_HI] = closing.hi
    head[P_TARGET0] = min(max(closing.p0, closing.lo), closing.hi)
    return PARAMS.check(head)


def pack_params(params, kind: float, hold: bool, weights: np.ndarray) -> np.ndarray:
    """``P`` of a tactile method: its :class:`~slipreflex.methods.baselines.TactileParams`, its kind,
    its trigger mode and its window weights (empty for NMSD)."""
    head = pack_closing(params.closing, hold)
    head[P_KIND] = kind
    head[P_TAXELS] = int(np.prod(params.shape))
    head[P_THRESHOLD] = params.threshold
    head[P_FS] = params.fs
    head[P_PERSIST] = getattr(params, "persist", 0)
    head[P_WINDOW] = len(weights)
    return np.concatenate([PARAMS.check(head), np.asarray(weights, dtype=np.float64)])


def init_state(P: np.ndarray) -> np.ndarray:
    """The initial state ``S`` for the parameter vector ``P`` (what ``reset`` restores)."""
    taxels = int(P[P_TAXELS])
    rows = int(P[P_WINDOW]) + 2 if P[P_KIND] == KIND_SWT else 2 if P[P_KIND] == KIND_NMSD else 0
    S = STATE.new(rows * taxels, tail=0.0)
    S[S_TARGET] = P[P_TARGET0]
    return STATE.check(S)
