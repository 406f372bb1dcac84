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
