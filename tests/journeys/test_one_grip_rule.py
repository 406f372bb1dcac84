"""One grip rule for every method and hand: the grip added is relative to the measured grasp,
whatever --p0 says, and at most one finger travel (and the method's own ceiling).

Every registered method is built exactly as ``slipreflex run`` builds it and run in simulated
time against a hand that measures its fingers (the Ability Hand's case: the grasp left them at
148/147/147), on the same drop, at --p0 0, 148 and 500."""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest
from loop_fakes import LogHand, StillSource

from slipreflex import methods
from slipreflex.commands.run import add_arguments, build_reflex, parse_p0
from slipreflex.core.grip import TRAVEL, Grip
from slipreflex.core.hardware import DAQ_PERIOD_S, TRIPOD, Finger
from slipreflex.core.interfaces import TactileSample
from slipreflex.methods.baselines import rest_threshold
from slipreflex.rig.devices.ability import sites_from_array
from slipreflex.rig.devices.simrig import SimRig
from slipreflex.rig.runtime import run_loop

SEED = 165
P0S = (0, 148, 500)


class _MeasuringHand:
    """The simulated hand as `run` sees a hand that reports its fingers; logs every command."""

    def __init__(self, sim):
        self.sim, self.hand, self.log = sim, sim.rig.hand, []

    def set_positions(self, targets):
        raise AssertionError(f"a position was sent: {targets}")

    def close_fingers(self, fingers, speed):
        self.log.append((round(self.sim.rig.t, 9), "close", tuple(fingers)))
        self.hand.close_fingers(fingers, speed)

    def hold(self, fingers):
        self.log.append((round(self.sim.rig.t, 9), "stop", tuple(fingers)))
        self.hand.hold(fingers)

    def positions(self):
        return {f: float(v) for f, v in self.hand.positions().items()}


class _DaqSource:
    def __init__(self, sim):
        self.sim = sim

    def read(self, timeout):
        rig = self.sim.rig
        return rig.advance_to(rig.t + 4 * DAQ_PERIOD_S)

    def close(self):
        pass


class _TouchSource:
    """The index fingertip's six sites at the method's rate, in simulated time."""

    def __init__(self, sim, fs):
        self.sim, self.fs, self.seq = sim, fs, 0

    def read_frames(self, timeout):
        rig = self.sim.rig
        rig.advance_to(rig.t + 1.0 / self.fs)
        self.seq += 1
        return [TactileSample(self.seq, rig.t, sites_from_array(self.sim.tactile(Finger.INDEX)))]

    def close(self):
        pass


def _args(method, p0, threshold=None):
    p = argparse.ArgumentParser()
    add_arguments(p)
    argv = ["--hand", "h", "--hand-type", "ability", "--p0", str(p0), "--method", method]
    spec = methods.get(method)
    argv += ["--daq", "d"] if spec.input_kind == "slip" else ["--tactile-threshold", f"{threshold:.6g}"]
    return p.parse_args(argv)


def _threshold(method):
    sim = SimRig("TX", seed=SEED)
    sim.grasp()
    spec = methods.get(method)
    src = _TouchSource(sim, spec.fs)
    frames = np.array([src.read_frames(0)[0].frame for _ in range(int(spec.fs))])
    return rest_threshold(frames, method, spec.fs)


def _drop(method, p0, threshold):
    sim = SimRig("TX", seed=SEED)
    sim.grasp()
    hand = _MeasuringHand(sim)
    args = _args(method, p0, threshold)
    reflex, _ = build_reflex(args, parse_p0(args.p0))
    spec = methods.get(method)
    source = _DaqSource(sim) if spec.input_kind == "slip" else _TouchSource(sim, spec.fs)
    sim.perturb("drop")
    res = run_loop(source, hand, reflex, p0=parse_p0(args.p0), duration=1.5, watchdog=0.5,
                   clock=lambda: sim.rig.t, guard=False)
    return res, hand.log


@pytest.mark.slow
@pytest.mark.parametrize("method", methods.names())
def test_every_method_adds_the_same_grip_at_every_p0_on_the_same_drop(method):
    thr = _threshold(method) if methods.get(method).input_kind == "tactile" else None
    runs = {p0: _drop(method, p0, thr) for p0 in P0S}
    right, right_log = runs[148]
    for p0, (res, log) in runs.items():
        assert log == right_log, (method, p0)             # the very same closings at the same times
        assert res.grip_added == right.grip_added, (method, p0)
        assert "no-grip-room" not in {f.kind for f in res.faults}, (method, p0)
        assert all(v <= TRAVEL + 1e-9 for v in res.grip_added.values())


def test_at_the_board_ceiling_a_reflex_says_it_can_add_no_grip():
    """The fixed-point board twin built at 500 (its absolute ceiling): a fault, never 'faults: none'."""
    res = _plugin_run(methods.make("dath-board", p0=500.0), p0=500)
    assert res.faults[0].kind == "no-grip-room" and "faults: none" not in res.summary()
    assert res.grip_added == {}


class _Plugin:
    """A registered method gone wrong: a fixed command from the first sample on."""

    input_kind, name = "slip", "plugin"

    def __init__(self, command, start=148.0, offsets=None):
        self.out, self.command = command, start
        self.finger_offsets = offsets or {}
        self.last_filtered = self.last_threshold = self.last_count = None
        self.last_event = False

    def step(self, volts, position=None):
        return self.out


def _plugin_run(reflex, p0=148, hand=None):
    src = StillSource()
    return run_loop(src, hand or LogHand(), reflex, p0=p0, duration=1.0, watchdog=0.5,
                    clock=lambda: src.now, guard=False)


@pytest.mark.parametrize("plugin", [_Plugin(1e9), _Plugin(600.0, start=-1e6),
                                    _Plugin(149.0, offsets={Finger.MIDDLE: 1e7}), _Plugin(math.nan),
                                    _Plugin(-1e6)], ids=["1e9", "start-1e6", "offset-1e7", "nan", "-1e6"])
def test_a_plugin_command_adds_at_most_one_finger_travel(plugin):
    res = _plugin_run(plugin)
    assert all(0.0 <= v <= TRAVEL for v in res.grip_added.values()), res.grip_added
    kinds = {f.kind for f in res.faults}
    if plugin.out != plugin.out:
        assert "command-rejected" in kinds and res.grip_added == {}
    elif plugin.out > 1e6 or plugin.command < -1e5:
        assert "mpi-saturated" in kinds and max(res.grip_added.values()) > 0
    if plugin.finger_offsets:  # the middle finger's group reached its ceiling: said so
        assert res.grip_added["middle"] <= TRAVEL and "mpi-saturated" in kinds


def test_grip_never_exceeds_its_ceiling_and_has_none_unless_given():
    assert Grip(0.0, TRIPOD).rise(600.0) == [600.0]  # the simulator's loops: as their compiled twin
    g = Grip(-1e6, TRIPOD, ceiling=-1e6 + TRAVEL)
    assert g.rise(1e9) == [TRAVEL] and g.rise(2e9) == [0.0]


def test_a_method_that_raises_in_step_is_a_fault_with_the_fingers_held_and_a_summary():
    class Broken(_Plugin):
        steps = 0

        def step(self, volts, position=None):
            self.steps += 1
            if self.steps > 40:  # the warm-up's copy and the first 39 samples pass
                raise ZeroDivisionError("boom")
            return self.out

    hand = LogHand()
    res = _plugin_run(Broken(150.0), hand=hand)
    assert [f.kind for f in res.faults] == ["reflex-error"]
    assert res.error and "ZeroDivisionError: boom" in res.error and "ended early" in res.summary()
    assert hand.log[-1][0] == "stop" and {k for k, _ in hand.log} <= {"close", "stop"}


def test_a_method_that_raises_on_its_first_sample_is_refused_before_anything_is_sent():
    from slipreflex.core.errors import ParameterError

    class Broken(_Plugin):
        def step(self, volts, position=None):
            raise KeyError("x")

    hand = LogHand()
    with pytest.raises(ParameterError, match="raised in step"):
        _plugin_run(Broken(150.0), hand=hand)
    assert hand.log == []
