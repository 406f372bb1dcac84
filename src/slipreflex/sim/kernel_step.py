"""The physics step: :func:`step_until` advances the rig and samples its sensors.

The model is described in :mod:`slipreflex.sim.kernel` (which re-exports
:func:`step_until`).
"""

# ruff: noqa: F405 (the slot constants come from _kernel_layout's star import; pyright checks the names)
from __future__ import annotations

import numpy as np
from numba import njit

from ..core._numba_cache import stamped_cache
from . import _kernel_layout as KL
from . import kernel_calm as KA
from . import kernel_contacts as KC
from . import kernel_noise as KN
from . import kernel_sensors as KS
from ._kernel_layout import *  # noqa: F403 (every slot of the vectors, as in the layouts: the step reads them all)
from .kernel_calm import (
    _CALM_FM,
    _CALM_OM,
    _CALM_PHI,
    _CALM_Q,
    _CALM_RATIO,
    _CALM_RATIO_CUFF,
    _CALM_RECHECK,
    _CALM_SLIP,
    _CALM_V,
    _fire_end,
    _load_stop,
    _load_switch,
    _tactile_end,
)
from .kernel_contacts import (
    _coulomb_contact,
    _coulomb_post,
    _grip_force,
    _rs_contact,
    _sensed_shear,
    _shoulder,
    _wall_dent,
    slosh_mode,
    tilt_inertia,
)
from .kernel_noise import _uniform, normal
from .kernel_sensors import _quant_g, _sensor_volts, _track_at

__all__: list[str] = []   # internal: slipreflex.sim.kernel gathers the names

#: the files whose code and constants the step compiles into itself (its cache is stamped with them)
_CACHE = stamped_cache(__file__, KL.__file__, KN.__file__, KC.__file__, KS.__file__, KA.__file__)
_COS30 = 0.8660254037844386

@njit(cache=_CACHE)
def step_until(S, C, P, keys, D, W, track, tac_rates, tac_next, tac_contact, n_end, daq_out, tac_out, ev_out,
               counts):
    """Advance the physics to step ``n_end``; write DAQ rows, tactile snapshots and events.

    ``counts`` receives the number of rows written to each output. Stops
    early (without error) if an output buffer would overflow; the caller
    sizes them so that this does not happen.
    """
    dt = P[P_DT]
    g = P[P_G]
    nd = 0
    ntac = 0
    nev = 0
    n = C[C_N]
    cap_daq = daq_out.shape[0]
    cap_tac = tac_out.shape[0]
    cap_ev = ev_out.shape[0]
    nsamp = tac_rates.shape[0]
    key0 = keys[0]
    key1 = keys[1]
    key5 = keys[5]
    key6 = keys[6]
    ms_eta, ms_per_m, ms_w2, ms_2zw, ms_w = P[P_MS_ETA], P[P_MS_PER_M], P[P_MS_W2], P[P_MS_2ZW], P[P_MS_W]
    inc = P[P_INCIPIENT]
    ringing = True   # a pad's resonator may hold a value from the last call: look once
    mv_f, mv_w, mv_inv_dt = P[P_MV_F], P[P_MV_W], P[P_MV_INV_SPEED] / P[P_DT]
    taper, taper_sin, grip = P[P_TAPER], P[P_TAPER_SIN], P[P_GRIP]
    lev0, lev1, lev2, zg, drop_e = P[P_LEVER0], P[P_LEVER0 + 1], P[P_LEVER0 + 2], P[P_ZG], P[P_DROP_E]
    # loop invariants and the states every step reads, kept in locals (numba cannot tell that the
    # output arrays do not alias S and P, so it would reload them from memory every step)
    kservo = P[P_KSERVO]
    stall = P[P_STALL]
    qc = P[P_QC]
    lam = P[P_LAM]
    kn = P[P_KN]
    pen1, pen2, n1w, n2w = P[P_WALL_PEN1], P[P_WALL_PEN2], P[P_WALL_N1], P[P_WALL_N2]
    k2w, k3w = P[P_WALL_K2], P[P_WALL_K3]
    droop = P[P_DROOP] / stall
    mb = P[P_MB]
    acc_alpha = P[P_ACC_ALPHA]
    klat = P[P_KLAT]
    clat = P[P_CLAT]
    x = S[S_X]
    v = S[S_V]
    a_prev = S[S_A]
    yb = S[S_YB]
    vb = S[S_VB]
    y1 = S[S_Y1]
    v1 = S[S_V1]
    th = S[S_TH]
    om = S[S_OM]
    coarse = np.int64(P[P_COARSE])
    acc_lq = P[P_ACC_LQ]
    alpha_coarse = P[P_ACC_ALPHA_H + coarse] if coarse <= ALPHA_STEPS else -np.expm1(coarse * acc_lq)
    # the step at whose end the next DAQ row is taken (for the counter's value daq_at; recomputed when it
    # moves), and the last IMU reading before it (seen_j) and its step
    daq_at = C[C_DAQ_AT1] - 1
    daq_end = C[C_DAQ_END]
    seen_j = C[C_SEEN_J] if daq_at >= 0 else np.int64(-1)
    seen_end = C[C_SEEN_END]
    acc_t = P[P_ACC_T]
    daq_t = P[P_DAQ_T]
    n_switch = n   # the next step where a load switches (a drop's release, a pour's start or stop): look first
    while n < n_end:
        if nev + 3 + D.shape[0] > cap_ev or nd + 2 > cap_daq:
            break
        # the step: one fine step, or (adaptive, while nothing needs the fine step) ``ms`` of them at once,
        # ending where the next sample is due; ``h`` its length, loads taken at its middle ``tl``
        ms = 1
        if coarse > 1 and n >= C[C_RECHECK]:
            # calm: nothing in the rig needs the fine step (the conditions are written out here, not in a
            # helper: an inlined helper taking arrays costs an atomic reference count per array and call)
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
                ncc = S[S_NC]
                for i in range(3):
                    bs = S_C0 + i * SC_SIZE
                    bp = P_C0 + i * PC_SIZE
                    rs = P[bp + PC_LAW] == LAW_RATE_STATE
                    if i == 2 and rs and S[bs + SC_PHI] < _CALM_PHI:
                        # the cuff weakened, creeping or stuck for a moment between creeps: a yield releases
                        # at most _CALM_PHI of its static-to-kinetic drop
                        if S[bs + SC_STUCK] == 0.0 and S[bs + SC_W] * coarse * dt > _CALM_SLIP * P[bp + PC_DC]:
                            calm = False
                    elif S[bs + SC_STUCK] > 0.0:
                        lim = (P[bp + PC_MUK] + (P[bp + PC_MUS] - P[bp + PC_MUK]) * S[bs + SC_PHI] if rs
                               else P[bp + PC_MUS])
                        if abs(S[bs + SC_FT]) > (_CALM_RATIO if i < 2 else _CALM_RATIO_CUFF) * lim * ncc:
                            calm = False
                    else:
                        calm = False
            cap = coarse
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
            if calm:
                # the coarse step ends where the next IMU, DAQ or tactile sample is taken (each from the state
                # at its instant, as with fixed steps), before a drop's release and where a pour's water
                # starts or stops
                if n >= n_switch:
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
                if C[C_DAQ] != daq_at:
                    daq_at = C[C_DAQ]
                    daq_end = _fire_end(daq_at * daq_t, dt)
                    # the IMU reading the row will carry: the last taken by the row's step (the readings
                    # before it are drawn by no one, and end no step)
                    seen_j = np.int64(np.floor((daq_end * dt + 1e-12) / acc_t)) + 1
                    while seen_j >= 0 and _fire_end(seen_j * acc_t, dt) > daq_end:
                        seen_j -= 1
                    seen_end = _fire_end(seen_j * acc_t, dt)
                ms = min(cap, n_end - n, n_switch - n, daq_end - n)
                if seen_j >= C[C_ACC]:
                    ms = min(ms, seen_end - n)
                for si in range(nsamp):
                    ms = min(ms, _tactile_end(tac_next[si], tac_rates[si], dt) - n)
                if ms < 1:
                    ms = 1
            else:
                C[C_RECHECK] = n + _CALM_RECHECK
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
        # ---- fingers (in a coarse step of a held bottle within _CALM_Q of their targets: their motors quiet)
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
        qbar = (S[S_Q0] + S[S_Q0 + 1] + S[S_Q0 + 2]) / 3.0
        pen = (qbar - qc) * lam
        pen_full = pen
        # past grip_travel the fingertips are on the shoulder, whose radius shrinks as the bottle slides; tilted,
        # each contact is at its own height, and the three equal normal forces (the bottle shifts sideways
        # until they balance) follow the mean of their gaps
        tilted = th != 0.0 or om != 0.0
        xmax = x
        if tilted:
            shl, xmax = _shoulder(x, th, lev0, lev1, lev2, grip)
        else:
            shl = x - grip if x > grip else 0.0
        if taper > 0.0 and shl > 0.0:
            pen -= taper * shl
        if tilted:
            # the tilted body's section in the grasp's plane is an ellipse, R / cos(th) across the axis: it
            # presses the fingertips off the axis further in (second order in the tilt)
            pen += P[P_TILT_PEN] * (1.0 / np.cos(th) - 1.0)
        fallen = S[S_FALLEN] > 0.0
        nc = _grip_force(pen, kn, pen1, pen2, n1w, n2w, k2w, k3w) if not fallen else 0.0
        S[S_NC] = nc
        # ---- loads
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
        # the weight in the grip's frame: gravity less the grip's acceleration (down positive)
        geff = g - gacc if gacc != 0.0 else g
        # ---- the jet's splash: a one-pole (Ornstein-Uhlenbeck) noise drawn on a fixed 1 ms grid and
        # interpolated, so it does not depend on dt; the grid (and the slosh mode's coefficients, which
        # change with the fill) advances only while a jet flows, catching up on its first use
        fspl = 0.0
        if fjet > 0.0:
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
        x_old = x
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
                    ev_out[nev, 0] = t1
                    ev_out[nev, 1] = E_LANDED
                    ev_out[nev, 2] = x
                    nev += 1
            if D[d, D_LANDED] > 0.0:
                mland += D[d, D_M]
            D[d, D_VZ] += (geff - f / D[d, D_M]) * h
            D[d, D_Z] += D[d, D_VZ] * h
            fdrop += f
            if f != 0.0 and drop_e != 0.0:
                # its force on the bottom, at the eccentricity; the bottom point z_g below the axis moves
                # sideways with the tilt, shortening the lever
                mdrop += f * (drop_e - zg * th)
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
        # ---- the slosh (sideways): slosh mass m1 on the spring m1 k tanh(k h) (g - a) and damper c1,
        # tied to the bottle, which the grasp holds sideways; the jet's force drives the mode (equal and
        # opposite on the bottle: a vertical jet gives the pair no sideways momentum)
        # the digits' motor forces, radial at 0, 120 and 240 degrees from the accelerometer's x axis
        flat = S[S_FM0] - 0.5 * (S[S_FM0 + 1] + S[S_FM0 + 2]) if (moving and nc > 0.0) else 0.0
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
        # ---- bottle
        a = 0.0
        if S[S_SUPPORTED] > 0.0:
            S[S_FT] = 0.0
        elif fallen:
            a = wload / m
            v += a * h
            x += v * h
            S[S_FT] = 0.0
        else:
            # thumb and index pads with the same constants see the same x, v and N, so they
            # evolve identically: compute the thumb's and copy it (P_PADS_SAME)
            # the tilt: each contact's point moves down by its lever times the tilt (the tilt moves only
            # when tilted or pushed: a bottle that never tilts runs the same arithmetic as without it)
            tilt_now = tilted or mdrop != 0.0
            same = P[P_PADS_SAME] > 0.0 and not tilt_now
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
            a = (wload - ftot) / m
            v += a * h
            x += v * h
            th_old = th
            if tilt_now:
                # the contacts' tangential forces at their levers (each bounded by its friction: together
                # the friction couple), the drop's eccentric force and gravity on the centre of mass below
                # the axis (restoring) turn the bottle about the axis
                inertia, mgd = tilt_inertia(mw, P)
                om += (mom + mdrop - g * mgd * th) / inertia * h
                th += om * h
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
            if sliding and S[S_STUCK] > 0.0:
                ev_out[nev, 0] = t0
                ev_out[nev, 1] = E_ONSET
                ev_out[nev, 2] = x_old
                nev += 1
            elif not sliding and S[S_STUCK] == 0.0:
                ev_out[nev, 0] = t1
                ev_out[nev, 1] = E_STICK
                ev_out[nev, 2] = x
                nev += 1
            # the pads' micro-slip events: a Poisson process of rate w / D_c while a pad slides, each releasing
            # ms_eta of the static-to-kinetic drop (mu_s - mu_k) N of sensed shear into the pad's resonator
            if ms_eta > 0.0 and (ringing or S[S_C0 + SC_STUCK] == 0.0 or S[S_C0 + SC_SIZE + SC_STUCK] == 0.0):
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
            S[S_STUCK] = 0.0 if sliding else 1.0
            S[S_S] = s_mean
            S[S_W] = w_min if sliding else 0.0
            S[S_FT] = ftot
            # the contacts are lost where the shoulder has taken up the fingertips' travel (a contact past
            # grip_travel without a shoulder); tilted, by the contacts' own positions
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
                ev_out[nev, 0] = t1
                ev_out[nev, 1] = E_FALLEN
                ev_out[nev, 2] = x
                nev += 1
        S[S_X] = x
        S[S_V] = v
        S[S_A] = a
        S[S_TH] = th
        S[S_OM] = om
        a_prev = a
        # the IMU's DLPF states; flushed to zero below 1e-200 m/s^2 (they decay toward an exact zero at rest
        # and would otherwise sit in the subnormal range, where every step's arithmetic is slow)
        # (the IMU reads the bottle's acceleration in the world: the grip's added)
        af = S[S_AF] + ((a + gacc if gacc != 0.0 else a) - S[S_AF]) * alpha_h
        S[S_AF] = af if abs(af) > 1e-200 else 0.0
        # the accelerometer's x axis (radial at the thumb, 30 degrees off the normal of the tilt axis) also
        # reads gravity tilted with the bottle
        afl = S[S_AFL] + (S[S_ALAT] + (_COS30 * g * th if th != 0.0 and not fallen else 0.0) - S[S_AFL]) * alpha_h
        S[S_AFL] = afl if abs(afl) > 1e-200 else 0.0
        # ---- accelerometer ticks (own ODR)
        while C[C_ACC] * acc_t <= t1 + 1e-12:
            j = C[C_ACC]
            # a DAQ row carries the latest reading: with adaptive steps only the readings a row will carry are
            # drawn (the last before each row; the others would be overwritten unseen: the same rows)
            seen = True
            if coarse > 1:
                if C[C_DAQ] != daq_at:
                    daq_at = C[C_DAQ]
                    daq_end = _fire_end(daq_at * daq_t, dt)
                    seen_j = np.int64(np.floor((daq_end * dt + 1e-12) / acc_t)) + 1
                    while seen_j >= 0 and _fire_end(seen_j * acc_t, dt) > daq_end:
                        seen_j -= 1
                    seen_end = _fire_end(seen_j * acc_t, dt)
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
        # ---- DAQ ticks (slip sensor, flow, latest accel)
        while C[C_DAQ] * P[P_DAQ_T] <= t1 + 1e-12 and nd < cap_daq:
            k = C[C_DAQ]
            tk = k * P[P_DAQ_T]
            frac = (tk - t0) / h
            if frac < 0.0:
                frac = 0.0
            xk = x_old + frac * (x - x_old)
            # in contact the middle fingertip turns as far as it advances into the wall (the cuff's
            # compression and the wall's dent under N), rolling the spot over the surface, and the dent
            # opens the sensor's gap where the spot sits beside the cuff's contact
            spot = xk
            extra = (P[P_QC] - S[S_Q0 + 2]) * P[P_LAM]
            if nc > 0.0:
                dent = _wall_dent(nc, n1w, n2w, P[P_WALL_KW_INV], P[P_WALL_KW2_INV], P[P_WALL_DLIN],
                                  P[P_WALL_DCOL])
                spot += P[P_SPOT_K] * (nc * P[P_CUFF_INV] + dent) / lam
                extra = P[P_DENT_FRAC] * dent
            daq_out[nd, O_T] = tk
            if S[S_FALLEN] > 0.0:
                rho = 0.0
                extra = 0.0
            else:
                ti, fr = _track_at(spot, P[P_TRACK_OFF], P[P_TRACK_DX], track.shape[0])
                rho = track[ti] + fr * (track[ti + 1] - track[ti])
            daq_out[nd, O_VOLTS] = _sensor_volts(rho, extra, P[P_GAP], P[P_VCC], P[P_VSAT], P[P_KNEE],
                                                 P[P_VNOISE], key0, k, P[P_ADC_LSB], P[P_ADC_MAX])
            daq_out[nd, O_AX] = S[S_AX]
            daq_out[nd, O_AY] = S[S_AY]
            daq_out[nd, O_AZ] = S[S_AZ]
            daq_out[nd, O_AFRESH] = S[S_AFRESH]
            S[S_AFRESH] = 0.0
            # litres through the flow sensor at tk (the pumps start at W_START; written out, not in a helper:
            # an inlined helper taking W would cost a reference count per row)
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
        # ---- tactile snapshots
        for si in range(nsamp):
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
        n += ms
        C[C_STEPS] += 1
    C[C_N] = n
    C[C_DAQ_AT1] = daq_at + 1
    C[C_DAQ_END] = daq_end
    C[C_SEEN_J] = seen_j
    C[C_SEEN_END] = seen_end
    counts[0] = nd
    counts[1] = ntac
    counts[2] = nev
