"""The host side of the reflex on the board: ``run --board-reflex`` checks the board live
against its Python twin and records it; ``replay`` covers such recordings.

The board's bytes are the real firmware's: daq-reflex.elf (and its wrong-rounding
negative control) run under simavr, their UART bytes fed to the real-time loop through
a pyserial ``loop://`` port.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest
import serial

from slipreflex.cli import main
from slipreflex.core import hardware as hw
from slipreflex.files.recording import METADATA_NAME, Recorder, read_recording
from slipreflex.methods import board
from slipreflex.rig.devices import wire
from slipreflex.rig.devices.daq import SerialDaq
from slipreflex.rig.replay import replay
from slipreflex.rig.runtime import run_loop

ROOT = Path(__file__).resolve().parents[2]
FIRMWARE = ROOT / "firmware"
SECONDS = 1.5


class Hand:
    def __init__(self):
        self.pos = {f: 0.0 for f in hw.TRIPOD}
        self.sent = []

    def set_positions(self, targets):
        self.sent.append(dict(targets))
        self.pos.update(targets)

    def close_fingers(self, fingers, speed):
        self.sent.append(("close", tuple(fingers)))

    def positions(self):
        return dict(self.pos)

    def hold(self, fingers):
        pass


@pytest.fixture(scope="module")
def captures(tmp_path_factory, tools):
    """UART bytes of the reflex firmware and of its wrong-rounding build, 1.5 s each."""
    tools("make", "cc", "avr-gcc", "avr-libc", "simavr")
    root = tmp_path_factory.mktemp("host")
    build = root / "build"
    elves = ["daq-reflex.elf", "daq-reflex-wrong-rounding.elf"]
    proc = subprocess.run(["make", "-C", str(FIRMWARE), f"BUILD={build}",
                           *(f"{build}/{e}" for e in elves), f"{build}/harness"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    out = {}
    for elf in elves:
        d = root / elf
        d.mkdir()
        run = subprocess.run([str(build / "harness"), str(build / elf), str(d), str(SECONDS)],
                             capture_output=True, text=True)
        assert run.returncode == 0, run.stdout + run.stderr
        out[elf] = (d / "uart.bin").read_bytes()
    return out


def _run(data: bytes, path: Path | None):
    """The loop over a board that sent ``data``; returns (result, twin, hand)."""
    port = serial.serial_for_url("loop://", timeout=0, do_not_open=True)
    port.buffer_size = len(data) + 1          # the whole capture fits (default 4096 bytes)
    port.open()
    port.write(data)
    params = board.BoardParams.firmware()
    twin = board.CheckedBoardReflex(params)
    hand = Hand()
    rec = None
    if path is not None:
        meta = {"board_params": json.dumps(params.to_dict()), "reflex": twin.name}
        rec = Recorder(path, metadata={METADATA_NAME: meta})
    with SerialDaq(port) as daq:
        res = run_loop(board.BoardSource(daq, twin), hand, twin, p0=100.0, recorder=rec,
                       duration=0.6, watchdog=0.5, guard=False)
    if rec is not None:
        rec.close()
    port.close()
    return res, twin, hand


@pytest.mark.slow
def test_live_check_of_the_real_firmware_finds_no_mismatch_and_records_it(captures, tmp_path):
    data = captures["daq-reflex.elf"]
    n = len(data) // wire.FRAME_LEN_REFLEX
    res, twin, hand = _run(data, tmp_path / "board.mcap")
    assert twin.checked == n == res.samples and twin.mismatches == 0
    assert not [f for f in res.faults if f.kind == "board-mismatch"]
    rec = read_recording(tmp_path / "board.mcap")
    state = rec.topic("/board/state")
    assert len(state) == n and all(m["match"] for m in state)
    assert sum(m["spike"] for m in state) == res.events > 50 and any(m["fault"] for m in state)
    # the commands the loop used are the board's own
    board_cmds = [m["command"] for m in state if m["window"]]
    assert [m["target"] for m in rec.topic("/hand/commands")] == board_cmds
    # replay: the twin again, against both the loop's record and the board's own output
    rp = replay(tmp_path / "board.mcap")
    assert rp.identical and rp.board_events == rp.replayed_events
    assert rp.board_commands == rp.replayed_commands and len(rp.board_commands) == n // 16
    assert "board commands" in rp.summary()


@pytest.mark.slow
def test_a_board_with_the_wrong_rounding_is_a_recorded_fault(captures, tmp_path):
    res, twin, _ = _run(captures["daq-reflex-wrong-rounding.elf"], tmp_path / "bad.mcap")
    bad = [f for f in res.faults if f.kind == "board-mismatch"]
    assert bad and twin.mismatches > 0
    assert bad[0].message.startswith("seq 1: the board says x=")    # first difference: the filter
    faults = read_recording(tmp_path / "bad.mcap").topic("/faults")
    assert any(f["kind"] == "board-mismatch" for f in faults)


@pytest.mark.slow
def test_one_corrupted_command_is_caught_and_replay_shows_it(captures, tmp_path):
    frames = wire.FrameParser().feed(captures["daq-reflex.elf"])
    k = next(i for i, f in enumerate(frames) if f.reflex.window and i > 100)
    f = frames[k]
    forged = wire.ReflexFields(f.reflex.bits, f.reflex.v, f.reflex.command + 1, f.reflex.x)
    raw = b"".join(wire.encode_frame(g.seq, g.adc, g.accel if g.accel_fresh else None, g.flow_pulses,
                                     g.flags & ~wire.FLAG_ACCEL_FRESH,
                                     reflex=forged if i == k else g.reflex)
                   for i, g in enumerate(frames))
    res, twin, _ = _run(raw, tmp_path / "forged.mcap")
    bad = [x for x in res.faults if x.kind == "board-mismatch"]
    assert len(bad) == 1 and twin.mismatches == 1
    assert bad[0].message == (f"seq {f.seq}: the board says command={f.reflex.command + 1}, "
                              f"the twin command={f.reflex.command}")
    rp = replay(tmp_path / "forged.mcap")
    assert not rp.identical and "board commands" in rp.summary() and "DIFFERENT" in rp.summary()


@pytest.mark.slow
def test_a_version_1_board_is_named(tmp_path):
    data = b"".join(wire.encode_frame(seq=k, adc=300) for k in range(40))
    res, twin, _ = _run(data, None)
    bad = [f for f in res.faults if f.kind == "board-mismatch"]
    assert len(bad) == 1 and "version-1 frame" in bad[0].message and twin.mismatches == 40


def test_cli_board_reflex_refuses_chain_options_before_opening_ports(capsys):
    assert main(["run", "--daq", "loop://", "--hand", "loop://", "--p0", "100", "--board-reflex",
                 "--kp", "3", "--no-record"]) == 2
    assert "--kp cannot be changed with --board-reflex" in capsys.readouterr().err
