"""A researcher's first day: advice that holds, figures from what the controller saw, commands that
do what they say."""

import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from slipreflex.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[2]


# -- one list syntax ---------------------------------------------------------------------------

def test_calibrate_takes_the_comma_list_the_readme_shows(capsys):
    assert build_parser().parse_args(["calibrate", "--bottles", "TR,DK,TX"]).bottles == ("TR", "DK", "TX")
    assert main(["calibrate", "--bottles", "TR,XX"]) == 2           # checked before any work
    assert "unknown bottle 'XX'" in capsys.readouterr().err


@pytest.mark.parametrize("argv, option, right", [
    (["calibrate", "--bottles", "TR", "DK", "TX"], "--bottles", "--bottles TR,DK,TX"),
    (["reproduce", "--methods", "dath", "fixed", "--trials", "1"], "--methods", "--methods dath,fixed"),
    (["study", "--experiments", "drop", "pour"], "--experiments", "--experiments drop,pour"),
])
def test_space_separated_names_are_refused_with_the_right_form(capsys, argv, option, right):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and option in err[0] and right in err[0] and "comma-separated" in err[0]


# -- scan --------------------------------------------------------------------------------------

@pytest.mark.parametrize("argv, says", [
    (["--layout", "stand:5,white:10,black:15"], "longer than --layout 'stand:5,white:10,black:15' (30 mm)"),
    (["--distance", "60"], "longer than the paper's layout (50 mm)"),
    (["--objects", "MISSING.toml"], "--objects MISSING.toml: no such file"),
])
def test_scan_refuses_what_it_cannot_do_before_any_work(tmp_path, capsys, argv, says):
    out = tmp_path / "scan"
    assert main(["scan", "--out", str(out), *argv]) == 2
    assert says in capsys.readouterr().err
    assert not out.exists()


# -- virtual-rig -------------------------------------------------------------------------------

class _QuietRig:
    """No samples; remembers when it was perturbed and the hand's targets."""

    def __init__(self):
        self.perturbed = []
        self.got = {}
        rig = self

        class Hand:
            @staticmethod
            def set_positions(targets):
                rig.got.update(targets)

            @staticmethod
            def positions():
                return dict(rig.got)
        self.hand = Hand

    def advance_to(self, t):
        return []

    def perturb(self, kind):
        self.perturbed.append(kind)


def _wait(cond, seconds=10.0):
    import time

    deadline = time.monotonic() + seconds
    while not cond() and time.monotonic() < deadline:
        time.sleep(0.01)
    return cond()


def test_virtual_rig_schedule_waits_for_run_and_announces_each_perturbation():
    from slipreflex.core.hardware import Finger
    from slipreflex.rig.devices.ilimb import ILimb
    from slipreflex.rig.devices.virtual import VirtualDevices

    said = []
    rig = _QuietRig()
    with VirtualDevices(rig, schedule=[("drop", 0.05)], schedule_from="connect", on_event=said.append) as dev:
        assert not _wait(lambda: rig.perturbed, 0.4)       # nobody connected: the schedule waits
        with ILimb(dev.hand_path) as hand:
            hand.set_positions({Finger.MIDDLE: 200})
            assert _wait(lambda: rig.perturbed)
        dev.trigger("pour", "signal")
        assert _wait(lambda: len(rig.perturbed) == 2)
    assert said[0].startswith("client connected at") and "schedule starts now" in said[0]
    drop, pour = said[1], said[2]
    assert drop.startswith("drop at") and drop.endswith("(schedule)") and pour.endswith("(signal)")
    (_, t_drop), _ = dev.triggered
    assert t_drop >= dev.connected_at + 0.05 >= 0.4


def test_virtual_rig_summary_gives_the_fall_time_and_caps_the_slide():
    from slipreflex.rig.devices.simrig import SimRig
    from slipreflex.sim import Pour

    sim = SimRig("TR", pour=Pour(rate_l_min=6.0, volume_ml=300.0))
    sim.grasp()
    sim.advance_to(0.0)
    sim.perturb("pour")
    sim.advance_to(12.0)
    r = sim.rig
    assert r.fallen and r.displacement > 0.1                 # free fall far below the grip
    line = sim.status()
    fall = float(line.split("FALLEN at t=")[1].split(" s")[0])
    assert abs(fall - (r.fall_time - (r.t - 12.0))) < 0.01 and fall < 11.5
    shown = float(line.split("displaced ")[1].split(" mm")[0])
    assert shown == pytest.approx(r.bottle.grip_travel_m * 1e3)


# -- help and docs agree with the code -----------------------------------------------------------

def _sub(name):
    parser = build_parser()
    return next(a for a in parser._subparsers._group_actions[0].choices.items() if a[0] == name)[1]


def _option(parser, flag):
    return next(a for a in parser._actions if flag in a.option_strings)


def test_detect_and_run_offer_the_same_presets():
    from slipreflex.methods.chain.params import PRESETS

    assert list(_option(_sub("detect"), "--preset").choices) == list(_option(_sub("run"), "--preset").choices) \
        == sorted(PRESETS)


def test_defaults_are_shown_as_numbers():
    helps = {cmd: _sub(cmd).format_help() for cmd in ("reproduce", "run", "detect", "virtual-rig", "scan")}
    assert not any("PAPER_" in h for h in helps.values())
    reproduce = " ".join(helps["reproduce"].split())
    for text in ("(default 0.01, the paper's)", "(default 0.02, the paper's)", "(default 1, the paper's)",
                 "(default 500, the paper's)"):
        assert text in reproduce


def test_the_p0_example_is_what_virtual_rig_prints():
    from slipreflex.rig.devices.simrig import SimRig

    line = SimRig("TR", seed=0).grasp().p0_text()           # virtual-rig's defaults: TR, seed 0
    assert line in " ".join(_sub("run").format_help().split())
    assert line in (ROOT / "docs/runtime.md").read_text()
    for doc in ("README.md", "docs/runtime.md"):
        text = (ROOT / doc).read_text()
        assert "thumb=149" not in text and "index=147,middle=147" not in text


def test_study_docs_install_from_the_repository_or_a_wheel():
    text = (ROOT / "docs/study.md").read_text()
    assert "pip install slipreflex" not in text and "not on PyPI" in text
    assert "pip wheel" in text and "slipreflex-0.1.0-py3-none-any.whl" in text


# -- the first run ------------------------------------------------------------------------------

@pytest.mark.slow
def test_an_empty_numba_cache_is_seen_as_cold(tmp_path):
    code = "from slipreflex.reproduce.warmup import cold_kernels; print(len(cold_kernels()))"
    env = {**__import__("os").environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stderr
    from slipreflex.reproduce.warmup import KERNELS

    assert int(r.stdout) == len(KERNELS)


def test_the_estimate_counts_the_compilation_of_a_cold_cache(tmp_path, capsys, monkeypatch):
    import slipreflex.commands.reproduce as command
    import slipreflex.reproduce.experiments as ex

    class Stop(Exception):
        pass

    def stop(*a, **k):
        raise Stop

    monkeypatch.setattr(command, "run_reproduce", stop)     # patched where the command calls it
    said = {}
    for cold in ([], ["closed._closed_slip"]):
        monkeypatch.setattr(command, "cold_kernels", lambda cold=cold: cold)
        with pytest.raises(Stop):
            main(["reproduce", "--trials", "1", "--bottles", "TR", "--experiments", "drop", "--jobs", "2",
                  "--out", str(tmp_path / "r")])
        said[bool(cold)] = capsys.readouterr().err
    assert "compiles the kernels once" in said[True] and "compiles" not in said[False]
    small = ex.ReproduceConfig(trials=1, bottles=("TR",), experiments=("drop",))
    assert ex.estimate_wall_s(small, 2, cold=True) >= ex.estimate_wall_s(small, 2) + 15


@pytest.mark.slow          # a fresh interpreter loads every kernel; warmup's doctests stay fast
def test_the_kernels_are_compiled_before_the_workers_start():
    """Workers are forked after the parent compiled the closed loops: one compilation, not one per worker."""
    code = """
import slipreflex.reproduce.experiments as ex
from slipreflex.sim import closed
seen = []
def pool(calls, jobs, finished, done):
    seen.append((jobs, bool(closed._closed_slip.signatures), bool(closed._closed_tactile.signatures)))
ex.run_cells = pool
ex.run_reproduce(ex.ReproduceConfig(trials=1, bottles=("TR",), experiments=("drop",), methods=("dath", "nmsd")),
                 jobs=2, progress=False, plots=False)
print(seen)
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "[(2, True, True)]"


# -- figures draw what the controller saw ---------------------------------------------------------

def _trial(method, experiment="drop", bottle="DK", k=0, **cfg):
    from slipreflex.reproduce.experiments import Cell, ReproduceConfig, calibrate, run_trial, trial_seed

    config = ReproduceConfig(trials=1, bottles=(bottle,), experiments=(experiment,), **cfg)
    th = calibrate(config) if method in ("nmsd", "swt") else {}
    cell = Cell(experiment, bottle, method, k, trial_seed(config.seed, experiment, bottle, k))
    return run_trial(cell, config, th, keep_plot=True)


@pytest.mark.parametrize("compiled", [True, False])
def test_the_loop_records_what_its_reflex_computed(compiled):
    from slipreflex.core.hardware import SLIP_FINGER
    from slipreflex.methods.chain import SlipReflex
    from slipreflex.reproduce.experiments import DEFAULT_SEED, trial_seed
    from slipreflex.sim import PAPER_DROP, run_closed_loop
    from slipreflex.sim.loop import reflex_log
    from slipreflex.sim.variations import grasped_rig

    # the first of the default drop trials on which DATH spikes (the check below needs spikes)
    for bottle, k in ((b, k) for k in range(4) for b in ("DK", "TX", "TR")):
        rig, g = grasped_rig(bottle, trial_seed(DEFAULT_SEED, "drop", bottle, k), 0.8)
        rig.perturb(PAPER_DROP, at=rig.t + 0.5)
        reflex = SlipReflex(dath=True, p0=float(round(g.positions[SLIP_FINGER])))
        t0 = rig.t
        tr = run_closed_loop(rig, reflex, 1.0, compiled=compiled)
        log = reflex_log(tr)
        if (log["event"] > 0).any():
            break
    fed = tr.t[tr.t > t0 + 1e-12]                      # a sample at t0 came before the loop: never the reflex's
    assert log["t"][0] > t0 and np.array_equal(log["t"], fed[:log["t"].size]) and fed.size - log["t"].size <= 1
    # every command the loop sent is the recorded MPI state at that input, at a window's end
    at = np.searchsorted(log["t"], tr.cmd_t)
    assert np.array_equal(log["command"][at], tr.cmd_value) and (log["count"][at] >= 0).all()
    # each window count is the number of recorded spikes in that window
    ends = np.flatnonzero(log["count"] >= 0)
    starts = np.concatenate(([-1], ends[:-1]))
    spikes = np.cumsum(log["event"] > 0)
    assert np.array_equal(spikes[ends] - np.where(starts >= 0, spikes[np.maximum(starts, 0)], 0), log["count"][ends])
    assert log["count"].max() > 0


@pytest.mark.parametrize("method", ["dath", "nmsd", "swt"])
def test_trial_figures_draw_the_recorded_detections(method):
    rows, plot = _trial(method)
    assert plot.event_t is not None and "the reflex computed" in plot.event_label
    response = rows[0].onset_s + rows[0].response_ms / 1e3
    rises = np.asarray(plot.cmd_t)[1:][np.diff(np.asarray(plot.cmd_v)) > 0]
    if len(plot.event_t) == 0:             # nothing detected: nothing drawn, no rise and no response
        assert np.isnan(response) and plot.sensor is not None and rises.size == 0
    else:                                  # the command never rises before the first drawn detection
        assert rises.size == 0 or float(np.min(plot.event_t)) <= float(rises[0]) + 1e-9
        # a response (a rise in the slip's window) comes after it; a detection may also come after the
        # window (DATH's threshold adapting down to the noise long after a slip), then with no response
        assert np.isnan(response) or float(np.min(plot.event_t)) <= response + 1e-9
    if method == "dath":
        assert plot.counts is not None and int(np.sum(plot.counts)) == len(plot.event_t)
    else:
        assert plot.sensor_threshold > 0


# -- advice that holds ------------------------------------------------------------------------

JAR = """[bottles.JAR]          # a 250 g jar whose pads grip with mu 0.4
mass_kg = 0.25
height_m = 0.12
diameter_m = 0.07
mu_s = 0.4
mu_k = 0.3
surface = "TR"
"""


def _jar_config(**kw):
    import tempfile

    from slipreflex.reproduce.experiments import ReproduceConfig
    from slipreflex.sim import BOTTLES, load_objects
    from slipreflex.sim.uncertain import Plant

    path = Path(tempfile.mkdtemp()) / "jar.toml"
    path.write_text(JAR)
    plant = Plant(bottles={**BOTTLES, **load_objects(path).bottles})
    return ReproduceConfig(bottles=("JAR",), plant=plant, **kw), path


@pytest.mark.slow
def test_the_suggested_grasp_force_was_simulated_on_the_runs_trials_before_it_is_printed(tmp_path, capsys):
    import re

    from slipreflex.reproduce.experiments import trial_seed
    from slipreflex.reproduce.grasping import GRASP_MARGIN, grasp_holds

    config, path = _jar_config(trials=3, methods=("dath",))
    assert main(["reproduce", "--objects", str(path), "--bottles", "JAR", "--methods", "dath", "--trials", "3",
                 "--out", str(tmp_path / "r"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "cannot hold it" in err
    m = re.search(r"use --grasp-force ([0-9.]+) \(simulated before this message: .* in 6 of 6 of this run's "
                  r"trial grasps, variations included; ([0-9.]+) N was the weakest", err)
    assert m, err
    force, weakest = float(m.group(1)), float(m.group(2))
    assert force >= weakest * GRASP_MARGIN - 1e-9
    seeds = [trial_seed(config.seed, e, "JAR", k) for e in ("drop", "pour") for k in range(3)]
    assert all(grasp_holds(config, "JAR", force, seeds))
    assert not all(grasp_holds(config, "JAR", weakest / 1.1, seeds))     # the weakest is the edge


def test_a_trial_whose_object_left_before_the_load_is_void_and_reported_apart():
    from slipreflex.analysis.report import report_markdown, summarize, terminal_table
    from slipreflex.reproduce.experiments import Cell, run_trial, trial_seed

    config, _ = _jar_config(trials=6, methods=("dath",), experiments=("drop",), grasp_force_n=1.95)
    rows = []
    for k in (4, 5):            # at 1.95 N trial 5's grasp lets the jar go during the rest; trial 4 holds
        cell = Cell("drop", "JAR", "dath", k, trial_seed(config.seed, "drop", "JAR", k))
        rows += run_trial(cell, config, {})[0]
    void = [r for r in rows if r.fell_before_load]
    assert [r.trial for r in void] == [5] and void[0].fell_out_s < void[0].perturbation_s
    s = summarize(rows)[0]
    assert s["n_void"] == 1 and s["trial_success_n"] == 1 and s["event_success_n"] == len(rows) - len(void)
    table = terminal_table([s])
    assert "Void trials" in table and "drop JAR DATH 1 of 2" in table
    md = report_markdown(summary=[s], rows=rows, figures=[], setup=[], discussion=[])
    assert "**Void trials (the object left the grasp before the perturbation" in md


# -- success per trial and per slip event; grip added without slip --------------------------------

def test_success_is_counted_per_trial_and_per_slip_event_and_named_so(tmp_path):
    from slipreflex.analysis.figures import success_chart
    from slipreflex.analysis.report import report_markdown, summarize, terminal_table

    rows = [{"experiment": "drop", "bottle": "TX", "method": "dath", "trial": k, "seed": k, "event": e,
             "n_events": 1, "success": not (k == 9 and e == 1), "grip_without_slip": 0.0}
            for k in range(10) for e in range(2 if k == 9 else 1)]
    s = summarize(rows)[0]
    assert (s["trial_success_n"], s["event_success_n"]) == (10, 11)
    assert s["trial_success_rate"] == 0.9 and s["event_success_rate"] == pytest.approx(10 / 11)
    table = terminal_table([s])
    assert "success/trial" in table and "success/slip event" in table and "90% of 10" in table
    assert "91% of 11" in table
    md = report_markdown(summary=[s], rows=rows, figures=[], setup=[], discussion=[])
    assert "| success per trial | success per slip event |" in md and "| 90% of 10 | 91% of 11 |" in md
    assert success_chart([s], tmp_path / "s.png").stat().st_size > 1000


def test_grip_added_before_any_slip_is_measured():
    """The docs' can under the pour: DATH squeezes when the water lands, with no slip at all."""
    from importlib.resources import files

    from slipreflex.analysis.report import summarize, terminal_table
    from slipreflex.reproduce.experiments import Cell, ReproduceConfig, run_trial, trial_seed
    from slipreflex.sim import BOTTLES, HandParams, load_objects
    from slipreflex.sim.uncertain import Plant

    objs = load_objects(files("slipreflex") / "data/objects/example.toml")
    config = ReproduceConfig(trials=1, bottles=("CAN",), experiments=("pour",),
                             plant=Plant(bottles={**BOTTLES, **objs.bottles}))
    cell = Cell("pour", "CAN", "dath", 0, trial_seed(config.seed, "pour", "CAN", 0))
    rows, _ = run_trial(cell, config, {})
    assert rows[0].n_true_slips == 0                                       # no slip ...
    assert rows[0].grip_without_slip > 100                                 # yet the hand closed
    # the closing digits' motors shake the bottle, and the paper's accelerometer recipe may read that as a
    # slip: then the closing came first (a response time <= 0); without the motors' vibration, no response
    assert np.isnan(rows[0].response_ms) or rows[0].response_ms <= 0
    quiet = dataclasses.replace(config, plant=dataclasses.replace(config.plant, hand=HandParams(motor_vibration_n=0.0)))
    still, _ = run_trial(cell, quiet, {})
    assert still[0].n_true_slips == 0 and np.isnan(still[0].response_ms) and still[0].grip_without_slip > 100
    s = summarize(rows)[0]
    assert s["grip_without_slip_mean"] == rows[0].grip_without_slip
    assert f"{rows[0].grip_without_slip:.0f} units" in terminal_table([s])


def test_the_run_draws_success_and_grip_figures(tmp_path):
    from slipreflex.analysis.outputs import _figure_tasks
    from slipreflex.reproduce.experiments import ReproduceConfig, ReproduceResult

    res = ReproduceResult(ReproduceConfig(trials=1), [], [{"experiment": "drop", "bottle": "TR", "method": "dath",
                                                         "grip_without_slip_mean": 5.0}], {}, {}, 0.0, 1)
    names = [t[0] for t in _figure_tasks(res, tmp_path)]
    assert "success.png" in names and "grip_without_slip.png" in names


# -- the figures a reader of the paper misses ------------------------------------------------------

def _texts_of_saved_figures(monkeypatch):
    import matplotlib.figure

    seen = []
    real = matplotlib.figure.Figure.savefig

    def keep(fig, *a, **k):
        seen.append([t.get_text() for ax in fig.axes for t in ax.texts]
                    + [ax.get_title() for ax in fig.axes] + [fig._suptitle.get_text() if fig._suptitle else ""])
        return real(fig, *a, **k)
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", keep)
    return seen


@pytest.mark.slow
def test_the_scan_figure_draws_the_papers_levels(tmp_path, monkeypatch):
    seen = _texts_of_saved_figures(monkeypatch)
    assert main(["scan", "--out", str(tmp_path)]) == 0
    texts = " ".join(seen[-1])
    assert "paper 0.3-0.5 V" in texts and "paper 3.32-3.35 V" in texts and "the paper's levels" in texts


def test_calibrate_draws_the_open_loop_calibration(tmp_path, monkeypatch, capsys):
    seen = _texts_of_saved_figures(monkeypatch)
    png = tmp_path / "cal" / "calibration.png"
    assert main(["calibrate", "--bottles", "TR", "--figure", str(png)]) == 0
    assert png.stat().st_size > 5000 and f"wrote {png}" in capsys.readouterr().out
    texts = " ".join(seen[-1])
    assert "Open-loop calibration" in texts and "TR: pad mu_s" in texts


def test_a_run_draws_nmsd_and_swt_trials_and_zooms_that_zoom(tmp_path):
    from slipreflex.analysis.outputs import _figure_tasks, zoom_window
    from slipreflex.reproduce.experiments import ReproduceConfig, run_reproduce

    res = run_reproduce(ReproduceConfig(trials=1, bottles=("DK", "TX"), experiments=("drop",)), jobs=1,
                        progress=False)
    names = [t[0] for t in _figure_tasks(res, tmp_path)]
    for m in ("dath", "nmsd", "swt"):
        assert f"trial_drop_DK_{m}.png" in names
    assert "trial_drop_TX_dath.png" in names and "trial_drop_TX_nmsd.png" not in names
    answered = [p for key, p in sorted(res.plots.items()) if key[2] == "dath" and
                np.isfinite(p.onsets).any() and np.isfinite(p.responses).any()]
    assert answered, "no DATH drop trial with an onset and a response to zoom on"
    plot = answered[0]
    lo, hi = zoom_window(plot, "drop")
    full = plot.xlim[1] - plot.xlim[0]
    assert hi - lo <= full / 3 and lo < min(plot.onsets) and hi > max(plot.responses)


def test_the_method_table_in_the_docs_is_the_scripts_format():
    import runpy

    script = runpy.run_path(str(ROOT / "scripts" / "docs" / "method_table.py"))
    row = {"response_mean_ms": "58.4", "response_sd_ms": "27.1", "response_n": "3", "n_events": "3",
           "trial_success_rate": "1.0"}
    assert script["cell"](row) == "58 ± 27 (3)"
    assert script["cell"]({**row, "response_n": "0", "n_events": "0", "trial_success_rate": "0.0"}) == \
        "- (no slip), 0 %"
    text = (ROOT / "docs" / "method.md").read_text()
    assert "c26cb00" not in text and "python -m scripts.docs.method_table OUT/summary.csv" in text
    table = script["table"]([{"experiment": "drop", "bottle": "TR", "method": m, **row}
                             for m in script["ORDER"]])
    assert table.splitlines()[0] in text                         # the docs' header is the script's
