"""Watching a run as a lab would: a Foxglove WebSocket client and LSL inlets on loopback.

A run over the virtual devices publishes through ``--live`` (slipreflex.rig.live) and ``--lsl``
(slipreflex.rig.lsl); a WebSocket client speaking the Foxglove protocol subscribes to every
advertised channel and an LSL inlet resolves the outlets, and what they receive is compared
with the run's own MCAP recording. Each extra skips, with its reason, where its package or
native library cannot load (scripts/bootstrap.sh installs both, so CI runs them).
"""

from __future__ import annotations

import contextlib
import json
import os
import struct
import threading
import time
import uuid
from pathlib import Path

import pytest

from slipreflex.cli import main
from slipreflex.core.taps import Tap
from slipreflex.files.recording import TOPICS, read_recording, schema
from slipreflex.rig.runtime import run_loop

# liblsl reads its configuration once, at its first call: on this machine only (no multicast).
os.environ.setdefault("LSLAPICFG", str(Path(__file__).parents[1] / "data" / "lsl_loopback.cfg"))


def _foxglove():
    pytest.importorskip("foxglove", reason="foxglove-sdk (slipreflex[live]) is not installed")
    return pytest.importorskip("websockets.sync.client",
                               reason="websockets (a foxglove-sdk test client) is not installed")


def _pylsl():
    try:
        import pylsl
    except ImportError as err:
        pytest.skip(f"pylsl (slipreflex[lsl]) is not installed: {err}")
    except (OSError, RuntimeError) as err:
        pytest.skip(f"pylsl's native liblsl does not load: {err}")
    return pylsl


class FoxgloveClient:
    """A Foxglove WebSocket client: subscribes to every advertised channel, keeps what arrives."""

    def __init__(self, url: str, expect_channels: int) -> None:
        from slipreflex.rig.live import WS_SUBPROTOCOLS

        ws_client = _foxglove()
        self.stack = contextlib.ExitStack()
        self.ws = self.stack.enter_context(ws_client.connect(url, subprotocols=list(WS_SUBPROTOCOLS),
                                                             open_timeout=10))
        self.subprotocol = self.ws.subprotocol
        self.channels: dict[int, dict] = {}
        deadline = time.monotonic() + 10
        while len(self.channels) < expect_channels and time.monotonic() < deadline:
            msg = json.loads(self.ws.recv(timeout=10))
            if msg["op"] == "advertise":
                self.channels.update({c["id"]: c for c in msg["channels"]})
        self.subs = {k: cid for k, cid in enumerate(sorted(self.channels))}
        self.ws.send(json.dumps({"op": "subscribe",
                                 "subscriptions": [{"id": k, "channelId": c} for k, c in self.subs.items()]}))
        self.got: dict[str, list[tuple[int, dict]]] = {}
        self.thread = threading.Thread(target=self._read, daemon=True)
        self.thread.start()

    def _read(self) -> None:
        from websockets.exceptions import ConnectionClosed

        while True:
            try:
                data = self.ws.recv(timeout=30)
            except (ConnectionClosed, TimeoutError):
                return
            if isinstance(data, bytes) and data[0] == 1:  # MessageData: op, subscription, log time, payload
                _, sub, log_time = struct.unpack_from("<BIQ", data)
                topic = self.channels[self.subs[sub]]["topic"]
                self.got.setdefault(topic, []).append((log_time, json.loads(data[13:])))

    def wait_subscribed(self, view, timeout: float = 10.0) -> None:
        """Until the server has taken every subscription (a message logged before is not sent)."""
        deadline = time.monotonic() + timeout
        while not view.watched() and time.monotonic() < deadline:
            self.thread.join(0.01)
        assert view.watched(), "the server did not take the subscriptions"

    def wait_for(self, counts: dict[str, int], timeout: float = 15.0) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if all(len(self.got.get(t, [])) >= n for t, n in counts.items()):
                return
            self.thread.join(0.05)

    def close(self) -> None:
        self.stack.close()
        self.thread.join(5)


def _resolve(pylsl, source_id: str):
    found = pylsl.resolve_byprop("source_id", source_id, 1, 10.0)
    assert found, f"no LSL stream with source_id {source_id}"
    inlet = pylsl.StreamInlet(found[0], max_buflen=60, recover=False)
    inlet.open_stream(10.0)
    return inlet


def _pull(inlet, n: int, timeout: float = 15.0):
    data, stamps = [], []
    deadline = time.monotonic() + timeout
    while len(data) < n and time.monotonic() < deadline:
        d, ts = inlet.pull_chunk(timeout=0.2)
        data += d
        stamps += ts
    return data, stamps


def test_live_topics_share_the_recording_schemas():
    pytest.importorskip("foxglove", reason="foxglove-sdk (slipreflex[live]) is not installed")
    from slipreflex.rig.live import RUN_TOPICS, LiveView

    with LiveView(("127.0.0.1", 0), RUN_TOPICS + ("/tactile/frames", "/rig/truth")) as view:
        for topic, channel in view.channels.items():
            name, data = schema(topic)
            assert channel.schema().name == name and bytes(channel.schema().data) == data
            fields = json.loads(data)["properties"]
            flat = {k: v for k, v in fields.items() if "type" in v and v["type"] not in ("array", "object")}
            if topic not in ("/hand/commands", "/stats"):  # the two with a list or map field
                assert flat == fields, topic


@pytest.mark.slow
def test_run_over_the_virtual_rig_watched_live_and_recorded_by_lsl(tmp_path):
    """The whole path: virtual devices -> run_loop -> recording + Foxglove server + LSL outlets."""
    _foxglove()
    pylsl = _pylsl()
    from test_runtime import _recorder, _reflex, rig_and_drivers

    from slipreflex.rig.live import RUN_TOPICS, LiveView
    from slipreflex.rig.lsl import SAMPLE_CHANNELS, LslOutlets

    path = tmp_path / "live.mcap"
    name = f"test-{uuid.uuid4().hex[:8]}"
    reflex = _reflex()
    view = LiveView(("127.0.0.1", 0), RUN_TOPICS).start()
    client = FoxgloveClient(view.url, len(RUN_TOPICS))
    client.wait_subscribed(view)
    outlets = LslOutlets(name).start()
    inlets = [_resolve(pylsl, f"{outlets.source_id}-{kind}") for kind in ("samples", "markers")]
    try:
        with rig_and_drivers(tmp_path, schedule=[("drop", 0.5)]) as (dev, daq, hand):
            with _recorder(path, reflex) as rec:
                res = run_loop(daq, hand, reflex, recorder=rec, duration=1.5, taps=[view, outlets])
        view.flush()
        outlets.flush()
        rec = read_recording(path)
        recorded = {t: rec.topic(t) for t in RUN_TOPICS if rec.topic(t)}
        assert {"/daq/samples", "/chain/state", "/chain/events", "/chain/windows",
                "/hand/commands", "/hand/grip"} <= set(recorded)
        assert res.events > 0 and res.commands_sent > 0
        client.wait_for({t: len(m) for t, m in recorded.items()})

        # every advertised channel: the recording's schema, and the recording's messages, in order
        assert client.subprotocol in ("foxglove.sdk.v1", "foxglove.websocket.v1")
        assert {c["topic"] for c in client.channels.values()} == set(RUN_TOPICS)
        for c in client.channels.values():
            assert (c["schemaName"], c["schema"].encode()) == schema(c["topic"])
            assert c["encoding"] == "json" and c["schemaEncoding"] == "jsonschema"
        for topic, msgs in recorded.items():
            got = client.got.get(topic, [])
            assert [m for _, m in got] == msgs, topic
            assert [ns for ns, _ in got] == rec.log_times[topic], topic
        assert view.dropped == 0 and view.error is None

        # LSL: one sample per DAQ sample, in order, stamped on the board's clock
        data, stamps = _pull(inlets[0], res.samples)
        samples = rec.topic("/daq/samples")
        state = rec.topic("/chain/state")
        assert len(data) == len(samples) == res.samples
        col = {c: [row[k] for row in data] for k, c in enumerate(SAMPLE_CHANNELS)}
        assert col["slip_volts"] == [m["slip_volts"] for m in samples]
        assert col["event"] == [float(m["event"]) for m in state]
        assert col["threshold"] == [m["threshold"] for m in state]
        board_t = [m["t"] for m in samples]
        assert all(b > a for a, b in zip(stamps, stamps[1:]))
        assert max(abs((s - stamps[0]) - (t - board_t[0])) for s, t in zip(stamps, board_t)) < 1e-6
        # the offset maps the first sample's arrival onto LSL's clock: within the run's span of now
        assert abs(stamps[0] - (pylsl.local_clock() - 10)) < 10
        markers, mstamps = _pull(inlets[1], res.events + res.commands + len(res.faults), timeout=10)
        texts = [m[0] for m in markers]
        assert texts.count("spike") == res.events
        assert sum(x.startswith("command ") and x.endswith(" sent") for x in texts) == res.commands_sent
        assert sum(x.startswith("command ") for x in texts) == res.commands
        assert [x.split(":")[0][6:] for x in texts if x.startswith("fault ")] == [f.kind for f in res.faults]
        spike_t = [t for x, t in zip(texts, mstamps) if x == "spike"]
        event_t = [m["t"] + outlets.offset for m in rec.topic("/chain/events")]
        assert max(abs(a - b) for a, b in zip(spike_t, event_t)) < 1e-6
    finally:
        client.close()
        view.close()
        outlets.close()


def test_tap_that_fails_or_falls_behind_never_reaches_the_loop():
    class Broken(Tap):
        def handle(self, topic, msg, log_time_ns):
            raise RuntimeError("viewer gone")

    tap = Broken("broken", capacity=3)
    for k in range(5):
        tap.put("/faults", {"k": k}, k)  # not started: two do not fit
    tap.start()
    tap.close()
    assert tap.dropped == 2 + 2 and isinstance(tap.error, RuntimeError)  # the first raised, two dropped


@pytest.mark.slow
def test_cli_live_and_lsl_options_are_checked_before_anything_runs(tmp_path, capsys):
    base = ["run", "--daq", "loop://", "--hand", "loop://", "--p0", "100", "--no-record", "--duration", "1"]
    assert main(base + ["--live", "host:port"]) == 2
    err = capsys.readouterr().err
    assert "--live 'host:port'" in err and "running" not in err
    assert main(base + ["--live", "70000"]) == 2
    assert "0..65535" in capsys.readouterr().err
    assert main(["virtual-rig", "--live", "x:y", "--duration", "0.1"]) == 2
    assert "--live" in capsys.readouterr().err
    assert main(["replay", str(tmp_path / "none.mcap"), "--live", "-1"]) == 2
    assert "--live" in capsys.readouterr().err


def test_cli_live_port_in_use_is_one_line_before_the_ports_open(capsys):
    pytest.importorskip("foxglove", reason="foxglove-sdk (slipreflex[live]) is not installed")
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        code = main(["run", "--daq", "loop://", "--hand", "loop://", "--p0", "100", "--no-record",
                     "--duration", "1", "--live", f"127.0.0.1:{port}"])
    out = capsys.readouterr()
    assert code == 2 and f"127.0.0.1:{port}" in out.err and "running" not in out.out
    assert len(out.err.strip().splitlines()) == 1


@pytest.mark.slow
def test_virtual_rig_live_publishes_the_rigs_truth(tmp_path):
    """``virtual-rig --live``: a client watching the simulated rig's truth as it runs."""
    import subprocess
    import sys

    _foxglove()
    proc = subprocess.Popen([sys.executable, "-m", "slipreflex", "virtual-rig", "--live", "127.0.0.1:0",
                             "--duration", "4", "--schedule", "drop@0.5",
                             "--schedule-from", "start"],  # no run connects: count from the rig's start
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = None
        for line in proc.stdout:
            if line.startswith("live view: "):
                url = line.split()[2]
                break
        assert url and url.startswith("ws://127.0.0.1:")
        client = FoxgloveClient(url, 1)
        assert [c["topic"] for c in client.channels.values()] == ["/rig/truth"]
        client.wait_for({"/rig/truth": 300}, timeout=20)
        client.close()
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    truth = [m for _, m in client.got["/rig/truth"]]
    assert len(truth) >= 300
    t = [m["t"] for m in truth]
    assert all(b > a for a, b in zip(t, t[1:]))
    fields = json.loads(schema("/rig/truth")[1])["properties"]
    assert all(set(m) == set(fields) for m in truth)
    assert all(m["middle"] > 0 and m["ring"] is None for m in truth)
    assert max(m["load_mass"] for m in truth) > min(m["load_mass"] for m in truth)  # the drop landed


@pytest.mark.slow
def test_replay_plays_a_recording_to_a_live_client_as_recorded(tmp_path, capsys):
    _foxglove()
    from test_runtime import ToyRig

    from slipreflex.commands.replay import play
    from slipreflex.rig.devices.virtual import VirtualDevices
    from slipreflex.rig.live import LiveView

    path = tmp_path / "r.mcap"
    with VirtualDevices(ToyRig(), schedule=[("drop", 0.3)]) as dev:
        assert main(["run", "--daq", dev.daq_path, "--hand", dev.hand_path, "--p0", "150",
                     "--duration", "1.0", "--record", str(path)]) == 0
    rec = read_recording(path)
    topics = [t for t in rec.messages if rec.messages[t]]
    with LiveView(("127.0.0.1", 0), topics) as view:
        client = FoxgloveClient(view.url, len(topics))
        client.wait_subscribed(view)
        n = play(rec, [view], pace=4.0)
        client.wait_for({t: len(rec.topic(t)) for t in topics})
        client.close()
    assert n == sum(len(rec.topic(t)) for t in topics)
    for t in topics:
        assert [m for _, m in client.got[t]] == rec.topic(t)
        assert [ns for ns, _ in client.got[t]] == rec.log_times[t]
    capsys.readouterr()
    assert main(["replay", str(path), "--live", "127.0.0.1:0", "--pace", "0"]) == 0
    out = capsys.readouterr().out
    assert f"played {n} messages" in out and "identical" in out


def test_shipped_layout_is_built_by_its_script_and_plots_recorded_fields():
    import importlib.util

    root = Path(__file__).resolve().parents[2]
    spec = importlib.util.spec_from_file_location("foxglove_layout", root / "scripts" / "dev" / "foxglove_layout.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    for path in script.series_paths():
        topic, _, field = path.partition(".")
        assert topic in TOPICS, path
        assert not field or field in json.loads(schema(topic)[1])["properties"], path
    shipped = json.loads((root / "foxglove" / "slipreflex.json").read_text())
    text = json.dumps(shipped)
    assert all(path in text for path in script.series_paths())
    pytest.importorskip("foxglove", reason="foxglove-sdk (slipreflex[live]) builds the layout")
    assert script.main(["--check"]) == 0


@pytest.mark.slow
def test_lsl_samples_of_a_tactile_run_carry_each_taxel(tmp_path):
    pylsl = _pylsl()
    import numpy as np

    from slipreflex.core.interfaces import TactileSample
    from slipreflex.rig.lsl import LslOutlets, tactile_channels
    from slipreflex.rig.runtime import tactile_message

    outlets = LslOutlets(f"tac-{uuid.uuid4().hex[:8]}", fs=260.0, taxels=6).start()
    try:
        inlet = _resolve(pylsl, f"{outlets.source_id}-samples")
        info = inlet.info()
        assert info.channel_count() == 2 + 6 + 4 and info.type() == "tactile"
        ns0 = time.time_ns()
        frames = [np.arange(6.0) * 0.1 + k for k in range(5)]
        for k, f in enumerate(frames):
            s = TactileSample(k, k / 260.0, f)
            outlets.put("/tactile/frames", tactile_message(s, 150.0), ns0 + k)
            outlets.put("/chain/state", {"seq": k, "t": s.t, "filtered": None, "threshold": 40.0,
                                         "event": k == 3}, ns0 + k)
        outlets.flush()
        data, stamps = _pull(inlet, 5)
    finally:
        outlets.close()
    names = tactile_channels(6)[0]
    assert [row[names.index("taxel_5")] for row in data] == [f[5] for f in frames]
    assert [row[names.index("total")] for row in data] == [float(f.sum()) for f in frames]
    assert [row[names.index("event")] for row in data] == [0, 0, 0, 1, 0]
    assert np.allclose(np.diff(stamps), 1 / 260.0)
