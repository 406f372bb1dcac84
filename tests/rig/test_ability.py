"""The PSYONIC Ability Hand: its published UART protocol, the driver, and the virtual hand on a pty."""

from __future__ import annotations

import re
import threading

import numpy as np
import pytest
import serial

from slipreflex.core.errors import DataError, DeviceError, ParameterError
from slipreflex.core.hardware import Finger
from slipreflex.core.interfaces import Hand, TactileSource
from slipreflex.rig.devices import ability as ab
from slipreflex.rig.devices.simrig import SimRig
from slipreflex.rig.devices.virtual import VirtualDevices
from slipreflex.rig.hands import get_hand, open_hand


def test_frames_follow_the_icd_byte_for_byte():
    # position command: address, header 0x10, six int16 LE of deg * 32767 / 150, checksum, stuffed
    frame = ab.encode_positions([15.0, 0, 0, 0, 0, -15.0])
    body = ab.unstuff(frame)[0]
    assert body[:2] == b"\x50\x10" and len(body) == 15 and sum(body) % 256 == 0
    assert int.from_bytes(body[2:4], "little", signed=True) == round(15 * 32767 / 150)
    assert int.from_bytes(body[12:14], "little", signed=True) == -round(15 * 32767 / 150)
    # stuffing: 0x7E and 0x7D inside a frame are escaped, and unstuffing restores them
    payload = bytes(range(0x70, 0x80))
    assert ab.unstuff(b"\x00\x7e" + ab.stuff(payload)[1:]) == [payload]
    assert ab.stuff(payload).count(0x7E) == 2
    # reply: 12-bit touch values two per three bytes, all 4096 values round-trip
    touch = list(range(0, 4096, 137))[:30]
    reply = ab.decode_reply(ab.unstuff(ab.encode_reply([1.0] * 6, [5] * 6, touch, status=3))[0])
    assert list(reply.touch) == touch and reply.currents == (5,) * 6 and reply.status == 3
    assert ab.touch_counts(ab.touch_newtons(np.arange(4096))).tolist() == list(range(4096))
    bad = bytearray(ab.unstuff(ab.encode_reply([0.0] * 6))[0])
    bad[30] ^= 1
    with pytest.raises(DataError, match="checksum"):
        ab.decode_reply(bytes(bad))
    with pytest.raises(ParameterError, match="6 angles"):
        ab.encode_positions([200.0] * 6)


def _virtual(tmp_path, pour=None, drop=None, **kw):
    rig = SimRig("TR", seed=3, pour=pour, drop=drop)
    grasp = rig.grasp()
    return VirtualDevices(rig, hand_type="ability", link_dir=str(tmp_path), **kw), grasp


@pytest.mark.slow
def test_driver_against_the_virtual_hand_positions_commands_and_touch(tmp_path):
    dev, grasp = _virtual(tmp_path)
    with dev:
        with open_hand("ability", dev.hand_path, fs=260.0) as hand:
            assert isinstance(hand, Hand) and isinstance(hand, TactileSource) and hand.shape == (6,)
            measured = hand.positions()
            # the first reply carries the grasp: the tripod where the sim's grasp left it
            for f in (Finger.THUMB, Finger.INDEX, Finger.MIDDLE):
                assert measured[f] == pytest.approx(grasp.positions[f], abs=0.05)
            frames = []
            for _ in range(200):
                frames += hand.read_frames(0.01)
                if len(frames) >= 40:
                    break
            assert len(frames) >= 40
            assert [s.seq for s in frames] == list(range(frames[0].seq, frames[0].seq + len(frames)))
            assert all(b.t >= a.t for a, b in zip(frames, frames[1:]))
            touched = np.array([s.frame for s in frames])
            assert touched.shape[1:] == (6,) and (touched > ab.touch_newtons([1])[0]).any()
            # a command moves the named finger only; the others stay at their measured position
            hand.set_positions({Finger.MIDDLE: grasp.positions[Finger.MIDDLE] + 10})
            for _ in range(100):
                hand.read_frames(0.01)
                if hand.positions()[Finger.MIDDLE] > grasp.positions[Finger.MIDDLE] + 5:
                    break
            now = hand.positions()
            assert now[Finger.MIDDLE] > grasp.positions[Finger.MIDDLE] + 5
            assert now[Finger.INDEX] == pytest.approx(grasp.positions[Finger.INDEX], abs=1.0)
            with pytest.raises(ParameterError, match="0..500"):
                hand.set_positions({Finger.INDEX: 600})
            with pytest.raises(ParameterError, match="no wrist"):
                hand.set_positions({Finger.WRIST: 10})
    assert dev.emulator.commands > 40 and dev.emulator.rejected == 0


def test_a_silent_port_is_one_line_naming_it():
    loop = serial.serial_for_url("loop://", timeout=0)  # echoes the request back: no reply frame
    with pytest.raises(DeviceError, match="no reply from an Ability Hand"):
        ab.AbilityHand(loop, reply_timeout=0.05)
    assert get_hand("ability").tactile and not get_hand("ilimb").tactile


def _rest_threshold(dev, seconds=1.0):
    """NMSD's threshold from the virtual hand's touch sites at rest, as a lab calibrates it."""
    import time

    from slipreflex.methods.baselines import rest_threshold

    frames = []
    with open_hand("ability", dev.hand_path, fs=260.0) as hand:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            frames += [s.frame for s in hand.read_frames(0.01)]
    return rest_threshold(np.array(frames), "nmsd", 260.0)


def _drop_after(dev, commands, timeout=30.0):
    """Trigger the drop once the virtual hand has answered ``commands`` commands."""
    import time

    deadline = time.monotonic() + timeout
    while dev.emulator.commands < commands and time.monotonic() < deadline:
        time.sleep(0.01)
    dev.trigger("drop")


@pytest.mark.slow
def test_run_nmsd_on_the_ability_hands_touch_sensors_over_the_virtual_hand(tmp_path, capsys):
    """``run --hand-type ability --method nmsd``: no DAQ, the fingertip is the tactile source."""
    from slipreflex.cli import main
    from slipreflex.files.recording import read_recording
    from slipreflex.sim import Drop

    path = tmp_path / "nmsd.mcap"
    # a 50 g drop: the paper's 10 g one is at the edge of what the simulated pads show the array
    # (whether NMSD fires on it depends on where in the rig's real-time steps it lands)
    dev, grasp = _virtual(tmp_path, drop=Drop(mass_kg=0.05, height_m=0.02))
    with dev:
        thr = _rest_threshold(dev)
        # the drop comes half a second of frames into the run, however long the start takes
        threading.Thread(target=_drop_after, args=(dev, dev.emulator.commands + 130), daemon=True).start()
        code = main(["run", "--hand", dev.hand_path, "--hand-type", "ability", "--method", "nmsd",
                     "--tactile-threshold", f"{thr:.6g}", "--p0", grasp.p0_text(), "--duration", "3.0",
                     "--record", str(path)])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "touch sensors of the ability hand" in out
    rec = read_recording(path)
    frames = rec.topic("/tactile/frames")
    assert 100 < len(frames) <= 1.1 * 260 * 3.0  # one frame per period at most (a reply per request)
    assert {f"taxel_{k}" for k in range(6)} <= set(frames[0]) and not rec.topic("/daq/samples")
    assert rec.metadata["slipreflex"]["reflex"] == "nmsd" and rec.metadata["slipreflex"]["hand_type"] == "ability"
    assert [m["seq"] for m in frames] == list(range(frames[0]["seq"], frames[0]["seq"] + len(frames)))
    assert len(rec.topic("/chain/events")) > 0 and any(m["sent"] for m in rec.topic("/hand/commands"))
    # replaying NMSD over the recorded frames finds the same detections
    capsys.readouterr()
    assert main(["replay", str(path), "--method", "nmsd", "--threshold", f"{thr:.6g}"]) == 0
    assert f"nmsd: events {len(rec.topic('/chain/events'))}," in capsys.readouterr().out


@pytest.mark.slow
def test_run_dath_with_the_daq_and_the_ability_hand(tmp_path, capsys):
    """``run --hand-type ability``: the slip sensor on the DAQ, the commands to the Ability Hand."""
    from slipreflex.cli import main
    from slipreflex.files.recording import read_recording

    path = tmp_path / "ab.mcap"
    from slipreflex.methods import make
    from slipreflex.sim import Pour

    # the pour's clock starts at connect; on a cold numba cache the chain's first compile (run's warm-up,
    # after connect) would outlast the slip, so this process compiles it first, as an earlier run would have
    warm = make("dath")
    warm.step(0.5), warm.step(0.6)
    # a fast pour: past the first slip (200 ml) about 2.5 s after it starts
    # the pour's clock starts at run's first packet, so a slow start under load cannot miss it
    dev, grasp = _virtual(tmp_path, Pour(rate_l_min=6.0, volume_ml=300.0), schedule=[("pour", 0.5)],
                          schedule_from="connect")
    with dev:
        code = main(["run", "--daq", dev.daq_path, "--hand", dev.hand_path, "--hand-type", "ability",
                     "--p0", grasp.p0_text(), "--duration", "4.0", "--record", str(path)])
        closed = dev.rig.rig.hand.positions()
    out = capsys.readouterr().out
    assert code == 0, out
    rec = read_recording(path)
    sent = [m for m in rec.topic("/hand/commands") if m["sent"]]
    # every closing reached the hand, after the driver's first read and the run's safe-start hold (one closing
    # may carry several sent rises: the fingers keep closing while the command rises window after window)
    closings = int(re.search(r"\((\d+) closings?\)", out).group(1))
    assert sent and closings >= 1 and dev.emulator.commands >= 2 + closings and dev.emulator.rejected == 0
    assert closed[Finger.MIDDLE] > grasp.positions[Finger.MIDDLE]  # the reflex closed the hand
    assert all(closed[f] >= grasp.positions[f] - 0.5 for f in (Finger.THUMB, Finger.INDEX, Finger.MIDDLE))


def test_while_a_reflex_runs_the_driver_refuses_a_position_that_would_open():
    from slipreflex.rig.devices.ability import AbilityHand

    class Port:  # the hand's side, in memory: replies to every frame with the grasp
        def __init__(self):
            self.hand = ab.VirtualAbilityHand(self)
            self.pos = {Finger.INDEX: 200.0, Finger.MIDDLE: 200.0, Finger.THUMB: 200.0}
            self.out = b""
            self.written = []

        # the rig the virtual hand answers from
        def positions(self):
            return dict(self.pos)

        def set_positions(self, t):
            self.pos.update(t)

        # a pyserial-like port
        timeout, port = 0, "mem://ability"

        @property
        def in_waiting(self):
            return len(self.out)

        def write(self, data):
            self.written.append(bytes(data))
            self.out += self.hand.feed(bytes(data))
            return len(data)

        def flush(self):
            pass

        def read(self, n):
            data, self.out = self.out[:n], self.out[n:]
            return data

    port = Port()
    port.hand.rig = type("Rig", (), {"hand": port})()
    hand = AbilityHand(port, reply_timeout=0.5)
    assert hand.positions()[Finger.INDEX] == pytest.approx(200.0, abs=0.05)
    hand.reflex_running()
    sent = len(port.written)
    with pytest.raises(ParameterError, match="refused while a reflex runs"):
        hand.set_positions({Finger.INDEX: 150.0})
    assert len(port.written) == sent  # nothing written
    with pytest.raises(ParameterError, match="refused while a reflex runs"):
        hand.set_positions({Finger.INDEX: 250.0})  # not even upward: closing and holding only
    hand.close_fingers([Finger.INDEX], 625.0)
    hand.hold([Finger.INDEX])
    # the hold is velocity 0 for every finger (a position at a stale reading could open one)
    _, header, speeds = ab.decode_command(ab.unstuff(port.written[-1])[0])
    assert header == 0x20 and speeds == [0.0] * 6
    hand.reflex_running(False)
    hand.set_positions({Finger.INDEX: 150.0})  # a grasp routine may open again
