"""MCAP recordings: round trip, crash tolerance (SIGKILL), full disk, unwritable path."""

from __future__ import annotations

import contextlib
import errno
import io
import json
import os
import subprocess
import sys
import textwrap
import threading
import time

import pytest

from conftest import reap_child
from slipreflex.files.recording import METADATA_NAME, TOPICS, Recorder, RecordingError, read_recording


def test_round_trip_and_foxglove_facing_format(tmp_path):
    path = tmp_path / "r.mcap"
    with Recorder(path, metadata={METADATA_NAME: {"reflex": "dath"}}) as rec:
        for k in range(1000):
            assert rec.write("/daq/samples", {"seq": k, "t": k * 0.003, "slip_volts": 0.1 * k,
                                              "flow_pulses": 0, "arrival": 0.0, "position": None}, k)
        rec.write("/faults", {"time": 1.0, "kind": "watchdog", "message": "m", "action": "held"}, 2000)
    r = read_recording(path)
    assert r.complete
    assert [m["seq"] for m in r.topic("/daq/samples")] == list(range(1000))
    assert [m["slip_volts"] for m in r.topic("/daq/samples")] == [0.1 * k for k in range(1000)]
    assert r.topic("/faults")[0]["kind"] == "watchdog"
    assert r.metadata[METADATA_NAME]["reflex"] == "dath"
    # Every channel is JSON with a JSON schema (what Foxglove needs), read with mcap's own reader.
    from mcap.reader import make_reader
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        assert {c.topic for c in summary.channels.values()} == set(TOPICS)
        assert all(c.message_encoding == "json" for c in summary.channels.values())
        assert all(s.encoding == "jsonschema" for s in summary.schemas.values())
        for s in summary.schemas.values():
            assert json.loads(s.data)["type"] == "object"
        n = sum(1 for _ in reader.iter_messages(topics=["/daq/samples"]))
    assert n == 1000


_CHILD = textwrap.dedent("""
    import sys, time
    from slipreflex.files.recording import Recorder
    rec = Recorder(sys.argv[1], flush_interval=0.25)
    k = 0
    t0 = time.perf_counter()
    while True:
        # 333 messages per second, paced by the clock like the real loop
        while time.perf_counter() - t0 < k / 333.0:
            time.sleep(0.0005)
        rec.write("/chain/events", {"seq": k, "t": k / 333.0}, k)
        rec.maybe_flush()
        if k % 50 == 0:
            print(k, flush=True)
        k += 1
""")


@pytest.mark.slow
def test_sigkill_leaves_a_file_readable_up_to_about_a_second_before(tmp_path):
    path = tmp_path / "killed.mcap"
    proc = subprocess.Popen([sys.executable, "-c", _CHILD, str(path)], stdout=subprocess.PIPE,
                            text=True)
    killer = threading.Timer(90, proc.kill)  # bounds the test if the child hangs
    killer.start()
    try:
        last = -1
        deadline = time.monotonic() + 30
        while last < 700 and time.monotonic() < deadline:  # ~2 s of messages written
            line = proc.stdout.readline()
            if not line:
                break
            last = int(line)
        assert last >= 700, "child did not get going"
        proc.kill()
        proc.wait(timeout=10)
    finally:
        reap_child(proc, killer)
    # a run killed mid-way leaves its recording under NAME.part (named NAME only when closed)
    assert not path.exists()
    r = read_recording(f"{path}.part")
    assert not r.complete
    seqs = [m["seq"] for m in r.topic("/chain/events")]
    assert seqs == list(range(len(seqs)))  # nothing garbled, nothing missing before the cut
    assert seqs[-1] >= last - 333  # within one second (333 messages) of the kill


def test_unwritable_path_and_full_disk_fail_before_the_run(tmp_path):
    with pytest.raises(RecordingError, match="no-such-dir"):
        Recorder(tmp_path / "no-such-dir" / "r.mcap")
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        if not os.access(ro, os.W_OK):  # (as root, permissions do not apply)
            with pytest.raises(RecordingError, match="cannot create"):
                Recorder(ro / "r.mcap")
    finally:
        ro.chmod(0o700)
    if os.path.exists("/dev/full"):
        with pytest.raises(RecordingError, match="/dev/full"):
            Recorder("/dev/full")


class _FillingDisk(io.RawIOBase):
    """A file that accepts ``room`` bytes, then fails with ENOSPC."""

    def __init__(self, room):
        self.data = bytearray()
        self.room = room

    def writable(self):
        return True

    def write(self, b):
        if len(self.data) + len(b) > self.room:
            raise OSError(errno.ENOSPC, "No space left on device")
        self.data += b
        return len(b)

    def tell(self):
        return len(self.data)


def test_disk_full_mid_run_stops_recording_without_raising():
    disk = _FillingDisk(room=20_000)
    buf = io.BufferedWriter(disk)
    rec = Recorder(buf, chunk_size=2_000, flush_interval=0.0, compression="none")
    results = []
    for k in range(2000):
        results.append(rec.write("/chain/events", {"seq": k, "t": k * 0.003}, k))
        rec.maybe_flush()
    assert results[0] and not results[-1]
    assert isinstance(rec.error, OSError) and rec.error.errno == errno.ENOSPC
    assert not rec.ok
    rec.close()  # does not raise either
    with contextlib.suppress(OSError):
        buf.close()


@pytest.mark.realtime
@pytest.mark.slow
def test_sigkilled_run_leaves_a_recording_that_replays(tmp_path):
    """End to end: `slipreflex run` on the virtual rig, killed with SIGKILL mid-run."""
    from slipreflex.rig.devices.simrig import SimRig
    from slipreflex.rig.devices.virtual import VirtualDevices
    from slipreflex.rig.replay import replay

    sim = SimRig("TR", seed=2)
    p0 = sim.grasp().position
    target = tmp_path / "killed-run.mcap"
    path = tmp_path / "killed-run.mcap.part"   # named killed-run.mcap only when the run ends
    with VirtualDevices(sim, link_dir=str(tmp_path), schedule=[("drop", 0.5)]) as dev:
        proc = subprocess.Popen([sys.executable, "-m", "slipreflex", "run", "--daq", dev.daq_path,
                                 "--hand", dev.hand_path, "--p0", f"{p0:g}", "--record", str(target)],
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        killer = threading.Timer(90, proc.kill)  # bounds the test if the child hangs
        killer.start()
        try:
            assert proc.stdout.readline().startswith("running")
            n = 0
            deadline = time.monotonic() + 60
            while n < 600 and time.monotonic() < deadline:  # about 1.8 s of samples on disk
                n = len(read_recording(path).topic("/daq/samples"))
                time.sleep(0.05)
            assert n >= 600
            proc.kill()
            proc.wait(timeout=10)
        finally:
            reap_child(proc, killer)
    assert not target.exists()
    rec = read_recording(path)
    assert not rec.complete and len(rec.topic("/daq/samples")) >= n
    assert rec.topic("/hand/commands") and rec.topic("/chain/state")
    assert replay(rec).identical


def _chain_recording(path, commands):
    from slipreflex.methods.chain import ReflexParams
    meta = {METADATA_NAME: {"reflex_params": json.dumps(ReflexParams(p0=100.0).to_dict())}}
    with Recorder(path, metadata=meta) as rec:
        for k in range(32):
            rec.write("/daq/samples", {"seq": k, "t": k * 0.003, "slip_volts": 0.4, "flow_pulses": 0,
                                       "arrival": 0.0, "position": None}, k)
        for seq, target in commands:
            rec.write("/hand/commands", {"seq": seq, "t": seq * 0.003, "target": target,
                                         "fingers": ["middle"], "sent": True, "latency": 1e-4}, 40)


def test_replay_detects_a_recording_it_cannot_reproduce(tmp_path, capsys):
    from slipreflex.cli import main

    good, bad = tmp_path / "good.mcap", tmp_path / "bad.mcap"
    _chain_recording(good, [(15, 100.0), (31, 100.0)])
    _chain_recording(bad, [(15, 100.0), (31, 105.0)])
    assert main(["replay", str(good)]) == 0
    assert "commands: recorded 2, replayed 2 - identical" in capsys.readouterr().out
    assert main(["replay", str(bad)]) == 1
    assert "DIFFERENT from #1" in capsys.readouterr().out


def test_reading_something_that_is_not_a_recording(tmp_path, capsys):
    from slipreflex.cli import main
    from slipreflex.core.errors import DataError

    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not an mcap file at all")
    with pytest.raises(DataError, match="not an MCAP file"):
        read_recording(junk)
    plain = tmp_path / "plain.mcap"
    with Recorder(plain):
        pass
    assert main(["replay", str(plain)]) == 2
    assert "no chain parameters" in capsys.readouterr().err
    assert main(["export", str(plain)]) == 2
    assert "no slip-sensor samples" in capsys.readouterr().err


@pytest.mark.slow
def test_the_recording_package_imports_nothing_of_the_chain_or_the_board():
    """The file format sits below the chain: replay, which needs the chain and the board's twin, is above it."""
    from test_imports import _graph

    edges = _graph()
    seen, todo = set(), [m for m in edges
                         if m == "slipreflex.files.recording" or m.startswith("slipreflex.files.recording.")]
    assert "slipreflex.files.recording.format" in todo and "slipreflex.files.recording.reader" in todo
    while todo:
        module = todo.pop()
        if module not in seen:
            seen.add(module)
            todo.extend(edges.get(module, {}))
    above = sorted(m for m in seen if m.split(".")[1] in ("chain", "board", "replay", "runtime", "sim"))
    assert not above, f"the recording package reaches {above}"
    assert "slipreflex.files.recording" in _graph()["slipreflex.rig.replay"]     # the check sees a real edge


def test_every_public_name_is_importable_from_the_package():
    import slipreflex.files.recording as recording
    from slipreflex.files.recording import export, format, reader, recover, writer

    for module in (export, format, reader, recover, writer):
        for name in module.__all__:
            assert getattr(recording, name) is getattr(module, name), (module.__name__, name)
            assert name in recording.__all__, name
    assert recording.RecordingError.__module__ == "slipreflex.files.recording"
