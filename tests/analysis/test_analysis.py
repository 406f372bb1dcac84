"""Onset detection, events and every metric on synthetic / hand-built traces."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipreflex.analysis.events import segment_events
from slipreflex.analysis.metrics import controller_activity, increases, response_time, suppressed
from slipreflex.analysis.onset import OnsetParams, accel_envelope, detect_onset, select_axis
from slipreflex.analysis.paper import PAPER, paper_value
from slipreflex.analysis.report import (
    SUMMARY_COLUMNS,
    comparison_markdown,
    read_csv,
    summarize,
    terminal_table,
    write_csv,
)
from slipreflex.analysis.trial import RESULT_COLUMNS, TrialStreams, analyse_trial
from slipreflex.core.errors import DataError, ParameterError

FS = 333.0


def _accel(seconds=3.0, seed=0, noise=0.003):
    t = np.arange(int(seconds * FS)) / FS
    a = np.random.default_rng(seed).normal(0.0, noise, (t.size, 3))
    a[:, 2] += 1.0  # gravity on z
    return t, a


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("onset", [1.0, 1.37, 2.2])
def test_onset_of_a_step_burst_is_found_within_a_few_samples(seed, onset):
    t, a = _accel(seed=seed)
    m = t >= onset
    # slip: a sudden, decaying oscillation on the y axis (like the paper's Fig. 10 A)
    tau = t[m] - onset
    a[m, 1] += 0.3 * np.exp(-tau / 0.1) * np.sin(2 * np.pi * 25 * tau + np.pi / 2)
    r = detect_onset(t, a, window=(onset - 0.2, onset + 0.6))   # the induction interval
    assert r.axis == 1
    assert r.found
    assert 0.0 <= r.time - onset < 0.012         # causal 30 Hz filter: a few samples late


def test_onset_respects_the_window_and_the_rest_threshold():
    t, a = _accel(seed=3)
    a[(t > 0.6) & (t < 0.65), 0] += 0.5          # a knock before the induction interval
    a[t >= 2.0, 0] += 0.05
    r = detect_onset(t, a, window=(1.0, 2.9))
    assert 2.0 <= r.time < 2.02                  # the knock at 0.6 s is not a candidate
    r = detect_onset(t, a, window=(1.0, 1.9))
    assert not r.found and math.isnan(r.time) and r.index == -1
    # the threshold comes from the first 200 ms: mean + k sd of the envelope there
    base = r.envelope[t < 0.2]
    assert r.threshold == pytest.approx(base.mean() + 5.0 * base.std())


def test_onset_filter_is_30_hz_butterworth_and_rectifies():
    t = np.arange(2000) / FS
    x = 0.1 * np.sin(2 * np.pi * 5 * t)          # slow: passes the 30 Hz low-pass after rectifying
    env = accel_envelope(t, x, OnsetParams(baseline_s=0.2))
    assert env[500:].mean() == pytest.approx(0.1 * 2 / np.pi, rel=0.05)
    t = np.arange(4000) / 1000.0
    hf = 0.1 * np.sin(2 * np.pi * 150 * t) + 0.1 # fast ripple around a constant
    env = accel_envelope(t, hf, OnsetParams(baseline_s=0.2))
    # mean removed, rectified (DC of |sin| = 2/pi), its 300 Hz ripple filtered out
    assert env[500:].mean() == pytest.approx(0.1 * 2 / np.pi, rel=0.05)
    assert env[500:].std() < 0.002


def test_noise_episodes_below_three_thresholds_are_not_onsets():
    t, a = _accel(seed=4)
    r0 = detect_onset(t, a, window=(1.0, 2.9))
    a[(t >= 1.2) & (t < 1.21), 1] += 2.0 * r0.threshold   # a small knock: above threshold, under 3x
    a[t >= 2.0, 1] += 0.1                                 # the slip
    r = detect_onset(t, a, window=(1.0, 2.9))
    assert 2.0 <= r.time < 2.02
    literal = detect_onset(t, a, window=(1.0, 2.9), params=OnsetParams(peak_factor=0.0))
    assert 1.2 <= literal.time < 1.23                     # the paper's literal first candidate


def test_select_axis_and_bad_input():
    t, a = _accel()
    a[t > 1.5, 0] -= 0.2
    assert select_axis(t, a, (1.0, 2.0)) == 0
    with pytest.raises(DataError):
        detect_onset(t[:-1], a, (1.0, 2.0))
    with pytest.raises(ParameterError):
        detect_onset(t, a, (2.0, 1.0))


def test_increases_response_and_total_on_hand_built_commands():
    # MPI-like: a command every 48 ms, three increases, then flat, then a late false change
    cmd_t = np.array([1.000, 1.048, 1.096, 1.144, 1.192, 1.240, 2.400])
    cmd_v = np.array([200.0, 200.0, 215.0, 240.0, 240.0, 250.0, 255.0])
    assert increases(cmd_t, cmd_v, base=200.0).tolist() == [2, 3, 5, 6]
    assert response_time(1.02, cmd_t, cmd_v, window=(0.9, 3.0), base=200.0) == pytest.approx(0.076)
    act = controller_activity(cmd_t, cmd_v, window=(0.9, 3.0), base=200.0)
    assert act.first == 1.096 and act.last == 1.240 and act.n_increases == 3
    assert act.span == pytest.approx(0.144)
    assert act.rise == 50.0                      # the change at 2.4 s is a separate slip (gap > 0.5 s)
    # a response before the accelerometer onset is kept, with its sign
    assert response_time(1.2, cmd_t, cmd_v, window=(0.9, 3.0), base=200.0) == pytest.approx(-0.104)
    # no increase in the window -> NaN
    assert math.isnan(response_time(1.0, cmd_t, cmd_v, window=(3.0, 4.0), base=200.0))
    assert controller_activity(cmd_t, cmd_v, window=(3.0, 4.0)).n_increases == 0


def test_nmsd_total_is_closing_time():
    fs = 260.0
    n = 24                                       # two 45 ms quanta of 12 samples
    cmd_t = 1.0 + np.arange(n) / fs
    act = controller_activity(cmd_t, 300 + np.arange(1, n + 1), window=(0.5, 2.0), base=300.0)
    assert act.closing_time(fs) == pytest.approx(24 / 260.0)   # 2 x round(45 ms x 260 Hz) samples


def test_success_is_not_fallen_out_before_window_end():
    assert suppressed(float("nan"), 3.0) and suppressed(None, 3.0)
    assert not suppressed(2.9, 3.0)
    assert suppressed(3.5, 3.0)


def test_segment_pour_into_slip_events():
    t = np.arange(0.0, 30.0, 1 / FS)
    env = np.zeros_like(t)
    for t0, dur in ((12.0, 0.4), (12.6, 0.1), (24.0, 0.5)):   # 12.0 and 12.6 are one slip
        env[(t >= t0) & (t < t0 + dur)] = 1.0
    ev = segment_events(t, env, 0.3, (1.0, 29.0))
    assert segment_events(t, 0.5 * env, 0.3, (1.0, 29.0)) == []   # peaks under 3 x threshold: noise
    assert len(ev) == 2
    assert ev[0].onset == pytest.approx(12.0, abs=1 / FS)
    assert ev[0].end == pytest.approx(12.7, abs=2 / FS)
    assert ev[0].window[1] == pytest.approx(ev[1].onset - 0.1)
    assert ev[1].window[0] == pytest.approx(ev[1].onset - 0.1)


def _streams(**kw):
    t, a = _accel(seconds=4.0, seed=7)
    a[t >= 2.0, 1] += 0.1
    base = dict(experiment="drop", method="dath", bottle="TX", seed=11, trial=2, accel_t=t,
                accel=a, cmd_t=[2.05, 2.10, 2.20], cmd_v=[205.0, 215.0, 225.0], base_command=200.0,
                induction=(1.5, 3.0), t_end=4.0, fell_out_time=float("nan"), true_onsets=[1.995],
                method_fs=FS, threshold=0.008)
    base.update(kw)
    return TrialStreams(**base)


def test_analyse_trial_drop_row():
    rows = analyse_trial(_streams())
    assert len(rows) == 1
    r = rows[0]
    assert set(r) == set(RESULT_COLUMNS)
    assert 2.0 <= r["onset_s"] < 2.01
    assert r["response_ms"] == pytest.approx((2.05 - r["onset_s"]) * 1e3)
    assert r["total_ms"] == pytest.approx(150.0)
    assert r["onset_error_ms"] == pytest.approx((r["onset_s"] - 1.995) * 1e3)
    assert r["success"] and not r["fell_out"]
    rows = analyse_trial(_streams(fell_out_time=3.2, method="nmsd", method_fs=260.0))
    assert not rows[0]["success"] and rows[0]["fell_out"]
    assert rows[0]["total_ms"] == pytest.approx(3 / 260.0 * 1e3)


def test_a_late_command_is_not_a_response():
    rows = analyse_trial(_streams(cmd_t=[3.5, 3.6], cmd_v=[210.0, 220.0]))   # 1.5 s after the onset
    assert math.isnan(rows[0]["response_ms"]) and math.isnan(rows[0]["total_ms"])
    assert rows[0]["success"]


def test_analyse_trial_without_slip_gives_one_row():
    t, a = _accel(seconds=4.0, seed=8)
    rows = analyse_trial(_streams(accel_t=t, accel=a, experiment="pour", cmd_t=[], cmd_v=[]))
    assert len(rows) == 1 and rows[0]["n_events"] == 0 and math.isnan(rows[0]["response_ms"])


def test_summary_csv_and_tables(tmp_path):
    rows = []
    for m in ("dath", "nmsd"):
        for i in range(4):
            rows += analyse_trial(_streams(method=m, trial=i, seed=i,
                                           fell_out_time=3.5 if i == 0 else float("nan")))
    p = write_csv(tmp_path / "results.csv", rows)
    back = read_csv(p)
    assert list(back[0]) == list(RESULT_COLUMNS) and len(back) == 8
    back[0]["response_ms"] = ""                  # how write_csv stores a NaN
    summary = summarize(back)                    # works on the strings read back, too
    assert [s["method"] for s in summary] == ["dath", "nmsd"]
    s = summary[0]
    assert s["n_trials"] == 4 and s["event_success_rate"] == 0.75 and s["response_n"] == 3
    assert s["trial_success_rate"] == 0.75 and s["trial_success_n"] == 4
    assert s["total_mean_ms"] == pytest.approx(150.0)
    write_csv(tmp_path / "summary.csv", summary, SUMMARY_COLUMNS)
    assert read_csv(tmp_path / "summary.csv")[0]["paper_response_ms"] == "31.3 ± 4.16"
    md = comparison_markdown(summary)
    assert "| drop, response ms | TX | 31.3 ± 4.16 |" in md
    assert "75% of 4 slip events" in md and "no comparable run" in md
    assert "DATH" in terminal_table(summary)


def test_paper_table_is_complete():
    assert len(PAPER) == 32
    assert paper_value("pour", "response_ms", "DK", "swt").mean == 73.0
    assert paper_value("drop", "total_ms", "TX", "dath").note == "also 274.4"


def test_a_detected_onset_belongs_to_the_slip_under_way_not_to_the_nearest_in_time():
    """A creeping pour slip detected 1.3 s late is matched to its own start, never to the next slip."""
    from slipreflex.analysis.trial import EARLY_DETECTION_S, true_onset_for

    truth = np.array([2.0, 14.689, 16.117, 28.568])
    assert true_onset_for(truth, 15.963, 3.0, 30.5) == 14.689          # nearest-in-time would say 16.117
    assert true_onset_for(truth, 16.2, 3.0, 30.5) == 16.117
    assert true_onset_for(truth, 28.568 - EARLY_DETECTION_S / 2, 3.0, 34.0) == 28.568   # fired a bit early
    assert np.isnan(true_onset_for(truth, 2.5, 3.0, 34.0))              # before the induction: no slip of it
    assert np.isnan(true_onset_for(np.array([]), 5.0, 3.0, 34.0))
    assert true_onset_for(truth, float("nan"), 3.0, 34.0) == 14.689
