"""A new user's first hour: the steps after set-up that the README promises."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from stk500_standin import Bootloader, read_hex  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def _flash(board: Bootloader, build: Path) -> subprocess.CompletedProcess:
    return subprocess.run(["make", "-C", str(ROOT / "firmware"), "flash", f"BUILD={build}", f"PORT={board.port}"],
                          capture_output=True, text=True, timeout=300)


@pytest.mark.slow
@pytest.mark.needs_tools("make", "avr-gcc", "avr-libc", "avrdude")
def test_make_flash_programs_an_uno_through_avrdude(tmp_path):
    """README: `make -C firmware flash PORT=...` builds the hex and avrdude writes and verifies it."""
    with Bootloader() as board:
        r = _flash(board, tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "avrdude -p m328p -c arduino" in r.stdout
    image = read_hex(tmp_path / "daq.hex")
    assert len(image) > 1000 and board.pages_written == -(-max(image) // 128)
    assert all(board.flash[a] == b for a, b in image.items())
    assert "bytes of flash verified" in r.stderr


@pytest.mark.slow
@pytest.mark.needs_tools("make", "avr-gcc", "avr-libc", "avrdude")
def test_make_flash_refuses_a_board_that_is_not_an_uno(tmp_path):
    """The stand-in's answers matter: a Mega's signature stops avrdude before it writes."""
    with Bootloader(signature=bytes([0x1E, 0x98, 0x01])) as board:
        r = _flash(board, tmp_path)
    assert r.returncode != 0
    assert "signature" in r.stderr.lower() and board.pages_written == 0


def _one_line_exit_2(capsys, argv, *fragments):
    from slipreflex.cli import main
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""                       # nothing started: no grasp, no ports, no trial
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in captured.err, captured.err
    for fragment in fragments:
        assert fragment in lines[0]
    return lines[0]


def test_virtual_rig_link_dir_that_cannot_be_made_is_one_line(capsys, tmp_path):
    _one_line_exit_2(capsys, ["virtual-rig", "--link-dir", "/proc/nope", "--duration", "1"],
                     "--link-dir /proc/nope", "cannot create the directory")
    (tmp_path / "f").write_text("x")
    _one_line_exit_2(capsys, ["virtual-rig", "--link-dir", str(tmp_path / "f"), "--duration", "1"],
                     f"--link-dir {tmp_path / 'f'}: is a file, not a directory")
    _one_line_exit_2(capsys, ["virtual-rig", "--link-dir", str(tmp_path / "f" / "sub"), "--duration", "1"],
                     "--link-dir", "Not a directory")


def test_output_dir_creates_and_proves_writable(tmp_path):
    from slipreflex.core.errors import ParameterError
    from slipreflex.files.paths import output_dir
    d = output_dir(tmp_path / "a" / "b", "--out")
    assert d.is_dir() and list(d.iterdir()) == []   # the probe file is gone
    ro = tmp_path / "ro"
    ro.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=1m", "tmpfs", str(ro)], capture_output=True)
    if os.path.ismount(ro):
        try:
            try:
                output_dir(ro, "--out")
                raise AssertionError("a read-only directory was accepted")
            except ParameterError as err:
                assert "cannot write into the directory" in str(err)
        finally:
            subprocess.run(["umount", str(ro)], check=True)


def test_cli_turns_an_os_error_into_one_line(capsys, tmp_path, monkeypatch):
    """Anything the machine refuses mid-command (disk full, file vanished): one line, exit 2."""
    import slipreflex.commands.detect as detect

    def refuse(args):
        raise OSError(28, "No space left on device", str(tmp_path / "x.csv"))
    monkeypatch.setattr(detect, "run", refuse)
    from slipreflex.cli import main
    assert main(["detect", "whatever.csv"]) == 2
    err = capsys.readouterr().err
    assert err == f"slipreflex detect: error: {tmp_path / 'x.csv'}: No space left on device\n"


def test_batch_functions_take_matlab_row_and_column_vectors():
    import numpy as np

    import slipreflex as sr
    from slipreflex.core.errors import DataError
    raw = 0.4 + 0.02 * np.sin(np.arange(96) / 2.0)
    flat = sr.run_chain(raw, dath=True)
    for shaped in (raw[None, :], raw[:, None]):
        res = sr.run_chain(shaped, dath=True)
        np.testing.assert_array_equal(res.commands, flat.commands)
        np.testing.assert_array_equal(sr.lowpass(shaped), sr.lowpass(raw))
        np.testing.assert_array_equal(sr.encode(shaped), sr.encode(raw))
    np.testing.assert_array_equal(sr.count_windows(flat.events[None, :]), flat.counts)
    np.testing.assert_array_equal(sr.mpi(flat.counts[:, None]), sr.mpi(flat.counts))
    try:
        sr.run_chain(np.ones((2, 48)))
        raise AssertionError("a 2 x 48 matrix was accepted")
    except DataError as err:
        assert "shape (2, 48)" in str(err)


def test_progress_in_a_log_is_one_line_per_tenth_without_carriage_returns():
    import io

    from slipreflex.files.progress import Progress
    log = io.StringIO()
    ticks = iter(range(1000))
    with Progress(240, desc="trials", unit="trial", file=log, clock=lambda: float(next(ticks))) as p:
        for _ in range(240):
            p.update()
    text = log.getvalue()
    assert "\r" not in text
    lines = text.splitlines()
    assert len(lines) == 10
    assert lines[0].startswith("trials: 24/240 (10 %)") and "left" in lines[0]
    assert lines[-1].startswith("trials: 240/240 (100 %)")
    quiet = io.StringIO()
    with Progress(240, file=quiet, enabled=False) as p:
        p.update(240)
    assert quiet.getvalue() == ""


def test_progress_on_a_terminal_is_a_live_bar():
    import io

    from slipreflex.files.progress import Progress
    term = io.StringIO()
    with Progress(10, desc="trials", file=term, tty=True) as p:
        p.update(10)
    assert "\r" in term.getvalue() and "10/10" in term.getvalue()


def _reproduce_then_signal(tmp_path, send):
    """Start a reproduction, wait for its first progress line, signal it; (exit, stderr, out dir)."""
    import signal as sig
    out = tmp_path / "r"
    cmd = [sys.executable, "-m", "slipreflex", "reproduce", "--out", str(out), "--jobs", "2", "--trials", "40",
           "--bottles", "TR", "--methods", "dath", "--experiments", "pour"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    err = []
    for line in proc.stderr:            # the estimate, then one line per tenth of the trials
        err.append(line)
        if line.startswith("trials:"):
            break
    send(proc, sig)
    try:
        _, rest = proc.communicate(timeout=60)   # the kill timer: a hang fails here, not forever
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, sig.SIGKILL)
        proc.communicate()
        raise AssertionError("reproduce did not stop after the signal") from None
    return proc.returncode, "".join(err) + rest, out


@pytest.mark.slow
@pytest.mark.parametrize("send", [
    lambda p, sig: os.killpg(p.pid, sig.SIGINT),        # Ctrl-C reaches the parent and every worker
    lambda p, sig: p.send_signal(sig.SIGTERM),          # kill PID: the parent only
], ids=["ctrl-c", "sigterm"])
def test_interrupted_reproduce_writes_the_finished_trials_marked_partial(tmp_path, send):
    import re

    from slipreflex.analysis.report import read_csv
    code, err, out = _reproduce_then_signal(tmp_path, send)
    assert code == 130, err
    assert err.startswith("40 trials on 2 worker(s): about ")
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    m = re.search(r"slipreflex reproduce: interrupted after (\d+) of 40 trials", err)
    assert m, err
    n = int(m.group(1))
    assert 4 <= n < 40                  # the 10 % line had come; queued trials were cancelled
    assert (out / "results.csv").read_text().startswith(f"# partial: interrupted after {n} of 40 trials\n")
    assert (out / "summary.csv").read_text().startswith(f"# partial: interrupted after {n} of 40 trials\n")
    rows = read_csv(out / "results.csv")
    assert len({r["trial"] for r in rows}) == n
    report = (out / "report.md").read_text().splitlines()
    assert any(f"Partial run: interrupted after {n} of 40 trials" in line for line in report[:4])
    assert not (out / "figures").exists()


@pytest.mark.parametrize("out, says", [
    ("README.md", "--out README.md: is a file, not a directory"),
    ("README.md/sub", "--out README.md/sub: cannot create the directory (Not a directory)"),
    ("/proc/nope", "--out /proc/nope: cannot create the directory"),
])
def test_reproduce_out_is_checked_before_the_first_trial(capsys, monkeypatch, out, says):
    import slipreflex.reproduce.experiments as ex

    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(ex, "run_trial", lambda *a, **k: pytest.fail("a trial ran"))
    before = (ROOT / "README.md").read_bytes()
    line = _one_line_exit_2(capsys, ["reproduce", "--out", out, "--trials", "1", "--jobs", "1"], says)
    assert line.startswith("slipreflex reproduce: error:")
    assert (ROOT / "README.md").read_bytes() == before


def test_method_names_take_any_case(tmp_path, capsys):
    from slipreflex.cli import build_parser
    args = build_parser().parse_args(["reproduce", "--methods", "DATH,Fixed,nmsd,SWT"])
    assert args.methods == ("dath", "fixed", "nmsd", "swt")


@pytest.mark.slow
def test_seeds_are_derived_in_time_linear_in_the_trials(monkeypatch):
    """3000 trials: every seed comes from O(1) spawned children (it was O(trials) each)."""
    import numpy as np

    from slipreflex.reproduce.experiments import ReproduceConfig, trial_seed
    spawned = []
    real = np.random.SeedSequence

    class Counting(real):
        def spawn(self, n):
            spawned.append(n)
            return super().spawn(n)
    monkeypatch.setattr(np.random, "SeedSequence", Counting)
    trial_seed.__globals__["_cell_sequence"].cache_clear()
    cells = ReproduceConfig(trials=3000, methods=("dath",)).cells()
    assert len(cells) == 18000 and 0 < sum(spawned) <= 5 * 6     # (2 + 3) children per experiment and bottle
    # Same bits as spawning: SeedSequence(m).spawn(2)[e].spawn(3)[b].spawn(k + 1)[k].
    monkeypatch.setattr(np.random, "SeedSequence", real)
    trial_seed.__globals__["_cell_sequence"].cache_clear()
    ss = np.random.SeedSequence(11).spawn(2)[1].spawn(3)[2].spawn(8)[7]
    assert trial_seed(11, "pour", "TX", 7) == int(ss.generate_state(2, dtype=np.uint64)[0] >> np.uint64(1))


@pytest.mark.slow
def test_reproduce_estimates_its_run_time_before_starting(tmp_path, capsys, monkeypatch):
    import slipreflex.commands.reproduce as command
    import slipreflex.reproduce.experiments as ex
    from slipreflex.cli import main
    from slipreflex.core.errors import ParameterError

    def stop(*a, **k):
        raise ParameterError("stopped by the test")
    monkeypatch.setattr(command, "run_reproduce", stop)
    assert main(["reproduce", "--out", str(tmp_path), "--trials", "3000", "--jobs", "2"]) == 2
    err = capsys.readouterr().err.splitlines()
    from slipreflex.commands.reproduce import LONG_RUN_S
    from slipreflex.files.progress import format_duration

    est = ex.estimate_wall_s(ex.ReproduceConfig(trials=3000), 2)
    assert est > LONG_RUN_S
    assert err[0] == (f"72000 trials on 2 worker(s): about {format_duration(est)} "
                      "(a long run: fewer --trials, --bottles or --methods shorten it)")
    assert main(["reproduce", "--out", str(tmp_path), "--trials", "1", "--jobs", "2"]) == 2
    assert "long run" not in capsys.readouterr().err


OBJECTS = """
[bottles.JAR]
mass_kg = 0.25
diameter_m = 0.07
mu_s = {mu_s}
mu_k = {mu_k}
surface = "TX"

[drops.HEAVY]
mass_kg = 0.02
height_m = 0.05

[pours.FAST]
rate_l_min = 2.0
volume_ml = 300
"""


def _objects_file(tmp_path, mu_s=1.2, mu_k=1.0):
    p = tmp_path / "objs.toml"
    p.write_text(OBJECTS.format(mu_s=mu_s, mu_k=mu_k))
    return p


@pytest.mark.slow
def test_reproduce_with_own_objects_compares_with_the_paper_only_where_they_are_the_papers(tmp_path, capsys):
    from slipreflex.analysis.report import read_csv
    from slipreflex.cli import main
    objs = _objects_file(tmp_path)
    out = tmp_path / "r"
    assert main(["reproduce", "--objects", str(objs), "--bottles", "JAR,TR", "--drop", "HEAVY", "--trials", "1",
                 "--methods", "DATH", "--jobs", "1", "--no-progress", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    rows = read_csv(out / "results.csv")
    assert {(r["experiment"], r["bottle"]) for r in rows} == {(e, b) for e in ("drop", "pour") for b in ("JAR", "TR")}
    report = (out / "report.md").read_text()
    first = report.splitlines()[2]
    assert first.startswith("**Not the paper's objects: bottle JAR, drop (20 g from 5 cm). The paper's numbers "
                            "are compared only where the bottle and its load are the paper's")
    assert printed.startswith("Not the paper's objects: bottle JAR, drop (20 g from 5 cm).")
    paper_table, yours = report.split("## Your objects (no paper values)")
    assert "| pour, response ms | TR |" in paper_table             # the paper's bottle under the paper's pour
    assert "drop, response ms" not in paper_table and "JAR" not in paper_table.split("## Run")[1].split("##")[1]
    assert "drop  JAR" in yours and "drop  TR" in yours and "pour  JAR" in yours and "pour  TR" not in yours


def test_own_objects_names_are_checked_before_any_work(tmp_path, capsys):
    objs = _objects_file(tmp_path)
    for argv, says in [
        (["reproduce", "--drop", "HEAVY"], "--drop HEAVY: no such drop (give --objects FILE.toml)"),
        (["reproduce", "--objects", str(objs), "--pour", "SLOW"], f"--pour SLOW: no such pour ({objs} has FAST)"),
        (["reproduce", "--objects", str(objs), "--bottles", "JAR,XX"],
         "bottles: unknown 'XX' (known: TR, DK, TX, JAR)"),
        (["reproduce", "--objects", str(tmp_path)], f"{tmp_path}: is a directory, not a TOML file"),
        (["virtual-rig", "--objects", str(objs), "--bottle", "POT"], "--bottle POT: unknown (known: TR, DK, TX, JAR)"),
        (["virtual-rig", "--objects", str(objs), "--drop", "NOPE"], f"--drop NOPE: no such drop ({objs} has HEAVY)"),
    ]:
        _one_line_exit_2(capsys, argv + ["--out" if argv[0] == "reproduce" else "--duration",
                                         str(tmp_path / "o") if argv[0] == "reproduce" else "0"], says)


def test_a_grasp_that_cannot_hold_the_object_says_what_to_change(tmp_path, capsys):
    """Item 14: a 250 g jar with mu 0.4 in the 0.8 N grasp; --grasp-force makes it hold."""
    from slipreflex.cli import main
    objs = _objects_file(tmp_path, mu_s=0.4, mu_k=0.3)
    for argv in (["virtual-rig", "--objects", str(objs), "--bottle", "JAR", "--duration", "0"],
                 ["reproduce", "--objects", str(objs), "--bottles", "JAR", "--trials", "1", "--out", str(tmp_path)]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert "bottle JAR: the 0.8 N grasp cannot hold it" in err and "--grasp-force" in err
    assert main(["virtual-rig", "--objects", str(objs), "--bottle", "JAR", "--grasp-force", "3",
                 "--duration", "0"]) == 0
    assert "grasp: bottle JAR" in capsys.readouterr().out


@pytest.fixture
def captured_figures(monkeypatch):
    """The matplotlib figures the figure functions would save, kept open for inspection."""
    from slipreflex.analysis import figures as F
    figs = []

    def keep(plt, fig, path, layout=True):
        figs.append(fig)
        return Path(path)
    monkeypatch.setattr(F, "_save", keep)
    return figs


def _summary(rates):
    out = []
    for (e, b, m), rate in rates.items():
        out.append({"experiment": e, "bottle": b, "method": m, "trial_success_rate": rate, "trial_success_n": 10,
                    "response_mean_ms": 30.0, "response_sd_ms": 50.0, "response_n": 7,
                    "total_mean_ms": 300.0, "total_sd_ms": 40.0, "total_n": 7})
    return out


def test_success_chart_starts_at_zero_shows_zero_bars_the_papers_values_and_n(captured_figures, tmp_path):
    from slipreflex.analysis import figures as F
    s = _summary({("pour", "TR", "dath"): 1.0, ("pour", "TR", "swt"): 0.0})
    F.success_chart(s, tmp_path / "s.png")
    fig = captured_figures[0]
    ax = fig.axes[0]
    assert ax.get_ylim()[0] == 0 and ax.get_ylim()[1] > 100
    texts = [t.get_text() for t in ax.texts]
    assert "0\n10 trials" in texts and "10 trials" in texts       # the zero bar is labelled, n shown
    assert "per trial (bars), per slip event (dots)" in ax.get_title()
    paper = [ln for ln in ax.get_lines() if ln.get_marker() == "D"]
    assert [tuple(ln.get_ydata()) for ln in paper] == [(100.0,)]   # the paper's "100 %" for DATH pour
    assert fig.legends and not ax.get_legend()


def test_bar_chart_clips_sd_at_zero_and_shows_n(captured_figures, tmp_path):
    from slipreflex.analysis import figures as F
    F.bar_chart(_summary({("drop", "TR", "dath"): 1.0}), "drop", "response", tmp_path / "b.png")
    ax = captured_figures[0].axes[0]
    assert ax.get_ylim()[0] == 0
    lows = [seg[0][1] for coll in ax.collections for seg in coll.get_segments()]
    assert min(lows) >= 0                                          # mean 30, sd 50: the bar stops at 0
    assert "n=7" in [t.get_text() for t in ax.texts]


def test_trial_figure_says_what_happened_keeps_legends_off_the_data_and_zooms_every_axis(captured_figures,
                                                                                         tmp_path):
    import numpy as np

    from slipreflex.analysis import figures as F
    t = np.linspace(0, 30, 9000)
    tp = F.TrialPlot(title="pour TR dath", accel_t=t, accel=np.sin(t), sensor_t=t, sensor=t, event_t=[14.8],
                     cmd_t=[14.8, 15.0], cmd_v=[150, 200], load_t=t, load=t * 500 / 30, onsets=[14.6],
                     responses=[14.8], lasts=[15.0], xlim=(14.3, 15.3),
                     outcome="slip at 14.60 s, detected and caught (response 200 ms)")
    F.plot_trial(tp, tmp_path / "t.png")
    fig = captured_figures[0]
    assert "detected and caught" in fig._suptitle.get_text()
    assert fig.legends and not any(ax.get_legend() for ax in fig.axes)
    volume = fig.axes[0]
    lo, hi = volume.get_ylim()
    assert 14.3 * 500 / 30 - 20 < lo and hi < 15.3 * 500 / 30 + 20   # scaled to the zoom, not 0..500


@pytest.mark.slow
def test_scan_figure_names_its_regions_and_shows_both_thresholds(tmp_path, monkeypatch):
    import matplotlib
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    from slipreflex.cli import main
    kept = []
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig))
    assert main(["scan", "--out", str(tmp_path), "--distance", "50"]) == 0
    fig = kept[-1]
    overview = fig.axes[0]
    names = [t.get_text() for t in overview.texts if not t.get_text().startswith("paper ")]   # + the paper's levels
    assert names == ["stand", "white", "black", "stand"]
    for ax in fig.axes:
        labels = [ln.get_label() for ln in ax.get_lines()]
        if "threshold fixed" in labels:
            fixed, dath = (ax.get_lines()[labels.index(f"threshold {m}")] for m in ("fixed", "dath"))
            assert fixed.get_zorder() > dath.get_zorder() and dath.get_linewidth() > fixed.get_linewidth()
            assert ax.get_legend() is not None and ax.get_legend().get_bbox_to_anchor().y0 < ax.bbox.y0
