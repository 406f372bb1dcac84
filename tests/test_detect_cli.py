"""``slipreflex detect``: outputs, summary, and one-line errors on malformed files."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import slipreflex as sr
from slipreflex.cli import main
from slipreflex.csvfiles import read_slip_csv

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "slip_example.csv"


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


def test_single_column_needs_fs(tmp_path, capsys):
    p = tmp_path / "one.csv"
    p.write_text("0.4\n0.41\n0.4\n" * 20)
    assert main(["detect", str(p)]) == 2
    assert "--fs" in capsys.readouterr().err
    assert main(["detect", str(p), "--fs", "333.33"]) == 0
    assert (tmp_path / "one.windows.csv").exists()


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
