"""The state-array layout of the compiled chain step (an internal API).

:func:`slipreflex.methods.chain._kernels.chain_step` runs one raw sample through the
whole chain (filter -> encoder -> windows -> MPI, docs/method.md) on two float64
vectors: ``P``, the parameters, read only, made by :func:`pack_params` from a
:class:`~slipreflex.methods.chain.ReflexParams`; and ``S``, the state, made by
:func:`init_state`. :class:`~slipreflex.methods.chain.SlipReflex` is a thin shell around
one ``(S, P)`` pair and :func:`~slipreflex.methods.chain.run_chain` loops the same step
in compiled code, so a compiled closed loop that holds ``S`` and ``P`` and calls
``chain_step(S, P, raw, position)`` runs the very chain ``SlipReflex`` runs.
This module holds only numpy code, so importing it does not import numba.

Examples
--------
>>> from slipreflex.methods.chain import ReflexParams
>>> P = pack_params(ReflexParams(dath=True))
>>> S = init_state(P)
>>> int(P[P_N]), float(S[S_THETA]), float(S[S_LAST_COUNT])
(16, 0.008, -1.0)
"""

from __future__ import annotations

import numpy as np

from ...core._slots import Layout
from ._shared import _clip, _design

__all__ = ["pack_params", "init_state"]

# Two float64 vectors hold everything:
#
# P, the parameters (read only), built by pack_params(ReflexParams):
#   P_FILTER       0 off, 1 Butterworth, 2 moving mean
#   P_THETA0       base threshold theta0 (V)
#   P_DATH         1 with DATH
#   P_D            DATH duration (samples)
#   P_FLOOR        DATH floor (V)
#   P_X0, P_X0_GIVEN   initial reference, and 1 if given (else the first filtered sample)
#   P_ACC_RESET    periodic accumulator reset every this many samples, 0 = never
#   P_LEAK, P_LEAK_ON  accumulator factor per sample exp(-1/tau), and 1 if the leak is on
#   P_N            window length (samples)
#   P_P0, P_M0     P0, and the initial command clip(p0)
#   P_KP, P_KI     gains
#   P_RESET_AFTER  zero windows before the MPI reset, -1 = never
#   P_LO, P_HI     saturation
#   P_EVENT        1 for the event-driven MPI
#   P_MEAN_M       moving-mean length M
#   P_NSEC         number of second-order sections; then 6 * P_NSEC sos coefficients
#                  (from P_SOS) and 2 * P_NSEC steady-state factors zi0
#
# S, the state, built by init_state(P); reset() is S[:] = init_state(P):
#   S_STARTED      1 once a finite sample has arrived (filter and reference set)
#   S_PREV, S_ACC, S_THETA, S_REMAINING, S_CLOCK   encoder state (docs/method.md section 1.2 + periodic reset)
#   S_COUNT, S_FILLED   spikes and samples in the current window
#   S_PBASE, S_H, S_M   MPI: P0, integral h, command (never decreases)
#   S_ZEROS        zero windows in a row (window MPI), samples since the last spike (event MPI)
#   S_SLIDE, S_SLIDE_POS   event MPI: spikes in the last N samples, ring position
#   S_MEAN_N, S_MEAN_POS   moving mean: samples held, ring position
#   S_LAST_X, S_LAST_EVENT, S_LAST_THETA, S_LAST_ACC, S_LAST_COUNT   diagnostics of the
#                  last step (filtered sample, NaN if skipped; spike; threshold in force;
#                  accumulator before its reset; window count or -1)
#   S_SKIPPED      non-finite samples skipped since the reset
#   then the filter state zi (2 * P_NSEC), the event ring (N), the mean ring (M).

PARAMS = Layout("the chain's parameters P", """
    FILTER THETA0 DATH D FLOOR X0 X0_GIVEN ACC_RESET LEAK LEAK_ON N
    P0 M0 KP KI RESET_AFTER LO HI EVENT MEAN_M NSEC""", prefix="P_")
(P_FILTER, P_THETA0, P_DATH, P_D, P_FLOOR, P_X0, P_X0_GIVEN, P_ACC_RESET, P_LEAK, P_LEAK_ON, P_N,
 P_P0, P_M0, P_KP, P_KI, P_RESET_AFTER, P_LO, P_HI, P_EVENT, P_MEAN_M, P_NSEC) = PARAMS.slots
P_SOS = PARAMS.size   # the sos coefficients, then zi0, follow the named slots

STATE = Layout("the chain's state S", """
    STARTED=0 PREV ACC=0 THETA REMAINING=0 CLOCK=0 COUNT=0 FILLED=0 PBASE H=0 M
    ZEROS=0 SLIDE=0 SLIDE_POS=0 MEAN_N=0 MEAN_POS=0 LAST_X=nan LAST_EVENT=0 LAST_THETA
    LAST_ACC=0 LAST_COUNT=-1 SKIPPED=0""", prefix="S_")
(S_STARTED, S_PREV, S_ACC, S_THETA, S_REMAINING, S_CLOCK, S_COUNT, S_FILLED, S_PBASE, S_H, S_M,
 S_ZEROS, S_SLIDE, S_SLIDE_POS, S_MEAN_N, S_MEAN_POS, S_LAST_X, S_LAST_EVENT, S_LAST_THETA,
 S_LAST_ACC, S_LAST_COUNT, S_SKIPPED) = STATE.slots
S_ZI = STATE.size     # the filter state zi, the event ring and the mean ring follow

FILTER_OFF, FILTER_BUTTERWORTH, FILTER_MEAN = 0.0, 1.0, 2.0


def pack_params(params) -> np.ndarray:
    """The parameter vector P of :func:`chain_step` for a :class:`ReflexParams`."""
    p = params
    sos, zi0 = _design(p.fs, p.cutoff)
    kind = FILTER_OFF if not p.filter else FILTER_MEAN if p.filter_kind == "mean" else FILTER_BUTTERWORTH
    e = p.encoder
    head = PARAMS.new()
    head[P_FILTER] = kind
    head[P_THETA0] = p.threshold
    head[P_DATH] = float(p.dath)
    head[P_D] = p.dath_samples
    head[P_FLOOR] = p.dath_floor
    head[P_X0] = 0.0 if p.x0 is None else p.x0
    head[P_X0_GIVEN] = float(p.x0 is not None)
    head[P_ACC_RESET] = 0 if p.acc_reset is None else p.acc_reset
    head[P_LEAK] = e.leak_factor
    head[P_LEAK_ON] = float(p.acc_leak is not None)
    head[P_N] = p.n
    head[P_P0] = p.p0
    head[P_M0] = _clip(p.p0, p.lo, p.hi)
    head[P_KP] = p.kp
    head[P_KI] = p.ki
    head[P_RESET_AFTER] = -1 if p.reset_after is None else p.reset_after
    head[P_LO] = p.lo
    head[P_HI] = p.hi
    head[P_EVENT] = float(p.mpi_mode == "event")
    head[P_MEAN_M] = p.lowpass.window
    head[P_NSEC] = sos.shape[0]
    return np.concatenate([PARAMS.check(head), sos.ravel(), zi0.ravel()])



def init_state(P: np.ndarray) -> np.ndarray:
    """The initial state vector S for the parameter vector ``P`` (what ``reset`` restores)."""
    nsec = int(P[P_NSEC])
    size = S_ZI + 2 * nsec + int(P[P_N]) + int(P[P_MEAN_M])
    S = STATE.new(size - S_ZI, tail=0.0)
    S[S_THETA] = P[P_THETA0]
    S[S_PREV] = P[P_X0]
    S[S_PBASE] = P[P_P0]
    S[S_M] = P[P_M0]
    S[S_LAST_THETA] = P[P_THETA0]
    return STATE.check(S)
