"""Any registered method that applies to a command's input reaches it: detect, replay, run, virtual-rig."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from slipreflex import methods
from slipreflex.cli import main
from slipreflex.files.csvfiles import read_slip_csv
from slipreflex.methods.chain import run_chain

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "slip_example.csv"


@pytest.mark.slow  # the chain compiles on first use
@pytest.mark.parametrize("name", ["dath-event", "dath-floor", "dath-leak", "authors-gui"])
def test_detect_runs_every_chain_variant_as_registered(tmp_path, name, capsys):
    assert main(["detect", str(EXAMPLE), "--method", name.upper(), "--out", str(tmp_path / "d")]) == 0
    assert f"method {name}" in capsys.readouterr().out
    t, x = read_slip_csv(EXAMPLE)
    params = methods.make(name).params
    expected = run_chain(x, type(params).from_dict({**params.to_dict(), "fs": params.fs, "p0": 0.0}))
    got = np.loadtxt(tmp_path / "d.samples.csv", delimiter=",", skiprows=1, usecols=None, ndmin=2)
    header = (tmp_path / "d.samples.csv").read_text().splitlines()[0].split(",")
    assert got[:, header.index("event")].astype(bool).tolist() == expected.events.astype(bool).tolist()


def test_detect_refuses_a_method_its_input_cannot_feed_in_one_line(tmp_path, capsys):
    for name, words in (("nmsd", "reads tactile frames"), ("swt", "reads tactile frames"),
                        ("dath-board", "give --board"), ("nope", "unknown 'nope'")):
        assert main(["detect", str(EXAMPLE), "--method", name, "--out", str(tmp_path / "d")]) == 2
        err = capsys.readouterr().err
        assert words in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "d.samples.csv").exists()


@pytest.mark.slow
def test_replay_runs_a_registered_method_over_a_recording(tmp_path, capsys):
    from test_runtime import ToyRig

    from slipreflex.files.recording import read_recording
    from slipreflex.rig.devices.virtual import VirtualDevices

    path = tmp_path / "r.mcap"
    with VirtualDevices(ToyRig(), schedule=[("drop", 0.3)]) as dev:
        assert main(["run", "--daq", dev.daq_path, "--hand", dev.hand_path, "--p0", "150",
                     "--duration", "1.0", "--record", str(path)]) == 0
    capsys.readouterr()
    rec = read_recording(path)
    assert main(["replay", str(path), "--method", "dath-event"]) == 0
    out = capsys.readouterr().out
    reflex = methods.make("dath-event", p0=150.0)
    events = 0
    for m in rec.topic("/daq/samples"):
        reflex.step(m["slip_volts"], m["position"])
        events += bool(reflex.last_event)
    assert f"dath-event: events {events}," in out and events > 0
    assert main(["replay", str(path), "--method", "nmsd"]) == 2
    err = capsys.readouterr().err
    assert "reads tactile frames" in err and len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_run_dath_event_over_the_virtual_ilimb_records_and_replays(tmp_path, capsys):
    from test_runtime import ToyRig

    from slipreflex.files.recording import read_recording
    from slipreflex.rig.devices.virtual import VirtualDevices

    path = tmp_path / "ev.mcap"
    with VirtualDevices(ToyRig(), schedule=[("drop", 0.3)]) as dev:
        assert main(["run", "--daq", dev.daq_path, "--hand", dev.hand_path, "--p0", "150",
                     "--method", "dath-event", "--duration", "1.2", "--record", str(path)]) == 0
    assert "running dath-event reflex" in capsys.readouterr().out
    rec = read_recording(path)
    assert rec.metadata["slipreflex"]["reflex"] == "dath-event"
    assert methods.make("dath-event").params.to_dict()["mpi_mode"] == "event"
    assert '"mpi_mode": "event"' in rec.metadata["slipreflex"]["reflex_params"]
    assert rec.topic("/chain/events") and any(m["sent"] for m in rec.topic("/hand/commands"))
    assert main(["replay", str(path)]) == 0  # the variant's chain, rebuilt from the recording
    assert "identical" in capsys.readouterr().out


def test_run_refuses_a_method_its_devices_cannot_feed_before_any_port_opens(tmp_path, capsys):
    base = ["run", "--hand", "loop://", "--p0", "100", "--no-record", "--duration", "1"]
    cases = [(["--daq", "loop://", "--method", "nmsd", "--tactile-threshold", "40"],
              "nmsd reads tactile frames, which --daq loop:// and the i-Limb does not supply"),
             (["--method", "dath"], "reads slip-sensor samples, which no --daq and the i-Limb"),
             (["--daq", "loop://", "--method", "dath-event", "--kp", "3"], "--kp applies to fixed and dath only"),
             (["--hand-type", "ability", "--method", "nmsd"], "needs --tactile-threshold > 0"),
             (["--daq", "loop://", "--tactile-threshold", "3"], "--tactile-threshold is for a tactile method"),
             (["--daq", "loop://", "--method", "nope"], "unknown 'nope'")]
    for extra, words in cases:
        assert main(base + extra) == 2, extra
        err = capsys.readouterr().err
        assert words in err and len(err.strip().splitlines()) == 1, err
