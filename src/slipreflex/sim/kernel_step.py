"""The physics step: :func:`step_until` advances the rig and samples its sensors.

The model is described in :mod:`slipreflex.sim.kernel` (which re-exports
:func:`step_until`).
"""

# ruff: noqa: F405 (the slot constants come from _kernel_layout's star import; pyright checks the names)
from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

from ..core._numba_cache import stamped_cache
from . import _kernel_layout as KL
from . import kernel_calm as KA
from . import kernel_contacts as KC
from . import kernel_noise as KN
from . import kernel_sensors as KS
from ._kernel_layout import *  # noqa: F403 (every slot of the vectors, as in the layouts: the step reads them all)
from .kernel_calm import _coarse_steps, _row_sample
from .kernel_contacts import (
    _coulomb_contact,
    _coulomb_post,
    _grip_force,
    _rs_contact,
    _sensed_shear,
    _shoulder,
    _wall_dent,
    mass_cap,
    slosh_mode,
    tilt_inertia,
)
from .kernel_noise import _uniform, normal
from .kernel_sensors import _quant_g, _sensor_volts, _track_at

__all__: list[str] = []   # internal: slipreflex.sim.kernel gathers the names

#: the files whose code and constants the step compiles into itself (its cache is stamped with them)
_CACHE = stamped_cache(__file__, KL.__file__, KN.__file__, KC.__file__, KS.__file__, KA.__file__)
_COS30 = 0.8660254037844386


def _borrowed(typingctx, arr):
    """``_borrow(arr)``: ``arr`` without its memory owner, so numba counts no references to it (valid while ``arr``
    lives: within the call that borrows it). An inlined piece taking an array otherwise costs an atomic reference
    count per array and call that numba's pruning does not remove."""
    if not isinstance(arr, types.Array):
        return None

    def codegen(context, builder, sig, args):
        src = context.make_array(sig.args[0])(context, builder, args[0])
        out = context.make_array(sig.return_type)(context, builder)
        for field in ("nitems", "itemsize", "data", "shape", "strides"):
            setattr(out, field, getattr(src, field))
        out.meminfo = cgutils.get_null_value(out.meminfo.type)
        out.parent = cgutils.get_null_value(out.parent.type)
        return out._getvalue()

    return arr(arr), codegen


_borrow: Any = intrinsic(_borrowed)   # called in the kernels with the array alone (numba passes the typing context)


@njit(cache=_CACHE, inline="always")
def _step_span(P, n, ms, dt, coarse, acc_alpha, alpha_coarse, acc_lq):
    """``(t0, h, t1, tl, alpha_h)``: a step of ``ms`` fine steps from step ``n``: its start, length and end, the
    instant its loads are taken at (its middle) and the IMU's DLPF factor over it."""
    t0 = n * dt
    if ms == 1:
        h = dt
        t1 = (n + 1) * dt
        tl = t0
        alpha_h = acc_alpha
    else:
        h = ms * dt
        t1 = (n + ms) * dt
        tl = t0 + 0.5 * (ms - 1) * dt
        alpha_h = (alpha_coarse if ms == coarse else P[P_ACC_ALPHA_H + ms] if ms <= ALPHA_STEPS
                   else -np.expm1(ms * acc_lq))
    return t0, h, t1, tl, alpha_h


@njit(cache=_CACHE, inline="always")
def _fingers(S, ms, h, dt, kservo, droop, stall, mv_f, mv_w, mv_inv_dt):
    """The three finger servos over the step; whether a motor turned (in a coarse step of a held bottle within
    _CALM_Q of their targets: their motors quiet)."""
    nc_prev = S[S_NC]
    moving = False
    quiet = ms > 1 and S[S_FALLEN] == 0.0
    for i in range(3):
        q = S[S_Q0 + i]
        tg = S[S_TGT0 + i]
        e = tg - q
        r = kservo * e
        sp = S[S_SPD0 + i]
        if r > 0.0:
            # closing against the load: the DC motor's torque-speed line
            spc = sp * (1.0 - droop * nc_prev)
            if r > spc:
                r = spc if spc > 0.0 else 0.0
        elif r < -sp:
            r = -sp
        if r > 0.0 and nc_prev >= stall:
            r = 0.0
        qn = q + r * h
        if (tg - qn) * e < 0.0:
            qn = tg
        S[S_Q0 + i] = qn
        if quiet:
            S[S_FM0 + i] = 0.0
        # the digit's motor shakes its contact while it turns: rotor unbalance, force and frequency
        # proportional to the speed
        if mv_f > 0.0 and not quiet:
            if qn != q:
                mvr = abs(qn - q) * (mv_inv_dt if ms == 1 else mv_inv_dt * dt / h)
                ph = S[S_MPH0 + i] + mv_w * mvr * h
                if ph > 6.283185307179586:
                    ph -= 6.283185307179586
                S[S_MPH0 + i] = ph
                S[S_FM0 + i] = mv_f * mvr * np.sin(ph)
                moving = True
            elif S[S_FM0 + i] != 0.0:
                S[S_FM0 + i] = 0.0
    return moving


@njit(cache=_CACHE, inline="always")
def _normal_force(S, P, x, th, tilted, lev0, lev1, lev2, grip, taper, qc, lam, wall):
    """``(nc, pen, pen_full, shl)``: the fingertips' normal force (0 once fallen) at their mean travel ``pen``
    (``pen_full`` before the shoulder) and the mean distance the contacts have gone onto the shoulder."""
    kn, pen1, pen2, n1w, n2w, k2w, k3w = wall
    qbar = (S[S_Q0] + S[S_Q0 + 1] + S[S_Q0 + 2]) / 3.0
    pen = (qbar - qc) * lam
    pen_full = pen
    # past grip_travel the fingertips are on the shoulder, whose radius shrinks as the bottle slides; tilted,
    # each contact is at its own height, and the three equal normal forces (the bottle shifts sideways
    # until they balance) follow the mean of their gaps
    if tilted:
        shl, _ = _shoulder(x, th, lev0, lev1, lev2, grip)
    else:
        shl = x - grip if x > grip else 0.0
    if taper > 0.0 and shl > 0.0:
        pen -= taper * shl
    if tilted:
        # the tilted body's section in the grasp's plane is an ellipse, R / cos(th) across the axis: it
        # presses the fingertips off the axis further in (second order in the tilt)
        pen += P[P_TILT_PEN] * (1.0 / np.cos(th) - 1.0)
    nc = _grip_force(pen, kn, pen1, pen2, n1w, n2w, k2w, k3w) if not S[S_FALLEN] > 0.0 else 0.0
    S[S_NC] = nc
    return nc, pen_full, shl


@njit(cache=_CACHE, inline="always")
def _timed_loads(W, tl):
    """``(mw, fjet, gacc)`` at ``tl``: the water poured so far, the jets' force and the grip's acceleration."""
    mw = 0.0
    fjet = 0.0
    gacc = 0.0
    for p in range(W.shape[0]):
        ta = W[p, W_START] + W[p, W_DELAY]
        if tl > ta:
            mw += W[p, W_RATE_KG_S] * min(tl - ta, W[p, W_DUR])
            if tl - ta < W[p, W_DUR]:
                fjet += W[p, W_JET_N]
                if W[p, W_ACC] != 0.0:
                    gacc += W[p, W_ACC] * np.sin(W[p, W_ACC_W] * (tl - ta))
    return mw, fjet, gacc


@njit(cache=_CACHE, inline="always")
def _splash(S, C, P, key5, tl, fjet, mw, ms, g):
    """The jet's splash force at ``tl``: a one-pole (Ornstein-Uhlenbeck) noise drawn on a fixed 1 ms grid and
    interpolated, so it does not depend on dt; the grid (and the slosh mode's coefficients, which change with
    the fill) advances only while a jet flows, catching up on its first use."""
    gdt = P[P_SPL_DT]
    advanced = False
    tenth = False
    while (C[C_SPL] + 1) * gdt <= tl:
        j = C[C_SPL] + 1
        S[S_SPL0] = S[S_SPL1]
        S[S_SPL1] = P[P_SPL_RHO] * S[S_SPL1] + P[P_SPL_SIG] * normal(key5, j + 1)
        C[C_SPL] = j
        advanced = True
        tenth = tenth or j % 10 == 0
    fr = tl * P[P_SPL_INV] - C[C_SPL]
    fspl = P[P_SPL_RMS] * fjet * (S[S_SPL0] + fr * (S[S_SPL1] - S[S_SPL0]))
    # the mode follows the fill every 10 ms (0.17 ml at 1 L/min: its mass changes by < 0.1 %; a coarse
    # step that passes a tenth grid point updates it too)
    if (advanced and (C[C_SPL] % 10 == 0 or (ms > 1 and tenth))) or S[S_M1] == 0.0:
        kth, m1, zeta, beta = slosh_mode(mw, P[P_SLOSH_R], P[P_RHO_W], P[P_ZETA0], P[P_PHIJ])
        S[S_KTH] = kth
        S[S_M1] = m1
        S[S_C1] = 2.0 * zeta * m1 * np.sqrt(kth * g)
        S[S_BETA] = beta
        if P[P_COARSE] > 1:
            C[C_CAP] = mass_cap(mw, m1, P, np.int64(P[P_COARSE]))
    return fspl


@njit(cache=_CACHE, inline="always")
def _event(ev_out, nev, t, kind, x):
    """Write the event row ``(t, kind, x)`` after the ``nev`` rows of ``ev_out``; the new row count."""
    ev_out[nev, 0] = t
    ev_out[nev, 1] = kind
    ev_out[nev, 2] = x
    return nev + 1


@njit(cache=_CACHE, inline="always")
def _drops(D, ev_out, nev, x, v, th, om, tilted, t1, h, geff, drop_e, zg):
    """The dropped masses over the step (released, in flight, landing with an event row, resting):
    ``(fdrop, mdrop, mland, nev)``, their force on the bottom, its moment about the tilt axis, the landed mass."""
    fdrop = 0.0
    mdrop = 0.0
    mland = 0.0
    for d in range(D.shape[0]):
        if t1 <= D[d, D_REL]:
            continue
        if D[d, D_ACT] == 0.0:
            D[d, D_ACT] = 1.0
            D[d, D_Z] = x - D[d, D_H0]
            D[d, D_VZ] = 0.0
        # the mass lands on the bottom off the tilt axis, where the bottom moves with the tilt
        xbot = x + drop_e * th if tilted else x
        pd = D[d, D_Z] - xbot
        f = 0.0
        if pd > 0.0:
            f = D[d, D_KC] * pd + D[d, D_CC] * (D[d, D_VZ] - (v + drop_e * om if tilted else v))
            if f < 0.0:
                f = 0.0
            if D[d, D_LANDED] == 0.0:
                D[d, D_LANDED] = 1.0
                nev = _event(ev_out, nev, t1, E_LANDED, x)
        if D[d, D_LANDED] > 0.0:
            mland += D[d, D_M]
        D[d, D_VZ] += (geff - f / D[d, D_M]) * h
        D[d, D_Z] += D[d, D_VZ] * h
        fdrop += f
        if f != 0.0 and drop_e != 0.0:
            # its force on the bottom, at the eccentricity; the bottom point z_g below the axis moves
            # sideways with the tilt, shortening the lever
            mdrop += f * (drop_e - zg * th)
    return fdrop, mdrop, mland, nev


@njit(cache=_CACHE, inline="always")
def _axial_load(S, W, mb, mw, mland, ms, t1, dt, g, geff, fjet, fspl, fdrop, nc, shl, fallen, taper, taper_sin):
    """The load along the axis on the held bottle (recorded in ``S_LOAD``, its mass in ``S_MASS``): ``(m, wload)``."""
    m = mb + mw
    mrec = mw
    if ms > 1:
        # the truth's mass as the fixed steps record it: at the start of the step that ends at t1
        mrec = 0.0
        tr = t1 - dt
        for p in range(W.shape[0]):
            ta = W[p, W_START] + W[p, W_DELAY]
            if tr > ta:
                mrec += W[p, W_RATE_KG_S] * min(tr - ta, W[p, W_DUR])
        S[S_MASS] = mb + mrec + mland
    else:
        S[S_MASS] = m + mland
    wload = m * geff + fjet + fspl + fdrop
    # on the shoulder the three normal forces lean along the axis and push the bottle out of the grasp
    if taper > 0.0 and shl > 0.0 and not fallen:
        wload += 3.0 * nc * taper_sin
    # recorded with the mass recorded (the splash and the drops' forces: the step's)
    S[S_LOAD] = wload if ms == 1 else wload + (mrec - mw) * g
    return m, wload


@njit(cache=_CACHE, inline="always")
def _slosh(S, yb, vb, y1, v1, a_prev, m, mland, fjet, fspl, flat, h, g, klat, clat, fallen):
    """The slosh (sideways) over the step: slosh mass m1 on the spring m1 k tanh(k h) (g - a) and damper c1, tied
    to the bottle, which the grasp holds sideways; the jet's force drives the mode (equal and opposite on the
    bottle: a vertical jet gives the pair no sideways momentum). Returns ``(yb, vb, y1, v1)``."""
    if S[S_M1] > 0.0 and not fallen:
        m1 = S[S_M1]
        du = v1 - vb
        fs = m1 * S[S_KTH] * (g - a_prev) * (y1 - yb) + S[S_C1] * du
        fq = S[S_BETA] * (fjet + fspl)
        S[S_FWAT] = fs - fq
        ab = (fs - fq + flat - klat * yb - clat * vb) / (m + mland - m1)
        v1 += (fq - fs) / m1 * h
        y1 += v1 * h
        vb += ab * h
        yb += vb * h
        S[S_V1] = v1
        S[S_Y1] = y1
        S[S_VB] = vb
        S[S_YB] = yb
        S[S_ALAT] = ab
    elif (flat != 0.0 or vb != 0.0 or yb != 0.0) and not fallen:
        # no water: the bottle alone on the grasp's sideways stiffness
        ab = (flat - klat * yb - clat * vb) / (m + mland)
        vb += ab * h
        yb += vb * h
        if abs(yb) < 1e-15 and abs(vb) < 1e-12:
            yb = 0.0
            vb = 0.0
        S[S_VB] = vb
        S[S_YB] = yb
        S[S_ALAT] = ab
        S[S_FWAT] = 0.0
    else:
        S[S_ALAT] = 0.0
        S[S_FWAT] = 0.0
    return yb, vb, y1, v1


@njit(cache=_CACHE, inline="always")
def _contact_forces(S, C, P, x, v, th, om, nc, ms, h, dt, tilt_now, same):
    """Each contact's friction force on the bottle over the step (its law's state updated): ``(ftot, mom)``,
    their sum and their moment about the tilt axis."""
    ftot = 0.0
    mom = 0.0
    for i in range(3):
        bs = S_C0 + i * SC_SIZE
        if i == 1 and same:
            ftot += S[S_C0 + SC_FT]
            continue
        bp = P_C0 + i * PC_SIZE
        xi = x
        vi = v
        if tilt_now:
            lv = P[P_LEVER0 + i]
            xi = x + lv * th
            vi = v + lv * om
        if P[bp + PC_LAW] == LAW_RATE_STATE:
            hdec = P[bp + PC_HEAL_DECAY]
            if ms > 1 and S[bs + SC_PHI] < 1.0:
                hdec = (P[P_HEAL_DECAY_H + i * (ALPHA_STEPS + 1) + ms] if ms <= ALPHA_STEPS
                        else np.exp(-h / P[bp + PC_HEAL]))
            F, s_new, w, z, d, phi, it, ok = _rs_contact(
                P[bp + PC_KT], P[bp + PC_CT], S[bs + SC_S], P[bp + PC_MUS], P[bp + PC_MUK], S[bs + SC_PHI],
                S[bs + SC_Z], S[bs + SC_W], P[bp + PC_A], P[bp + PC_V0], P[bp + PC_DC], P[bp + PC_HEAL],
                hdec, xi, vi, nc, h, dt)
            S[bs + SC_S] = s_new
            S[bs + SC_Z] = z
            if d != 0.0:
                S[bs + SC_DIR] = d
            S[bs + SC_STUCK] = 1.0 if d == 0.0 else 0.0
            S[bs + SC_PHI] = phi
            S[bs + SC_W] = w
            if it > C[C_NITER]:
                C[C_NITER] = it
            if not ok:
                C[C_NFAIL] += 1
        else:
            F, stk, d, w = _coulomb_contact(P[bp + PC_KT], P[bp + PC_CT], S[bs + SC_S], P[bp + PC_MUS],
                                            P[bp + PC_MUK], P[bp + PC_VS], S[bs + SC_STUCK],
                                            S[bs + SC_DIR], S[bs + SC_W], xi, vi, nc)
            S[bs + SC_STUCK] = stk
            S[bs + SC_DIR] = d
            S[bs + SC_W] = w
        S[bs + SC_FT] = F
        ftot += F
        if tilt_now:
            mom -= F * P[P_LEVER0 + i]
    return ftot, mom


@njit(cache=_CACHE, inline="always")
def _contacts_after(S, P, x_old, x, th_old, th, tilt_now, same, dt):
    """The contacts after the bottle moved (a Coulomb pad relaxes, the index pad copies the thumb's):
    ``(sliding, s_mean, w_min)``, whether all three slide, their mean slid distance and smallest speed."""
    sliding = True
    s_mean = 0.0
    w_min = np.inf
    for i in range(3):
        if i == 1 and same:
            for j in range(SC_SIZE):
                S[S_C0 + SC_SIZE + j] = S[S_C0 + j]
        bs = S_C0 + i * SC_SIZE
        bp = P_C0 + i * PC_SIZE
        if not (i == 1 and same) and P[bp + PC_LAW] != LAW_RATE_STATE and S[bs + SC_STUCK] == 0.0:
            lv = P[P_LEVER0 + i] if tilt_now else 0.0
            s_new, stk, w = _coulomb_post(S[bs + SC_FT], P[bp + PC_KT], P[bp + PC_DECAY], S[bs + SC_S],
                                          S[bs + SC_DIR], x_old + lv * th_old, x + lv * th, dt)
            S[bs + SC_S] = s_new
            S[bs + SC_STUCK] = stk
            S[bs + SC_W] = w
        if S[bs + SC_STUCK] > 0.0:
            sliding = False
        s_mean += S[bs + SC_S] / 3.0
        if S[bs + SC_W] < w_min:
            w_min = S[bs + SC_W]
    return sliding, s_mean, w_min


@njit(cache=_CACHE, inline="always")
def _micro_slips(S, C, P, key6, n, nc, dt, ms_eta, ms_per_m, ms_w2, ms_2zw, ms_w):
    """The pads' micro-slip events: a Poisson process of rate w / D_c while a pad slides, each releasing ms_eta
    of the static-to-kinetic drop (mu_s - mu_k) N of sensed shear into the pad's resonator, which rings down.
    Returns whether a resonator still rings."""
    ringing = False
    for i in range(2):
        bs = S_C0 + i * SC_SIZE
        bp = P_C0 + i * PC_SIZE
        iy = S_VY0 + 2 * i
        vy = S[iy]
        vv = S[iy + 1]
        if S[bs + SC_STUCK] == 0.0 and S[bs + SC_W] > 0.0:
            if _uniform(key6, 2 * n + i) < S[bs + SC_W] * dt * ms_per_m:
                vv -= S[bs + SC_DIR] * ms_eta * (P[bp + PC_MUS] - P[bp + PC_MUK]) * nc * ms_w
                C[C_MS0 + i] += 1
        if vv != 0.0 or vy != 0.0:
            vv -= (ms_w2 * vy + ms_2zw * vv) * dt
            vy += vv * dt
            if abs(vy) < 1e-12 and abs(vv) < 1e-9:
                vy = 0.0
                vv = 0.0
            S[iy] = vy
            S[iy + 1] = vv
            if vy != 0.0:
                ringing = True
    return ringing


@njit(cache=_CACHE, inline="always")
def _slip_events(S, ev_out, nev, sliding, t0, t1, x_old, x):
    """An onset row when every contact starts to slide, a stick row when one sticks again: the new row count."""
    if sliding and S[S_STUCK] > 0.0:
        nev = _event(ev_out, nev, t0, E_ONSET, x_old)
    elif not sliding and S[S_STUCK] == 0.0:
        nev = _event(ev_out, nev, t1, E_STICK, x)
    return nev


@njit(cache=_CACHE, inline="always")
def _lose_contacts(S, ev_out, nev, x, th, tilt_now, pen_full, t1, lev0, lev1, lev2, grip, taper):
    """The contacts are lost where the shoulder has taken up the fingertips' travel (a contact past grip_travel
    without a shoulder; tilted, by the contacts' own positions): the bottle falls, with an event row."""
    if tilt_now:
        shl, xmax = _shoulder(x, th, lev0, lev1, lev2, grip)
        lost = taper * shl > pen_full if taper > 0.0 else xmax > grip
    else:
        lost = (x > grip + pen_full / taper) if taper > 0.0 else (x > grip)
    if lost:
        S[S_FALLEN] = 1.0
        S[S_TFALL] = t1
        S[S_STUCK] = 0.0
        for i in range(3):
            S[S_C0 + i * SC_SIZE + SC_STUCK] = 0.0
            S[S_C0 + i * SC_SIZE + SC_FT] = 0.0
        nev = _event(ev_out, nev, t1, E_FALLEN, x)
    return nev


@njit(cache=_CACHE, inline="always")
def _held(S, C, P, ev_out, nev, key6, x, v, th, om, nc, ms, n, h, dt, g, t0, t1, m, mw, wload, mdrop, tilted,
          pen_full, ringing, lv, grip, taper, micro):
    """The bottle in the grasp over the step: its contacts, its motion along the axis and about the tilt axis,
    its slip events and the pads' micro-slips. Returns ``(a, x, v, th, om, nev, ringing)``."""
    # thumb and index pads with the same constants see the same x, v and N, so they evolve identically:
    # compute the thumb's and copy it (P_PADS_SAME); the tilt moves only when tilted or pushed (a bottle
    # that never tilts runs the same arithmetic as without it)
    tilt_now = tilted or mdrop != 0.0
    same = P[P_PADS_SAME] > 0.0 and not tilt_now
    ftot, mom = _contact_forces(S, C, P, x, v, th, om, nc, ms, h, dt, tilt_now, same)
    x_old = x
    a = (wload - ftot) / m
    v += a * h
    x += v * h
    th_old = th
    if tilt_now:
        # the contacts' tangential forces at their levers (each bounded by its friction: together the
        # friction couple), the drop's eccentric force and gravity on the centre of mass below the axis
        # (restoring) turn the bottle about the axis
        inertia, mgd = tilt_inertia(mw, P)
        om += (mom + mdrop - g * mgd * th) / inertia * h
        th += om * h
    sliding, s_mean, w_min = _contacts_after(S, P, x_old, x, th_old, th, tilt_now, same, dt)
    nev = _slip_events(S, ev_out, nev, sliding, t0, t1, x_old, x)
    ms_eta, ms_per_m, ms_w2, ms_2zw, ms_w = micro
    if ms_eta > 0.0 and (ringing or S[S_C0 + SC_STUCK] == 0.0 or S[S_C0 + SC_SIZE + SC_STUCK] == 0.0):
        ringing = _micro_slips(S, C, P, key6, n, nc, dt, ms_eta, ms_per_m, ms_w2, ms_2zw, ms_w)
    S[S_STUCK] = 0.0 if sliding else 1.0
    S[S_S] = s_mean
    S[S_W] = w_min if sliding else 0.0
    S[S_FT] = ftot
    nev = _lose_contacts(S, ev_out, nev, x, th, tilt_now, pen_full, t1, lv[0], lv[1], lv[2], grip, taper)
    return a, x, v, th, om, nev, ringing


@njit(cache=_CACHE, inline="always")
def _unheld(S, x, v, wload, m, h):
    """The bottle out of the grasp over the step, ``(a, x, v)``: at rest on its support, or falling freely."""
    S[S_FT] = 0.0
    if S[S_SUPPORTED] > 0.0:
        return 0.0, x, v
    a = wload / m
    v += a * h
    x += v * h
    return a, x, v


@njit(cache=_CACHE, inline="always")
def _imu_filter(S, a, gacc, alpha_h, g, th, fallen):
    """The IMU's DLPF states over the step (the bottle's acceleration in the world: the grip's added; the x axis,
    radial at the thumb, 30 degrees off the normal of the tilt axis, also reads gravity tilted with the bottle);
    flushed to zero below 1e-200 m/s^2 (they decay toward an exact zero at rest and would otherwise sit in the
    subnormal range, where every step's arithmetic is slow)."""
    af = S[S_AF] + ((a + gacc if gacc != 0.0 else a) - S[S_AF]) * alpha_h
    S[S_AF] = af if abs(af) > 1e-200 else 0.0
    afl = S[S_AFL] + (S[S_ALAT] + (_COS30 * g * th if th != 0.0 and not fallen else 0.0) - S[S_AFL]) * alpha_h
    S[S_AFL] = afl if abs(afl) > 1e-200 else 0.0


@njit(cache=_CACHE, inline="always")
def _imu_ticks(S, C, P, key1, t1, coarse, daq_at, daq_end, seen_j, seen_end, g, acc_t, daq_t, dt):
    """The accelerometer's readings due by ``t1`` (its own ODR). A DAQ row carries the latest reading: with
    adaptive steps only the readings a row will carry are drawn (the last before each row; the others would be
    overwritten unseen: the same rows). Returns ``(daq_at, daq_end, seen_j, seen_end)``."""
    while C[C_ACC] * acc_t <= t1 + 1e-12:
        j = C[C_ACC]
        seen = True
        if coarse > 1:
            if C[C_DAQ] != daq_at:
                daq_at = C[C_DAQ]
                daq_end, seen_j, seen_end = _row_sample(daq_at, daq_t, acc_t, dt)
            # the reading the next row carries is the last taken by the row's step
            seen = j == seen_j
        if not seen:
            S[S_AFRESH] = 1.0
            C[C_ACC] = j + 1
            continue
        spec = 1.0 - S[S_AF] / g
        lsb = P[P_ACC_LSB]
        rng = P[P_ACC_RANGE]
        # the slosh shakes the bottle sideways along the accelerometer's x axis (the jet's offset)
        S[S_AX] = _quant_g(P[P_TILT_X] * spec + S[S_AFL] / g + P[P_ACC_NOISE] * normal(key1, 3 * j), lsb, rng)
        S[S_AY] = _quant_g(P[P_TILT_Y] * spec + P[P_ACC_NOISE] * normal(key1, 3 * j + 1), lsb, rng)
        S[S_AZ] = _quant_g(P[P_TILT_Z] * spec + P[P_ACC_NOISE] * normal(key1, 3 * j + 2), lsb, rng)
        S[S_AFRESH] = 1.0
        C[C_ACC] = j + 1
    return daq_at, daq_end, seen_j, seen_end


@njit(cache=_CACHE, inline="always")
def _slip_volts(S, P, track, key0, k, xk, nc, lam, n1w, n2w):
    """The slip sensor's reading for DAQ row ``k`` with the bottle at ``xk``. In contact the middle fingertip
    turns as far as it advances into the wall (the cuff's compression and the wall's dent under N), rolling
    the spot over the surface, and the dent opens the sensor's gap where the spot sits beside the cuff's
    contact."""
    spot = xk
    extra = (P[P_QC] - S[S_Q0 + 2]) * P[P_LAM]
    if nc > 0.0:
        dent = _wall_dent(nc, n1w, n2w, P[P_WALL_KW_INV], P[P_WALL_KW2_INV], P[P_WALL_DLIN], P[P_WALL_DCOL])
        spot += P[P_SPOT_K] * (nc * P[P_CUFF_INV] + dent) / lam
        extra = P[P_DENT_FRAC] * dent
    if S[S_FALLEN] > 0.0:
        rho = 0.0
        extra = 0.0
    else:
        ti, fr = _track_at(spot, P[P_TRACK_OFF], P[P_TRACK_DX], track.shape[0])
        rho = track[ti] + fr * (track[ti + 1] - track[ti])
    return _sensor_volts(rho, extra, P[P_GAP], P[P_VCC], P[P_VSAT], P[P_KNEE], P[P_VNOISE], key0, k, P[P_ADC_LSB],
                         P[P_ADC_MAX])


@njit(cache=_CACHE, inline="always")
def _daq_rows(daq_out, S, C, P, W, track, key0, nd, cap_daq, t0, t1, h, x_old, x, v, a, nc, lam, n1w, n2w):
    """The DAQ rows due by ``t1`` (slip sensor, flow, the latest IMU reading, the truth): the new row count."""
    while C[C_DAQ] * P[P_DAQ_T] <= t1 + 1e-12 and nd < cap_daq:
        k = C[C_DAQ]
        tk = k * P[P_DAQ_T]
        frac = (tk - t0) / h
        if frac < 0.0:
            frac = 0.0
        xk = x_old + frac * (x - x_old)
        daq_out[nd, O_T] = tk
        daq_out[nd, O_VOLTS] = _slip_volts(S, P, track, key0, k, xk, nc, lam, n1w, n2w)
        daq_out[nd, O_AX] = S[S_AX]
        daq_out[nd, O_AY] = S[S_AY]
        daq_out[nd, O_AZ] = S[S_AZ]
        daq_out[nd, O_AFRESH] = S[S_AFRESH]
        S[S_AFRESH] = 0.0
        # litres through the flow sensor at tk (the pumps start at W_START)
        litres = 0.0
        for p in range(W.shape[0]):
            if tk > W[p, W_START]:
                litres += W[p, W_RATE_L_S] * min(tk - W[p, W_START], W[p, W_DUR])
        daq_out[nd, O_PULSES] = np.floor(P[P_FLOW_K] * litres + P[P_FLOW_PHASE]) if litres > 0.0 else 0.0
        daq_out[nd, O_X] = xk
        daq_out[nd, O_V] = v
        daq_out[nd, O_S] = S[S_S]
        daq_out[nd, O_STUCK] = S[S_STUCK]
        daq_out[nd, O_NC] = nc
        daq_out[nd, O_MASS] = S[S_MASS]
        daq_out[nd, O_Q0] = S[S_Q0]
        daq_out[nd, O_Q1] = S[S_Q0 + 1]
        daq_out[nd, O_Q2] = S[S_Q0 + 2]
        daq_out[nd, O_FALLEN] = S[S_FALLEN]
        daq_out[nd, O_A] = a
        daq_out[nd, O_ALAT] = S[S_ALAT]
        daq_out[nd, O_LOAD] = S[S_LOAD]
        daq_out[nd, O_FWAT] = S[S_FWAT]
        nd += 1
        C[C_DAQ] = k + 1
    return nd


@njit(cache=_CACHE, inline="always")
def _tactile_rows(tac_out, S, C, P, tac_rates, tac_next, tac_contact, ntac, cap_tac, t1, nc, inc):
    """The tactile snapshots due by ``t1`` at each sampler's rate: the new row count."""
    for si in range(tac_rates.shape[0]):
        while tac_next[si] <= (t1 + 1e-12) * tac_rates[si] and ntac < cap_tac:
            tac_out[ntac, T_ID] = si
            tac_out[ntac, T_IDX] = tac_next[si]
            tac_out[ntac, T_T] = tac_next[si] / tac_rates[si]
            bc = S_C0 + tac_contact[si] * SC_SIZE
            tac_out[ntac, T_NC] = nc + S[S_FM0 + tac_contact[si]] if nc > 0.0 else nc
            fsen = _sensed_shear(S[bc + SC_FT], nc, S[bc + SC_PHI], P, tac_contact[si], inc) + (
                S[S_VY0 + 2 * tac_contact[si]] if tac_contact[si] < 2 else 0.0)
            # the pad's surface carries at most the Cattaneo-Mindlin shear of full slip, 1.5 mu_s N (the
            # ringing of earlier events cannot outlast the normal force that carried it)
            fmax = 1.5 * P[P_C0 + tac_contact[si] * PC_SIZE + PC_MUS] * nc
            tac_out[ntac, T_FT] = min(max(fsen, -fmax), fmax)
            tac_out[ntac, T_S] = S[bc + SC_S]
            tac_out[ntac, T_FALLEN] = S[S_FALLEN]
            tac_out[ntac, T_W] = S[bc + SC_W] if S[bc + SC_STUCK] == 0.0 else 0.0
            tac_out[ntac, T_MS] = C[C_MS0 + tac_contact[si]] if tac_contact[si] < 2 else 0.0
            ntac += 1
            tac_next[si] += 1
    return ntac


@njit(cache=_CACHE)
def step_until(S, C, P, keys, D, W, track, tac_rates, tac_next, tac_contact, n_end, daq_out, tac_out, ev_out,
               counts):
    """Advance the physics to step ``n_end``; write DAQ rows, tactile snapshots and events.

    ``counts`` receives the number of rows written to each output. Stops
    early (without error) if an output buffer would overflow; the caller
    sizes them so that this does not happen. Each step runs the pieces above
    in order; the arrays are borrowed (:func:`_borrow`) so that handing them
    to the inlined pieces costs no reference counting.
    """
    S, C, P, D, W, track = _borrow(S), _borrow(C), _borrow(P), _borrow(D), _borrow(W), _borrow(track)
    tac_rates, tac_next, tac_contact = _borrow(tac_rates), _borrow(tac_next), _borrow(tac_contact)
    daq_out, tac_out, ev_out = _borrow(daq_out), _borrow(tac_out), _borrow(ev_out)
    dt, g, n = P[P_DT], P[P_G], C[C_N]
    nd, ntac, nev = 0, 0, 0
    key0, key1, key5, key6 = keys[0], keys[1], keys[5], keys[6]
    micro = (P[P_MS_ETA], P[P_MS_PER_M], P[P_MS_W2], P[P_MS_2ZW], P[P_MS_W])
    ringing = True   # a pad's resonator may hold a value from the last call: look once
    mv_f, mv_w, mv_inv_dt = P[P_MV_F], P[P_MV_W], P[P_MV_INV_SPEED] / P[P_DT]
    taper, taper_sin, grip = P[P_TAPER], P[P_TAPER_SIN], P[P_GRIP]
    lv = (P[P_LEVER0], P[P_LEVER0 + 1], P[P_LEVER0 + 2])
    drop_e, zg = P[P_DROP_E], P[P_ZG]
    # loop invariants and the states every step reads, kept in locals (numba cannot tell that the output
    # arrays do not alias S and P, so it would reload them from memory every step)
    kservo, stall, qc, lam = P[P_KSERVO], P[P_STALL], P[P_QC], P[P_LAM]
    wall = (P[P_KN], P[P_WALL_PEN1], P[P_WALL_PEN2], P[P_WALL_N1], P[P_WALL_N2], P[P_WALL_K2], P[P_WALL_K3])
    droop = P[P_DROOP] / stall
    mb, acc_alpha, klat, clat = P[P_MB], P[P_ACC_ALPHA], P[P_KLAT], P[P_CLAT]
    x, v, a_prev, th, om = S[S_X], S[S_V], S[S_A], S[S_TH], S[S_OM]
    yb, vb, y1, v1 = S[S_YB], S[S_VB], S[S_Y1], S[S_V1]
    coarse = np.int64(P[P_COARSE])
    acc_lq = P[P_ACC_LQ]
    alpha_coarse = P[P_ACC_ALPHA_H + coarse] if coarse <= ALPHA_STEPS else -np.expm1(coarse * acc_lq)
    # the step at whose end the next DAQ row is taken (for the counter's value daq_at; recomputed when it
    # moves), and the last IMU reading before it (seen_j) and its step
    daq_at, daq_end = C[C_DAQ_AT1] - 1, C[C_DAQ_END]
    seen_j = C[C_SEEN_J] if daq_at >= 0 else np.int64(-1)
    seen_end = C[C_SEEN_END]
    acc_t, daq_t = P[P_ACC_T], P[P_DAQ_T]
    n_switch = n   # the next step where a load switches (a drop's release, a pour's start or stop): look first
    while n < n_end:
        if nev + 3 + D.shape[0] > ev_out.shape[0] or nd + 2 > daq_out.shape[0]:
            break
        # one fine step, or (adaptive, while nothing needs the fine step) ``ms`` of them at once
        ms = 1
        if coarse > 1 and n >= C[C_RECHECK]:
            # the coarse step's bound for the bottle as the slosh mode last saw it filled: longer as it fills
            ms, n_switch, daq_at, daq_end, seen_j, seen_end = _coarse_steps(
                S, C, P, D, W, tac_rates, tac_next, n, n_end, n_switch, daq_at, daq_end, seen_j, seen_end, x, v,
                th, om, coarse if C[C_CAP] < coarse else C[C_CAP], dt, g)
        t0, h, t1, tl, alpha_h = _step_span(P, n, ms, dt, coarse, acc_alpha, alpha_coarse, acc_lq)
        moving = _fingers(S, ms, h, dt, kservo, droop, stall, mv_f, mv_w, mv_inv_dt)
        tilted = th != 0.0 or om != 0.0
        nc, pen_full, shl = _normal_force(S, P, x, th, tilted, lv[0], lv[1], lv[2], grip, taper, qc, lam, wall)
        fallen = S[S_FALLEN] > 0.0
        mw, fjet, gacc = _timed_loads(W, tl)
        # the weight in the grip's frame: gravity less the grip's acceleration (down positive)
        geff = g - gacc if gacc != 0.0 else g
        fspl = _splash(S, C, P, key5, tl, fjet, mw, ms, g) if fjet > 0.0 else 0.0
        x_old = x
        fdrop, mdrop, mland, nev = _drops(D, ev_out, nev, x, v, th, om, tilted, t1, h, geff, drop_e, zg)
        m, wload = _axial_load(S, W, mb, mw, mland, ms, t1, dt, g, geff, fjet, fspl, fdrop, nc, shl, fallen, taper,
                               taper_sin)
        # the digits' motor forces, radial at 0, 120 and 240 degrees from the accelerometer's x axis
        flat = S[S_FM0] - 0.5 * (S[S_FM0 + 1] + S[S_FM0 + 2]) if (moving and nc > 0.0) else 0.0
        yb, vb, y1, v1 = _slosh(S, yb, vb, y1, v1, a_prev, m, mland, fjet, fspl, flat, h, g, klat, clat, fallen)
        if S[S_SUPPORTED] > 0.0 or fallen:
            a, x, v = _unheld(S, x, v, wload, m, h)
        else:
            a, x, v, th, om, nev, ringing = _held(S, C, P, ev_out, nev, key6, x, v, th, om, nc, ms, n, h, dt, g, t0,
                                                  t1, m, mw, wload, mdrop, tilted, pen_full, ringing, lv, grip,
                                                  taper, micro)
        S[S_X], S[S_V], S[S_A], S[S_TH], S[S_OM] = x, v, a, th, om
        a_prev = a
        _imu_filter(S, a, gacc, alpha_h, g, th, fallen)
        daq_at, daq_end, seen_j, seen_end = _imu_ticks(S, C, P, key1, t1, coarse, daq_at, daq_end, seen_j, seen_end,
                                                       g, acc_t, daq_t, dt)
        nd = _daq_rows(daq_out, S, C, P, W, track, key0, nd, daq_out.shape[0], t0, t1, h, x_old, x, v, a, nc, lam,
                       wall[3], wall[4])
        ntac = _tactile_rows(tac_out, S, C, P, tac_rates, tac_next, tac_contact, ntac, tac_out.shape[0], t1, nc,
                             P[P_INCIPIENT])
        n += ms
        C[C_STEPS] += 1
    C[C_N], C[C_DAQ_AT1], C[C_DAQ_END], C[C_SEEN_J], C[C_SEEN_END] = n, daq_at + 1, daq_end, seen_j, seen_end
    counts[0], counts[1], counts[2] = nd, ntac, nev
