"""NMSD and SWT-SD's compiled step: called from numba it is the streaming object, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from slipreflex.core.errors import DataError
from slipreflex.core.hardware import NMSD_FS, SWT_FS
from slipreflex.core.interfaces import CompiledReflex
from slipreflex.methods.baselines import NMSD, SWTSD, Closer, ClosingParams, nmsd_detections, rest_threshold
from slipreflex.methods.baselines import _kernels as K
from slipreflex.methods.baselines import _layout as L


@njit
def _loop(step, S, P, frames, positions, out, stat, level):
    """What a compiled closed loop does: the step per frame, from numba, on the object's S."""
    for k in range(frames.shape[0]):
        out[k] = step(S, P, frames[k], positions[k])
        stat[k] = S[L.S_STAT]
        level[k] = S[L.S_LEVEL]


@njit
def _coefficients(S, P, frames, out):
    """SWT-SD's per-taxel coefficient after each frame, read from the state the step keeps."""
    for k in range(frames.shape[0]):
        K.tactile_step(S, P, frames[k], np.nan)
        coef = L.S_ARRAYS + (int(P[L.P_WINDOW]) + 1) * frames.shape[1]     # layout: ring, run, c_k
        for t in range(frames.shape[1]):
            out[k, t] = S[coef + t]


def _frames(fs, shape, seed, nan_every=0):
    """Noisy frames with slips (a sudden drop, a slide, a vibration) and optional NaN frames."""
    rng = np.random.default_rng(seed)
    k = int(2.0 * fs)
    f = 0.5 + rng.normal(0.0, 0.004, (k, *shape))
    flat = f.reshape(k, -1)
    t = np.arange(k) / fs
    flat[:, 0] += np.where(t > 0.6, -0.3, 0.0) + np.where((t > 1.2) & (t < 1.4), 0.05 * np.sin(380 * t), 0.0)
    flat[:, -1] += -2.0 * np.clip(t - 0.9, 0.0, 0.2)
    if nan_every:
        flat[nan_every::nan_every, rng.integers(flat.shape[1])] = np.nan
    return f


def _reflex(cls, shape, frames):
    fs = cls.params_class(threshold=1.0, speed=1.0).fs
    thr = rest_threshold(frames[: int(0.5 * fs)], cls.name, fs)
    return cls(threshold=thr, speed=520.0, p0=100.0, shape=shape)


def _stream(r, frames, positions):
    """The object's commands and diagnostics; a refused (non-finite) frame gives NaN and changes nothing."""
    out, stat, level = [], [], []
    for fr, p in zip(frames, positions):
        before = r.compiled()[1].copy()
        try:
            u = r.step(fr, None if np.isnan(p) else p)
        except DataError:
            np.testing.assert_array_equal(r.compiled()[1], before)     # refused before anything changed
            u = None
        out.append(np.nan if u is None else u)
        stat.append(r.last_statistic)
        level.append(r.last_level)
    return np.array(out), np.array(stat), np.array(level, dtype=float)


@pytest.mark.parametrize("cls", [NMSD, SWTSD])
@pytest.mark.parametrize("shape", [(4, 4), (7,), (1,)])
@pytest.mark.parametrize("with_positions", [False, True])
@pytest.mark.parametrize("nan_every", [0, 37])
def test_the_compiled_step_from_numba_is_the_streaming_object(cls, shape, with_positions, nan_every):
    frames = _frames(cls.params_class(threshold=1.0, speed=1.0).fs, shape, seed=len(shape), nan_every=nan_every)
    k = len(frames)
    rng = np.random.default_rng(7)
    positions = (np.where(rng.random(k) < 0.3, 100.0 + rng.normal(0, 30, k), np.nan) if with_positions
                 else np.full(k, np.nan))
    a = _reflex(cls, shape, np.nan_to_num(frames, nan=0.5))       # the object, stepped from Python
    b = _reflex(cls, shape, np.nan_to_num(frames, nan=0.5))       # its twin, stepped from numba
    expect, stat, level = _stream(a, frames, positions)
    step, S, P = b.compiled()
    out, cstat, clevel = np.empty(k), np.empty(k), np.empty(k)
    _loop(step, S, P, np.ascontiguousarray(frames.reshape(k, -1)), positions, out, cstat, clevel)
    np.testing.assert_array_equal(out, expect)          # NaN in the same places, equal bits elsewhere
    np.testing.assert_array_equal(cstat, stat)
    np.testing.assert_array_equal(clevel, level)
    assert np.isfinite(out).sum() > 5                   # the slips made it close
    np.testing.assert_array_equal(b.compiled()[1], a.compiled()[1])
    assert (b.detections, b.closing_s, b.last_event) == (a.detections, a.closing_s, a.last_event)


@pytest.mark.parametrize("cls", [NMSD, SWTSD])
def test_the_object_goes_on_from_where_the_compiled_loop_left_it_and_reset_restores_in_place(cls):
    frames = _frames(cls.params_class(threshold=1.0, speed=1.0).fs, (4, 4), seed=3)
    k, half = len(frames), len(frames) // 2
    positions = np.where(np.arange(k) % 5 == 0, 140.0, np.nan)
    whole = _reflex(cls, (4, 4), frames)
    expect, _, _ = _stream(whole, frames, positions)
    r = _reflex(cls, (4, 4), frames)
    step, S, P = r.compiled()
    initial = S.copy()
    out = np.empty(half)
    _loop(step, S, P, np.ascontiguousarray(frames[:half].reshape(half, -1)), positions[:half], out,
          np.empty(half), np.empty(half))
    rest, _, _ = _stream(r, frames[half:], positions[half:])
    np.testing.assert_array_equal(np.r_[out, rest], expect)
    assert np.isfinite(rest).any() and np.isfinite(out).any()
    assert isinstance(r, CompiledReflex)
    r.reset()
    assert r.compiled()[1] is S                          # the live array, restored in place
    np.testing.assert_array_equal(S, initial)
    assert S.tobytes() == initial.tobytes()
    again, _, _ = _stream(r, frames, positions)
    np.testing.assert_array_equal(again, expect)


def test_swt_coefficients_are_pywavelets_swt_and_the_detections_follow_bit_for_bit():
    import pywt

    rng = np.random.default_rng(11)
    frames = rng.normal(size=(400, 16)) * 10 ** rng.uniform(-2, 1, size=(400, 16))
    r = SWTSD(threshold=0.5, speed=380.0, persist=2, shape=(16,))
    step, S, P = r.compiled()
    coef = np.empty_like(frames)
    _coefficients(S, P, frames, coef)
    win = np.lib.stride_tricks.sliding_window_view(frames, 8, axis=0)      # (393, 16, 8), oldest first
    direct = pywt.swt(np.ascontiguousarray(win), "haar", level=3, axis=-1)[0][1][..., 0]
    np.testing.assert_allclose(coef[7:], direct, rtol=1e-12, atol=1e-12)
    # the ON signal from pywt's coefficients with the persistence rule, against the compiled step's
    over = np.zeros_like(frames, dtype=bool)
    over[7:] = np.abs(direct) > 0.5
    run, on = np.zeros(16), np.zeros(len(frames), dtype=bool)
    for k in range(len(frames)):
        run = np.where(over[k], run + 1, 0)
        on[k] = (run > 2).any()
    assert 0 < on.sum() < len(on)
    r2 = SWTSD(threshold=0.5, speed=380.0, persist=2, shape=(16,))
    out, stat, level = np.empty(400), np.empty(400), np.empty(400)
    _loop(*r2.compiled(), frames, np.full(400, np.nan), out, stat, level)
    np.testing.assert_array_equal(level.astype(bool), on)
    np.testing.assert_allclose(stat[7:], np.abs(direct).max(axis=1), rtol=1e-12, atol=1e-12)


def test_nmsd_compiled_detections_are_the_batch_detections():
    frames = _frames(NMSD_FS, (4, 4), seed=5)
    r = _reflex(NMSD, (4, 4), frames)
    step, S, P = r.compiled()
    events = []
    for f in frames.reshape(len(frames), -1):
        step(S, P, f, np.nan)
        events.append(S[L.S_EVENT] != 0.0)
    det = nmsd_detections(frames, NMSD_FS, threshold=r.params.threshold)
    assert det.sum() > 0
    np.testing.assert_array_equal(events, det)
    assert r.detections == det.sum()


def test_the_compiled_step_refuses_a_frame_of_the_wrong_size_and_skips_a_non_finite_one():
    r = SWTSD(threshold=0.1, speed=SWT_FS)
    step, S, P = r.compiled()
    with pytest.raises(ValueError, match="taxel"):
        step(S, P, np.zeros(15), np.nan)
    before = S.copy()
    bad = np.zeros(16)
    bad[3] = np.inf
    assert np.isnan(step(S, P, bad, 100.0))
    assert S.tobytes() == before.tobytes()


def test_the_closer_is_the_compiled_closing_rule():
    p = ClosingParams(fs=100.0, speed=1000.0, close_s=0.05, p0=0.0, hi=480.0)
    c = Closer(p)
    c.trigger()
    assert c.step(position=300.0) == 310.0 and c.remaining == 4 and c.triggers == 1
    c.reset()
    assert c._S.tobytes() == Closer(p)._S.tobytes()
    with pytest.raises(Exception, match="mode"):
        c.feed(True, "sometimes")
    # an episode starts from max(target, position); positions during it do not move the ramp
    c = Closer(ClosingParams(fs=100.0, speed=1000.0, close_s=0.03))
    c.trigger()
    assert [c.step(200.0), c.step(300.0), c.step(300.0), c.step(300.0)] == [210.0, 220.0, 230.0, None]
    c.feed(True, "hold")
    c.feed(True, "hold")                                 # hold: no second quantum while one runs
    assert c.remaining == 3 and c.step(100.0) == 240.0 and c.step(500.0) == 250.0
