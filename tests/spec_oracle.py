"""A literal, slow transcription of docs/method.md section 1, independent of the package.

Used as the oracle the package's batch and streaming code must match bit for bit.
Sections 1.1-1.4 (the paper's chain), 1.6 (the authors' rig code, ``authors_gui``)
and the variants of docs/method.md (accumulator reset and leak, MPI without reset,
the event-driven MPI) are transcribed rule by rule.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import butter, sosfilt, sosfilt_zi


def lowpass(raw, fs, cutoff):
    raw = np.asarray(raw, dtype=float)
    if raw.size == 0:
        return raw.copy()
    sos = butter(2, cutoff, fs=fs, output="sos")
    return sosfilt(sos, raw, zi=sosfilt_zi(sos) * raw[0])[0]


def encode(x, theta0=0.008, dath=False, D=16, x0=None, floor=0.0, acc_reset=None, leak=None):
    """docs/method.md section 1.2; ``acc_reset`` clears acc every that many samples.

    ``leak`` is a time constant (samples).
    """
    x = [float(v) for v in x]
    if not x:
        return [], []
    prev = x0 if x0 is not None else x[0]
    acc, theta, remaining, c = 0.0, theta0, 0, 0
    ys, thetas = [], []
    for xk in x:
        d = xk - prev
        if leak is None:
            acc = acc + d
        else:
            acc = acc * math.exp(-1.0 / leak) + d
        thetas.append(theta)
        y = 1 if abs(acc) > theta else 0
        if y:
            acc = 0.0
        if acc_reset is not None:
            c = c + 1
            if c >= acc_reset:
                c = 0
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
        if R is not None and zeros == R:
            P0 = m if positions is None else positions[z]
            h = 0.0
            zeros = 0
    return out


def moving_mean(raw, M):
    """docs/method.md section 1.6 filter: the mean of the last M raw samples (of those so far at the start)."""
    out = []
    for k in range(len(raw)):
        window = raw[max(0, k - M + 1):k + 1]
        total = 0.0
        for v in window:
            total = total + float(v)
        out.append(total / len(window))
    return out


def event_mpi(y, n=16, p0=0.0, kp=5.0, ki=5.0, R=10, lo=0.0, hi=500.0, positions=None):
    """docs/method.md, event-driven MPI: the command after every sample of the spike train y."""
    P0, h, m_prev, quiet = p0, 0.0, min(max(p0, lo), hi), 0
    out = []
    for k, yk in enumerate(y):
        s = float(sum(y[max(0, k - n + 1):k + 1]))
        h = h + yk
        PI = P0 + kp * s + ki * h
        m = min(max(max(PI, m_prev), lo), hi)
        out.append(m)
        m_prev = m
        quiet = 0 if yk else quiet + 1
        if R is not None and quiet == R * n:
            P0 = m if positions is None else positions[k]
            h = 0.0
            quiet = 0
    return out


def authors_gui(raw, fs, p0=125.0):
    """docs/method.md section 1.6, rule by rule: (filtered, events, window counts, commands).

    M = round(fs / 5), R = int(0.1 fs), W = int(0.03 fs); theta = 0.005 V fixed;
    prev = 0.0, acc = 0, c = 0; the accumulator cleared every R samples; windows of W;
    PI = clip(P0 + 5 v + 5 h, 0, 500), m = max(PI, m_prev), no reset.
    """
    M, R, W = round(fs / 5), int(0.1 * fs), int(0.03 * fs)
    x = moving_mean(raw, M)
    theta, prev, acc, c = 0.005, 0.0, 0.0, 0
    ys = []
    for xk in x:
        acc = acc + (xk - prev)
        y = 1 if abs(acc) > theta else 0
        if y:
            acc = 0.0
        c = c + 1
        if c >= R:
            c = 0
            acc = 0.0
        prev = xk
        ys.append(y)
    v = [sum(ys[i:i + W]) for i in range(0, len(ys) - len(ys) % W, W)]
    P0, h, m_prev, cmds = p0, 0.0, p0, []
    for vz in v:
        h = h + vz
        PI = min(max(P0 + 5.0 * vz + 5.0 * h, 0.0), 500.0)
        m = max(PI, m_prev)
        m_prev = m
        cmds.append(m)
    return x, ys, v, cmds
