"""slipreflex benchmark's operating-point protocol: episodes, tolerance, the choice on training trials,
intervals, the chance line, given thresholds, trial-level labels, channels, the baselines, safe outputs."""

from __future__ import annotations

import csv
import dataclasses
import math
import os

import numpy as np
import pytest

from slipreflex.benchmark import read_folder, read_trial, shipped_dataset
from slipreflex.benchmark.evaluate import evaluate
from slipreflex.benchmark.protocol import ProtocolConfig, chance, choose_index, folds, poisson_rate_ci, roc_auc, wilson
from slipreflex.benchmark.sweep import Sweep, alarm_time, episode_starts, score_at
from slipreflex.cli import main
from slipreflex.core.errors import DataError, ParameterError
from slipreflex.core.validation import LIMITS

OPTICAL_FS = 1000.0 / 3.0


def _write(path, header, rows, preamble=()):
    lines = [f"# {k}: {v}" for k, v in preamble] + [",".join(header)]
    lines += [",".join(str(c) for c in r) for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def _optical(path, onset_s=None, seconds=2.0, level=0.5):
    """A quiet, exactly constant optical trace; from ``onset_s`` a slip drops it by 1 V/s."""
    t = np.arange(int(seconds * OPTICAL_FS)) / OPTICAL_FS
    x = np.full(len(t), level)
    slip = np.zeros(len(t), int)
    if onset_s is not None:
        on = t >= onset_s
        x[on] -= 1.0 * (t[on] - onset_s)
        slip[on] = 1
    return _write(path, ["t", "x", "slip"], [[f"{a:.6f}", f"{b:.6f}", c] for a, b, c in zip(t, x, slip)])


def _sweep(name, positive, hit, fa, neg=60.0, lat=None, window=0.5):
    hit = np.asarray(hit, bool)
    return Sweep(name, positive, np.arange(float(len(hit))), hit,
                 np.asarray(lat if lat is not None else [np.nan] * len(hit), float), np.asarray(fa, int), neg,
                 np.zeros(len(hit)), window if positive else np.nan)


# --- the pieces, by hand ----------------------------------------------------------------------------------


def test_episodes_merge_within_the_refractory_gap_and_time_in_alarm_is_their_union():
    det = np.array([0.0, 0.1, 0.2, 1.0, 1.3])
    assert episode_starts(det, 0.25).tolist() == [0.0, 1.0, 1.3]
    assert episode_starts(det, 0.35).tolist() == [0.0, 1.0]
    assert alarm_time(det, 0.25, 0.0, 10.0) == pytest.approx(0.45 + 0.25 + 0.25)   # [0, .45), [1, 1.25), [1.3, 1.55)
    assert alarm_time(det, 0.25, 0.1, 1.1) == pytest.approx(0.35 + 0.1)


def test_score_at_counts_hits_in_the_tolerance_window_and_episodes_before_it(tmp_path):
    t = np.arange(30) / 10.0
    slip = ((t >= 2.0) & (t < 2.5)).astype(int)
    tr = read_trial(_write(tmp_path / "a.csv", ["t", "x", "slip"], [[f"{a:.1f}", 0, s] for a, s in zip(t, slip)]))
    ev = np.isin(np.arange(30), [3, 4, 10, 19])                # 0.3+0.4 one episode, 1.0, then 1.9: 0.1 s early
    hit, lat, fa, neg, alarm, win = score_at(tr, tr.t, ev, refractory_s=0.25, tolerance_s=0.1)
    assert (hit, fa) == (True, 2) and lat == pytest.approx(-100.0)
    assert neg == pytest.approx(1.9) and win == pytest.approx(0.6)              # [1.9, 2.4 + 0.1]
    assert alarm == pytest.approx(0.35 + 0.25)
    hit0, *_ = score_at(tr, tr.t, ev, refractory_s=0.25, tolerance_s=0.0)       # no tolerance: 1.9 is a false alarm
    assert not hit0


def test_the_threshold_is_the_lowest_whose_training_false_alarms_stay_under_the_target():
    ctrl = _sweep("c", False, [0] * 5, [12, 3, 6, 1, 0], neg=60.0)              # per minute: 12, 3, 6, 1, 0
    assert choose_index([ctrl], "onset", 5.0) == 3                              # 3 at index 1 but 6 above it
    assert choose_index([ctrl], "onset", 6.0) == 1
    assert choose_index([ctrl], "onset", 0.0) == 4
    slip = _sweep("s", True, [1, 1, 1, 0, 0], [0] * 5)
    tl = [dataclasses.replace(slip, window_s=np.nan), dataclasses.replace(ctrl, hit=np.array([1, 1, 0, 0, 0], bool))]
    assert choose_index(tl, "trial", 0.0) == 2                                  # best accuracy, highest threshold


def test_folds_are_by_trial():
    assert folds(["a", "b", "c"], None) == [([1, 2], [0]), ([0, 2], [1]), ([0, 1], [2])]
    assert folds(["a", "b", "c"], ["b"]) == [([0, 2], [1])]
    with pytest.raises(ParameterError, match="'z' is not a trial"):
        folds(["a", "b"], ["z"])
    with pytest.raises(ParameterError, match="holds out every trial"):
        folds(["a", "b"], ["a", "b"])


def test_intervals_are_scipys_wilson_and_the_exact_poisson():
    from scipy.stats import binomtest

    lo, hi = wilson(3, 3)
    assert (lo, hi) == pytest.approx(tuple(binomtest(3, 3).proportion_ci(method="wilson")))
    assert lo == pytest.approx(0.4385, abs=1e-4) and hi == 1.0
    lo, hi = poisson_rate_ci(4, 2.0)
    assert (lo, hi) == pytest.approx((1.0899 / 2, 10.2416 / 2), abs=1e-3)
    assert math.isnan(wilson(0, 0)[0])


def test_the_chance_line_matches_a_simulated_poisson_alarm():
    rate, windows, tol = 0.8, [0.5, 1.0, 2.0], 0.1
    det, lat = chance(rate, windows, tol)
    rng = np.random.default_rng(0)
    first = rng.exponential(1.0 / rate, size=(200_000, len(windows)))
    inside = first < np.array(windows)
    assert det == pytest.approx(inside.mean(axis=0).sum(), abs=0.01)
    assert lat == pytest.approx(1000 * (first[inside].mean() - tol), abs=5.0)
    assert chance(0.0, windows, tol) == (0.0, pytest.approx(math.nan, nan_ok=True))


def test_roc_auc_of_a_perfect_and_a_useless_detector():
    pos = _sweep("p", True, [1, 1, 0], [0, 0, 0], neg=0.0)
    neg = _sweep("n", False, [1, 0, 0], [0, 0, 0])
    assert roc_auc([pos, neg]) == 1.0
    assert roc_auc([pos, _sweep("n", False, [1, 1, 0], [0, 0, 0])]) == pytest.approx(0.5)


# --- given thresholds: the paper's 8 mV on a quiet constant optical trace ----------------------------------


def _optical_set(tmp_path):
    folder = tmp_path / "optical"
    folder.mkdir()
    _optical(folder / "slip1.csv", onset_s=0.6)                    # the onset inside any 1 s calibration span
    _optical(folder / "slip2.csv", onset_s=0.8, level=0.45)
    _optical(folder / "rest.csv")
    return folder


@pytest.mark.slow
def test_a_given_threshold_scores_a_constant_optical_trace_with_no_false_alarm(tmp_path, capsys):
    folder = _optical_set(tmp_path)
    out = tmp_path / "out"
    assert main(["benchmark", str(folder), "--methods", "fixed", "dath", "--threshold", "fixed=0.008",
                 "dath=0.008", "--bootstrap", "20", "--no-figures", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "given thresholds (not chosen): fixed 0.008, DATH 0.008" in text
    with open(out / "operating_points.csv", newline="") as fh:
        rows = {r["method"]: r for r in csv.DictReader(fh)}
    for m in ("fixed", "dath"):
        r = rows[m]
        assert (r["detected"], r["slip_trials"], r["false_alarms"], r["fixed"]) == ("2", "2", "0", "1")
        assert float(r["threshold_median"]) == 0.008 and 0 < float(r["median_latency_ms"]) < 100


def test_a_constant_rest_recording_gives_no_threshold_one_line(tmp_path, capsys):
    folder = _optical_set(tmp_path)
    assert main(["benchmark", str(folder), "--methods", "fixed", "--rest", str(folder / "rest.csv"),
                 "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "does not vary on the rest recording" in err


@pytest.mark.slow
def test_thresholds_from_a_separate_rest_recording(tmp_path):
    trials = read_folder(shipped_dataset())
    from slipreflex.benchmark.evaluate import rest_thresholds

    thr = rest_thresholds(trials[0], ["fixed", "nmsd", "energy"], "data", 5.0)
    ev = evaluate(trials[1:], methods=("fixed", "nmsd", "energy"), thresholds=thr,
                  protocol=ProtocolConfig(bootstrap=0))
    assert ev.fixed == thr and all(p.thresholds == (thr[p.method],) * 6 for p in ev.points)


# --- trial-level labels: classification ---------------------------------------------------------------------


def _touch_set(tmp_path, n=4):
    folder = tmp_path / "touch"
    folder.mkdir()
    rng = np.random.default_rng(5)
    t = np.arange(120) / 100.0
    for i in range(n):
        for kind in ("slip", "no-slip"):
            x = 100 + 20 * np.tanh(5 * (t - 0.5))[:, None] + rng.normal(0, 0.2, (120, 3))
            if kind == "slip":
                x[60:90] += rng.normal(0, 4.0, (30, 3))                 # the vibration of slip
            _write(folder / f"{kind}{i}.csv", ["t", "a", "b", "c"], [[f"{a:.2f}", *(f"{v:.3f}" for v in r)]
                                                                      for a, r in zip(t, x)],
                   (("trial-label", kind),))
    return folder


@pytest.mark.slow
def test_trial_level_labels_score_as_classification(tmp_path, capsys):
    folder = _touch_set(tmp_path)
    assert main(["benchmark", str(folder), "--methods", "energy", "fixed", "--bootstrap", "50", "--no-figures",
                 "--out", str(tmp_path / "o")]) == 0
    text = capsys.readouterr().out
    assert "trial-level labels (no onset): classification" in text and "AUC" in text
    with open(tmp_path / "o" / "operating_points.csv", newline="") as fh:
        energy = next(r for r in csv.DictReader(fh) if r["method"] == "energy")
    assert energy["kind"] == "trial" and float(energy["area"]) == 1.0
    assert (energy["trials"], energy["correct"]) == ("8", "8")


def test_trial_label_errors(tmp_path):
    p = _write(tmp_path / "a.csv", ["t", "x", "slip"], [[i, 0, 0] for i in range(10)], (("trial-label", "slip"),))
    with pytest.raises(DataError, match="both a '# trial-label' line and a 'slip' column"):
        read_trial(p)
    p = _write(tmp_path / "b.csv", ["t", "x"], [[i, 0] for i in range(10)], (("trial-label", "maybe"),))
    with pytest.raises(DataError, match="must be one of slip, no-slip"):
        read_trial(p)
    folder = tmp_path / "mixed"
    folder.mkdir()
    _write(folder / "a.csv", ["t", "x", "slip"], [[i, 0, 0] for i in range(10)])
    _write(folder / "b.csv", ["t", "x"], [[i, 0] for i in range(10)], (("trial-label", "slip"),))
    with pytest.raises(DataError, match="a data set uses one kind of label"):
        read_folder(folder)


# --- channels without a layout say how they were aggregated ---------------------------------------------


@pytest.mark.parametrize("aggregate", ["any", "sum", "magnitude"])
def test_channels_without_a_layout_name_their_aggregation(tmp_path, capsys, aggregate):
    folder = tmp_path / "chans"
    folder.mkdir()
    rng = np.random.default_rng(2)
    t = np.arange(300) / 100.0
    for i in range(3):
        x = rng.normal(0, 0.01, (300, 4)).cumsum(axis=0)
        x[200:] += np.linspace(0, 3, 100)[:, None] if i else 0.0
        _write(folder / f"t{i}.csv", ["t", "a", "b", "c", "d", "slip"],
               [[f"{a:.2f}", *(f"{v:.4f}" for v in r), int(i > 0 and k >= 200)] for k, (a, r) in enumerate(zip(t, x))])
    args = ["benchmark", str(folder), "--methods", "fixed", "--aggregate", aggregate, "--bootstrap", "0",
            "--no-figures", "--out", str(tmp_path / "o")]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert f"4 channel(s), no layout line: aggregation {aggregate}" in text
    assert main([*args[:2], "--channels", "a", "c", *args[2:]]) == 0
    assert "2 channel(s) chosen by --channels" in capsys.readouterr().out
    assert main([*args[:2], "--channels", "zz", *args[2:]]) == 2
    assert "--channels: 'zz' is not a channel" in capsys.readouterr().err


# --- the shipped set, the baselines -----------------------------------------------------------------------


@pytest.mark.slow
def test_the_shipped_set_prints_the_operating_point_table(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["benchmark", "--bootstrap", "100", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "protocol: leave-one-trial-out" in text and "at most 10 false alarms per minute" in text
    assert "chance: detected, latency ms" in text and "[0.44, 1.00]" in text
    assert "DATH, event MPI (data): the same scores as DATH" in text
    with open(out / "operating_points.csv", newline="") as fh:
        rows = {r["method"]: r for r in csv.DictReader(fh)}
    from slipreflex.benchmark import learned

    assert {"dath", "fixed", "nmsd", "swt", "authors-gui", "dath-leak", "energy"} <= set(rows)
    assert ("learned" in rows) == (learned.available() is None)
    assert ("not run: learned: needs scikit-learn" in text) == (learned.available() is not None)
    for r in rows.values():
        assert len(r) and float(r["false_alarms_per_min"]) <= 30          # the target holds roughly held out
        assert float(r["chance_detected"]) < int(r["detected"])            # every method beats chance
        assert 0 <= float(r["area_lo"]) <= float(r["area"]) <= float(r["area_hi"]) <= 1
    assert (out / "curves.png").stat().st_size > 10_000


@pytest.mark.slow
def test_the_learned_baseline_trains_on_training_trials_only(monkeypatch):
    pytest.importorskip("sklearn")
    from slipreflex.benchmark import learned

    trials = read_folder(shipped_dataset())
    seen = []
    real = learned.fit

    def spy(train, **kw):
        seen.append({tr.name for tr in train})
        return real(train, **kw)

    monkeypatch.setattr(learned, "fit", spy)
    ev = evaluate(trials, methods=("learned",), protocol=ProtocolConfig(bootstrap=0))
    assert len(seen) == len(trials)
    for tr, names in zip(trials, seen):
        assert tr.name not in names and len(names) == len(trials) - 1
    assert ev.points[0].method == "learned" and ev.points[0].slip_trials == 3


def test_a_declared_split_is_named_and_checked(tmp_path, capsys):
    folder = _optical_set(tmp_path)
    args = ["benchmark", str(folder), "--methods", "fixed", "--bootstrap", "0", "--no-figures"]
    assert main([*args, "--test-trials", "slip2", "--out", str(tmp_path / "o")]) == 0
    assert "declared split: 1 held-out trial(s) (slip2), 2 training" in capsys.readouterr().out
    assert main([*args, "--test-trials", "nope", "--out", str(tmp_path / "o2")]) == 2
    assert "'nope' is not a trial" in capsys.readouterr().err


# --- outputs are a new set; inputs are bounded -----------------------------------------------------------


@pytest.mark.parametrize("protocol, name", [("operating", "operating_points.csv"), ("operating", "curves.png"),
                                            ("rest-k", "summary.csv"), ("rest-k", "slip1.png")])
def test_the_users_files_in_out_are_never_replaced(tmp_path, capsys, protocol, name):
    folder = _optical_set(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / name).write_text("mine")
    args = ["benchmark", str(folder), "--protocol", protocol, "--methods", "fixed", "--rates", "data",
            "--calibration-s", "0.5", "--bootstrap", "0", "--out", str(out)]
    assert main(args) == 2
    assert f"{name} exists and was not written by slipreflex benchmark" in capsys.readouterr().err
    assert (out / name).read_text() == "mine"


def test_a_symlink_planted_in_out_is_not_followed(tmp_path, capsys):
    folder = _optical_set(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    os.symlink(victim, out / "curves.png")
    assert main(["benchmark", str(folder), "--methods", "fixed", "--bootstrap", "0", "--out", str(out)]) == 2
    assert "curves.png exists" in capsys.readouterr().err
    assert victim.read_text() == "precious" and os.path.islink(out / "curves.png")


@pytest.mark.slow
def test_a_second_run_replaces_its_own_set(tmp_path):
    folder = _optical_set(tmp_path)
    out = tmp_path / "out"
    args = ["benchmark", str(folder), "--methods", "fixed", "--bootstrap", "0", "--out", str(out)]
    assert main(args) == 0 and main([*args, "--no-figures"]) == 0
    assert sorted(p.name for p in out.iterdir()) == [".slipreflex-outputs.json", "operating_points.csv"]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this system")
def test_a_fifo_named_like_a_trial_is_refused_without_blocking(tmp_path, capsys):
    folder = _optical_set(tmp_path)
    os.mkfifo(folder / "x.csv")
    assert main(["benchmark", str(folder), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "x.csv: not a regular file" in err


def test_a_folder_over_the_trials_limit_is_refused_before_reading(tmp_path, monkeypatch):
    folder = _optical_set(tmp_path)
    monkeypatch.setitem(LIMITS, "trials", dataclasses.replace(LIMITS["trials"], hi=2))
    with pytest.raises(DataError, match="3 trial files, more than the 2 a data set may have"):
        read_folder(folder)


@pytest.mark.parametrize("limit, value, needle", [
    ("csv_samples", 100, "more than 100 samples"),
    ("csv_line_bytes", 10, "longer than 10 characters"),
    ("text_file_bytes", 1000, "more than the 1000 a trial file may have"),
])
def test_inputs_are_under_the_limits_table(tmp_path, capsys, monkeypatch, limit, value, needle):
    folder = _optical_set(tmp_path)
    monkeypatch.setitem(LIMITS, limit, dataclasses.replace(LIMITS[limit], hi=value))
    assert main(["benchmark", str(folder), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and needle in err and "Limits" in err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("protocol", ["operating", "rest-k"])
def test_long_work_is_estimated_before_it_starts(tmp_path, capsys, monkeypatch, protocol):
    import slipreflex.commands.benchmark as command

    monkeypatch.setattr(command, "_SAY_ESTIMATE_S", 0.0)
    started = []
    monkeypatch.setattr(command, "evaluate", lambda *a, **k: started.append(capsys.readouterr().err) or 1 / 0)
    monkeypatch.setattr(command, "run_trial", lambda *a, **k: started.append(capsys.readouterr().err) or 1 / 0)
    folder = _optical_set(tmp_path)
    with pytest.raises(ZeroDivisionError):
        main(["benchmark", str(folder), "--protocol", protocol, "--methods", "fixed", "--rates", "data",
              "--calibration-s", "0.5", "--bootstrap", "0", "--out", str(tmp_path / "o")])
    assert "3 trial(s), 1998 samples, 1 method(s): about" in started[0]      # printed before the work


def test_many_tiny_trials_get_an_estimate_of_their_cost(capsys, monkeypatch):
    import slipreflex.commands.benchmark as command

    first = read_folder(shipped_dataset())[0]
    command._estimate([dataclasses.replace(first, t=first.t[:8])] * 10_000, 11, ("data",), 41, figures=False)
    err = capsys.readouterr().err
    assert "10000 trial(s), 80000 samples, 11 method(s): about" in err and " h" in err


# --- what the tables say ----------------------------------------------------------------------------------


def test_every_empty_vs_sim_cell_says_why_and_the_header_gives_the_datas_rate():
    from slipreflex.benchmark.vs_sim import MEASURES, Comparison, format_comparison

    full = {k: 1.0 for k, _ in MEASURES}
    rows = {"real, controls": {**full, "slip_force_ratio": math.nan, "slip_over_motion": math.nan},
            "simulated drop": {**full, "motion_force_ratio": math.nan}}
    text = format_comparison(Comparison(tuple(rows), rows, 36.0, {}))
    assert text.splitlines()[0].startswith("measure (all at 36.0 Hz, the data's rate)")
    cells = [c for line in text.splitlines()[2:len(MEASURES) + 2] for c in line.split("  ") if c.strip()]
    assert "-" not in cells                                     # no bare dash
    assert "(1) a control has no slip" in text
    assert "(2) less than 0.25 s (or 8 samples) of non-slip time after the calibration span" in text


def test_a_detector_in_alarm_most_of_the_time_is_flagged():
    from slipreflex.benchmark.evaluate import Evaluation
    from slipreflex.benchmark.optable import format_points
    from slipreflex.benchmark.protocol import OperatingPoint

    busy = OperatingPoint("energy", "data", "onset", (1.0,), slip_trials=3, detected=3, false_alarms=50,
                          negative_min=1.0, alarm_fraction=0.9, chance_detected=2.9, chance_latency_ms=10.0)
    quiet = dataclasses.replace(busy, method="fixed", alarm_fraction=0.1)
    table = format_points(Evaluation("onset", [busy, quiet], [], {}, {}, ProtocolConfig(), "loto", "x"))
    lines = {line.split()[0]: line for line in table.splitlines()[-2:]}
    assert "90 % (!)" in lines["energy"] and "(!)" not in lines["fixed"]
    assert "2.9, 10" in lines["energy"]                         # the chance line beside it


@pytest.mark.parametrize("given", ["fixed", "fixed=-1", "fixed=abc", "nmsd=0.1"])
def test_a_bad_threshold_is_one_line(tmp_path, capsys, given):
    folder = _optical_set(tmp_path)
    assert main(["benchmark", str(folder), "--methods", "fixed", "--threshold", given,
                 "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--threshold" in err


def test_ctrl_c_keeps_the_finished_methods(tmp_path, capsys, monkeypatch):
    import slipreflex.benchmark.evaluate as ev_mod

    folder = _optical_set(tmp_path)
    real = ev_mod.prepare

    def stop_at_dath(name, *args, **kwargs):
        if name == "dath":
            raise KeyboardInterrupt
        return real(name, *args, **kwargs)

    monkeypatch.setattr(ev_mod, "prepare", stop_at_dath)
    out = tmp_path / "out"
    assert main(["benchmark", str(folder), "--methods", "fixed", "dath", "--bootstrap", "0", "--out", str(out)]) == 130
    with open(out / "operating_points.csv", newline="") as fh:
        assert [r["method"] for r in csv.DictReader(fh)] == ["fixed"]
    assert "interrupted; 1 finished method(s) kept" in capsys.readouterr().out
