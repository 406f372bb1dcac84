"""A literal, slow transcription of shared SPEC section 1, independent of the package.

Used as the oracle the package's batch and streaming code must match bit for bit.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import butter, sosfilt, sosfilt_zi


def lowpass(raw, fs, cutoff):
    raw = np.asarray(raw, dtype=float)
    if raw.size == 0:
        return raw.copy()
    sos = butter(2, cutoff, fs=fs, output="sos")
    return sosfilt(sos, raw, zi=sosfilt_zi(sos) * raw[0])[0]


def encode(x, theta0=0.008, dath=False, D=16, x0=None, floor=0.0):
    x = [float(v) for v in x]
    if not x:
        return [], []
    prev = x0 if x0 is not None else x[0]
    acc, theta, remaining = 0.0, theta0, 0
    ys, thetas = [], []
    for xk in x:
        d = xk - prev
        acc = acc + d
        thetas.append(theta)
        y = 1 if abs(acc) > theta else 0
        if y:
            acc = 0.0
        if dath:
            if remaining > 0:
                remaining -= 1
                if remaining == 0:
                    theta = theta0
            elif y:
                theta = max(abs(d), floor)
                remaining = D
        prev = xk
        ys.append(y)
    return ys, thetas


def windows(y, n=16):
    return [sum(y[i:i + n]) for i in range(0, len(y) - len(y) % n, n)]


def mpi(v, p0=0.0, kp=5.0, ki=5.0, R=10, lo=0.0, hi=500.0, positions=None):
    P0, h, m_prev, zeros = p0, 0.0, min(max(p0, lo), hi), 0
    out = []
    for z, vz in enumerate(v):
        h = h + vz
        PI = P0 + kp * vz + ki * h
        m = min(max(max(PI, m_prev), lo), hi)
        out.append(m)
        m_prev = m
        zeros = zeros + 1 if vz == 0 else 0
        if zeros == R:
            P0 = m if positions is None else positions[z]
            h = 0.0
            zeros = 0
    return out
