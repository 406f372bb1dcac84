"""The reflex on the microcontroller, end to end under simavr.

The firmware built with the reflex on board (ATmega328P, version-2 frames) and the
standalone ATmega2560 build (i-Limb packets on UART1) run in firmware/test/harness.c;
firmware/test/check_board.py compares every frame with the Python twin and checks the
hand packets and their latency; the wrong-rounding build is the negative control.
Needs the same tools as tests/test_firmware.py (scripts/bootstrap.sh installs them).
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from slipreflex import board, hardware
from slipreflex.cli import main as cli_main

ROOT = Path(__file__).resolve().parents[1]
FIRMWARE = ROOT / "firmware"


def _load(name: str):
    spec = importlib.util.spec_from_file_location(f"slipreflex_fw_{name}", FIRMWARE / "test" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


check_board = _load("check_board")
check_capture = _load("check_capture")
board_sim = _load("board_sim")
gen = _load("gen_board_vectors")


@pytest.fixture(scope="module")
def build(tmp_path_factory, tools):
    tools("make", "cc", "avr-gcc", "avr-libc", "simavr")
    out = tmp_path_factory.mktemp("fwb") / "build"
    targets = [f"{out}/{t}" for t in ("daq-reflex.elf", "daq-reflex-wrong-rounding.elf",
                                      "hand2560.elf", "harness")]
    proc = subprocess.run(["make", "-C", str(FIRMWARE), f"BUILD={out}", *targets],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out


def _harness(build_dir: Path, elf: str, outdir: Path, seconds: float, *args: str) -> Path:
    outdir.mkdir(parents=True, exist_ok=True)
    proc = subprocess.run([str(build_dir / "harness"), str(build_dir / elf), str(outdir),
                           str(seconds), *args], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return outdir


def slip_like(seed: int, k: int) -> np.ndarray:
    """Counts like the slip sensor's: a level, quiet stretches, slips (fast texture),
    a disconnected sensor (near 0 V) and a stuck converter (identical readings)."""
    rng = np.random.default_rng(seed)
    x = 300 + np.cumsum(rng.normal(0, 0.3, k))
    for start in range(400, k - 200, 900):          # slips: texture at 30-60 Hz
        n = int(rng.integers(80, 200))
        x[start:start + n] += rng.uniform(3, 12) * np.sin(np.arange(n) * rng.uniform(0.6, 1.2))
    adc = np.clip(np.round(x + rng.normal(0, 0.6, k)), 0, 1023).astype(int)
    adc[k // 3:k // 3 + 40] = 2                       # sensor unplugged for 120 ms
    adc[2 * k // 3:2 * k // 3 + 1100] = adc[2 * k // 3 - 1]   # stuck for 3.3 s
    return adc


def test_reflex_config_header_is_the_twins():
    assert (FIRMWARE / "reflex" / "reflex_config.h").read_text() == gen.config_header()


@pytest.mark.slow
def test_board_reflex_equals_twin_on_every_sample(build, tmp_path):
    """Random full-range readings (every conversion, 10 s): the DAQ part is as clean as
    the plain firmware's and every frame carries the twin's chain output."""
    out = _harness(build, "daq-reflex.elf", tmp_path, 10)
    cap = check_capture.check(out)
    assert cap.ok, cap.summary()
    rep = check_board.check(out)
    assert rep.ok, rep.summary()
    assert rep.samples >= 3330 and rep.windows >= 208 and rep.spikes > 1000 and rep.faults > 10
    assert cap.busy_share < 0.15                      # DAQ + chain within the budget


@pytest.mark.slow
def test_standalone_mega_drives_the_hand(build, tmp_path):
    """ATmega2560: injected slip-like signal with a sensor fault and a stuck converter;
    the hand packets are valid, carry the rising commands, none during a fault, and leave
    within 1 ms of the sample that completes the window."""
    adc = slip_like(1, 6000)
    (tmp_path / "adc.txt").write_text("\n".join(map(str, adc)))
    out = _harness(build, "hand2560.elf", tmp_path / "cap", len(adc) * 0.003 + 0.01,
                   "--mcu", "atmega2560", "--adc", str(tmp_path / "adc.txt"))
    assert check_capture.check(out).ok
    rep = check_board.check(out)
    assert rep.ok, rep.summary()
    assert len(rep.packets) >= 4 and rep.faults >= 40 + 100
    positions = [p for _, p in rep.packets]
    assert positions == sorted(set(positions)) and positions[-1] <= hardware.FINGER_MAX
    assert max(rep.latencies) < hardware.F_CPU // 1000        # under 1 ms, in CPU cycles
    # Each packet went out at a window the twin says rose, on a good reading.
    res = board.run_board_chain(adc, board.BoardParams.firmware())
    for sample, pos in rep.packets:
        assert not res.faults[sample] and (sample + 1) % 16 == 0
        assert pos == res.commands[(sample + 1) // 16 - 1]


@pytest.mark.slow
def test_negative_control_wrong_rounding_is_rejected_under_simavr(build, tmp_path):
    out = _harness(build, "daq-reflex-wrong-rounding.elf", tmp_path, 3)
    assert check_capture.check(out).ok                # the DAQ itself is fine ...
    rep = check_board.check(out)
    assert not rep.ok                                 # ... its chain is not the twin's
    assert any("filtered sample differs" in e for e in rep.errors), rep.errors


@pytest.mark.slow
@pytest.mark.parametrize("damage", ["hand_byte", "hand_dropped", "frame_command"])
def test_checker_rejects_damaged_captures(build, tmp_path, damage):
    adc = slip_like(2, 3000)
    (tmp_path / "adc.txt").write_text("\n".join(map(str, adc)))
    out = _harness(build, "hand2560.elf", tmp_path / "cap", len(adc) * 0.003 + 0.01,
                   "--mcu", "atmega2560", "--adc", str(tmp_path / "adc.txt"))
    assert check_board.check(out).ok
    if damage == "hand_byte":         # a position one unit lower in the second packet
        data = bytearray((out / "uart1.bin").read_bytes())
        data[15 + 5] -= 1
        (out / "uart1.bin").write_bytes(bytes(data))
    elif damage == "hand_dropped":    # the second packet never left
        data = (out / "uart1.bin").read_bytes()
        cyc = np.fromfile(out / "uart1_cycles.bin", dtype="<u8")
        (out / "uart1.bin").write_bytes(data[:15] + data[30:])
        np.r_[cyc[:15], cyc[30:]].astype("<u8").tofile(out / "uart1_cycles.bin")
    else:                             # one frame claims another command (CRC fixed up)
        from slipreflex.devices import wire
        data = bytearray((out / "uart.bin").read_bytes())
        k = 100 * wire.FRAME_LEN_REFLEX
        data[k + 20] ^= 1
        crc = wire.crc16(bytes(data[k + 2:k + 26]))
        data[k + 26:k + 28] = crc.to_bytes(2, "big")
        (out / "uart.bin").write_bytes(bytes(data))
    rep = check_board.check(out)
    assert not rep.ok, rep.summary()


@pytest.mark.slow
@pytest.mark.needs_tools("make", "cc", "avr-gcc", "avr-libc", "simavr")
def test_runner_and_detect_board_write_the_same_files(tmp_path, capsys):
    """Item 5: the simavr runner on a CSV of counts and `detect --board` on the same file."""
    adc = slip_like(3, 1500)
    csv = tmp_path / "adc.csv"
    csv.write_text("adc\n" + "\n".join(map(str, adc)) + "\n")
    assert board_sim.main([str(csv), str(tmp_path / "board.csv"), "--p0", "120"]) == 0
    assert cli_main(["detect", "--board", "--method", "fixed", "--p0", "120", str(csv),
                     "--out", str(tmp_path / "twin")]) == 0
    for part in ("samples", "windows"):
        got = (tmp_path / f"board.{part}.csv").read_text()
        assert got == (tmp_path / f"twin.{part}.csv").read_text()
    windows = (tmp_path / "board.windows.csv").read_text().splitlines()
    assert windows[0] == "window,v,command" and len(windows) == 1 + len(adc) // 16
    assert windows[1].endswith(",120")                # p0 reached the firmware build
    assert "1500 samples through the board" in capsys.readouterr().out


def test_detect_board_rejects_bad_input(tmp_path, capsys):
    csv = tmp_path / "bad.csv"
    csv.write_text("adc\n300\n1024\n")
    assert cli_main(["detect", "--board", str(csv)]) == 2
    assert "line 3: column 'adc' is not a count 0..1023: '1024'" in capsys.readouterr().err
