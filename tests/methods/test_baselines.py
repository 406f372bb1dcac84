"""NMSD and SWT-SD: streaming == batch, the closing rule, the threshold rule."""

from __future__ import annotations

import numpy as np
import pytest

from slipreflex.core.errors import DataError, ParameterError
from slipreflex.core.hardware import NMSD_FS, SWT_FS
from slipreflex.core.interfaces import Reflex
from slipreflex.methods.baselines import (
    NMSD,
    SWTSD,
    ClosingParams,
    NMSDParams,
    SWTParams,
    closing_commands,
    nmsd_commands,
    nmsd_detections,
    nmsd_statistic,
    rest_threshold,
    swt_commands,
    swt_on,
    swt_statistic,
)


def _synthetic(fs: float, seconds: float, seed: int, noise: float = 0.005) -> np.ndarray:
    """Tactile frames: 0.3 N per taxel, noise, and two slip bursts (falling force + ripple)."""
    rng = np.random.default_rng(seed)
    k = int(seconds * fs)
    t = np.arange(k) / fs
    f = 0.3 + rng.normal(0.0, noise, size=(k, 4, 4))
    for t0, dur in ((0.5, 0.08), (1.2, 0.2)):
        m = (t >= t0) & (t < t0 + dur)
        ramp = np.where(m, (t - t0), 0.0) + np.where(t >= t0 + dur, dur, 0.0)
        ripple = np.where(m, 0.05 * np.sin(2 * np.pi * 60 * t), 0.0)
        f[:, 0, :] += ripple[:, None]           # vibration on one row (NMSD sees it)
        f[:, 1, :] += -3.0 * ramp[:, None]      # a steady force decrease on another (SWT sees it)
    return f


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_nmsd_streaming_equals_batch(seed, stream, assert_same_commands):
    frames = _synthetic(NMSD_FS, 2.0, seed)
    params = NMSDParams(threshold=rest_threshold(frames[:100], "nmsd", NMSD_FS), speed=800.0, p0=120.0)
    positions = np.where(np.arange(len(frames)) % 3 == 0, 150.0 + seed, np.nan)
    for pos in (None, positions):
        batch = nmsd_commands(frames, params, positions=pos)
        r = NMSD(params)
        out = stream(r, frames, pos)
        assert_same_commands(batch, out)
        assert np.isfinite(batch).sum() > 0
        # reset restores the initial state: a second pass gives the same bits
        r.reset()
        np.testing.assert_array_equal(stream(r, frames, pos), out)
    det = nmsd_detections(frames, NMSD_FS, threshold=params.threshold)
    r = NMSD(params)
    events = []
    for fr in frames:
        r.step(fr)
        events.append(r.last_event)
    np.testing.assert_array_equal(det, events)
    assert r.detections == det.sum()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_swt_streaming_equals_batch(seed, stream, assert_same_commands):
    frames = _synthetic(SWT_FS, 2.0, seed)
    params = SWTParams(threshold=rest_threshold(frames[:150], "swt", SWT_FS), speed=800.0, p0=120.0)
    positions = np.where(np.arange(len(frames)) % 4 == 0, 140.0, np.nan)
    for pos in (None, positions):
        batch = swt_commands(frames, params, positions=pos)
        r = SWTSD(params)
        out = stream(r, frames, pos)
        assert_same_commands(batch, out)
        assert np.isfinite(batch).sum() > 0
    on = swt_on(frames, threshold=params.threshold)
    r = SWTSD(params)
    ons = []
    for fr in frames:
        r.step(fr)
        ons.append(r.last_on)
    np.testing.assert_array_equal(on, ons)


def test_swt_statistic_is_level3_haar_first_coefficient():
    rng = np.random.default_rng(3)
    f = rng.normal(size=(40, 4, 4))
    s = swt_statistic(f)
    assert np.all(s[:7] == 0.0)
    for k in range(7, 40):
        w = f[k - 7:k + 1]
        expect = (w[:4].sum(axis=0) - w[4:].sum(axis=0)) / (2 * np.sqrt(2))
        np.testing.assert_allclose(s[k], expect, rtol=1e-12, atol=1e-12)
    # and it is what pywt.swt itself gives on every 8-sample window
    import pywt
    win = np.lib.stride_tricks.sliding_window_view(f.reshape(40, 16), 8, axis=0)
    direct = pywt.swt(np.ascontiguousarray(win), "haar", level=3, axis=-1)[0][1][..., 0]
    np.testing.assert_allclose(s[7:].reshape(-1, 16), direct, rtol=1e-12, atol=1e-12)


def test_swt_on_needs_persistence():
    f = np.zeros((40, 4, 4))
    f[10:, 2, 1] = 1.0                       # a step: |cD3| > 0 for 8 samples (k = 10..17)
    on = swt_on(f, threshold=0.1, persist=8)
    assert not on.any()                      # the change lasts only 8 samples: not slip
    f[10:, 2, 1] = 0.2 * np.arange(30)       # a ramp: the change persists
    on = swt_on(f, threshold=0.1, persist=8)
    first = int(np.argmax(on))
    over = np.abs(swt_statistic(f)[:, 2, 1]) > 0.1
    assert first == int(np.argmax(over)) + 8
    assert on[first:].all()


def test_nmsd_statistic_and_detection_on_a_force_drop():
    f = np.full((20, 4, 4), 0.5)
    f[10:, 3, 0] = 0.2                       # sudden 0.3 N drop on one taxel
    s = nmsd_statistic(f, fs=260.0)
    assert s[10, 3, 0] == pytest.approx(-0.3 * 260.0)
    assert s[11, 3, 0] == pytest.approx(0.3 * 260.0)
    det = nmsd_detections(f, fs=260.0, threshold=10.0)
    # rising edges only: the drop (k=10) is over threshold at 10 and 11 -> one detection
    assert np.flatnonzero(det).tolist() == [10]


def test_each_detection_adds_45_ms_of_closing():
    p = ClosingParams(fs=NMSD_FS, speed=520.0, p0=100.0)
    n = p.samples_per_close
    assert n == round(0.045 * NMSD_FS)
    trig = np.zeros(100, dtype=bool)
    trig[[5, 8]] = True                      # second detection while still closing
    out = closing_commands(trig, p)
    assert np.isfinite(out).sum() == 2 * n
    assert out[5] == pytest.approx(100.0 + 520.0 / NMSD_FS)
    assert np.nanmax(out) == pytest.approx(100.0 + 2 * n * 520.0 / NMSD_FS)
    # hold mode: continuous ON closes for whole quanta only while ON
    on = np.zeros(100, dtype=bool)
    on[10:10 + n + 1] = True                 # ON one sample longer than a quantum
    out = closing_commands(on, p, mode="hold")
    assert np.isfinite(out).sum() == 2 * n


def test_closing_saturates_and_starts_from_the_hand():
    p = ClosingParams(fs=100.0, speed=1000.0, close_s=0.5, p0=0.0, hi=480.0)
    trig = np.zeros(60, dtype=bool)
    trig[0] = True
    pos = np.full(60, np.nan)
    pos[0] = 300.0
    out = closing_commands(trig, p, positions=pos)
    assert out[0] == 310.0
    assert np.nanmax(out) == 480.0
    assert np.isfinite(out).sum() == 18      # 310 .. 480, then no change at the limit


def test_rest_threshold_rejects_almost_all_rest_noise():
    rest = 0.3 + np.random.default_rng(9).normal(0.0, 0.005, size=(6000, 4, 4))
    thr = rest_threshold(rest[:2000], "nmsd", NMSD_FS)
    assert nmsd_detections(rest[2000:], NMSD_FS, threshold=thr).sum() <= 1
    thr = rest_threshold(rest[:2000], "swt", SWT_FS)
    assert not swt_on(rest[2000:], threshold=thr).any()
    with pytest.raises(DataError):
        rest_threshold(np.zeros((100, 4, 4)), "nmsd")
    with pytest.raises(ParameterError):
        rest_threshold(rest, "fixed")


def test_interface_and_validation():
    for r in (NMSD(threshold=1.0, speed=500.0), SWTSD(threshold=1.0, speed=500.0)):
        assert isinstance(r, Reflex)
        assert r.input_kind == "tactile"
        with pytest.raises(DataError):
            r.step(np.zeros(16))
        with pytest.raises(DataError):
            r.step(np.full((4, 4), np.nan))
    with pytest.raises(ParameterError, match="bogus"):
        NMSD(threshold=1.0, speed=500.0, bogus=3)
    with pytest.raises(ParameterError, match="threshold"):
        SWTParams(threshold=0.0, speed=1.0)
    with pytest.raises(ParameterError, match="persist"):
        SWTParams(threshold=1.0, speed=1.0, persist=-1)
    for bad in (np.zeros(5), np.zeros((5, 3, 4, 2))):    # any (K, rows, cols) or (K, channels), nothing else
        with pytest.raises(DataError):
            nmsd_statistic(bad)
    assert NMSD(NMSDParams(threshold=1.0, speed=2.0), threshold=3.0).params.threshold == 3.0
