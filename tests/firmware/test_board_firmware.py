"""The reflex on the microcontroller, end to end under simavr.

The firmware built with the reflex on board (ATmega328P, version-2 frames) and the
standalone ATmega2560 build (i-Limb CLOSE and STOP packets on UART1: grip only added)
run in firmware/test/harness.c; firmware/test/check_board.py compares every frame and
every hand packet with the Python twin (slipreflex.methods.board) and checks the packets'
latency and the closings' length; the wrong-rounding build is the negative control.
Needs the same tools as tests/firmware/test_firmware.py (scripts/bootstrap.sh installs them).
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from slipreflex.cli import main as cli_main
from slipreflex.core import hardware
from slipreflex.methods import board
from slipreflex.rig.devices import ilimb, wire

ROOT = Path(__file__).resolve().parents[2]
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
                                      "hand2560.elf", "hand2560-wrong-rounding.elf", "harness")]
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


slip_like = board_sim.slip_like


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


def _mega(build_dir: Path, adc, out: Path) -> Path:
    """Run hand2560.elf from ``build_dir`` on the counts ``adc``; return the capture dir."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "adc.txt").write_text("\n".join(map(str, adc)))
    return _harness(build_dir, "hand2560.elf", out / "cap", len(adc) * 0.003 + 0.01,
                    "--mcu", "atmega2560", "--adc", str(out / "adc.txt"))


def _raw_commands(data: bytes) -> set[int]:
    """The command byte of every finger in every 15-byte tripod packet, read without a parser."""
    size = 3 + 4 * len(hardware.TRIPOD)
    return {data[k + 3 + 4 * f] for k in range(0, len(data) - size + 1, size)
            for f in range(len(hardware.TRIPOD))}


@pytest.mark.slow
def test_standalone_mega_drives_the_hand(build, tmp_path):
    """ATmega2560: injected slip-like signal with a sensor fault and a stuck converter.
    Every packet is CLOSE (full PWM) or STOP for the tripod, the twin's, at the twin's
    sample, under 1 ms after it; each closing lasts its grip's g / 625 s rounded up to
    whole 3 ms samples; a rise while closing makes the closing longer (seed 4 has a
    closing that four windows' rises make longer)."""
    adc = slip_like(4, 6000)
    out = _mega(build, adc, tmp_path)
    assert check_capture.check(out).ok
    rep = check_board.check(out)
    assert rep.ok, rep.summary()
    assert rep.faults >= 40 + 100
    kinds = [c for _, c in rep.packets]
    assert kinds.count("CLOSE") >= 4 and set(kinds) == {"CLOSE", "STOP"}
    assert all(a != b or a == "STOP" for a, b in zip(kinds, kinds[1:]))   # never CLOSE twice
    assert _raw_commands((out / "uart1.bin").read_bytes()) == {0, 1}      # STOP, CLOSE only
    assert max(rep.latencies) < hardware.F_CPU // 1000        # under 1 ms, in CPU cycles
    res = board.run_board_chain(adc, board.BoardParams.firmware())
    trace = board.board_hand(res)
    assert [(k, c.name) for k, c in trace.packets[1:]] == rep.packets
    for k, kind in rep.packets:
        if kind == "CLOSE":                                   # a good reading that owes grip
            assert not res.faults[k] and trace.left[k] > 0
        else:                                                 # time up, or a fault starts
            assert trace.left[k] == 0 or (res.faults[k] and not res.faults[k - 1])
    # Closings measured from the UART1 bytes: g / 625 s, rounded up to whole samples.
    assert len(rep.closings) >= 4
    for g, got, exact in rep.closings:
        samples = -(-8 * g // 15)
        assert abs(got - samples * 48000) < check_board.CLOSING_JITTER_CYCLES
        assert got > exact - check_board.CLOSING_JITTER_CYCLES and samples * 48000 - exact < 48000
    # At least one closing was extended by a rise that came while the fingers closed.
    windows_in = [int(np.count_nonzero(trace.rises[c:s])) for (c, kc), (s, _) in
                  zip(rep.packets, rep.packets[1:]) if kc == "CLOSE"]
    assert max(windows_in) >= 2, windows_in


@pytest.mark.slow
def test_negative_control_hand_rounded_down_is_rejected(build, tmp_path):
    """A firmware whose closings are rounded down to whole samples (STOP one sample early
    whenever g is not a multiple of 15/8) sends the right kinds of packet, but not at the
    twin's samples: the checker says so."""
    adc = slip_like(4, 6000)
    good = check_board.check(_mega(build, adc, tmp_path / "good"))
    assert good.ok, good.summary()
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "adc.txt").write_text("\n".join(map(str, adc)))
    out = _harness(build, "hand2560-wrong-rounding.elf", tmp_path / "bad" / "cap",
                   len(adc) * 0.003 + 0.01, "--mcu", "atmega2560", "--adc",
                   str(tmp_path / "bad" / "adc.txt"))
    rep = check_board.check(out)
    assert not rep.ok
    assert any("frames flagged HAND" in e or "not g / 625 s" in e for e in rep.errors), rep.errors


@pytest.mark.slow
def test_mega_fault_during_closing_stops_and_resumes(build, tmp_path):
    """A sensor unplugged while the fingers close: STOP at its first reading, the rest of
    the closing owed and sent (CLOSE) at the next good reading, STOP when it is done."""
    adc = slip_like(1, 6000)
    trace = board.board_hand(board.run_board_chain(adc, board.BoardParams.firmware()))
    (c, _), (s, _) = next((a, b) for a, b in zip(trace.packets, trace.packets[1:])
                          if a[1] == hardware.HandCommand.CLOSE and b[0] - a[0] >= 16)
    adc = adc.copy()
    adc[c + 4:c + 9] = 2                                       # unplugged for 15 ms
    out = _mega(build, adc, tmp_path)
    rep = check_board.check(out)
    assert rep.ok, rep.summary()
    got = [p for p in rep.packets if c <= p[0] <= s + 10]
    assert got[:3] == [(c, "CLOSE"), (c + 4, "STOP"), (c + 9, "CLOSE")], got
    # The whole closing still gets its time: the cut part is owed, not lost.
    assert got[3][1] == "STOP" and got[3][0] - (c + 9) + 4 == s - c, (got, s)


def _after_restart(out: Path, dest: Path) -> int:
    """Copy the part of a capture after the firmware's (first) restart into ``dest``, as
    a capture of its own; return the restart's cycle."""
    lines = (out / "events.txt").read_text().splitlines()
    restart = next(int(ln.split()[1]) for ln in lines if ln.startswith("R "))
    dest.mkdir()
    (dest / "events.txt").write_text("\n".join(ln for ln in lines if ln[0] in "AX" and
                                              int(ln.split()[1]) >= restart) + "\n")
    for name in ("uart", "uart1"):
        data = (out / f"{name}.bin").read_bytes()
        cyc = np.fromfile(out / f"{name}_cycles.bin", dtype="<u8")
        keep = cyc >= restart
        (dest / f"{name}.bin").write_bytes(bytes(np.frombuffer(data, dtype=np.uint8)[keep]))
        cyc[keep].astype("<u8").tofile(dest / f"{name}_cycles.bin")
    return restart


@pytest.mark.slow
def test_mega_watchdog_reset_while_closing_sends_stop_and_resumes(build, tmp_path):
    """The sample clock stops in the middle of a closing (a hung interrupt): no more
    samples, the watchdog resets the board 60 ms later, and the restarted firmware sends
    STOP before its first sample (the closing the hang left running ends there; never
    OPEN). Its MPI resumes from the grip already added (the level kept in .noinit), so
    after the reset the board is exactly the twin started at that level."""
    adc = slip_like(4, 6000)
    trace = board.board_hand(board.run_board_chain(adc, board.BoardParams.firmware()))
    (c, _), (s, _) = next((a, b) for a, b in zip(trace.packets, trace.packets[1:])
                          if a[1] == hardware.HandCommand.CLOSE and b[0] - a[0] >= 20)
    res = board.run_board_chain(adc, board.BoardParams.firmware())
    level = int(res.commands[(c + 1) // 16 - 1])             # the command that rose at c
    (tmp_path / "adc.txt").write_text("\n".join(map(str, adc)))
    stall_s = (c + 5.5) * hardware.DAQ_PERIOD_S               # between samples c+5 and c+6
    out = _harness(build, "hand2560.elf", tmp_path / "cap", len(adc) * 0.003 + 0.01, "--mcu",
                   "atmega2560", "--adc", str(tmp_path / "adc.txt"), "--stall-at", f"{stall_s:.6f}")
    events = (out / "events.txt").read_text().splitlines()
    stall = next(int(ln.split()[1]) for ln in events if ln.startswith("S "))
    restart = _after_restart(out, tmp_path / "after")
    assert 0.055 < (restart - stall) / hardware.F_CPU < 0.07          # the 60 ms watchdog
    data = (out / "uart1.bin").read_bytes()
    cyc = np.fromfile(out / "uart1_cycles.bin", dtype="<u8")
    packets = ilimb.PacketParser().feed(data)
    kinds = [(int(cyc[15 * j]), p[0].command) for j, p in enumerate(packets)]
    before = [k for t, k in kinds if t < restart]
    after = [(t, k) for t, k in kinds if t >= restart]
    assert before[-1] == hardware.HandCommand.CLOSE                     # closing when it hung
    first_sample = min(int(ln.split()[1]) for ln in events if ln.startswith("A ")
                       and int(ln.split()[1]) > restart)
    assert after[0][1] == hardware.HandCommand.STOP and after[0][0] < first_sample
    assert _raw_commands(data) <= {0, 1}
    # After the reset: the twin with p0 = the level, on the readings the board took then.
    rep = check_board.check(tmp_path / "after", p0=level)
    assert rep.ok, rep.summary()
    frames = wire.FrameParser().feed((tmp_path / "after" / "uart.bin").read_bytes())
    assert frames[0].seq == 0 and frames[0].reflex.command == level > 0


@pytest.mark.slow
def test_mega_never_opens_on_simulated_drop_and_pour(tmp_path, tools):
    """The standalone firmware on the slip-sensor counts of a whole simulated drop and a
    whole simulated pour (the simulator's closed loop with the board's twin, TX bottle),
    built with the grasp's p0: every byte on UART1 is in a CLOSE or a STOP packet, never
    an OPEN or a POSITION, and the packets are the twin's."""
    tools("make", "cc", "avr-gcc", "avr-libc", "simavr")
    from slipreflex.reproduce.experiments import ReproduceConfig, trial_seed
    from slipreflex.sim import Rig, run_closed_loop

    config = ReproduceConfig()
    for exp in ("drop", "pour"):
        rig = Rig("TX", seed=trial_seed(config.seed, exp, "TX", 0))
        p0 = int(round(rig.grasp().positions[hardware.SLIP_FINGER]))
        params = board.BoardParams.firmware(p0=p0)
        rig.perturb(config.pour if exp == "pour" else config.drop, at=rig.t + config.rest_s)
        tr = run_closed_loop(rig, board.BoardReflex(params), config.duration(exp))
        adc = [board.adc_counts(v) for v in tr.volts.tolist()]
        bdir = tmp_path / f"build-p0{p0}"
        if not (bdir / "hand2560.elf").exists():
            proc = subprocess.run(["make", "-C", str(FIRMWARE), f"BUILD={bdir}", f"REFLEX_P0={p0}",
                                   f"{bdir}/hand2560.elf", f"{bdir}/harness"],
                                  capture_output=True, text=True)
            assert proc.returncode == 0, proc.stdout + proc.stderr
        out = _mega(bdir, adc, tmp_path / exp)
        rep = check_board.check(out, p0=p0)
        assert rep.ok, (exp, rep.summary())
        assert rep.samples >= len(adc)
        codes = {c for cmds in rep.hand_commands for c in cmds}
        assert codes == {hardware.HandCommand.STOP, hardware.HandCommand.CLOSE}, (exp, codes)
        assert _raw_commands((out / "uart1.bin").read_bytes()) == {0, 1}
        assert hardware.HandCommand.OPEN not in codes and hardware.HandCommand.POSITION not in codes
        assert sum(c == "CLOSE" for _, c in rep.packets) >= 1        # the reflex did act


@pytest.mark.slow
def test_negative_control_wrong_rounding_is_rejected_under_simavr(build, tmp_path):
    out = _harness(build, "daq-reflex-wrong-rounding.elf", tmp_path, 3)
    assert check_capture.check(out).ok                # the DAQ itself is fine ...
    rep = check_board.check(out)
    assert not rep.ok                                 # ... its chain is not the twin's
    assert any("filtered sample differs" in e for e in rep.errors), rep.errors


@pytest.mark.slow
@pytest.mark.parametrize("damage", ["hand_byte", "hand_open", "hand_position", "hand_late_stop",
                                    "hand_dropped", "frame_command"])
def test_checker_rejects_damaged_captures(build, tmp_path, damage):
    adc = slip_like(2, 3000)
    out = _mega(build, adc, tmp_path)
    good = check_board.check(out)
    assert good.ok and good.packets[0][1] == "CLOSE" and good.packets[1][1] == "STOP"
    if damage == "hand_byte":         # the first CLOSE's PWM one lower (packet 0 is the start's STOP)
        data = bytearray((out / "uart1.bin").read_bytes())
        data[15 + 5] -= 1
        (out / "uart1.bin").write_bytes(bytes(data))
    elif damage in ("hand_open", "hand_position"):   # the first CLOSE made an OPEN or a POSITION
        data = bytearray((out / "uart1.bin").read_bytes())
        for f in range(3):
            data[15 + 3 + 4 * f] = 2 if damage == "hand_open" else 3
        (out / "uart1.bin").write_bytes(bytes(data))
    elif damage == "hand_late_stop":  # the first STOP one sample later: the closing too long
        cyc = np.fromfile(out / "uart1_cycles.bin", dtype="<u8")
        cyc[30:] += 48000
        cyc.astype("<u8").tofile(out / "uart1_cycles.bin")
    elif damage == "hand_dropped":    # the second packet never left
        data = (out / "uart1.bin").read_bytes()
        cyc = np.fromfile(out / "uart1_cycles.bin", dtype="<u8")
        (out / "uart1.bin").write_bytes(data[:15] + data[30:])
        np.r_[cyc[:15], cyc[30:]].astype("<u8").tofile(out / "uart1_cycles.bin")
    else:                             # one frame claims another command (CRC fixed up)
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
