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
    # the first event rings as the closed form: (dF w / w_d) exp(-zeta w t) sin(w_d t), dF = eta (mu_s - mu_k) N
    k0 = int(np.argmax(y != 0))
    b = r1.bottle
    d_f = tp.slip_events * (b.mu_s - b.mu_k) * a1[k0, K.T_NC]
    seg = np.abs(y[k0:k0 + 40])            # 5 ms, before the next event
    best = np.inf
    for tau in np.linspace(0.0, 1.0 / FS, 26):   # the event falls somewhere in the step before the first snapshot
        t = a1[k0:k0 + 40, K.T_T] - a1[k0, K.T_T] + tau
        want = d_f * w / wd * np.exp(-tp.slip_vibration_zeta * w * t) * np.abs(np.sin(wd * t))
        best = min(best, float(np.max(np.abs(seg - want))))
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
