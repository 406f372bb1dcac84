"""The adaptive stepping's rules: when the rig is calm, and where a coarse step must end.

With ``P_COARSE`` > 1, :func:`slipreflex.sim.kernel_step.step_until` takes several
fine steps at once while nothing in the rig needs the fine step (docs/simulator.md,
"Adaptive stepping"). Internal module.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core._numba_cache import stamped_cache
from . import _kernel_layout as KL

__all__: list[str] = []   # internal: slipreflex.sim.kernel gathers the names

#: the files whose code and constants these kernels compile into themselves (their cache is stamped with them)
_CACHE = stamped_cache(__file__, KL.__file__)

#: The adaptive stepping (``P_COARSE`` > 1, :func:`step_until`): a contact counts as calm while it sticks with
#: its force under this share of its static threshold (the cuff: ``_CALM_RATIO_CUFF``; its yield alone is no
#: gross slip, and the fast slide that follows it takes fine steps) (the splash's peaks are ~3 % of it; a pour's load
#: takes ~0.2 s to rise by 5 %), or, the cuff only, once its state has weakened under ``_CALM_PHI`` (its
#: friction within that share of the static-to-kinetic drop of kinetic) while it sticks or creeps slower than
#: ``_CALM_SLIP`` of its slip-weakening distance per coarse step ...
_CALM_RATIO = 0.9
_CALM_RATIO_CUFF = 0.99
_CALM_SLIP = 0.5
_CALM_PHI = 0.25
#: ... and the bottle while it moves slower than ``_CALM_V`` (m/s; the stick resonance's ringing at 2.5 um,
#: a held pour's splash ~6e-5 m/s) and turns slower than ``_CALM_OM`` (rad/s), a dropped mass resting
#: on the bottom when its speed and its spring's deviation from rest are under ``_CALM_V`` as well.
_CALM_V = 1e-3
_CALM_OM = 1e-3
#: A finger counts as still within this many position units of its target (2 um of travel; its servo then
#: turns it at most 0.4 units/s, 1e-3 of full speed: its motor's shake, 1e-5 N at 0.1 Hz, is left out).
_CALM_Q = 1e-2
#: ... and its motor's shake under this force (N; 1e-5 N within _CALM_Q of the target).
_CALM_FM = 1e-4
#: Fine steps after a calm check that failed before the next one (the check costs a few ns).
_CALM_RECHECK = 8


@njit(cache=_CACHE, inline="always")
def _fire_end(T, dt):
    """The step count ``k`` at whose end a sample due at ``T`` is taken: the least ``k`` with
    ``T <= k dt + 1e-12`` (the sensors' rule in :func:`step_until`)."""
    k = np.int64(np.ceil((T - 1e-12) / dt))
    while T <= (k - 1) * dt + 1e-12:
        k -= 1
    while T > k * dt + 1e-12:
        k += 1
    return k


@njit(cache=_CACHE, inline="always")
def _tactile_end(j, r, dt):
    """The step count at whose end tactile sample ``j`` of a sampler at ``r`` Hz is taken: the least ``k``
    with ``j <= (k dt + 1e-12) r``."""
    k = np.int64(np.ceil((j / r - 1e-12) / dt))
    while j <= ((k - 1) * dt + 1e-12) * r:
        k -= 1
    while j > (k * dt + 1e-12) * r:
        k += 1
    return k


@njit(cache=_CACHE, inline="always")
def _load_switch(n, t_switch, dt):
    """The first step ``k > n`` whose start lies past ``t_switch`` (a pour's water arrives at ``k dt >
    t_switch``), or a step count far away when that step is not after ``n``."""
    k = np.int64(np.floor(t_switch / dt))
    while k > 0 and (k - 1) * dt > t_switch:
        k -= 1
    while k * dt <= t_switch:
        k += 1
    return k if k > n else np.int64(1) << 62


@njit(cache=_CACHE, inline="always")
def _load_stop(n, ta, dur, dt):
    """The first step ``k > n`` with ``k dt - ta >= dur`` (a pour's water stops), or a step count far away."""
    k = np.int64(np.floor((ta + dur) / dt))
    while k > 0 and (k - 1) * dt - ta >= dur:
        k -= 1
    while k * dt - ta < dur:
        k += 1
    return k if k > n else np.int64(1) << 62
