"""Safe start: `run` never opens the hand, whatever --p0 says."""

from __future__ import annotations

import json

import pytest

from slipreflex.cli import main
from slipreflex.core.errors import ParameterError
from slipreflex.core.hardware import DAQ_PERIOD_S, TRIPOD, Finger
from slipreflex.files.recording import METADATA_NAME, read_recording
from slipreflex.methods.chain import SlipReflex
from slipreflex.rig.devices.simrig import SimRig
from slipreflex.rig.devices.virtual import VirtualDevices
from slipreflex.rig.runtime import run_loop, safe_start, start_positions


class _RigSource:
    """The simulated rig as a SampleSource in simulated time: each read advances it by a few
    sample periods and notes the lowest measured position of every tripod finger so far."""

    def __init__(self, sim, per_read=4):
        self.sim, self.per_read = sim, per_read
        self.lowest = dict(sim.rig.hand.positions())

    def read(self, timeout):
        rig = self.sim.rig
        out = rig.advance_to(rig.t + self.per_read * DAQ_PERIOD_S)
        for f, v in rig.hand.positions().items():
            self.lowest[f] = min(self.lowest[f], v)
        return out

    def close(self):
        pass


@pytest.mark.parametrize("p0", [0, 100])
def test_a_low_p0_never_lowers_a_finger_of_the_simulated_hand(p0):
    sim = SimRig("TX", seed=0)   # the textured bottle: its drop slip fires spikes
    grasp = sim.grasp()
    src = _RigSource(sim)
    sim.perturb("drop")  # a slip, so that the reflex raises its command
    res = run_loop(src, sim.hand, SlipReflex(p0=float(p0)), duration=1.5, watchdog=0.5,
                   clock=lambda: sim.rig.t)
    assert res.events > 0 and res.commands_sent > 0  # the reflex did act
    for f in TRIPOD:
        assert src.lowest[f] >= grasp.positions[f], (f, src.lowest, grasp.positions)
    assert res.start == {f.name.lower(): grasp.positions[f] for f in TRIPOD}
    assert res.initial_command == "STOP thumb,index,middle"
    assert sim.hand.positions()[Finger.MIDDLE] > grasp.positions[Finger.MIDDLE]  # it closed


def _watch(dev_holder, lowest, period=0.005, span=3.0):
    """VirtualDevices script entries that note the lowest measured tripod positions."""

    def look(dev):
        for f, v in dev.rig.hand.positions().items():
            if f in lowest:
                lowest[f] = min(lowest[f], v)

    return [(k * period, look) for k in range(int(span / period))]


def _run_on_virtual_rig(tmp_path, p0_text, schedule=(), extra=()):
    sim = SimRig("TX", seed=165)
    grasp = sim.grasp()
    lowest = {f: grasp.positions[f] for f in TRIPOD}
    path = tmp_path / "safe.mcap"
    with VirtualDevices(sim, link_dir=str(tmp_path), schedule=schedule,
                        script=_watch(None, lowest)) as dev:
        code = main(["run", "--daq", dev.daq_path, "--hand", dev.hand_path, "--p0", p0_text,
                     "--duration", "1.0", "--record", str(path), *extra])
    return code, grasp, lowest, path


@pytest.mark.realtime
@pytest.mark.slow
def test_run_with_p0_zero_holds_the_fingers_where_the_grasp_left_them(tmp_path, capsys):
    code, grasp, lowest, path = _run_on_virtual_rig(tmp_path, "0")
    assert code == 0, capsys.readouterr().err
    assert lowest == grasp.positions  # not one unit lower, anywhere, at any time
    rec = read_recording(path)
    assert json.loads(rec.metadata[METADATA_NAME]["p0"]) == {"thumb": 0, "index": 0, "middle": 0}
    assert rec.metadata["start"]["initial_command"] == "STOP thumb,index,middle"
    assert not any(m["sent"] for m in rec.topic("/hand/commands"))


@pytest.mark.realtime
@pytest.mark.slow
def test_the_virtual_rigs_printed_p0_does_not_open_the_thumb_when_the_reflex_acts(tmp_path, capsys):
    sim = SimRig("TX", seed=165)   # textured (its drop slip fires spikes); its thumb stops a unit further
    printed = sim.grasp().p0_text()
    assert printed == "thumb=148,index=147,middle=147"  # the thumb stops one unit further closed
    code, grasp, lowest, path = _run_on_virtual_rig(tmp_path, printed, schedule=[("drop", 0.2)])
    assert code == 0, capsys.readouterr().err
    assert lowest == grasp.positions
    sent = [m for m in read_recording(path).topic("/hand/commands") if m["sent"]]
    assert sent, "the drop made the reflex close"
    # every finger gets the same grip, from wherever it holds: the thumb is never held back to
    # the middle finger's start
    assert all(m["grip"]["thumb"] == m["grip"]["middle"] > 0 and m["targets"] == {} for m in sent)


@pytest.mark.parametrize("option, value, named", [
    ("--watchdog", "1e9", "--watchdog"), ("--watchdog", "0", "--watchdog"),
    ("--watchdog", "nan", "--watchdog"), ("--p0", "thumb=148,index=147", "middle"),
    ("--p0", "147.5", "THUMB"), ("--p0", "abc", "--p0"), ("--duration", "nan", "--duration"),
    ("--n", "0", "n"),
])
def test_every_option_is_checked_before_a_port_opens_or_a_byte_is_sent(tmp_path, capsys, option,
                                                                        value, named):
    class Rig:
        hand = None

        def advance_to(self, t):
            return []

    args = {"--p0": "147", "--watchdog": "0.1", "--duration": "1"}
    args[option] = value
    with VirtualDevices(Rig(), link_dir=str(tmp_path)) as dev:
        code = main(["run", "--daq", dev.daq_path, "--hand", dev.hand_path, "--no-record",
                     *[x for kv in args.items() for x in kv]])
        hand_bytes = dev.hand.read()
    err = capsys.readouterr().err
    assert code == 2 and named in err and len(err.strip().splitlines()) == 1, err
    assert hand_bytes == b"" and dev.hand_packets == 0  # nothing reached the hand port


def test_start_positions_and_safe_start_validate_before_sending():
    sent = []

    class Hand:
        def set_positions(self, t):
            sent.append(t)

        def positions(self):
            return {}

        def hold(self, fingers):
            sent.append("stop")

    with pytest.raises(ParameterError, match="ring"):
        start_positions({"ring": 3, "thumb": 1, "index": 1, "middle": 1})
    with pytest.raises(ParameterError, match="MIDDLE"):
        safe_start(Hand(), {Finger.THUMB: 1, Finger.INDEX: 1, Finger.MIDDLE: 501})
    assert sent == []
    assert safe_start(Hand(), 120) == {f: 120.0 for f in TRIPOD} and sent == ["stop"]
