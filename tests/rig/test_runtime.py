"""The real-time loop over virtual devices: commands, latency, watchdog, faults, replay, CLI."""

from __future__ import annotations

import contextlib
import errno
import io
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest
import serial

from slipreflex.cli import main
from slipreflex.core import hardware as hw
from slipreflex.core.interfaces import DaqSample
from slipreflex.files.csvfiles import read_slip_csv
from slipreflex.files.recording import METADATA_NAME, Recorder, read_recording
from slipreflex.methods.chain import SlipReflex
from slipreflex.rig.devices import wire
from slipreflex.rig.devices.daq import SerialDaq
from slipreflex.rig.devices.ilimb import ILimb, PacketParser
from slipreflex.rig.devices.virtual import VirtualDevices
from slipreflex.rig.replay import replay
from slipreflex.rig.runtime import run_loop

P0 = 150.0


class ToyHand:
    """Fingers jump to position targets and close at their speed while told to; keeps every
    position the fingers took."""

    def __init__(self):
        self.pos = {f: 0.0 for f in hw.TRIPOD}
        self.closing = {}
        self.history = []

    def set_positions(self, targets):
        self.pos.update({f: float(v) for f, v in targets.items()})
        self.history.append(dict(self.pos))

    def close_fingers(self, fingers, speed):
        self.closing.update({f: speed for f in fingers})

    def hold(self, fingers):
        for f in fingers:
            self.closing.pop(f, None)

    def tick(self, dt):
        if self.closing:
            self.pos.update({f: min(hw.FINGER_MAX, self.pos[f] + v * dt) for f, v in self.closing.items()})
            self.history.append(dict(self.pos))

    def positions(self):
        return dict(self.pos)


class ToyRig:
    """A sensor at 0.4 V that fluctuates while the object slips; a drop makes it slip
    until the middle finger has closed 20 units past where it was."""

    def __init__(self, seed=0):
        self.rng = np.random.default_rng(seed)
        self.k = 0
        self.hand = ToyHand()
        self.slip_until = None

    def perturb(self, kind):
        self.slip_until = self.hand.pos[hw.Finger.MIDDLE] + 20.0

    @property
    def slipping(self):
        return self.slip_until is not None and self.hand.pos[hw.Finger.MIDDLE] < self.slip_until

    def advance_to(self, t):
        out = []
        while (self.k + 1) * hw.DAQ_PERIOD_S <= t:
            v = 0.4 + (0.1 * self.rng.standard_normal() if self.slipping else 0.0)
            self.hand.tick(hw.DAQ_PERIOD_S)
            out.append(DaqSample(seq=self.k, t=self.k * hw.DAQ_PERIOD_S, slip_volts=v,
                                 accel_g=(0.0, 0.0, 1.0) if self.k % 10 == 0 else None,
                                 flow_pulses=self.k // 100))
            self.k += 1
        return out


@contextlib.contextmanager
def rig_and_drivers(tmp_path, **kw):
    dev = VirtualDevices(ToyRig(), link_dir=str(tmp_path), **kw)
    with dev:
        daq = SerialDaq(dev.daq_path, reconnect_interval=0.02)
        hand = ILimb(dev.hand_path, reconnect_interval=0.02)
        try:
            hand.set_positions({f: P0 for f in hw.TRIPOD})
            yield dev, daq, hand
        finally:
            daq.close()
            hand.close()


def _reflex(**kw):
    """A reflex built and run once before the devices start (the first build compiles),
    so the devices' scripted times fall inside the loop."""
    reflex = SlipReflex(p0=P0, **kw)
    reflex.step(0.4)
    reflex.reset()
    return reflex


def _recorder(path, reflex):
    import json
    return Recorder(path, metadata={METADATA_NAME: {"reflex_params": json.dumps(reflex.params.to_dict())}})


def _run_recorded(tmp_path, daq, hand, reflex, duration):
    """run_loop with a recording; checks that nothing the loop saw is missing from it."""
    path = tmp_path / "fault.mcap"
    with _recorder(path, reflex) as rec:
        res = run_loop(daq, hand, reflex, recorder=rec, duration=duration)
    r = read_recording(path)
    assert r.complete and res.recording_error is None
    assert len(r.topic("/daq/samples")) == res.samples
    assert len(r.topic("/hand/commands")) == res.commands
    assert sum(m["sent"] for m in r.topic("/hand/commands")) == res.commands_sent
    assert [f["kind"] for f in r.topic("/faults")] == [f.kind for f in res.faults]
    assert replay(r).identical
    return res


@pytest.mark.realtime
@pytest.mark.slow
def test_loop_over_virtual_devices_reacts_records_and_replays_exactly(tmp_path):
    path = tmp_path / "run.mcap"
    reflex = _reflex()
    with rig_and_drivers(tmp_path, schedule=[("drop", 0.6)]) as (dev, daq, hand):
        with _recorder(path, reflex) as rec:
            res = run_loop(daq, hand, reflex, recorder=rec, duration=1.6)
        assert dev.triggered and dev.triggered[0][0] == "drop"
        sent = [h[hw.Finger.MIDDLE] for h in dev.rig.hand.history]
    assert res.samples > 100 and res.commands > 5 and res.events > 0
    # Only a rise of the command goes out (as closing time); before the first the fingers stay held.
    rec_cmds = read_recording(path).topic("/hand/commands")
    level, rises = P0, []
    for m in rec_cmds:
        rises.append(m["target"] > level)
        level = max(level, m["target"])
    assert [m["sent"] for m in rec_cmds] == rises
    assert res.latencies.size == res.commands_sent == sum(rises) > 0
    assert np.all(res.latencies > 0)
    assert max(sent) >= P0 + 20 and min(sent) >= P0  # the reflex closed, never opened
    assert all(b >= a for a, b in zip(sent, sent[1:]))  # and no finger ever moved toward open
    assert not [f for f in res.faults if f.kind != "watchdog"]
    lat = res.latency_ms()
    assert 0 < lat["p50"] <= lat["p99"] <= lat["max"]
    assert "p99" in res.summary()

    rec = read_recording(path)
    assert rec.complete
    assert len(rec.topic("/daq/samples")) == res.samples
    assert len(rec.topic("/chain/events")) == res.events
    assert len(rec.topic("/hand/commands")) == res.commands
    assert rec.topic("/daq/imu") and rec.topic("/daq/flow") and rec.topic("/chain/windows")
    assert "run_summary" in rec.metadata
    rep = replay(path)
    assert rep.identical and len(rep.replayed_events) == res.events
    assert rep.replayed_commands == rep.recorded_commands

    # export -> detect
    assert main(["export", str(path), "--all"]) == 0
    t, x = read_slip_csv(tmp_path / "run.csv")
    assert x.tolist() == [m["slip_volts"] for m in rec.topic("/daq/samples")]
    assert (tmp_path / "run-commands.csv").exists()
    assert main(["detect", str(tmp_path / "run.csv"), "--out", str(tmp_path / "det")]) == 0


@pytest.mark.realtime
@pytest.mark.slow
def test_watchdog_holds_when_the_daq_stops_and_resumes_when_it_restarts(tmp_path):
    script = [(0.5, lambda d: d.pause_daq()), (0.9, lambda d: d.restart_daq())]
    reflex = _reflex()
    with rig_and_drivers(tmp_path, script=script) as (dev, daq, hand):
        res = _run_recorded(tmp_path, daq, hand, reflex, 1.5)
        history = list(dev.rig.hand.history)
        stops = dev.hand_packets
    kinds = [f.kind for f in res.faults]
    assert "watchdog" in kinds and "watchdog-clear" in kinds
    assert kinds.index("watchdog") < kinds.index("watchdog-clear")
    # the restarted board counts from 0 again: a new segment (a fault event), not a phantom gap
    assert res.daq_stats["resets"] == 1 and res.daq_stats["frames_lost"] == 0
    assert "daq-reset" in kinds
    # Holding stops the fingers where they are; no target ever went below the grasp.
    assert all(v >= P0 for h in history for v in h.values())
    assert stops > res.commands_sent  # the hold (STOP) packet reached the hand too
    assert res.samples > 0.5 * (1.5 - 0.4) * hw.DAQ_FS  # the loop kept running after


@pytest.mark.realtime
@pytest.mark.slow
def test_daq_port_that_disappears_and_comes_back(tmp_path):
    script = [(0.4, lambda d: d.unplug("daq")), (0.8, lambda d: d.replug("daq"))]
    reflex = _reflex()
    with rig_and_drivers(tmp_path, script=script) as (dev, daq, hand):
        res = _run_recorded(tmp_path, daq, hand, reflex, 1.4)
        history = list(dev.rig.hand.history)
    kinds = [f.kind for f in res.faults]
    # the port's loss and the watchdog both fire; which the loop notices first depends on the
    # machine's load (a busy machine can starve the loop into a stale gap before the unplug)
    assert {"daq-port", "watchdog", "watchdog-clear"} <= set(kinds)
    assert kinds.index("watchdog") < kinds.index("watchdog-clear")
    assert res.daq_stats["disconnects"] == 1 and res.daq_stats["reconnects"] == 1
    assert res.daq_stats["seq_gaps"] == 1  # the samples sent while unplugged are lost, and counted
    assert all(v >= P0 for h in history for v in h.values())
    assert res.samples > 0.5 * (1.4 - 0.4) * hw.DAQ_FS


@pytest.mark.realtime
@pytest.mark.slow
def test_hand_port_that_disappears_and_comes_back(tmp_path):
    script = [(0.5, lambda d: d.unplug("hand")), (0.9, lambda d: d.replug("hand"))]
    reflex = _reflex()
    with rig_and_drivers(tmp_path, script=script, schedule=[("drop", 0.55)]) as (dev, daq, hand):
        res = _run_recorded(tmp_path, daq, hand, reflex, 1.5)
        history = list(dev.rig.hand.history)
    kinds = [f.kind for f in res.faults]
    assert "hand-port" in kinds and "hand-port-restored" in kinds
    assert res.commands_sent < res.commands  # some commands could not be written...
    assert res.samples > 0.5 * 1.5 * hw.DAQ_FS  # ...but the loop never stopped
    assert hand.reconnects >= 1
    assert all(v >= P0 for h in history for v in h.values())
    assert max(h[hw.Finger.MIDDLE] for h in history) > P0  # the drop was answered


@pytest.mark.realtime
@pytest.mark.slow
def test_garbage_truncated_and_flipped_frames_while_running(tmp_path):
    bad = bytearray(wire.encode_frame(seq=1, adc=5))
    bad[9] ^= 0x04
    script = [(0.3, lambda d: d.inject_daq(b"\xa5\x5a\x01 garbage \x00\xff" * 3)),
              (0.5, lambda d: d.inject_daq(wire.encode_frame(seq=7, adc=1)[:11])),
              (0.7, lambda d: d.inject_daq(bytes(bad)))]
    reflex = _reflex()
    with rig_and_drivers(tmp_path, script=script) as (dev, daq, hand):
        res = _run_recorded(tmp_path, daq, hand, reflex, 1.0)
    st = res.daq_stats
    assert st["garbage_bytes"] >= 20 and st["truncated"] >= 1 and st["crc_errors"] >= 1
    assert st["resyncs"] >= 3
    # each kind of damage is a recorded fault event (not only a 1 Hz counter)
    kinds = {f.kind for f in res.faults}
    assert {"daq-garbage", "daq-truncated", "daq-crc"} <= kinds
    assert kinds <= {"daq-garbage", "daq-truncated", "daq-crc", "watchdog", "watchdog-clear"}
    assert res.samples > 0.5 * hw.DAQ_FS  # the good frames around the bad bytes all came through
    assert res.samples + 3 >= res.daq_stats["frames"]


class _Wild:
    """A reflex whose every command is not a number."""

    name, input_kind, fs = "wild", "slip", hw.FS_NOMINAL
    last_filtered, last_event, last_threshold, last_count = 0.0, False, 0.0, None

    def step(self, sample, position=None):
        return float("nan")

    def reset(self):
        pass


class _Samples:
    def __init__(self, n):
        self.left = [DaqSample(k, k * hw.DAQ_PERIOD_S, 0.4, None, 0) for k in range(n)]

    def read(self, timeout):
        out, self.left = self.left[:10], self.left[10:]
        return out

    def close(self):
        pass


def test_out_of_range_command_is_not_sent_and_the_loop_goes_on():
    loop = serial.serial_for_url("loop://", timeout=0)
    hand = ILimb(loop)
    res = run_loop(_Samples(50), hand, _Wild(), p0=P0, duration=0.4)
    assert res.samples == 50 and res.commands == 50 and res.commands_sent == 0
    rejected = [f for f in res.faults if f.kind == "command-rejected"]
    assert len(rejected) == 50 and "nan" in rejected[0].message
    # Only the safe start's and the watchdog's holds (STOP) reached the port: never the bad value.
    packets = PacketParser().feed(loop.read(10_000))
    assert packets and all(c.command == hw.HandCommand.STOP for p in packets for c in p)
    hand.close()
    loop.close()


class _FillingDisk(io.RawIOBase):
    def __init__(self, room):
        self.n, self.room = 0, room

    def writable(self):
        return True

    def write(self, b):
        if self.n + len(b) > self.room:
            raise OSError(errno.ENOSPC, "No space left on device")
        self.n += len(b)
        return len(b)

    def tell(self):
        return self.n


@pytest.mark.slow
def test_disk_full_mid_run_is_recorded_as_a_fault_and_the_reflex_keeps_running():
    buf = io.BufferedWriter(_FillingDisk(room=30_000))
    rec = Recorder(buf, chunk_size=1_000, compression="none")
    loop = serial.serial_for_url("loop://", timeout=0)
    hand = ILimb(loop)
    res = run_loop(_Samples(2000), hand, SlipReflex(p0=P0), recorder=rec, duration=0.5)
    rec.close()
    with contextlib.suppress(OSError):
        buf.close()
    # a still sensor: every window's command stays at p0, so nothing needs sending
    assert res.samples == 2000 and res.commands == 2000 // 16 and res.commands_sent == 0
    assert [f.kind for f in res.faults].count("recording") == 1
    assert "No space left" in res.recording_error
    hand.close()
    loop.close()


@pytest.mark.realtime
@pytest.mark.slow
def test_cli_run_over_virtual_devices_then_replay(tmp_path, capsys):
    path = tmp_path / "cli.mcap"
    with VirtualDevices(ToyRig(), link_dir=str(tmp_path), schedule=[("drop", 0.3)]) as dev:
        code = main(["run", "--daq", dev.daq_path, "--hand", dev.hand_path, "--p0", str(P0),
                     "--duration", "1.0", "--record", str(path)])
    out = capsys.readouterr().out
    assert code == 0
    assert "latency sample read->command: p50" in out and "latency frame arrival->command: p50" in out
    assert "seq_gaps" in out
    assert main(["replay", str(path)]) == 0
    assert "identical" in capsys.readouterr().out


def test_cli_refuses_bad_recording_path_and_bad_p0_before_running(tmp_path, capsys):
    code = main(["run", "--daq", "loop://", "--hand", "loop://", "--p0", "100",
                 "--record", str(tmp_path / "missing" / "r.mcap"), "--duration", "5"])
    err = capsys.readouterr().err
    assert code == 2 and "missing" in err and "running" not in err
    code = main(["run", "--daq", "loop://", "--hand", "loop://", "--p0", "600", "--no-record",
                 "--duration", "5"])
    assert code == 2 and "600" in capsys.readouterr().err
    code = main(["run", "--daq", str(tmp_path / "nodaq"), "--hand", "loop://", "--p0", "100"])
    assert code == 2 and "nodaq" in capsys.readouterr().err


@pytest.mark.slow
def test_ctrl_c_stops_cleanly_and_closes_the_recording(tmp_path):
    path = tmp_path / "int.mcap"
    proc = subprocess.Popen([sys.executable, "-m", "slipreflex", "run", "--daq", "loop://",
                             "--hand", "loop://", "--p0", "100", "--record", str(path)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    killer = threading.Timer(90, proc.kill)  # bounds the test if the child hangs
    killer.start()
    try:
        line = proc.stdout.readline()
        assert line.startswith("running"), line + proc.stderr.read()
        fault = proc.stderr.readline()  # no DAQ data: the watchdog fires after 100 ms
        assert "watchdog" in fault and "held" in fault
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    finally:
        killer.cancel()
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, err
    assert "samples 0" in out and "recorded to" in out
    rec = read_recording(path)
    assert rec.complete and "run_summary" in rec.metadata
    assert [f["kind"] for f in rec.topic("/faults")] == ["watchdog"]
