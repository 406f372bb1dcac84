"""``slipreflex detect``: outputs, summary, and one-line errors on malformed files."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import slipreflex as sr
from slipreflex.cli import main
from slipreflex.files.csvfiles import read_slip_csv

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "slip_example.csv"


def test_detect_writes_per_sample_and_per_window_csv(tmp_path, capsys):
    assert main(["detect", str(EXAMPLE), "--out", str(tmp_path / "ex"), "--method", "dath"]) == 0
    out = capsys.readouterr().out
    samples = np.genfromtxt(tmp_path / "ex.samples.csv", delimiter=",", names=True)
    windows = np.genfromtxt(tmp_path / "ex.windows.csv", delimiter=",", names=True)
    assert samples.dtype.names == ("t", "x", "threshold", "event")
    assert windows.dtype.names == ("t_end", "v", "command")
    t, raw = read_slip_csv(EXAMPLE)
    res = sr.run_chain(raw, fs=1 / np.median(np.diff(t)), dath=True)
    np.testing.assert_allclose(samples["x"], res.filtered, rtol=1e-12)
    assert samples["event"].sum() == res.events.sum() > 0
    np.testing.assert_array_equal(windows["command"], res.commands)
    np.testing.assert_allclose(windows["t_end"], t[15::16][: res.counts.size])
    assert f"events: {int(res.events.sum())}" in out
    assert f"final command: {res.commands[-1]:g}" in out
    assert "windows with slip:" in out


def test_detect_options_reach_the_chain(tmp_path):
    main(["detect", str(EXAMPLE), "--out", str(tmp_path / "a"), "--method", "fixed"])
    main(["detect", str(EXAMPLE), "--out", str(tmp_path / "b"), "--method", "fixed", "--threshold", "0.02",
          "--no-filter", "--n", "8", "--kp", "1", "--ki", "0"])
    a = np.genfromtxt(tmp_path / "a.windows.csv", delimiter=",", names=True)
    b = np.genfromtxt(tmp_path / "b.windows.csv", delimiter=",", names=True)
    assert (a.size, b.size) == (1000 // 16, 1000 // 8)
    _, raw = read_slip_csv(EXAMPLE)
    expected = sr.run_chain(raw, fs=1000 / 3, filter=False, threshold=0.02, n=8, kp=1.0, ki=0.0)
    np.testing.assert_array_equal(b["command"], expected.commands)


def test_single_column_needs_fs(tmp_path, capsys, monkeypatch):
    p = tmp_path / "in" / "one.csv"
    p.parent.mkdir()
    p.write_text("0.4\n0.41\n0.4\n" * 20)
    monkeypatch.chdir(tmp_path)
    assert main(["detect", str(p)]) == 2
    assert "--fs" in capsys.readouterr().err
    assert main(["detect", str(p), "--fs", "333.33"]) == 0
    # Outputs go to out/detect/NAME under the working directory, never beside the input.
    assert (tmp_path / "out" / "detect" / "one.windows.csv").exists()
    assert sorted(x.name for x in p.parent.iterdir()) == ["one.csv"]


@pytest.mark.slow
@pytest.mark.parametrize("content,needle", [
    ("", "empty"),
    ("t,y\n0,1\n", "line 1: missing column(s) x"),
    ("t,x\n0,0.4\n0.003,abc\n", "line 3: column 'x' is not a number: 'abc'"),
    ("t,x\n0,0.4\n0.003,0.41\n0.003,0.42\n", "line 4: time not increasing"),
    ("t,x\n0,0.4\n0.003\n", "line 3: expected 2 cells"),
    ("t,x\n0,nan\n", "line 2: column 'x' is not finite"),
    ("t,x\n", "no samples"),
])
def test_malformed_files_get_one_line_error_and_no_output(tmp_path, content, needle):
    p = tmp_path / "bad.csv"
    p.write_text(content)
    proc = subprocess.run([sys.executable, "-m", "slipreflex", "detect", str(p)], capture_output=True, text=True)
    assert proc.returncode == 2
    err = proc.stderr.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert str(p) in err and needle in err
    assert sorted(x.name for x in tmp_path.iterdir()) == ["bad.csv"]


def test_unreadable_file(tmp_path, capsys):
    assert main(["detect", str(tmp_path / "missing.csv")]) == 2
    err = capsys.readouterr().err
    assert "missing.csv" in err and "cannot read" in err


def test_bad_parameter_on_command_line_is_a_one_line_error(capsys):
    assert main(["detect", str(EXAMPLE), "--threshold", "-1"]) == 2
    assert "threshold" in capsys.readouterr().err


def _write(path, t, x):
    path.write_text("t,x\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(np.asarray(t).tolist(), np.asarray(x).tolist())))
    return path


def test_detect_on_an_export_reruns_the_run_with_its_p0_and_chain(tmp_path, capsys, monkeypatch):
    """An export's header carries p0 and the chain (docs/runtime.md); detect uses them."""
    import json

    from slipreflex.files.csvfiles import write_columns
    from slipreflex.files.recording import EXPORT_FORMAT
    from slipreflex.methods.chain import ReflexParams
    rng = np.random.default_rng(3)
    n = 1200
    x = 0.4 + np.where((np.arange(n) > 300) & (np.arange(n) < 500), 0.2 * rng.standard_normal(n), 0.0)
    params = ReflexParams(dath=True, p0=147.0)
    write_columns(tmp_path / "run.csv", {"t": (np.arange(n) + 1) * 0.003, "x": x}, preamble={
        "format": EXPORT_FORMAT, "reflex": "dath", "reflex_params": json.dumps(params.to_dict()),
        "p0": json.dumps({"thumb": 148.0, "index": 147.0, "middle": 147.0})})
    expected = sr.run_chain(x, params).commands
    monkeypatch.chdir(tmp_path)
    assert main(["detect", "run.csv"]) == 0
    out = capsys.readouterr().out
    assert "chain and p0 from the file's header" in out and "(p0 147)" in out
    windows = np.genfromtxt(tmp_path / "out" / "detect" / "run.windows.csv", delimiter=",", names=True)
    np.testing.assert_array_equal(windows["command"], expected)
    assert expected.max() > 147
    # An option given on the command line still wins over the header.
    assert main(["detect", "run.csv", "--p0", "0", "--out", "zero/run"]) == 0
    zero = np.genfromtxt(tmp_path / "zero" / "run.windows.csv", delimiter=",", names=True)
    assert zero["command"][0] < 147


def test_detect_warns_on_gaps_and_jitter_naming_the_first_bad_line(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    t = np.arange(200) * 0.003
    t[50:] += 0.003                       # one missing sample: the step ending at sample 50
    t[120] += 0.0008                      # jitter
    p = _write(tmp_path / "gap.csv", t, 0.4 + 0.001 * np.sin(np.arange(200)))
    assert main(["detect", str(p)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert f"{p}, line 52: time step 6 ms where the median is 3 ms (3 such step(s))" in err[0]
    assert "uniform sampling" in err[0]
    _write(tmp_path / "ok.csv", np.arange(200) * 0.003, np.full(200, 0.4))
    assert main(["detect", "ok.csv"]) == 0
    assert capsys.readouterr().err == ""


def test_detect_fs_that_disagrees_with_the_t_column_is_an_error(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    p = _write(tmp_path / "k.csv", np.arange(100) * 0.001, np.full(100, 0.4))
    assert main(["detect", str(p), "--fs", "333.33"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--fs 333.33 disagrees with the t column" in err and "1000.00 Hz" in err
    assert not (tmp_path / "out").exists()
    assert main(["detect", str(p), "--fs", "1000"]) == 0


def test_detect_prints_window_and_dath_lengths_in_ms(tmp_path, capsys, monkeypatch):
    """A 1 kHz file run with the paper's 16 samples: its windows are 16 ms, not 48."""
    monkeypatch.chdir(tmp_path)
    p = _write(tmp_path / "k.csv", np.arange(100) * 0.001, np.full(100, 0.4))
    assert main(["detect", str(p)]) == 0
    assert "windows: 16 samples = 16.0 ms; DATH: 16 samples = 16.0 ms" in capsys.readouterr().out
    assert main(["detect", str(p), "--method", "fixed", "--n", "48"]) == 0
    out = capsys.readouterr().out
    assert "windows: 48 samples = 48.0 ms" in out and "DATH" not in out


def test_detect_reports_the_mpi_saturating_at_500(tmp_path, capsys, monkeypatch):
    """When the command hit 500 and how many slip windows came after."""
    monkeypatch.chdir(tmp_path)
    n = 16 * 40
    x = 0.4 + np.where(np.arange(n) >= 160, 0.05 * np.sin(np.arange(n) * 0.9), 0.0)
    p = _write(tmp_path / "s.csv", np.arange(n) * 0.003, x)
    assert main(["detect", str(p), "--p0", "450", "--no-filter"]) == 0
    out = capsys.readouterr().out
    res = sr.run_chain(x, fs=1 / 0.003, dath=True, p0=450, filter=False)
    z = int(np.argmax(res.commands >= 500))
    assert res.commands[z] == 500 and z > 0
    later = int((res.counts[z + 1:] > 0).sum())
    assert later > 0
    assert (f"saturated: the command reached 500 (fully closed) at t = {(z + 1) * 16 * 0.003 - 0.003:.3f} s, "
            f"window {z}; {later} later window(s) with slip could not raise it") in out
    assert main(["detect", str(p), "--p0", "0", "--no-filter", "--ki", "0", "--kp", "0.1"]) == 0
    assert "saturated" not in capsys.readouterr().out


def test_detect_header_with_broken_reflex_params_is_one_line(tmp_path, capsys):
    p = tmp_path / "h.csv"
    p.write_text('# reflex_params: {"thresh": 1}\nt,x\n0,0.4\n0.003,0.4\n')
    assert main(["detect", str(p)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{p}: header line 'reflex_params': unknown reflex parameter(s): thresh" in err
