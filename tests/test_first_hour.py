"""A new user's first hour (issue 11): the steps after set-up that the README promises."""

import os
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from stk500_standin import Bootloader, read_hex  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def _flash(board: Bootloader, build: Path) -> subprocess.CompletedProcess:
    return subprocess.run(["make", "-C", str(ROOT / "firmware"), "flash", f"BUILD={build}", f"PORT={board.port}"],
                          capture_output=True, text=True, timeout=300)


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
    _one_line_exit_2(capsys, ["virtual-rig", "--link-dir", "/proc/nope", "--duration", "0"],
                     "--link-dir /proc/nope", "cannot create the directory")
    (tmp_path / "f").write_text("x")
    _one_line_exit_2(capsys, ["virtual-rig", "--link-dir", str(tmp_path / "f"), "--duration", "0"],
                     f"--link-dir {tmp_path / 'f'}: is a file, not a directory")
    _one_line_exit_2(capsys, ["virtual-rig", "--link-dir", str(tmp_path / "f" / "sub"), "--duration", "0"],
                     "--link-dir", "Not a directory")


def test_output_dir_creates_and_proves_writable(tmp_path):
    from slipreflex.errors import ParameterError
    from slipreflex.paths import output_dir
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
    from slipreflex.errors import DataError
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

    from slipreflex.progress import Progress
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

    from slipreflex.progress import Progress
    term = io.StringIO()
    with Progress(10, desc="trials", file=term, tty=True) as p:
        p.update(10)
    assert "\r" in term.getvalue() and "10/10" in term.getvalue()
