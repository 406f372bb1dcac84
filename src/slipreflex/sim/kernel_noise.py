"""Counter-based noise for the kernels: splitmix64 of a stream key and a sample index.

A trace does not depend on how a run is cut into calls: sample ``i`` of stream ``key``
is a function of the two alone. Internal module (:mod:`slipreflex.sim.kernel`
re-exports its public names).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core._numba_cache import stamped_cache

__all__: list[str] = []   # internal: slipreflex.sim.kernel gathers the names

#: the files whose code and constants these kernels compile into themselves (their cache is stamped with them)
_CACHE = stamped_cache(__file__)

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_TWO53 = 1.0 / 9007199254740992.0


@njit(cache=_CACHE, inline="always")
def _mix(z):
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@njit(cache=_CACHE, inline="always")
def _uniform(key, i):
    h = _mix(key + np.uint64(i) * _GOLDEN)
    return (float(h >> _S11) + 0.5) * _TWO53


@njit(cache=_CACHE)
def normal(key, i):
    """Standard normal number ``i`` of the stream ``key`` (counter-based, Box-Muller)."""
    u1 = _uniform(key, 2 * i)
    u2 = _uniform(key, 2 * i + 1)
    return np.sqrt(-2.0 * np.log(u1)) * np.cos(2.0 * np.pi * u2)


@njit(cache=_CACHE)
def normal_pair(key, i):
    """Standard normal numbers ``2 i`` and ``2 i + 1`` of the stream ``key``: both of one Box-Muller pair
    (the uniforms ``2 i``, ``2 i + 1``; ``normal(key, i)`` is the first of them)."""
    u1 = _uniform(key, 2 * i)
    u2 = _uniform(key, 2 * i + 1)
    r = np.sqrt(-2.0 * np.log(u1))
    return r * np.cos(2.0 * np.pi * u2), r * np.sin(2.0 * np.pi * u2)


@njit(cache=_CACHE)
def uniform(key, i):
    """Uniform number ``i`` in (0, 1) of the stream ``key`` (counter-based)."""
    return _uniform(key, i)


@njit(cache=_CACHE)
def derive_key(key, i):
    """A new stream key from ``key`` and a small integer (wrap-around arithmetic)."""
    return _mix(key ^ (np.uint64(i) * _GOLDEN))
