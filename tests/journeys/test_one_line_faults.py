"""One line, exit 2, and faults that tell the truth: a method raising in step(), a hand port lost
during a closing, a CSV with a byte order mark or a cell over the csv module's limit, a scheduler
that stalls its handshake or a tls:// address without configuration, --live on every interface."""

from __future__ import annotations

import argparse
import socket
import struct
import threading

import pytest
from loop_fakes import StillSource

from slipreflex.cli import main
from slipreflex.core.errors import DataError, DeviceError, ParameterError
from slipreflex.core.hardware import DAQ_FS, Finger
from slipreflex.files.csvfiles import read_recording
from slipreflex.methods.chain import SlipReflex
from slipreflex.rig.runtime import run_loop


class _Step:
    """Asks for 100 units more grip from the first sample on: one closing of 0.16 s."""

    input_kind, name, command = "slip", "step", 148.0
    last_filtered = last_threshold = last_count = None
    last_event = False

    def step(self, volts, position=None):
        return 248.0


class _PortLostAfterClose:
    """The CLOSE goes out; then the port is gone: every STOP fails."""

    def __init__(self):
        self.closed = False

    def set_positions(self, t):
        raise AssertionError("a position")

    def close_fingers(self, fingers, speed):
        self.closed = True

    def hold(self, fingers):
        if self.closed:
            raise DeviceError("/dev/ttyUSB0: i-Limb port lost")

    def positions(self):
        return {}


def test_a_hand_port_lost_during_a_closing_is_a_fault_with_the_true_grip():
    src = StillSource()
    res = run_loop(src, _PortLostAfterClose(), _Step(), p0=148, duration=0.5, watchdog=0.5,
                   clock=lambda: src.now, guard=False)
    kinds = [f.kind for f in res.faults]
    assert "stop-failed" in kinds and "grip-unknown" in kinds
    assert res.grip_unknown == ["thumb", "index", "middle"]
    text = res.summary()
    assert "thumb >= 100.0" in text and "STOP never reached thumb, index, middle" in text
    assert res.summary_metadata()["grip_unknown"] == '["thumb", "index", "middle"]'


def test_a_csv_with_a_byte_order_mark_reads_as_its_columns(tmp_path):
    p = tmp_path / "bom.csv"
    p.write_bytes("\ufefft,x\n0,0.4\n0.003,0.41\n".encode())
    rec = read_recording(p)
    assert rec.x.tolist() == [0.4, 0.41]


def test_a_csv_cell_over_the_csv_limit_is_one_line(tmp_path, capsys):
    p = tmp_path / "big.csv"
    p.write_text("t,x\n0,0.4\n0.003,\"" + "9" * 200_000 + "\"\n")
    with pytest.raises(DataError, match=r"line 3: not a CSV row"):
        read_recording(p)
    assert main(["detect", str(p)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "line 3" in err


def _fake_scheduler(header_only: bool):
    """A server that sends a Dask-looking handshake header (length, frame count), then nothing."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(1)
    stop = threading.Event()

    def serve():
        conn, _ = srv.accept()
        conn.sendall(struct.pack("<QQ", 100, 1))
        stop.wait(30)
        conn.close()

    threading.Thread(target=serve, daemon=True).start()
    return srv, stop, f"tcp://127.0.0.1:{srv.getsockname()[1]}"


def test_a_scheduler_that_sends_a_header_then_nothing_is_refused_within_the_timeout():
    from slipreflex.study.runner import probe_scheduler

    srv, stop, addr = _fake_scheduler(True)
    try:
        with pytest.raises(ParameterError, match="no Dask handshake within 1 s"):
            probe_scheduler(addr, timeout=1.0)
    finally:
        stop.set()
        srv.close()


def test_study_with_a_stalling_scheduler_is_one_line_and_writes_nothing(tmp_path, capsys, monkeypatch):
    pytest.importorskip("dask.distributed")
    from slipreflex.study import cluster

    monkeypatch.setattr(cluster, "SCHEDULER_TIMEOUT_S", 1.0)
    srv, stop, addr = _fake_scheduler(True)
    out = tmp_path / "study"
    try:
        assert main(["study", "--scheduler", addr, "--out", str(out), "--plants", "2", "--no-progress"]) == 2
    finally:
        stop.set()
        srv.close()
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "no Dask handshake" in err
    assert not out.exists() or not any(out.iterdir())


def test_tls_without_a_configuration_is_one_line():
    pytest.importorskip("dask")
    from slipreflex.study.runner import probe_scheduler

    with pytest.raises(ParameterError, match="tls:// needs Dask's TLS configuration"):
        probe_scheduler("tls://127.0.0.1:8786")


def test_live_on_every_interface_warns_and_loopback_does_not(capsys, monkeypatch):
    from slipreflex.commands import _live

    monkeypatch.setattr(_live, "require_foxglove", lambda: None)
    _live.check_live_arguments(argparse.Namespace(live="0.0.0.0:8765", lsl=None))
    assert "unauthenticated" in capsys.readouterr().err
    for ok in ("8765", "127.0.0.1:8765", "localhost:0", "[::1]:8765"):
        _live.check_live_arguments(argparse.Namespace(live=ok, lsl=None))
        assert capsys.readouterr().err == ""


@pytest.mark.slow
def test_run_with_a_method_that_raises_writes_the_summary_holds_and_exits_2(tmp_path, capsys):
    """``slipreflex run`` on the virtual rig with a registered plugin that fails after a second."""
    from slipreflex import methods
    from slipreflex.files.recording import read_recording as read_mcap
    from slipreflex.rig.devices.simrig import SimRig
    from slipreflex.rig.devices.virtual import VirtualDevices

    class Fails(SlipReflex):
        steps = 0

        def step(self, sample, position=None):
            self.steps += 1
            if self.steps > 300:
                raise RuntimeError("plugin bug")
            return super().step(sample, position)

    def build(p0, context, **params):
        return Fails(p0=p0, **params)

    methods.register(methods.MethodSpec(name="fails-later", label="fails", input_kind="slip", fs=DAQ_FS,
                                        build=build))
    sim = SimRig("TX", seed=165)
    grasp = sim.grasp()
    path = tmp_path / "r.mcap"
    try:
        with VirtualDevices(sim) as dev:
            code = main(["run", "--daq", dev.daq_path, "--hand", dev.hand_path, "--p0", grasp.p0_text(),
                         "--method", "fails-later", "--duration", "5", "--record", str(path)])
    finally:
        methods.unregister("fails-later")
    cap = capsys.readouterr()
    assert code == 2
    assert "ended early: method " in cap.out and "RuntimeError: plugin bug" in cap.out  # the summary is written
    assert cap.err.strip().splitlines()[-1].startswith("slipreflex run: error: method ")
    rec = read_mcap(path)
    assert any(f["kind"] == "reflex-error" for f in rec.topic("/faults"))
    assert sim.rig.hand.positions()[Finger.MIDDLE] >= grasp.positions[Finger.MIDDLE] - 0.5
