"""The kernel's contact laws: the grip's normal force, friction per contact, the tilt's inertia, the slosh mode.

Scalar helpers inlined into :func:`slipreflex.sim.kernel_step.step_until` (numba
``inline="always"``): they take and return scalars (an inlined helper taking an array
costs an atomic reference count per call, :mod:`slipreflex.sim.kernel`). Internal
module (:mod:`slipreflex.sim.kernel` re-exports its public names).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core._numba_cache import stamped_cache
from . import _kernel_layout as KL
from ._kernel_layout import (
    C_NFAIL,
    C_NITER,
    P_C0,
    P_COARSE_MAX,
    P_DT,
    P_IB,
    P_KLAT,
    P_KT_SUM,
    P_MB,
    P_MBD,
    P_RHO_W,
    P_SLOSH_R,
    P_TILT_K,
    P_ZG,
    PC_MUK,
    PC_MUS,
    PC_SIZE,
)

__all__: list[str] = []   # internal: slipreflex.sim.kernel gathers the names

#: the files whose code and constants these kernels compile into themselves (their cache is stamped with them)
_CACHE = stamped_cache(__file__, KL.__file__)

_NEWTON_MAX = 60
#: First zero of J1' (``params.SLOSH_ROOT``): the first antisymmetric slosh mode's k R.
_XI = 1.8411837813406593


@njit(cache=_CACHE, inline="always")
def _grip_force(pen, kn, pen1, pen2, n1, n2, k2, k3):
    """Normal force per contact at mean travel ``pen`` past contact: three straight pieces
    (:class:`slipreflex.sim.contacts.GripCurve`)."""
    if pen <= 0.0:
        return 0.0
    if pen <= pen1:
        return kn * pen
    if pen <= pen2:
        return n1 + k2 * (pen - pen1)
    return n2 + k3 * (pen - pen2)


@njit(cache=_CACHE, inline="always")
def _wall_dent(nc, n1, n2, kw_inv, kw2_inv, dlin, dcol):
    """The wall's dent (m) under one fingertip pressing with ``nc`` (the inverse of its three pieces)."""
    if nc <= n1:
        return nc * kw_inv
    if nc <= n2:
        return dlin + (nc - n1) * kw2_inv
    return dcol


@njit(cache=_CACHE, inline="always")
def _sensed_shear(ft, nc, phi, P, i, inc):
    """The shear (N) whose ratio to ``nc`` shifts the array's pressure centre: with ``inc`` = 1 the
    Cattaneo-Mindlin law of a contact whose slipping annulus grows from the edge as the load ratio
    ``q = |F_t| / (mu N)`` grows, ``(3 / 2) mu N [1 - (1 - q)^(2/3)]`` (``F_t`` at small ``q``, steepening
    to infinite slope at ``q = 1``), with ``inc`` = 0 the linear ``F_t``."""
    if inc <= 0.0 or nc <= 0.0:
        return ft
    bp = P_C0 + i * PC_SIZE
    mu = P[bp + PC_MUK] + (P[bp + PC_MUS] - P[bp + PC_MUK]) * phi
    q = abs(ft) / (mu * nc)
    if q > 1.0:
        q = 1.0
    m = 1.5 * mu * nc * (1.0 - (1.0 - q) ** (2.0 / 3.0))
    return (1.0 - inc) * ft + inc * (m if ft >= 0.0 else -m)


@njit(cache=_CACHE, inline="always")
def _shoulder(x, th, l0, l1, l2, grip):
    """The contacts past ``grip`` with the bottle slid ``x`` and tilted ``th``: the mean distance they have
    gone onto the shoulder (each contact at ``x + lever th``) and the furthest contact's position."""
    x0 = x + l0 * th
    x1 = x + l1 * th
    x2 = x + l2 * th
    past = (max(x0 - grip, 0.0) + max(x1 - grip, 0.0) + max(x2 - grip, 0.0)) / 3.0
    return past, max(x0, max(x1, x2))


@njit(cache=_CACHE, inline="always")
def tilt_inertia(mw, P):
    """The bottle's moment of inertia (kg m^2) about the tilt axis with ``mw`` kg of water, and its mass times
    the depth of its centre of mass below the axis (kg m): the empty bottle's (``P_IB``, ``P_MBD``) and the
    water as a rigid cylinder of its fill height ``h``, ``mw (R^2 / 4 + h^2 / 12 + (z_g - h / 2)^2)``. A
    dropped mass is a body of its own: it acts only through its contact force on the bottom."""
    r = P[P_SLOSH_R]
    zg = P[P_ZG]
    h = mw / (P[P_RHO_W] * np.pi * r * r)
    dw = zg - 0.5 * h
    return P[P_IB] + mw * (0.25 * r * r + h * h / 12.0 + dw * dw), P[P_MBD] + mw * dw


@njit(cache=_CACHE, inline="always")
def mass_cap(mw, m1, P, coarse):
    """Fine steps a coarse step may span with ``mw`` kg of water in the bottle (``m1`` of it sloshing):
    ``omega h <= 1`` for the stiffest mode of the bottle as it is now (along the axis on the contacts'
    shear stiffness ``P_KT_SUM``, sideways on ``P_KLAT`` without the slosh mass, in tilt on ``P_TILT_K``
    about :func:`tilt_inertia`), at least the empty bottle's ``coarse`` and at most ``P_COARSE_MAX``.
    Water only lowers these frequencies, so a bound from an earlier, smaller fill errs on the short side."""
    m = P[P_MB] + mw
    ml = m - m1 if m1 > 0.0 else m
    inertia, _ = tilt_inertia(mw, P)
    om2 = max(P[P_KT_SUM] / m, max(P[P_KLAT] / ml, P[P_TILT_K] / inertia))
    k = np.int64(1.0 / (np.sqrt(om2) * P[P_DT]))
    return min(np.int64(P[P_COARSE_MAX]), max(coarse, k))


@njit(cache=_CACHE, inline="always")
def _rs_solve(R, K, N, mu_st, a, v0, z_guess, w_guess=-1.0):
    """Scalar core of :func:`rs_slide_speed`: returns ``(w, z, iterations, converged)``.

    With ``w_guess >= 0`` (the sliding speed that goes with ``z_guess``, i.e. the previous
    step's), the start is one Newton step from ``z_guess`` taken with ``exp(z_guess) = 1 +
    w_guess / v0``, which costs no exponential: under a load that changes from step to step
    (the pour's splash) the solve then usually converges in one more step.
    """
    rp = R - N * mu_st
    na = N * a
    if na <= 0.0:
        return rp / K, np.log1p(rp / K / v0), 0, True
    kv = K * v0
    if z_guess > 0.0 and w_guess >= 0.0:
        e = 1.0 + w_guess / v0
        z = z_guess + (rp - kv * (e - 1.0) - na * z_guess) / (kv * e + na)
        if z <= 0.0:
            z = min(rp / na, np.log1p(rp / kv))
    elif z_guess > 0.0:
        z = z_guess
    else:
        z = min(rp / na, np.log1p(rp / kv))
    it = 0
    converged = False
    ez = 1.0
    dz = 0.0
    while it < _NEWTON_MAX:
        ez = np.exp(z)
        h = rp - kv * (ez - 1.0) - na * z
        dz = h / (-kv * ez - na)
        z -= dz
        it += 1
        # quadratic convergence: after a step of 1e-7 the error is of order 1e-14
        if abs(dz) <= 1e-7 * (1.0 + abs(z)):
            converged = True
            break
    if z < 0.0:
        return 0.0, 0.0, it, converged
    if converged and z > 0.5:
        # exp(z) = exp(z + dz) exp(-dz), the first factor from the last iteration (|dz| <= 1e-7 (1 + z): the
        # series' error is below 1e-21 (1 + z)^3; no cancellation, exp(z) > 1.6): one exponential saved
        return v0 * (ez * (1.0 - dz + 0.5 * dz * dz) - 1.0), z, it, converged
    return v0 * np.expm1(z), z, it, converged


@njit(cache=_CACHE, inline="always")
def rs_slide_speed(R, K, N, mu_st, a, v0, C, z_guess=0.0):
    """Sliding speed ``w >= 0`` of a rate-state contact: ``R - K w = N (mu_st + a ln(1 + w / v0))``.

    ``R`` is the trial (stuck) force magnitude, ``R > N mu_st``; ``K = k_t dt + c_t``.
    Newton's method in ``z = ln(1 + w / v0)``, where the residual is concave and
    decreasing, so Newton converges from any start (from the right of the root
    monotonically; from the left its first step lands on the right). It starts
    from ``z_guess`` (the previous step's ``z``) when positive, else from an
    upper bound of the root. Returns ``(w, z)``. ``C[C_NITER]`` keeps the most
    iterations one solve took and ``C[C_NFAIL]`` counts solves that did not
    converge.
    """
    w, z, it, converged = _rs_solve(R, K, N, mu_st, a, v0, z_guess)
    if it > C[C_NITER]:
        C[C_NITER] = it
    if not converged:
        C[C_NFAIL] += 1
    return w, z


@njit(cache=_CACHE, inline="always")
def _rs_contact(kt, ct, s, mus, muk, phi, z_prev, w_prev, a, v0, dc, heal_s, heal_decay, x, v, nc, dt, dt_fine):
    """One step of a rate-state contact (implicit, return mapping); scalars in and out.

    The contact sticks while the trial force ``k_t (x - s + v dt) + c_t v``
    stays within the static threshold ``N (mu_k + (mu_s - mu_k) phi)``;
    beyond it the sliding speed solves the force balance of pad and interface
    with the friction ``N (mu_k + (mu_s - mu_k) phi + a ln(1 + w / v0))``. The
    state ``phi`` (1 = fully healed) decays over the slip distance ``D_c`` and
    heals over ``t_heal``: ``dphi/dt = -phi w / D_c + (1 - phi) / t_heal``,
    integrated exactly over the step. While the contact keeps sliding the solve
    starts from a Newton step off the previous step's ``z_prev`` and ``w_prev``
    (see :func:`_rs_solve`), so one more Newton step usually converges. Returns
    ``(F, s, w, z, d, phi, it, ok)``:
    the force on the bottle (up when positive), the new anchor, sliding speed,
    solver variable (0 when stuck), direction (0 when stuck), state, and the
    solver's iterations and convergence.

    ``dt_fine`` is the fine step: the trial force's predictor ``v dt_fine`` (which damps the stuck pad like
    ``k_t dt_fine`` more) stays the fine step's in a coarse step of ``dt``, so a ringing grasp decays as
    with fixed steps.
    """
    mu_st = muk + (mus - muk) * phi
    A = kt * (x - s + v * dt_fine) + ct * v
    R = abs(A)
    w = 0.0
    z = 0.0
    d = 0.0
    it = 0
    ok = True
    if R <= mu_st * nc:
        F = A
    else:
        d = 1.0 if A > 0.0 else -1.0
        K = kt * dt + ct
        w, z, it, ok = _rs_solve(R, K, nc, mu_st, a, v0, z_prev, w_prev)
        F = d * (R - K * w)
        s = s + d * w * dt
    if w > 0.0:
        heal = 1.0 / heal_s
        rate = w / dc + heal
        phi_ss = heal / rate
        phi = phi_ss + (phi - phi_ss) * np.exp(-rate * dt)
    elif phi < 1.0:
        # stuck: heal toward 1 (the same update with w = 0, its factor precomputed)
        phi = 1.0 - (1.0 - phi) * heal_decay
    return F, s, w, z, d, phi, it, ok


@njit(cache=_CACHE, inline="always")
def _coulomb_contact(kt, ct, s, mus, muk, vs, stuck, d, w, x, v, nc):
    """Coulomb-Stribeck contact before the bottle moves (explicit); returns ``(F, stuck, d, w)``.

    ``mu(w) = mu_k + (mu_s - mu_k) exp(-(w / v_s)^2)``; finished by
    :func:`_coulomb_post` after the bottle has moved.
    """
    fp = kt * (x - s) + ct * v
    if stuck > 0.0 and abs(fp) > mus * nc:
        stuck = 0.0
        d = 1.0 if fp > 0.0 else -1.0
        w = 0.0
    if stuck > 0.0:
        return fp, stuck, d, w
    wr = w / vs
    return d * (muk + (mus - muk) * np.exp(-wr * wr)) * nc, stuck, d, w


@njit(cache=_CACHE, inline="always")
def _coulomb_post(F, kt, decay, s, d, x_old, x_new, dt):
    """Coulomb-Stribeck contact after the bottle moved: the massless pad relaxes toward
    ``F / k_t`` exactly, the anchor follows, and the contact sticks when it stops.
    Returns ``(s, stuck, w)``."""
    ueq = F / kt
    u = ueq + (x_old - s - ueq) * decay
    sn = x_new - u
    wn = (sn - s) / dt
    if wn * d <= 0.0:
        return s, 1.0, 0.0
    return sn, 0.0, abs(wn)


@njit(cache=_CACHE, inline="always")
def slosh_mode(mw, radius, rho, zeta0, phi_jet):
    """First antisymmetric slosh mode of ``mw`` kg of water in an upright cylinder of ``radius``.

    Returns ``(k tanh(k h), m1, zeta, beta)``: ``omega^2 = g k tanh(k h)`` with
    ``k = 1.8412 / R`` and fill height ``h``; the slosh mass of the
    equivalent spring-mass ``m1 = mw 2 tanh(k h) / ((xi^2 - 1) k h)``
    (Abramson 1966; Dodge 2000); the damping ratio of Stephens et al. (1962),
    ``zeta0 [1 + 0.318 / sinh(k h) (1 + (1 - h / R) / cosh(k h))]`` with the
    deep-fill ratio ``zeta0 = 0.79 sqrt(nu / (g^0.5 R^1.5))`` times the damping
    factor (:func:`slosh_zeta0`), at most 1; and ``beta``, the modal force on
    the slosh mass per newton of vertical force on the surface ``phi_jet =
    J1(k r_j) / J1(xi)`` of the way out: the mode's elevation at the wall ``q``
    and the slosh mass's displacement ``y1`` share the mode's potential energy,
    ``y1 = q (xi^2 - 1) / (2 xi tanh(k h))``, so ``beta = phi_jet 2 xi tanh(k h)
    / (xi^2 - 1)``. (``k h = xi h / R``: one exponential gives all three
    hyperbolic functions.)
    """
    h = mw / (rho * np.pi * radius * radius)
    kh = _XI * h / radius
    if kh <= 1e-9:
        return 0.0, mw * 2.0 / (_XI * _XI - 1.0), 1.0, 0.0
    e = np.exp(min(kh, 300.0))
    sh = 0.5 * (e - 1.0 / e)
    ch = 0.5 * (e + 1.0 / e)
    th = sh / ch
    m1 = mw * 2.0 * th / ((_XI * _XI - 1.0) * kh)
    zeta = zeta0 * (1.0 + 0.318 / sh * (1.0 + (1.0 - h / radius) / ch))
    if zeta > 1.0:
        zeta = 1.0
    return _XI / radius * th, m1, zeta, phi_jet * 2.0 * _XI * th / (_XI * _XI - 1.0)


def slosh_zeta0(radius, nu, g, damp_factor=1.0):
    """Deep-fill damping ratio of the first slosh mode, Stephens et al. (1962): ``0.79 sqrt(nu / (g^0.5 R^1.5))``.

    Examples
    --------
    >>> round(slosh_zeta0(0.0325, 1.004e-6, 9.81), 4)
    0.0058
    """
    return 0.79 * (nu / (g ** 0.5 * radius ** 1.5)) ** 0.5 * damp_factor
