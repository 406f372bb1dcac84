"""The pads' tactile slip signature: micro-slip events (rate, spectrum) and incipient slip (Cattaneo-Mindlin)."""

import dataclasses

import numpy as np
import pytest

from slipreflex.sim import PAPER_POUR, Rig, TactileParams
from slipreflex.sim import kernel as K

FS = 8000.0


def _pour(tactile, seed=3):
    """An open-loop pour on TR to fall-out; the index pad's snapshots (kernel rows) at FS and the rig."""
    rig = Rig("TR", seed=seed, tactile=tactile)
    rig.grasp()
    s = rig.tactile_sampler(FS)
    rows = []
    s.feed = lambda snap, params: rows.append(snap.copy())   # keep the raw snapshots
    rig.perturb(PAPER_POUR, at=rig.t + 0.1)
    rig.advance_block(rig.t + 20.0)
    assert rig.fallen
    return rig, np.concatenate(rows)


@pytest.fixture(scope="module")
def runs():
    off = TactileParams(slip_events=0.0, incipient_slip=0.0)
    return _pour(off), _pour(dataclasses.replace(off, slip_events=0.3)), _pour(dataclasses.replace(off,
                                                                                                    incipient_slip=1.0))


def test_events_do_not_touch_the_physics_and_come_one_per_slip_distance(runs):
    (r0, a0), (r1, a1), _ = runs
    # sensed only: the bottle's motion is the same bit for bit
    assert r0.fall_time == r1.fall_time
    assert np.array_equal(a0[:, K.T_S], a1[:, K.T_S])
    # a Poisson process of rate w / D_c: the count over the run is the distance slid over D_c (4 sd)
    slid = [abs(r1._S[K.S_C0 + i * K.SC_SIZE + K.SC_S]) for i in range(2)]
    for i in range(2):
        mean = slid[i] / r1.bottle.slip_distance_m
        assert mean > 100
        assert abs(int(r1._C[K.C_MS0 + i]) - mean) < 4 * np.sqrt(mean), (i, mean)
    assert int(r0._C[K.C_MS0]) == 0


def test_event_ringing_has_the_pad_resonance_spectrum_and_nothing_while_stuck(runs):
    from scipy.signal import welch

    (r0, a0), (r1, a1), _ = runs
    y = a1[:, K.T_FT] - a0[:, K.T_FT]          # the resonator's output alone
    sliding = a1[:, K.T_W] > 0
    assert np.all(y[: np.argmax(sliding)] == 0.0)     # no event before the first slide
    held = ~a1[:, K.T_FALLEN].astype(bool)
    f, p = welch(y[held][np.argmax(sliding):], fs=FS, nperseg=2048)
    tp = TactileParams(slip_events=0.3)
    w = 2 * np.pi * tp.slip_vibration_hz
    wd = w * np.sqrt(1 - tp.slip_vibration_zeta ** 2)
    assert f[np.argmax(p)] == pytest.approx(wd / (2 * np.pi), rel=0.05)
    # the first events ring as the closed form: each (dF w / w_d) exp(-zeta w t) sin(w_d t), dF = eta (mu_s - mu_k)
    # N, the sum of them (the pad is linear); the row counts the contact's events, so the window holds the first
    # two snapshot intervals with events and ends before a third (5 ms at most). A snapshot holds the state at
    # the end of the kernel step that contains its time, and an event kicks the pad in a kernel step of its
    # interval (which one is fitted): the closed form at the kernel's own times
    ev = a1[:, K.T_MS]
    k0 = int(np.argmax(ev > 0))
    assert np.all(y[:k0] == 0.0) and y[k0] != 0.0
    inc = np.flatnonzero(np.diff(ev[k0:k0 + 41]) > 0) + 1          # later intervals with events
    ks = [k0] + [k0 + int(j) for j in inc[:1]]
    k1 = k0 + 40 if len(inc) < 2 else k0 + int(inc[1])
    ms = [int(ev[k] - (ev[k - 1] if k > 0 else 0)) for k in ks]
    assert k1 - k0 >= 2 and sum(ms) <= 4
    b = r1.bottle
    d_f = tp.slip_events * (b.mu_s - b.mu_k) * a1[k0, K.T_NC]
    dt = r1.physics.dt
    tt = np.ceil(a1[:, K.T_T] / dt - 1e-9) * dt                  # the end of each snapshot's kernel step

    def ring(t):   # an event in the step ending at time 0 has moved the pad one step by then
        t = t + dt
        return np.where(t > 0, d_f * w / wd * np.exp(-tp.slip_vibration_zeta * w * t) * np.sin(wd * t), 0.0)

    steps = np.arange(0, int(np.ceil(1.0 / (FS * dt))) + 1) * dt    # the kernel steps of one snapshot interval
    best = np.inf
    for tau0 in steps:
        for tau1 in (steps if len(ks) > 1 else steps[:1]):
            want = ms[0] * ring(tt[k0:k1] - tt[ks[0]] + tau0)
            if len(ks) > 1:
                want = want + ms[1] * ring(tt[k0:k1] - tt[ks[1]] + tau1)
            best = min(best, float(np.max(np.abs(np.abs(y[k0:k1]) - np.abs(want)))))
    assert best < 0.06 * d_f     # the semi-implicit step at omega dt = 0.09


def test_incipient_slip_follows_cattaneo_mindlin_while_the_pad_holds(runs):
    (r0, a0), _, (r2, a2) = runs
    stuck = (a0[:, K.T_W] == 0) & (a0[:, K.T_NC] > 0) & ~a0[:, K.T_FALLEN].astype(bool)
    stuck[: np.argmax(a0[:, K.T_W] > 0)] &= True
    first_slide = int(np.argmax(a0[:, K.T_W] > 0))
    idx = np.flatnonzero(stuck[:first_slide])
    ft, nc = a0[idx, K.T_FT], a0[idx, K.T_NC]
    mu = r2.bottle.mu_s                           # healed, before any slide
    q = np.abs(ft) / (mu * nc)
    want = np.sign(ft) * 1.5 * mu * nc * (1 - (1 - np.minimum(q, 1)) ** (2 / 3))
    assert np.allclose(a2[idx, K.T_FT], want, rtol=1e-9, atol=1e-12)
    # the linear law at small load, steeper near slip
    assert q.max() > 0.9
    assert np.all(np.abs(a2[idx, K.T_FT]) >= np.abs(ft) - 1e-12)


def test_a_patch_shifted_off_the_array_reads_nothing_and_raises_nothing():
    # a snapshot whose shear is far beyond what its normal force carries (all Gaussian terms underflow)
    snap = np.zeros((1, K.T_SIZE))
    snap[0, K.T_NC], snap[0, K.T_FT] = 1e-12, 1.0
    out = np.empty((1, 4, 4))
    state = np.full((2, 4, 4), np.nan)
    K.tactile_frames(snap, np.uint64(1), 1.0, 0.9, 0.7, 0.0, 0.0, 1.0, 0.0, 0.0, state, out)
    assert np.all(out == 0.0)


def test_the_sensed_shear_never_exceeds_full_slip(runs):
    for rig, a in runs:
        ok = a[:, K.T_NC] > 0
        assert np.all(np.abs(a[ok, K.T_FT]) <= 1.5 * rig.bottle.mu_s * a[ok, K.T_NC] * (1 + 1e-12))
