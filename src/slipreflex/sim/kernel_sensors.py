"""The kernel's sensors: the slip sensor's volts, the IMU's quantization and the tactile array's frames.

Internal module (:mod:`slipreflex.sim.kernel` re-exports its public names).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core._numba_cache import stamped_cache
from . import _kernel_layout as KL
from . import kernel_noise as KN
from ._kernel_layout import (
    P_ADC_LSB,
    P_ADC_MAX,
    P_GAP,
    P_KNEE,
    P_LAM,
    P_QC,
    P_TRACK_DX,
    P_TRACK_OFF,
    P_VCC,
    P_VNOISE,
    P_VSAT,
    T_FALLEN,
    T_FT,
    T_IDX,
    T_NC,
    T_T,
)
from .kernel_noise import normal, normal_pair

__all__: list[str] = []   # internal: slipreflex.sim.kernel gathers the names

#: the files whose code and constants these kernels compile into themselves (their cache is stamped with them)
_CACHE = stamped_cache(__file__, KL.__file__, KN.__file__)

@njit(cache=_CACHE, inline="always")
def _track_at(pos, off, dx, nt):
    """Index ``i`` and fraction ``fr`` of surface position ``pos`` on a track of ``nt`` samples (clamped)."""
    fi = (pos + off) / dx
    i = int(np.floor(fi))
    if i < 0:
        i = 0
        fi = 0.0
    elif i > nt - 2:
        i = nt - 2
        fi = float(nt - 1)
    return i, fi - i


@njit(cache=_CACHE, inline="always")
def _sensor_volts(rho, extra, gap, vcc, vsat, knee, vnoise, key, k, lsb, code_max):
    """OPR5005 output (ADC volts) for reflectance ``rho`` with the finger ``extra`` metres further than
    the gap (before contact), electrical noise number ``k`` of stream ``key``, 10-bit ADC."""
    if extra > 0.0:
        r = extra / gap
        rho = rho / (1.0 + r * r)
    vlin = vcc * (1.0 - rho)
    z = (vlin - vsat) / knee
    if z > 0.0:
        v = vsat + knee * (z + np.log1p(np.exp(-z)))
    else:
        v = vsat + knee * np.log1p(np.exp(z))
    v += vnoise * normal(key, k)
    code = np.floor(v / lsb)
    if code < 0.0:
        code = 0.0
    elif code > code_max:
        code = code_max
    return code * lsb


@njit(cache=_CACHE, inline="always")
def _quant_g(val, lsb, full_range):
    c = np.floor(val / lsb + 0.5)
    hi = np.floor(full_range / lsb + 0.5) - 1.0
    lo = -np.floor(full_range / lsb + 0.5)
    if c > hi:
        c = hi
    elif c < lo:
        c = lo
    return c * lsb



@njit(cache=_CACHE)
def tactile_frames(snap, key, gain0, patch_sigma, shear_shift, noise, resolution, alpha, hyst, drift, state,
                   out):
    """Build ``(4, 4)`` frames (N per taxel) from tactile snapshots of one contact.

    ``snap`` rows are (id, index, t, N_c, F_t, s, fallen, w). The pressure
    patch is a Gaussian of ``patch_sigma`` taxels carrying ``N_c``, centred
    on the array and shifted along the bottle axis by ``shear_shift * F_t /
    N_c`` (the pad's shear). Each taxel then goes through the sensor (the
    array's sensitivity ``gain0``): a
    first-order low-pass (``alpha`` per frame), a play of half-width
    ``hyst`` (hysteresis), a creep gain ``1 + drift log10(1 + t)``, noise
    (stream ``key``, eight Box-Muller pairs per frame index), quantization and
    clipping at 0.
    ``state`` (2, 4, 4) holds the low-pass and play outputs between calls
    (NaN: start from the first frame).
    """
    inv2s2 = 1.0 / (2.0 * patch_sigma * patch_sigma)
    ex = np.empty(4)   # the patch is separable: its profile across the axis does not move
    ey = np.empty(4)
    sx = 0.0
    for a in range(4):
        ex[a] = np.exp(-(a - 1.5) * (a - 1.5) * inv2s2)
        sx += ex[a]
    inv_res = 1.0 / resolution if resolution > 0.0 else 0.0
    for r in range(snap.shape[0]):
        nc = snap[r, T_NC]
        idx = np.int64(snap[r, T_IDX])
        if nc > 0.0 and snap[r, T_FALLEN] == 0.0:
            tot = nc
            cy = 1.5 + shear_shift * snap[r, T_FT] / nc
        else:
            tot = 0.0
            cy = 1.5
        sy = 0.0
        for b in range(4):
            ey[b] = np.exp(-(b - cy) * (b - cy) * inv2s2)
            sy += ey[b]
        scale = tot / (sx * sy) if sy > 0.0 else 0.0   # a patch shifted far off the array (all terms underflow)
        gain = gain0 * (1.0 + drift * np.log10(1.0 + snap[r, T_T]))
        for b in range(4):
            for a2 in range(2):
                # one Box-Muller pair (stream key, pair idx * 8 + b * 2 + a2) serves two taxels
                n0, n1 = normal_pair(key, idx * 8 + b * 2 + a2)
                for k in range(2):
                    a = 2 * a2 + k
                    f = scale * ex[a] * ey[b]
                    if np.isnan(state[0, b, a]):
                        state[0, b, a] = f
                        state[1, b, a] = f
                    lp = state[0, b, a] + alpha * (f - state[0, b, a])
                    hy = state[1, b, a]
                    if hy < lp - hyst:
                        hy = lp - hyst
                    elif hy > lp + hyst:
                        hy = lp + hyst
                    state[0, b, a] = lp
                    state[1, b, a] = hy
                    y = hy * gain + noise * (n0 if k == 0 else n1)
                    if resolution > 0.0:
                        y = np.floor(y * inv_res + 0.5) * resolution
                    if y < 0.0:
                        y = 0.0
                    out[r, b, a] = y


@njit(cache=_CACHE)
def volts_along(P, track, keys, positions, out):
    """Slip-sensor volts at surface positions (sample k uses noise number k); for the scan."""
    for k in range(positions.shape[0]):
        ti, fr = _track_at(positions[k], P[P_TRACK_OFF], P[P_TRACK_DX], track.shape[0])
        rho = track[ti] + fr * (track[ti + 1] - track[ti])
        out[k] = _sensor_volts(rho, P[P_QC] * P[P_LAM], P[P_GAP], P[P_VCC], P[P_VSAT], P[P_KNEE],
                               P[P_VNOISE], keys[0], k, P[P_ADC_LSB], P[P_ADC_MAX])
