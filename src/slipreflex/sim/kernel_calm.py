"""The adaptive stepping's rules: when the rig is calm, and where a coarse step must end.

With ``P_COARSE`` > 1, :func:`slipreflex.sim.kernel_step.step_until` takes several
fine steps at once while nothing in the rig needs the fine step (docs/simulator.md,
"Adaptive stepping"). Internal module.
"""

# ruff: noqa: F405 (the slot constants come from _kernel_layout's star import; pyright checks the names)
from __future__ import annotations

import numpy as np
from numba import njit

from ..core._numba_cache import stamped_cache
from . import _kernel_layout as KL
from ._kernel_layout import *  # noqa: F403 (the vectors' slots, as in the layouts)

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


@njit(cache=_CACHE, inline="always")
def _calm_contacts(S, P, coarse, dt):
    """Whether every contact of a held bottle is calm (sticking with a margin; the cuff weakened: creeping slowly)."""
    ncc = S[S_NC]
    for i in range(3):
        bs = S_C0 + i * SC_SIZE
        bp = P_C0 + i * PC_SIZE
        rs = P[bp + PC_LAW] == LAW_RATE_STATE
        if i == 2 and rs and S[bs + SC_PHI] < _CALM_PHI:
            # the cuff weakened, creeping or stuck for a moment between creeps: a yield releases
            # at most _CALM_PHI of its static-to-kinetic drop
            if S[bs + SC_STUCK] == 0.0 and S[bs + SC_W] * coarse * dt > _CALM_SLIP * P[bp + PC_DC]:
                return False
        elif S[bs + SC_STUCK] > 0.0:
            lim = (P[bp + PC_MUK] + (P[bp + PC_MUS] - P[bp + PC_MUK]) * S[bs + SC_PHI] if rs
                   else P[bp + PC_MUS])
            if abs(S[bs + SC_FT]) > (_CALM_RATIO if i < 2 else _CALM_RATIO_CUFF) * lim * ncc:
                return False
        else:
            return False
    return True


@njit(cache=_CACHE, inline="always")
def _calm_rig(S, P, x, v, th, om, lev0, lev1, grip, coarse, dt):
    """Whether the bottle, the pads and the fingers are calm (a fallen bottle falls freely: always)."""
    # a fallen bottle falls freely (no contact, nothing rings on it, its fingers touch nothing)
    gone = S[S_FALLEN] > 0.0
    calm = gone or (abs(v) <= _CALM_V and abs(om) <= _CALM_OM)
    if calm and not gone:
        calm = S[S_VY0] == 0.0 and S[S_VV0] == 0.0 and S[S_VY1] == 0.0 and S[S_VV1] == 0.0
    if calm and not gone:
        calm = x + abs(th) * max(abs(lev0), abs(lev1)) < grip
    for i in range(3 if calm and not gone else 0):
        if abs(S[S_TGT0 + i] - S[S_Q0 + i]) > _CALM_Q or abs(S[S_FM0 + i]) > _CALM_FM:
            calm = False
    if calm and not gone and S[S_SUPPORTED] == 0.0:
        calm = _calm_contacts(S, P, coarse, dt)
    return calm


@njit(cache=_CACHE, inline="always")
def _calm_loads(D, W, calm, cap, n, x, v, g, dt):
    """``(calm, cap)``: the loads' say (a dropped mass in flight or bouncing: not calm; one resting on the
    bottom, or a shaking grip: coarse steps of at most ``cap``)."""
    for d in range(D.shape[0] if calm else 0):
        if D[d, D_ACT] > 0.0:
            # a mass resting on the bottom rings on its contact spring: omega h <= 1
            cap = min(cap, max(1, np.int64(1.0 / (np.sqrt(D[d, D_KC] / D[d, D_M]) * dt))))
            # a dropped mass in flight, or bouncing on the bottom (its speed or its spring's sag from
            # rest over _CALM_V)
            sag = D[d, D_Z] - x - D[d, D_M] * g / D[d, D_KC]
            if (D[d, D_LANDED] == 0.0 or abs(D[d, D_VZ] - v) > _CALM_V
                    or abs(sag) * np.sqrt(D[d, D_KC] / D[d, D_M]) > _CALM_V):
                calm = False
    for p in range(W.shape[0] if calm else 0):
        # a shaking grip: ten coarse steps a radian of its shake at most
        if W[p, W_ACC] != 0.0 and n * dt - W[p, W_START] - W[p, W_DELAY] < W[p, W_DUR]:
            cap = min(cap, max(1, np.int64(0.1 / (W[p, W_ACC_W] * dt))))
    return calm, cap


@njit(cache=_CACHE, inline="always")
def _next_switch(D, W, n, dt):
    """The next step from ``n`` at which a load switches: before a drop's release, where a pour's water starts or
    stops."""
    n_switch = np.int64(1) << 62
    for d in range(D.shape[0]):
        if D[d, D_ACT] == 0.0:
            k = _fire_end(D[d, D_REL] + 1e-12, dt) - 1   # the first k with (k + 1) dt > rel
            while (k + 1) * dt <= D[d, D_REL]:
                k += 1
            while k > 0 and k * dt > D[d, D_REL]:
                k -= 1
            if k >= n:
                n_switch = min(n_switch, k)
    for p in range(W.shape[0]):
        ta = W[p, W_START] + W[p, W_DELAY]
        n_switch = min(n_switch, _load_switch(n, ta, dt), _load_stop(n, ta, W[p, W_DUR], dt))
    return n_switch


@njit(cache=_CACHE, inline="always")
def _row_sample(daq_at, daq_t, acc_t, dt):
    """``(daq_end, seen_j, seen_end)``: the step at whose end DAQ row ``daq_at`` is taken, the IMU reading the row
    carries (the last taken by the row's step: the readings before it are drawn by no one, and end no step) and
    that reading's step."""
    daq_end = _fire_end(daq_at * daq_t, dt)
    seen_j = np.int64(np.floor((daq_end * dt + 1e-12) / acc_t)) + 1
    while seen_j >= 0 and _fire_end(seen_j * acc_t, dt) > daq_end:
        seen_j -= 1
    seen_end = _fire_end(seen_j * acc_t, dt)
    return daq_end, seen_j, seen_end


@njit(cache=_CACHE, inline="always")
def _coarse_steps(S, C, P, D, W, tac_rates, tac_next, n, n_end, n_switch, daq_at, daq_end, seen_j, seen_end, x, v,
                  th, om, coarse, dt, g):
    """The fine steps the next step takes at once, ``(ms, n_switch, daq_at, daq_end, seen_j, seen_end)``: 1 unless
    the rig is calm (then ``C_RECHECK`` is set a few steps ahead), else up to ``coarse``, ending where the next
    IMU, DAQ or tactile sample is taken (each from the state at its instant, as with fixed steps), before a
    drop's release and where a pour's water starts or stops."""
    ms = 1
    calm = _calm_rig(S, P, x, v, th, om, P[P_LEVER0], P[P_LEVER0 + 1], P[P_GRIP], coarse, dt)
    calm, cap = _calm_loads(D, W, calm, coarse, n, x, v, g, dt)
    if calm:
        if n >= n_switch:
            n_switch = _next_switch(D, W, n, dt)
        if C[C_DAQ] != daq_at:
            daq_at = C[C_DAQ]
            daq_end, seen_j, seen_end = _row_sample(daq_at, P[P_DAQ_T], P[P_ACC_T], dt)
        ms = min(cap, n_end - n, n_switch - n, daq_end - n)
        if seen_j >= C[C_ACC]:
            ms = min(ms, seen_end - n)
        for si in range(tac_rates.shape[0]):
            ms = min(ms, _tactile_end(tac_next[si], tac_rates[si], dt) - n)
        if ms < 1:
            ms = 1
    else:
        C[C_RECHECK] = n + _CALM_RECHECK
    return ms, n_switch, daq_at, daq_end, seen_j, seen_end
