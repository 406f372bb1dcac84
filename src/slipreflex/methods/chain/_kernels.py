"""numba kernels of the chain: one per-sample update per stage, composed.

The per-sample updates here are the arithmetic of docs/method.md sections 1.1-1.4 written once for
compiled code; the streaming objects in the sibling modules perform exactly the
same IEEE operations in the same order (no fastmath, so no FMA contraction), which
is why batch and streaming agree bit for bit. Imported lazily by the batch
functions so that ``import slipreflex`` does not pay for numba.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...core._numba_cache import stamped_cache
from . import _layout
from ._layout import (
    FILTER_BUTTERWORTH,
    FILTER_MEAN,
    P_ACC_RESET,
    P_D,
    P_DATH,
    P_EVENT,
    P_FILTER,
    P_FLOOR,
    P_HI,
    P_KI,
    P_KP,
    P_LEAK,
    P_LEAK_ON,
    P_LO,
    P_M0,
    P_MEAN_M,
    P_N,
    P_NSEC,
    P_P0,
    P_RESET_AFTER,
    P_SOS,
    P_THETA0,
    P_X0,
    P_X0_GIVEN,
    S_ACC,
    S_CLOCK,
    S_COUNT,
    S_FILLED,
    S_H,
    S_LAST_ACC,
    S_LAST_COUNT,
    S_LAST_EVENT,
    S_LAST_THETA,
    S_LAST_X,
    S_M,
    S_MEAN_N,
    S_MEAN_POS,
    S_PBASE,
    S_PREV,
    S_REMAINING,
    S_SKIPPED,
    S_SLIDE,
    S_SLIDE_POS,
    S_STARTED,
    S_THETA,
    S_ZEROS,
    S_ZI,
)

#: these kernels compile in the layout's slot constants: their cache is stamped with it too
_CACHE = stamped_cache(__file__, _layout.__file__)


@njit(cache=_CACHE, inline="always")
def sos_update(sos, zi, x):
    """One sample through every second-order section (scipy's sosfilt order)."""
    for s in range(sos.shape[0]):
        y = sos[s, 0] * x + zi[s, 0]
        zi[s, 0] = sos[s, 1] * x - sos[s, 4] * y + zi[s, 1]
        zi[s, 1] = sos[s, 2] * x - sos[s, 5] * y
        x = y
    return x


@njit(cache=_CACHE, inline="always")
def encoder_update(x, prev, acc, theta, remaining, clock, theta0, dath, dath_samples, floor,
                   acc_reset, leak, leak_on):
    """docs/method.md section 1.2 for one sample, with the accumulator's optional leak and periodic reset.

    Returns (event, acc_before_reset, theta_used, acc, theta, remaining, clock).
    ``acc_reset <= 0`` means no periodic reset; ``leak_on`` multiplies the old
    accumulator by ``leak`` before adding the new difference.
    """
    d = x - prev
    acc = acc * leak + d if leak_on else acc + d
    theta_used = theta
    acc_seen = acc
    event = abs(acc) > theta
    if event:
        acc = 0.0
    if acc_reset > 0:
        clock += 1
        if clock >= acc_reset:
            clock = 0
            acc = 0.0
    if dath:
        if remaining > 0:
            remaining -= 1
            if remaining == 0:
                theta = theta0
        elif event:
            ad = abs(d)
            theta = ad if ad > floor else floor
            remaining = dath_samples
    return event, acc_seen, theta_used, acc, theta, remaining, clock


@njit(cache=_CACHE, inline="always")
def mpi_update(v, p_base, h, m_prev, zeros, kp, ki, reset_after, lo, hi, position):
    """docs/method.md section 1.4 for one window; a reset takes ``position`` as P0, or the command if it is NaN.

    ``reset_after < 0`` never resets.
    """
    h = h + v
    pi = p_base + kp * v + ki * h
    m = pi if pi > m_prev else m_prev
    if m < lo:
        m = lo
    elif m > hi:
        m = hi
    zeros = zeros + 1 if v == 0.0 else 0
    if zeros == reset_after:
        p_base = m if np.isnan(position) else position
        h = 0.0
        zeros = 0
    return m, p_base, h, zeros


@njit(cache=_CACHE)
def lowpass_kernel(raw, sos, zi, out):
    for k in range(raw.size):
        out[k] = sos_update(sos, zi, raw[k])


@njit(cache=_CACHE)
def encode_kernel(x, prev, theta0, dath, dath_samples, floor, acc_reset, leak, leak_on,
                  events, acc_out, theta_out):
    acc = 0.0
    theta = theta0
    remaining = 0
    clock = 0
    for k in range(x.size):
        event, acc_seen, theta_used, acc, theta, remaining, clock = encoder_update(
            x[k], prev, acc, theta, remaining, clock, theta0, dath, dath_samples, floor,
            acc_reset, leak, leak_on)
        events[k] = event
        acc_out[k] = acc_seen
        theta_out[k] = theta_used
        prev = x[k]


@njit(cache=_CACHE)
def mpi_kernel(v, p0, m0, kp, ki, reset_after, lo, hi, out):
    p_base = p0
    h = 0.0
    m_prev = m0
    zeros = 0
    for z in range(v.size):
        m_prev, p_base, h, zeros = mpi_update(v[z], p_base, h, m_prev, zeros, kp, ki, reset_after, lo, hi,
                                              np.nan)
        out[z] = m_prev



# --- the composed chain over a state array (layout: slipreflex.methods.chain._layout) -------------

@njit(cache=_CACHE, inline="always")
def _offsets(P):
    """Start of zi, of the event ring and of the mean ring in the state vector."""
    nsec = int(P[P_NSEC])
    slide = S_ZI + 2 * nsec
    return nsec, slide, slide + int(P[P_N])


@njit(cache=_CACHE, inline="always")
def _filter_step(S, P, raw, first):
    kind = P[P_FILTER]
    nsec, _slide, mean = _offsets(P)
    if kind == FILTER_BUTTERWORTH:
        if first:
            z0 = P_SOS + 6 * nsec
            for i in range(2 * nsec):
                S[S_ZI + i] = P[z0 + i] * raw
        x = raw
        for s in range(nsec):  # sos_update's arithmetic, on the flat vectors
            c = P_SOS + 6 * s
            z = S_ZI + 2 * s
            y = P[c] * x + S[z]
            S[z] = P[c + 1] * x - P[c + 4] * y + S[z + 1]
            S[z + 1] = P[c + 2] * x - P[c + 5] * y
            x = y
        return x
    if kind == FILTER_MEAN:
        m = int(P[P_MEAN_M])
        pos = int(S[S_MEAN_POS])
        S[mean + pos] = raw
        pos = (pos + 1) % m
        S[S_MEAN_POS] = pos
        held = int(S[S_MEAN_N]) + 1
        if held > m:
            held = m
        S[S_MEAN_N] = held
        start = pos if held == m else 0
        total = 0.0
        for i in range(held):  # oldest first, as a literal sum over the last M samples
            total += S[mean + (start + i) % m]
        return total / held
    return raw


@njit(cache=_CACHE, inline="always")
def _encoder_step(S, P, x):
    event, acc_seen, theta_used, acc, theta, remaining, clock = encoder_update(
        x, S[S_PREV], S[S_ACC], S[S_THETA], int(S[S_REMAINING]), int(S[S_CLOCK]), P[P_THETA0],
        P[P_DATH] != 0.0, int(P[P_D]), P[P_FLOOR], int(P[P_ACC_RESET]), P[P_LEAK], P[P_LEAK_ON] != 0.0)
    S[S_ACC] = acc
    S[S_THETA] = theta
    S[S_REMAINING] = remaining
    S[S_CLOCK] = clock
    S[S_PREV] = x
    S[S_LAST_X] = x
    S[S_LAST_THETA] = theta_used
    S[S_LAST_ACC] = acc_seen
    return event


@njit(cache=_CACHE, inline="always")
def _event_mpi_step(S, P, event, position):
    """The event-driven MPI for one sample; returns the new command or NaN if unchanged."""
    n = int(P[P_N])
    _nsec, slide, _mean = _offsets(P)
    y = 1.0 if event else 0.0
    pos = int(S[S_SLIDE_POS])
    s = S[S_SLIDE] + y - S[slide + pos]
    S[slide + pos] = y
    S[S_SLIDE_POS] = (pos + 1) % n
    S[S_SLIDE] = s
    m_prev = S[S_M]
    h = S[S_H] + y
    pi = S[S_PBASE] + P[P_KP] * s + P[P_KI] * h
    m = pi if pi > m_prev else m_prev
    if m < P[P_LO]:
        m = P[P_LO]
    elif m > P[P_HI]:
        m = P[P_HI]
    quiet = 0.0 if event else S[S_ZEROS] + 1.0
    if quiet == P[P_RESET_AFTER] * n:
        S[S_PBASE] = m if np.isnan(position) else position
        h = 0.0
        quiet = 0.0
    S[S_H] = h
    S[S_ZEROS] = quiet
    S[S_M] = m
    return m if m != m_prev else np.nan


@njit(cache=_CACHE, inline="always")
def _chain_step(S, P, raw, position):
    """One raw sample through the whole chain; the new command, or NaN for none.

    ``position`` is the measured slip-finger position, NaN when unknown. A
    non-finite ``raw`` is skipped: no filter or encoder update, no spike, the
    window advances (SlipReflex.step's documented rule).
    """
    if np.isfinite(raw):
        first = S[S_STARTED] == 0.0
        S[S_STARTED] = 1.0
        x = _filter_step(S, P, raw, first)
        if first and P[P_X0_GIVEN] == 0.0:
            S[S_PREV] = x
        event = _encoder_step(S, P, x)
    else:
        event = False
        S[S_SKIPPED] += 1.0
        S[S_LAST_X] = np.nan
    S[S_LAST_EVENT] = 1.0 if event else 0.0
    out = np.nan
    if P[P_EVENT] != 0.0:
        out = _event_mpi_step(S, P, event, position)
    count = S[S_COUNT] + (1.0 if event else 0.0)
    filled = S[S_FILLED] + 1.0
    S[S_LAST_COUNT] = -1.0
    if filled == P[P_N]:
        S[S_LAST_COUNT] = count
        if P[P_EVENT] == 0.0:
            m, p_base, h, zeros = mpi_update(count, S[S_PBASE], S[S_H], S[S_M], int(S[S_ZEROS]),
                                             P[P_KP], P[P_KI], int(P[P_RESET_AFTER]), P[P_LO], P[P_HI],
                                             position)
            S[S_M] = m
            S[S_PBASE] = p_base
            S[S_H] = h
            S[S_ZEROS] = zeros
            out = m
        count = 0.0
        filled = 0.0
    S[S_COUNT] = count
    S[S_FILLED] = filled
    return out


@njit(cache=_CACHE)
def chain_step(S, P, raw, position):
    """One raw sample through the whole chain (state ``S``, parameters ``P``, layout in
    :mod:`slipreflex.methods.chain._layout`); the new command, or NaN for none. ``position`` is the
    measured slip-finger position, NaN when unknown; a non-finite ``raw`` is skipped."""
    return _chain_step(S, P, raw, position)


@njit(cache=_CACHE)
def chain_kernel(raw, S, P, x_out, events, acc_out, theta_out, counts, commands, sample_commands):
    """chain_step over a whole recording, keeping its per-sample and per-window outputs.

    From the initial state, a finite recording through the Butterworth (or no) filter and
    the windowed MPI runs stage by stage (:func:`_staged_chain`): the same updates in the
    same order per sample, so the same bits, with each stage's loop free of the others'
    branches (about twice as fast). Anything else steps the composed chain.
    """
    if S[S_STARTED] == 0.0 and P[P_FILTER] != FILTER_MEAN and P[P_EVENT] == 0.0 and np.isfinite(raw).all():
        _staged_chain(raw, P, x_out, events, acc_out, theta_out, counts, commands, sample_commands)
        return
    n = int(P[P_N])
    for k in range(raw.size):
        _chain_step(S, P, raw[k], np.nan)
        x_out[k] = S[S_LAST_X]
        events[k] = S[S_LAST_EVENT] != 0.0
        acc_out[k] = S[S_LAST_ACC]
        theta_out[k] = S[S_LAST_THETA]
        sample_commands[k] = S[S_M]
        if (k + 1) % n == 0:
            z = (k + 1) // n - 1
            counts[z] = int(S[S_LAST_COUNT])
            commands[z] = S[S_M]


@njit(cache=_CACHE)
def _staged_chain(raw, P, x_out, events, acc_out, theta_out, counts, commands, sample_commands):
    """chain_kernel's outputs from the initial state, one stage over the whole recording at a time."""
    nsec, _slide, _mean = _offsets(P)
    if P[P_FILTER] == FILTER_BUTTERWORTH:
        z0 = P_SOS + 6 * nsec
        sos = P[P_SOS:z0].reshape((nsec, 6))
        zi = np.empty((nsec, 2))
        for i in range(nsec):
            zi[i, 0] = P[z0 + 2 * i] * raw[0]
            zi[i, 1] = P[z0 + 2 * i + 1] * raw[0]
        for k in range(raw.size):
            x_out[k] = sos_update(sos, zi, raw[k])
    else:
        x_out[:] = raw
    prev = x_out[0] if P[P_X0_GIVEN] == 0.0 else P[P_X0]
    encode_kernel(x_out, prev, P[P_THETA0], P[P_DATH] != 0.0, int(P[P_D]), P[P_FLOOR], int(P[P_ACC_RESET]),
                  P[P_LEAK], P[P_LEAK_ON] != 0.0, events, acc_out, theta_out)
    n = int(P[P_N])
    p_base = P[P_P0]
    h = 0.0
    m = P[P_M0]
    zeros = 0
    reset_after = int(P[P_RESET_AFTER])
    for z in range(counts.size):
        c = 0
        for k in range(z * n, (z + 1) * n):
            c += events[k]
        counts[z] = c
        m, p_base, h, zeros = mpi_update(float(c), p_base, h, m, zeros, P[P_KP], P[P_KI], reset_after,
                                         P[P_LO], P[P_HI], np.nan)
        commands[z] = m
    m = P[P_M0]
    for k in range(raw.size):
        if (k + 1) % n == 0:
            m = commands[(k + 1) // n - 1]
        sample_commands[k] = m


def empty_like_chain(k: int, n: int):
    """Output arrays for ``chain_kernel`` over ``k`` samples and windows of ``n``."""
    w = k // n
    return (np.empty(k), np.empty(k, dtype=np.bool_), np.empty(k), np.empty(k),
            np.empty(w, dtype=np.int64), np.empty(w), np.empty(k))

