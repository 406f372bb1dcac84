"""The real-rig loop applies a reflex's finger_offsets (authors-gui: the middle finger + 20) as
that finger's extra grip at the first command, never as a position and never by opening a finger;
the recording lets replay reproduce them."""

from __future__ import annotations

import json

import pytest
from test_safe_start import _RigSource

from slipreflex.core.errors import ParameterError
from slipreflex.core.hardware import DAQ_PERIOD_S, FINGER_MAX, TRIPOD, Finger
from slipreflex.core.interfaces import DaqSample
from slipreflex.files.recording import METADATA_NAME, Recorder, read_recording
from slipreflex.methods.chain import SlipReflex
from slipreflex.rig.devices.simrig import SimRig
from slipreflex.rig.replay import replay
from slipreflex.rig.runtime import run_loop


def test_authors_gui_on_the_simulated_rig_sends_the_middle_finger_its_offset(tmp_path):
    sim = SimRig("TX", seed=0)  # the textured bottle: its drop slip fires spikes
    grasp = sim.grasp()
    start = grasp.positions
    reflex = SlipReflex.from_preset("authors-gui", p0=start[Finger.MIDDLE])
    src = _RigSource(sim)
    sim.perturb("drop")
    path = tmp_path / "gui.mcap"
    meta = {METADATA_NAME: {"reflex_params": json.dumps(reflex.params.to_dict())}}
    with Recorder(path, metadata=meta) as rec:
        res = run_loop(src, sim.hand, reflex, p0=start, recorder=rec, duration=1.0, watchdog=0.5,
                       clock=lambda: sim.rig.t)
    assert res.commands_sent > 0
    for f in TRIPOD:  # the safety rule: no finger ever below where it held at start
        assert src.lowest[f] >= start[f], (f, src.lowest, start)
    r = read_recording(path)
    assert json.loads(r.metadata["start"]["finger_offsets"]) == {"middle": 20.0}
    sent = [m for m in r.topic("/hand/commands") if m["sent"]]
    assert sent
    # replay re-runs the reflex; the grip of every command follows from its rise, and the
    # middle finger's offset adds 20 units once, at the first command
    rp = replay(r)
    assert rp.identical
    cmds = [c for _, _, c in rp.replayed_commands]
    level = start[Finger.MIDDLE]
    for k, (m, c) in enumerate(zip(r.topic("/hand/commands"), cmds)):
        rise = max(c - level, 0.0)
        level = max(level, c)
        want = {"thumb": rise, "index": rise, "middle": rise + (20.0 if k == 0 else 0.0)}
        assert m["grip"] == pytest.approx(want) and m["targets"] == {}, (m, c)
    # the middle finger (the sensor's) was told to close 20 units further than the others and
    # did close further (its stiff cuff on the bottle stalls it before all 20: the plant's physics)
    assert res.grip_added["middle"] == pytest.approx(res.grip_added["index"] + 20.0)
    pos = sim.hand.positions()
    assert pos[Finger.MIDDLE] - start[Finger.MIDDLE] >= pos[Finger.INDEX] - start[Finger.INDEX] + 10


class _Samples:
    def __init__(self, n):
        self.left = [DaqSample(k, k * DAQ_PERIOD_S, 0.4, None, 0) for k in range(n)]

    def read(self, timeout):
        out, self.left = self.left[:8], self.left[8:]
        return out

    def close(self):
        pass


class _Hand:
    def __init__(self):
        self.sent = []

    def set_positions(self, t):
        self.sent.append(dict(t))

    def close_fingers(self, fingers, speed):
        self.sent.append(("close", tuple(fingers)))

    def positions(self):
        return {}

    def hold(self, fingers):
        self.sent.append("stop")


class _Offset:
    """A reflex that asks for 470, 485, 500, ... and the middle finger + 20."""
    name, input_kind, fs, command = "offset", "slip", 1 / DAQ_PERIOD_S, 470.0

    def __init__(self, offsets):
        self.finger_offsets = offsets
        self.k = 0
        self.last_filtered, self.last_threshold, self.last_event, self.last_count = 0.4, 0.0, False, None

    def step(self, raw, position=None):
        self.k += 1
        return min(470.0 + 15 * (self.k - 1), FINGER_MAX)

    def reset(self):
        self.k = 0


def test_offsets_add_grip_once_and_a_negative_offset_never_opens_a_finger():
    hand = _Hand()
    start = {Finger.THUMB: 480.0, Finger.INDEX: 470.0, Finger.MIDDLE: 470.0}
    res = run_loop(_Samples(4), hand, _Offset({Finger.MIDDLE: 20.0, Finger.INDEX: -30.0}), p0=start,
                   duration=0.3, guard=False)
    assert hand.sent[0] == "stop"  # the safe start
    assert not [x for x in hand.sent if isinstance(x, dict)]  # no position, ever
    # 470 -> the middle closes 20 (its offset); 485 -> thumb and middle 15; 500 -> 15 again; the
    # index (-30) never rises above where it started, so it is never told to move at all
    assert res.grip_added == {"middle": 50.0, "thumb": 30.0}
    assert ("close", (Finger.INDEX,)) not in hand.sent


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), "20"])
def test_a_bad_offset_is_refused_before_anything_is_sent(bad):
    hand = _Hand()
    with pytest.raises(ParameterError, match="finger_offsets\\[middle\\]"):
        run_loop(_Samples(4), hand, _Offset({Finger.MIDDLE: bad}), p0=470.0, duration=0.2, guard=False)
    assert hand.sent == []  # not even the safe start's STOP


@pytest.mark.realtime
@pytest.mark.slow
def test_cli_run_with_the_authors_gui_preset_offsets_the_middle_finger_and_replays(tmp_path, capsys):
    from test_safe_start import _run_on_virtual_rig

    from slipreflex.cli import main

    code, grasp, lowest, path = _run_on_virtual_rig(tmp_path, "thumb=148,index=147,middle=147",
                                                    schedule=[("drop", 0.2)],
                                                    extra=("--preset", "authors-gui"))
    assert code == 0, capsys.readouterr().err
    assert lowest == grasp.positions  # no finger ever below where the grasp left it
    r = read_recording(path)
    assert r.metadata[METADATA_NAME]["reflex"] == "authors-gui"
    sent = [m for m in r.topic("/hand/commands") if m["sent"]]
    assert sent and sent[0]["grip"]["middle"] == sent[0]["grip"]["index"] + 20  # the offset, once
    assert all(m["grip"]["middle"] == m["grip"]["index"] for m in sent[1:])
    capsys.readouterr()
    assert main(["replay", str(path)]) == 0
    assert "identical" in capsys.readouterr().out


@pytest.mark.parametrize("option", [("--kp", "3"), ("--method", "fixed"), ("--no-filter",)])
def test_cli_run_refuses_a_preset_with_another_chain_option(tmp_path, capsys, option):
    from slipreflex.cli import main

    code = main(["run", "--daq", str(tmp_path / "no-daq"), "--hand", str(tmp_path / "no-hand"),
                 "--p0", "147", "--no-record", "--preset", "authors-gui", *option])
    err = capsys.readouterr().err
    assert code == 2 and option[0] in err and len(err.strip().splitlines()) == 1, err
