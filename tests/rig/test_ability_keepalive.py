"""The Ability Hand as PSYONIC runs it: never silent for its API timeout, replies read
continuously, a stalled finger reported, no position frame while a reflex runs; and the
virtual twin that catches each of these when it goes wrong."""

from __future__ import annotations

import time

import numpy as np
import pytest

from slipreflex.core.errors import ParameterError
from slipreflex.core.hardware import FINGER_SPEED_UNITS_S, Finger
from slipreflex.rig.devices import ability as ab
from slipreflex.rig.devices.simrig import SimRig
from slipreflex.rig.devices.virtual import VirtualDevices
from slipreflex.rig.hands import open_hand


class _Rig:
    """A rig for the twin alone: a hand that remembers its targets."""

    class hand:  # noqa: N801 - the rig's attribute, as SimRig names it
        pos: dict = {}

        @staticmethod
        def set_positions(t):
            _Rig.hand.pos.update(t)

        @staticmethod
        def positions():
            return dict(_Rig.hand.pos)

    def tactile(self, finger):
        return np.zeros((4, 4))


def test_the_twin_leaves_api_mode_after_a_silence_and_the_fingers_move():
    now = [0.0]
    _Rig.hand.pos = {Finger.INDEX: 200.0, Finger.MIDDLE: 200.0, Finger.THUMB: 200.0}
    twin = ab.VirtualAbilityHand(_Rig(), clock=lambda: now[0])
    twin.feed(ab.encode_read())
    now[0] = 0.25
    twin.tick()
    assert twin.api_timeouts == 0 and twin.in_api
    now[0] = 0.31
    twin.tick()
    assert twin.api_timeouts == 1 and not twin.in_api
    assert _Rig.hand.pos[Finger.INDEX] == 0.0  # the undesired movement, at its worst for a grasp


def test_the_twin_reports_a_stall_and_ignores_closing_until_opened():
    _Rig.hand.pos = {Finger.INDEX: 200.0, Finger.MIDDLE: 200.0, Finger.THUMB: 200.0}
    twin = ab.VirtualAbilityHand(_Rig())
    twin.stall(Finger.INDEX)
    reply = ab.decode_reply(ab.unstuff(twin.feed(ab.encode_read()))[0])
    assert ab.stalled_fingers(reply.status) == {Finger.INDEX}
    twin.feed(ab.encode_positions([ab.degrees_of(f, 300.0) for f in ab.ORDER]))
    assert _Rig.hand.pos[Finger.INDEX] == 200.0 and _Rig.hand.pos[Finger.MIDDLE] == pytest.approx(300.0, abs=0.01)
    twin.feed(ab.encode_positions([ab.degrees_of(f, 100.0) for f in ab.ORDER]))  # opening clears it
    reply = ab.decode_reply(ab.unstuff(twin.feed(ab.encode_read()))[0])
    assert reply.status == 0 and _Rig.hand.pos[Finger.INDEX] == pytest.approx(100.0, abs=0.01)


def test_a_keepalive_outside_the_api_timeout_is_refused():
    with pytest.raises(ParameterError, match="keepalive"):
        ab.AbilityHand("/nonexistent/tty", keepalive=0.3)


def _devices(tmp_path):
    rig = SimRig("TR", seed=3)
    grasp = rig.grasp()
    return VirtualDevices(rig, hand_type="ability", link_dir=str(tmp_path)), grasp


@pytest.mark.slow
def test_the_driver_keeps_the_hand_in_api_mode_and_its_positions_live_without_being_asked(tmp_path):
    """A DAQ run's case: nobody reads frames and no slip comes; the hand must still hear from the
    host, and positions() must follow a closing."""
    dev, grasp = _devices(tmp_path)
    with dev:
        with open_hand("ability", dev.hand_path) as hand:
            start = hand.positions()[Finger.MIDDLE]
            time.sleep(1.0)                                   # silence from the caller
            assert dev.emulator.api_timeouts == 0 and dev.emulator.in_api
            hand.close_fingers([Finger.MIDDLE], FINGER_SPEED_UNITS_S)
            time.sleep(0.15)
            hand.hold([Finger.MIDDLE])
            time.sleep(0.1)
            live = hand.positions()[Finger.MIDDLE]
            assert live > start + 5.0                         # read without read_frames
            assert abs(live - dev.rig.rig.hand.positions()[Finger.MIDDLE]) < 5.0
            time.sleep(0.5)
        assert dev.emulator.api_timeouts == 0


@pytest.mark.slow
def test_a_stalled_finger_is_a_fault_and_grip_sent_to_it_is_not_counted(tmp_path):
    from slipreflex.core.interfaces import DaqSample
    from slipreflex.rig.runtime import run_loop

    dev, grasp = _devices(tmp_path)

    class Src:  # a still slip sensor, one sample a read
        def __init__(self):
            self.k = 0

        def read(self, timeout):
            time.sleep(min(timeout, 0.003))
            self.k += 1
            return [DaqSample(self.k, self.k * 0.003, 0.4, None, 0)]

        def close(self):
            pass

    class Step:  # asks for 40 units more grip from the first sample on
        input_kind, name, command = "slip", "step", 148.0
        last_filtered = last_threshold = last_count = None
        last_event = False

        def step(self, volts, position=None):
            return 188.0

    with dev:
        dev.emulator.stall(Finger.INDEX)
        with open_hand("ability", dev.hand_path) as hand:
            time.sleep(0.05)
            assert hand.stalled() == {Finger.INDEX}
            res = run_loop(Src(), hand, Step(), p0=148, duration=0.4, watchdog=0.5, guard=False)
    assert "finger-stalled" in {f.kind for f in res.faults} and res.stalled == ["index"]
    assert res.grip_added["index"] == 0.0 and res.grip_added["thumb"] == pytest.approx(40.0, abs=0.5)
    assert "stalled" in res.summary()


def test_every_position_frame_is_refused_while_a_reflex_runs_the_empty_one_included():
    class Port:  # the hand's side, in memory
        timeout, port = 0, "mem://ability"

        def __init__(self):
            _Rig.hand.pos = {Finger.INDEX: 200.0, Finger.MIDDLE: 200.0, Finger.THUMB: 200.0}
            self.twin, self.out, self.written = ab.VirtualAbilityHand(_Rig()), b"", []

        @property
        def in_waiting(self):
            return len(self.out)

        def read(self, n=1):
            data, self.out = self.out[:n], self.out[n:]
            return data

        def write(self, data):
            self.written.append(bytes(data))
            self.out += self.twin.feed(bytes(data))
            return len(data)

        def close(self):
            pass

        is_open = True

    port = Port()
    hand = ab.AbilityHand(port)
    try:
        hand.reflex_running(True)
        before = len([w for w in port.written if ab.decode_command(ab.unstuff(w)[0])[1] & 0xF0 == 0x10])
        for targets in ({}, {Finger.INDEX: 500.0}, {Finger.INDEX: 0.0}):
            with pytest.raises(ParameterError, match="refused while a reflex runs"):
                hand.set_positions(targets)
        after = len([w for w in port.written if ab.decode_command(ab.unstuff(w)[0])[1] & 0xF0 == 0x10])
        assert before == after == 0
        hand.reflex_running(False)
        hand.set_positions({})       # outside a run a grasp routine may position the fingers
    finally:
        hand.close()
