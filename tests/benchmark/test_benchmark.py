"""slipreflex benchmark: the recorded-trial format, its errors, scoring, a hand-worked trial, the CLI."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from slipreflex.benchmark import (
    BenchmarkConfig,
    read_folder,
    read_trial,
    run_benchmark,
    run_trial,
    score,
    shipped_dataset,
)
from slipreflex.benchmark.run import applicable, reduce_channels, to_rate
from slipreflex.benchmark.trials import Layout
from slipreflex.cli import main
from slipreflex.core.errors import DataError, ParameterError

REST_K = ("--protocol", "rest-k")     # the earlier per-trial rule


def _write(path, header, rows, preamble=()):
    lines = [f"# {k}: {v}" for k, v in preamble] + [",".join(header)]
    lines += [",".join(str(c) for c in r) for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def _trial_rows(k=100, onset=70, fs=50.0):
    rng = np.random.default_rng(3)
    t = np.arange(k) / fs
    z = rng.normal(0.0, 1.0, (k, 4))
    z[onset:] += np.linspace(0, 40, k - onset)[:, None]
    return [[f"{t[i]:.3f}", *(f"{v:.4f}" for v in z[i]), int(i >= onset)] for i in range(k)]


# --- the format's errors: one line each, exit 2, nothing written ----------------------------------------


@pytest.mark.parametrize("header, rows, preamble, needle", [
    (["time", "a", "slip"], [[0, 1, 0]] * 10, (), "no 't' column"),
    (["t", "a", "label"], [[i, 1, 0] for i in range(10)], (), "no 'slip' column"),
    (["t", "a", "slip"], [[i if i != 5 else 3, 1, 0] for i in range(10)], (), "line 7: time does not increase"),
    (["t", "a", "b", "c", "slip"], [[i, 1, 2, 3, 0] for i in range(10)], (("layout", "2x2"),),
     "layout 2x2 needs 4 channel columns, the file has 3"),
    (["t", "a", "b", "slip"], [[i, 1, 2, 0] for i in range(10)], (("layout", "4 by 4"),), "is not RxC"),
    (["t", "a", "b", "slip"], [[i, 1, 2, 0] for i in range(10)],
     (("layout", "1x1x2"), ("components", "x,y"), ("normal", "z")), "normal component 'z'"),
    (["t", "a", "slip"], [[i, 1, 2 if i == 4 else 0] for i in range(10)], (), "line 6: slip must be 0 or 1"),
    (["t", "a", "slip"], [[i, "n/a" if i == 2 else 1, 0] for i in range(10)], (), "column 'a' is not a number"),
    (["t", "a", "slip"], [[i, 1, 0] for i in range(3)], (), "3 samples"),
])
def test_format_errors_are_one_line_exit_2_before_any_output(tmp_path, capsys, header, rows, preamble, needle):
    folder = tmp_path / "set"
    folder.mkdir()
    _write(folder / "good.csv", ["t", "a", "b", "c", "d", "slip"], _trial_rows(), (("layout", "2x2"),))
    _write(folder / "zbad.csv", header, rows, preamble)
    out = tmp_path / "out"
    assert main(["benchmark", str(folder), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert needle in err and "zbad.csv" in err
    assert not out.exists() or not any(out.iterdir())


def test_layout_parse_reads_components_and_normal():
    lay = Layout.parse("3x4x3", components="x, y, z", normal="y", channels=36, where="f")
    assert lay.shape == (1, 3, 4, 3) and lay.normal == 1 and lay.components == ("x", "y", "z")
    with pytest.raises(DataError, match="components 'x,y' name 2 components, layout 4x4x3 has 3"):
        Layout.parse("4x4x3", components="x,y", normal=None, channels=48, where="f")


def test_calibration_span_past_the_onset_is_an_error(tmp_path, capsys):
    folder = tmp_path / "set"
    folder.mkdir()
    _write(folder / "early.csv", ["t", "a", "b", "c", "d", "slip"], _trial_rows(onset=25), (("layout", "2x2"),))
    assert main(["benchmark", str(folder), *REST_K, "--out", str(tmp_path / "o")]) == 2
    assert "reaches past the labelled slip onset at 0.5 s" in capsys.readouterr().err


@pytest.mark.slow
def test_data_too_slow_for_the_chains_low_pass_is_an_error_before_work(tmp_path, capsys):
    folder = tmp_path / "slow"
    folder.mkdir()
    _write(folder / "slow.csv", ["t", "x", "slip"], [[r[0], r[1], r[-1]] for r in _trial_rows(fs=20.0, onset=30)])
    out = tmp_path / "o"
    assert main(["benchmark", str(folder), *REST_K, "--methods", "dath", "--out", str(out)]) == 2
    assert "dath cannot run at the data's 20 Hz (cutoff must be below fs/2" in capsys.readouterr().err
    assert not out.exists() or not any(out.iterdir())
    assert main(["benchmark", str(folder), *REST_K, "--methods", "dath", "--rates", "method", "--out", str(out)]) == 0


def test_a_method_that_does_not_apply_is_an_error_when_asked_for(tmp_path, capsys):
    folder = tmp_path / "set"
    folder.mkdir()
    _write(folder / "one.csv", ["t", "a", "slip"], [[r[0], r[1], r[-1]] for r in _trial_rows()])
    assert main(["benchmark", str(folder), "--methods", "nmsd", "--out", str(tmp_path / "o")]) == 2
    assert "nmsd does not apply to this data: it needs a tactile array" in capsys.readouterr().err


# --- scoring --------------------------------------------------------------------------------------------


def test_score_by_hand():
    t = np.arange(12) * 0.5                       # 0.0 .. 5.5 s
    slip = np.array([0, 0, 0, 0, 0, 0, 1, 1, 1, 0, 1, 0])
    det = np.zeros(12, bool)
    det[[0, 2, 5, 9, 10]] = True                  # 0: calibration; 2, 5: false alarms; 9, 10: after the first run
    s = score(t, slip, det, calibration_end=1.0)
    assert (s.onset_t, s.slip_end_t) == (3.0, 4.0)
    assert math.isnan(s.detection_t) and math.isnan(s.latency_ms) and not s.detected
    assert (s.false_alarms, s.scored_s, s.false_alarm_rate_per_min, s.detections) == (2, 2.0, 60.0, 5)
    det[7] = True
    s = score(t, slip, det, calibration_end=1.0)
    assert s.detection_t == 3.5 and s.latency_ms == 500.0 and s.detected


def test_score_of_a_control_counts_every_detection_after_the_calibration_span():
    s = score(np.arange(7.0), np.zeros(7), np.array([1, 0, 1, 0, 1, 1, 0], bool), calibration_end=2.0)
    assert not s.slips and math.isnan(s.onset_t)
    assert (s.false_alarms, s.scored_s, s.false_alarm_rate_per_min) == (3, 4.0, 45.0)


# --- one trial scored by hand, end to end ----------------------------------------------------------------


def _hand_trial(path):
    """10 Hz, 60 samples, layout 1x2 (taxels a, b), labelled slip at samples 40..49.

    Calibration span: the first 2.0 s (samples 0..19). There a alternates 0, 1, 0, 1 (NMSD's
    statistic (f_k - 2 f_(k-1) + f_(k-2)) * fs is +-20 N/s from sample 2 on) and b is 0, so
    the 36 pooled values are 18 of +-20 (mean 0) and 18 zeros: sd = sqrt(18 * 400 / 36) =
    sqrt(200), threshold = 5 sqrt(200) = 70.71 N/s. After it a stays at 1 (|s_20| = 10).
    b: a one-sample bump of 10 at sample 25 (|s| = 100, 200, 100 at 25, 26, 27: one
    rising edge at 25, a false alarm), a step to 8 at sample 43 (s = 80, -80, 0: a detection
    at 43, 4.3 s, 300 ms after the onset at 4.0 s), a one-sample bump to 18 at 55 (after the
    labelled slip: neither a detection of it nor a false alarm).
    """
    k = np.arange(60)
    a = np.where(k < 20, k % 2, 1).astype(float)
    b = np.zeros(60)
    b[25] = 10.0
    b[43:] = 8.0
    b[55] = 18.0
    slip = ((k >= 40) & (k < 50)).astype(int)
    rows = [[f"{i / 10:.1f}", a[i], b[i], slip[i]] for i in k]
    return _write(path, ["t", "a", "b", "slip"], rows, (("layout", "1x2"), ("unit", "N")))


def test_one_trial_scored_by_hand(tmp_path):
    trial = read_trial(_hand_trial(tmp_path / "hand.csv"))
    assert trial.fs == pytest.approx(10.0) and trial.onset_t == 4.0
    (run,) = run_trial(trial, BenchmarkConfig(methods=("nmsd",), rates=("data",), calibration_s=2.0))
    assert run.threshold == pytest.approx(5 * math.sqrt(200.0))
    assert np.flatnonzero(run.detections).tolist() == [25, 43, 55]
    s = run.score
    assert s.detection_t == pytest.approx(4.3) and s.latency_ms == pytest.approx(300.0)
    assert s.false_alarms == 1 and s.scored_s == pytest.approx(2.0)
    assert s.false_alarm_rate_per_min == pytest.approx(30.0)
    assert s.detections == 3


@pytest.mark.slow
def test_the_hand_trial_through_the_command(tmp_path, capsys):
    folder = tmp_path / "mine"
    folder.mkdir()
    _hand_trial(folder / "hand.csv")
    out = tmp_path / "out"
    assert main(["benchmark", str(folder), *REST_K, "--methods", "nmsd", "--rates", "data", "--calibration-s", "2",
                 "--out", str(out)]) == 0
    with open(out / "benchmark.csv", newline="") as fh:
        (row,) = list(csv.DictReader(fh))
    assert (row["trial"], row["method"], row["slips"], row["onset_t"], row["detection_t"], row["latency_ms"],
            row["false_alarms"], row["false_alarm_rate_per_min"]) == ("hand", "nmsd", "1", "4.0", "4.3", "300.0",
                                                                      "1", "30.0")
    assert (out / "hand.png").stat().st_size > 10_000 and (out / "summary.csv").is_file()
    assert "NMSD" in capsys.readouterr().out


# --- a user's folder and the shipped set -----------------------------------------------------------------


def test_a_users_folder_without_layout_runs_the_chain_methods_only(tmp_path, capsys):
    folder = tmp_path / "optical"
    folder.mkdir()
    for name, onset in (("a", 70), ("b", 80)):
        rows = _trial_rows(onset=onset)
        _write(folder / f"{name}.csv", ["t", "x", "slip"], [[r[0], r[1], r[-1]] for r in rows])
    out = tmp_path / "out"
    assert main(["benchmark", str(folder), *REST_K, "--methods", "fixed,DATH", "--no-figures", "--out", str(out)]) == 0
    with open(out / "benchmark.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 2 * 2 * 2                                   # trials x methods x rates
    assert {r["rate"] for r in rows} == {"data", "method"}
    assert not list(out.glob("*.png"))


def test_channels_without_layout_are_each_their_own():
    trial = read_folder(shipped_dataset())[0]
    bare = type(trial)(trial.name, trial.path, trial.t, trial.channels[:, :3], trial.channel_names[:3],
                       trial.slip, None)
    assert [n for n, _ in reduce_channels(bare, "z-sum")] == list(trial.channel_names[:3])
    assert applicable("nmsd", bare).startswith("needs a tactile array")
    z = reduce_channels(trial, "z-sum")[0][1]
    assert z[0] == 0 and z[5] == pytest.approx(trial.normal_frames()[5].sum() - trial.normal_frames()[0].sum())


def test_the_shipped_set_reads_as_described():
    trials = read_folder(shipped_dataset())
    assert len(trials) == 7 and [tr.slips for tr in trials].count(True) == 3
    for tr in trials:
        assert tr.layout.shape == (2, 4, 4, 3) and tr.layout.components == ("x", "y", "z")
        assert 59 < tr.fs < 61 and tr.normal_frames().shape == (len(tr.t), 8, 4)
        assert tr.onset_t is None or tr.onset_t > 1.0               # the default calibration span fits
    assert (shipped_dataset() / "LICENSE").read_text().startswith("MIT License")


def test_shipped_set_every_applicable_method_and_its_rates(tmp_path):
    trials = read_folder(shipped_dataset())
    runs, skipped = run_benchmark(trials, BenchmarkConfig(methods=("fixed", "nmsd", "swt")))
    assert not skipped and len(runs) == 7 * 3 * 2
    fs = {(r.method, r.rate): round(r.fs) for r in runs if r.trial == trials[0].name}
    assert fs == {("fixed", "data"): 60, ("fixed", "method"): 333, ("nmsd", "data"): 60, ("nmsd", "method"): 260,
                  ("swt", "data"): 60, ("swt", "method"): 380}
    swt = next(r for r in runs if r.method == "swt" and r.rate == "data")
    assert swt.params["persist"] == 0                               # the default reading: no persistence, at any rate
    for r in runs:                                                   # every threshold from the span before any onset
        assert r.threshold > 0 and r.score.slips == trials[[t.name for t in trials].index(r.trial)].slips


def test_board_methods_do_not_apply_and_are_listed(tmp_path, capsys):
    folder = tmp_path / "one"
    folder.mkdir()
    _write(folder / "x.csv", ["t", "x", "slip"], [[r[0], r[1], r[-1]] for r in _trial_rows()])
    out = tmp_path / "o"
    assert main(["benchmark", str(folder), *REST_K, "--rates", "data", "--no-figures", "--out", str(out)]) == 0
    out = capsys.readouterr().out
    assert "not run: dath-board" in out and "not run: nmsd: needs a tactile array" in out


def test_to_rate_keeps_a_band_limited_signal_and_the_clock():
    t = np.arange(120) / 59.8 + 0.002 * np.sin(np.arange(120))          # jittered time stamps
    x = np.sin(2 * np.pi * 3.0 * np.arange(120) / 59.8)
    t2, x2, fs2 = to_rate(t, x, 260.0)
    assert abs(fs2 - 260.0) < 1.0 and t2[0] == t[0] and t2[-1] <= t[-1]
    inner = slice(20, -20)
    truth = np.sin(2 * np.pi * 3.0 * np.arange(len(x2))[inner] / fs2)
    assert np.max(np.abs(x2[inner] - truth)) < 0.02


def test_config_rejects_unknown_names():
    with pytest.raises(ParameterError, match="reduction: unknown 'sum'"):
        BenchmarkConfig(reduction="sum")
    with pytest.raises(ParameterError, match="method: unknown"):
        BenchmarkConfig(methods=("nope",))


@pytest.mark.slow
def test_vs_sim_measures_every_source():
    from slipreflex.benchmark.vs_sim import MEASURES, compare

    c = compare(read_folder(shipped_dataset()), seed=2)
    assert c.sources == ("real, controls", "real, slip trials", "simulated pour", "simulated drop")
    for s in c.sources:
        for k, _ in MEASURES:
            if not (s == "real, controls" and k.startswith("slip")):
                assert math.isfinite(c.rows[s][k]), (s, k)
    assert c.rows["simulated pour"]["repeated_frames"] == 0.0


def test_benchmark_table_script_markers_and_compact_table():
    import runpy
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    script = runpy.run_path(str(root / "scripts" / "docs" / "benchmark_table.py"))
    for key, (begin, end) in script["MARKS"].items():
        text = (root / ("README.md" if key == "readme" else "docs/benchmark.md")).read_text()
        assert text.count(begin) == 1 and text.count(end) == 1, key
    row = {"label": "x", "detected": 2, "slip_trials": 3, "median_latency_ms": float("nan"),
           "false_alarms_per_min": 12.4, "pre_onset_false_alarms": 0}
    summary = [{**row, "method": "dath", "rate": "data", "same_detections_as": ""},
               {**row, "method": "dath", "rate": "method", "same_detections_as": "", "detected": 3},
               {**row, "method": "dath-event", "rate": "data", "same_detections_as": "dath"}]
    table = script["compact"](summary)
    assert table.splitlines()[2] == "| DATH | 2 / 3 | - / - | 12 / 12 |" and len(table.splitlines()) == 3


@pytest.mark.slow
def test_ctrl_c_keeps_the_finished_trials(tmp_path, monkeypatch, capsys):
    import slipreflex.benchmark.run as run_mod
    import slipreflex.commands.benchmark as command

    folder = tmp_path / "set"
    folder.mkdir()
    for name in ("a", "b", "c"):
        _write(folder / f"{name}.csv", ["t", "x", "slip"], [[r[0], r[1], r[-1]] for r in _trial_rows()])
    real = run_mod.run_trial

    def stop_at_b(trial, *args, **kwargs):
        if trial.name == "b":
            raise KeyboardInterrupt
        return real(trial, *args, **kwargs)

    monkeypatch.setattr(command, "run_trial", stop_at_b)       # where the command calls it
    out = tmp_path / "out"
    assert main(["benchmark", str(folder), *REST_K, "--methods", "fixed", "--rates", "data", "--out", str(out)]) == 130
    with open(out / "benchmark.csv", newline="") as fh:
        assert [r["trial"] for r in csv.DictReader(fh)] == ["a"]
    assert (out / "a.png").is_file() and not (out / "b.png").exists()
    assert "interrupted; 1 finished trial(s) kept" in capsys.readouterr().out


def test_shear_reduction_runs_and_needs_two_tangential_components(tmp_path):
    trial = read_folder(shipped_dataset())[-1]
    (run,) = run_trial(trial, BenchmarkConfig(methods=("fixed",), rates=("data",), reduction="shear-norm"))
    assert run.score.slips and run.threshold > 0
    folder = tmp_path / "n"
    folder.mkdir()
    p = _write(folder / "n.csv", ["t", "a", "b", "c", "d", "slip"], _trial_rows(), (("layout", "1x2x2"),))
    with pytest.raises(DataError, match="shear-norm needs two tangential components per taxel"):
        reduce_channels(read_trial(p), "shear-norm")
