"""numba kernels of the chain: one per-sample update per stage, composed.

The per-sample updates here are the arithmetic of SPEC 1.1-1.4 written once for
compiled code; the streaming objects in the sibling modules perform exactly the
same IEEE operations in the same order (no fastmath, so no FMA contraction), which
is why batch and streaming agree bit for bit. Imported lazily by the batch
functions so that ``import slipreflex`` does not pay for numba.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def sos_update(sos, zi, x):
    """One sample through every second-order section (scipy's sosfilt order)."""
    for s in range(sos.shape[0]):
        y = sos[s, 0] * x + zi[s, 0]
        zi[s, 0] = sos[s, 1] * x - sos[s, 4] * y + zi[s, 1]
        zi[s, 1] = sos[s, 2] * x - sos[s, 5] * y
        x = y
    return x


@njit(cache=True, inline="always")
def encoder_update(x, prev, acc, theta, remaining, theta0, dath, dath_samples, floor):
    """SPEC 1.2 for one sample; returns (event, acc_before_reset, theta_used, acc, theta, remaining)."""
    d = x - prev
    acc = acc + d
    theta_used = theta
    acc_seen = acc
    event = abs(acc) > theta
    if event:
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
    return event, acc_seen, theta_used, acc, theta, remaining


@njit(cache=True, inline="always")
def mpi_update(v, p_base, h, m_prev, zeros, kp, ki, reset_after, lo, hi):
    """SPEC 1.4 for one window, with the command itself as the reset position."""
    h = h + v
    pi = p_base + kp * v + ki * h
    m = pi if pi > m_prev else m_prev
    if m < lo:
        m = lo
    elif m > hi:
        m = hi
    zeros = zeros + 1 if v == 0.0 else 0
    if zeros == reset_after:
        p_base = m
        h = 0.0
        zeros = 0
    return m, p_base, h, zeros


@njit(cache=True)
def lowpass_kernel(raw, sos, zi, out):
    for k in range(raw.size):
        out[k] = sos_update(sos, zi, raw[k])


@njit(cache=True)
def encode_kernel(x, prev, theta0, dath, dath_samples, floor, events, acc_out, theta_out):
    acc = 0.0
    theta = theta0
    remaining = 0
    for k in range(x.size):
        event, acc_seen, theta_used, acc, theta, remaining = encoder_update(
            x[k], prev, acc, theta, remaining, theta0, dath, dath_samples, floor)
        events[k] = event
        acc_out[k] = acc_seen
        theta_out[k] = theta_used
        prev = x[k]


@njit(cache=True)
def mpi_kernel(v, p0, m0, kp, ki, reset_after, lo, hi, out):
    p_base = p0
    h = 0.0
    m_prev = m0
    zeros = 0
    for z in range(v.size):
        m_prev, p_base, h, zeros = mpi_update(v[z], p_base, h, m_prev, zeros, kp, ki, reset_after, lo, hi)
        out[z] = m_prev


@njit(cache=True)
def chain_kernel(raw, filter_on, sos, zi, x0, x0_given, theta0, dath, dath_samples, floor,
                 n, p0, m0, kp, ki, reset_after, lo, hi,
                 x_out, events, acc_out, theta_out, counts, commands):
    """The whole chain fused in one pass (filter -> encoder -> windows -> MPI)."""
    prev = x0
    acc = 0.0
    theta = theta0
    remaining = 0
    count = 0
    p_base = p0
    h = 0.0
    m_prev = m0
    zeros = 0
    for k in range(raw.size):
        x = sos_update(sos, zi, raw[k]) if filter_on else raw[k]
        if k == 0 and not x0_given:
            prev = x
        event, acc_seen, theta_used, acc, theta, remaining = encoder_update(
            x, prev, acc, theta, remaining, theta0, dath, dath_samples, floor)
        prev = x
        x_out[k] = x
        events[k] = event
        acc_out[k] = acc_seen
        theta_out[k] = theta_used
        if event:
            count += 1
        if (k + 1) % n == 0:
            z = (k + 1) // n - 1
            counts[z] = count
            m_prev, p_base, h, zeros = mpi_update(float(count), p_base, h, m_prev, zeros,
                                                  kp, ki, reset_after, lo, hi)
            commands[z] = m_prev
            count = 0


def empty_like_chain(k: int, n: int):
    """Output arrays for ``chain_kernel`` over ``k`` samples and windows of ``n``."""
    w = k // n
    return (np.empty(k), np.empty(k, dtype=np.bool_), np.empty(k), np.empty(k),
            np.empty(w, dtype=np.int64), np.empty(w))
