"""Every rule of docs/method.md section 1, with examples worked by hand and written out."""

import numpy as np
from scipy.signal import butter, sosfilt, sosfilt_zi

import slipreflex as sr

U = 1.0 / 1024.0  # exact binary unit, so hand-worked sums carry no rounding


# --- 1.1 low-pass ----------------------------------------------------------------

def test_lowpass_is_scipy_butterworth_started_at_steady_state():
    raw = np.random.default_rng(1).normal(0.4, 0.05, 2000)
    sos = butter(2, 10.0, fs=333.0, output="sos")
    expected = sosfilt(sos, raw, zi=sosfilt_zi(sos) * raw[0])[0]
    np.testing.assert_allclose(sr.lowpass(raw, fs=333.0, cutoff=10.0), expected, rtol=0, atol=1e-15)


def test_constant_input_gives_constant_output_from_first_sample():
    y = sr.lowpass(np.full(500, 3.33))
    np.testing.assert_allclose(y, 3.33, rtol=0, atol=1e-12)


def test_lowpass_attenuates_above_cutoff():
    fs = 333.0
    k = np.arange(3000)
    slow = sr.lowpass(np.sin(2 * np.pi * 2.0 * k / fs), fs=fs)[1000:]
    fast = sr.lowpass(np.sin(2 * np.pi * 60.0 * k / fs), fs=fs)[1000:]
    assert np.ptp(slow) > 1.9 and np.ptp(fast) < 0.1


def test_filter_can_be_switched_off():
    raw = np.array([0.1, 0.5, 0.2, 0.9])
    res = sr.run_chain(raw, filter=False)
    np.testing.assert_array_equal(res.filtered, raw)


# --- 1.2 encoder ---------------------------------------------------------------

def test_fixed_threshold_strictly_greater():
    # steps of exactly theta: |acc| == theta never fires, the next step does.
    x = np.array([0, 8, 16, 24]) * U
    assert sr.encode(x, threshold=8 * U, x0=0.0).tolist() == [False, False, True, False]


def test_accumulator_resets_after_spike_and_sums_both_signs():
    x = np.array([0, 5, 10, 6, 2, -3]) * U
    # acc: 0, 5, 10>8 spike->0, -4, -8 (not >8), -13 -> spike
    assert sr.encode(x, threshold=8 * U).tolist() == [False, False, True, False, False, True]


def test_paper_literal_x0_zero_startup_spike():
    x = np.full(20, 0.4)
    assert sr.encode(x, x0=0.0).tolist() == [True] + [False] * 19
    assert not sr.encode(x).any()  # default reference: the first sample, no start-up spike


def test_dath_activation_lowers_threshold_for_16_samples_then_expires():
    # Worked by hand (units of U, theta0 = 8):
    # idx1: acc 9 > 8 spike, d = 4 -> DATH theta = 4 for idx 2..17 (16 samples).
    # idx2..17: d = 5, acc 5 > 4 -> spike each (spikes while active do not re-arm).
    # idx18: threshold back to 8: acc 5 -> no spike. idx19: acc 10 > 8 spike, DATH theta = 5.
    # idx20: acc 5, not > 5 -> no spike (strict). idx21: acc 10 > 5 -> spike.
    steps = [5, 4] + [5] * 20
    x = np.cumsum(steps) * U
    tr = sr.encode_trace(x, threshold=8 * U, dath=True, dath_samples=16, x0=0.0)
    expected = [False, True] + [True] * 16 + [False, True, False, True]
    assert tr.events.tolist() == expected
    assert (tr.threshold / U).tolist() == [8, 8] + [4] * 16 + [8, 8, 5, 5]
    # The same signal with a fixed threshold fires only every second sample.
    fixed = sr.encode(x, threshold=8 * U, x0=0.0)
    assert fixed.sum() < tr.events.sum()


def test_dath_can_raise_threshold_above_theta0():
    # idx1: d = 10 > 8 spike -> theta = 10 for idx 2..17; idx2: d = 9.5 (acc 9.5) no spike
    # though it would beat theta0; idx18 (threshold back to 8): acc 9.5 > 8 spike.
    x = np.r_[0.0, 10.0, np.full(17, 19.5)] * U
    ev = sr.encode(x, threshold=8 * U, dath=True, x0=0.0)
    assert np.flatnonzero(ev).tolist() == [1, 18]
    assert np.flatnonzero(sr.encode(x, threshold=8 * U, x0=0.0)).tolist() == [1, 2]


def test_dath_floor_bounds_the_adaptive_threshold():
    x = np.r_[0.0, 9.0, 9.5, 10.0] * U  # spike at idx1 with d = 9
    tr = sr.encode_trace(x, threshold=8 * U, dath=True, dath_floor=12 * U, x0=0.0)
    assert (tr.threshold[2:] / U).tolist() == [12, 12]


def test_dath_duration_is_a_parameter():
    steps = [5, 4] + [5] * 10
    x = np.cumsum(steps) * U
    tr = sr.encode_trace(x, threshold=8 * U, dath=True, dath_samples=3, x0=0.0)
    assert (tr.threshold / U).tolist()[:7] == [8, 8, 4, 4, 4, 8, 8]


# --- 1.3 windows ---------------------------------------------------------------

def test_windows_aligned_to_first_sample_and_tail_dropped():
    y = np.zeros(40, dtype=bool)
    y[[0, 15, 16, 31, 32, 39]] = True
    assert sr.count_windows(y).tolist() == [2, 2]
    assert sr.count_windows(y, n=1).tolist() == y.astype(int).tolist()


def test_stream_emits_count_on_the_completing_sample():
    reflex = sr.SlipReflex()
    outs = [reflex.step(0.4) for _ in range(48)]
    assert [i for i, u in enumerate(outs) if u is not None] == [15, 31, 47]


# --- 1.4 MPI -------------------------------------------------------------------

def test_mpi_worked_example_with_reset_after_ten_zero_windows():
    # z1: h=2, PI = 0 + 10 + 10 = 20.  z2..z11 zero: PI = 10 < 20, m stays 20 (monotonic).
    # After the 10th zero window: P0 = 20, h = 0.  z12: v=1, PI = 20 + 5 + 5 = 30.
    v = [2] + [0] * 10 + [1]
    assert sr.mpi(v).tolist() == [20.0] * 11 + [30.0]
    # Without the reset the last command would have been max(0 + 5 + 15, 20) = 20.
    assert sr.mpi(v, reset_after=11).tolist()[-1] == 20.0


def test_mpi_reset_uses_measured_position_when_given():
    c = sr.MPIController()
    c.step(2)
    for _ in range(9):
        c.step(0, position=999.0)  # not a reset yet: ignored
    assert c.step(0, position=123.0) == 20.0  # 10th zero window: reset to 123
    assert c.p_base == 123.0 and c.integral == 0.0
    assert c.step(1) == 133.0


def test_mpi_never_decreases_even_if_measured_position_is_lower():
    c = sr.MPIController(p0=200.0)
    for _ in range(10):
        c.step(0, position=50.0)
    assert c.p_base == 50.0
    assert c.step(1) == 200.0  # PI = 50 + 5 + 5 = 60 < 200: command held


def test_mpi_saturates_at_500_and_clips_p0():
    assert sr.mpi([60, 1]).tolist() == [500.0, 500.0]
    assert sr.mpi([0], p0=800.0).tolist() == [500.0]
    assert sr.mpi([0], p0=-5.0).tolist() == [0.0]
    assert sr.mpi([1], lo=0.0, hi=7.0).tolist() == [7.0]


def test_mpi_matches_paper_gains():
    # Kp = Ki = 5: a single window with v = 4 from P0 = 100 -> 100 + 20 + 20.
    assert sr.mpi([4], p0=100.0).tolist() == [140.0]


# --- the composed chain ---------------------------------------------------------

def test_composed_chain_catches_a_slip_and_holds():
    rng = np.random.default_rng(3)
    rest = np.full(160, 0.40)
    slip = 0.40 + np.cumsum(rng.normal(0, 0.01, 160))
    raw = np.r_[rest, slip, np.full(320, slip[-1])]
    res = sr.run_chain(raw, dath=True)
    assert res.counts[:10].sum() == 0 and res.counts[10:20].sum() > 0
    assert np.all(np.diff(res.commands) >= 0)
    assert res.commands[-1] > 0
