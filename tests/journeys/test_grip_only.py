"""Grip only ever added: whatever --p0 says, the reflex never opens the hand and adds the same grip.

The grasp leaves the fingers at 148/147/147 (the virtual rig's TX bottle, seed 165); --p0 0, 100,
148, 200 and 500 are tried with a drop and a pour, in simulated time (exact, every closing
compared) and on the virtual rig through ``slipreflex run`` (real time)."""

from __future__ import annotations

import math
import os

import pytest
import serial

from slipreflex.cli import main
from slipreflex.commands.run import add_arguments, chain_params
from slipreflex.core.errors import ParameterError
from slipreflex.core.grip import Grip, span
from slipreflex.core.hardware import DAQ_PERIOD_S, FINGER_SPEED_UNITS_S, TRIPOD, Finger, HandCommand
from slipreflex.methods.chain import SlipReflex
from slipreflex.rig.devices.ilimb import ILimb, PacketParser
from slipreflex.rig.devices.simrig import SimRig
from slipreflex.rig.devices.virtual import VirtualDevices
from slipreflex.rig.runtime import run_loop

P0S = [0, 100, 148, 200, 500]
SEED = 165


def _cli_reflex(p0):
    """The reflex exactly as ``slipreflex run --p0 P0`` builds it."""
    import argparse

    p = argparse.ArgumentParser()
    add_arguments(p)
    args = p.parse_args(["--daq", "d", "--hand", "h", "--p0", str(p0)])
    return SlipReflex.from_params(chain_params(args, float(p0)))


class _ILimbLike:
    """The simulated hand as `run` sees the i-Limb: it reports no positions. Notes every command
    with the rig's time."""

    def __init__(self, sim):
        self.sim, self.hand, self.log = sim, sim.rig.hand, []

    def set_positions(self, targets):
        raise AssertionError(f"a position was sent: {targets}")

    def close_fingers(self, fingers, speed):
        self.log.append((round(self.sim.rig.t, 9), "close", tuple(fingers), speed))
        self.hand.close_fingers(fingers, speed)

    def hold(self, fingers):
        self.log.append((round(self.sim.rig.t, 9), "stop", tuple(fingers)))
        self.hand.hold(fingers)

    def positions(self):
        return {}


class _Source:
    """The rig in simulated time, 4 samples a read; notes every measured tripod position."""

    def __init__(self, sim):
        self.sim, self.seen = sim, []

    def read(self, timeout):
        rig = self.sim.rig
        out = rig.advance_to(rig.t + 4 * DAQ_PERIOD_S)
        self.seen.append(dict(rig.hand.positions()))
        return out

    def close(self):
        pass


def _simulated_run(p0, what, duration):
    sim = SimRig("TX", seed=SEED)
    grasp = sim.grasp()
    hand, src = _ILimbLike(sim), _Source(sim)
    sim.perturb(what)
    res = run_loop(src, hand, _cli_reflex(p0), p0=p0, duration=duration, watchdog=0.5,
                   clock=lambda: sim.rig.t, guard=False)
    return grasp, res, hand.log, src.seen, sim.rig.fallen


@pytest.mark.slow
@pytest.mark.parametrize("what, duration", [("drop", 1.5), ("pour", 32.0)])
def test_every_p0_adds_the_same_grip_never_opens_and_holds_the_bottle(what, duration):
    runs = {p0: _simulated_run(p0, what, duration) for p0 in P0S}
    grasp, right, right_log, _, right_fallen = runs[148]
    assert grasp.p0_text() == "thumb=148,index=147,middle=147"
    assert right_log and right.events > 0  # the reflex did close the hand
    assert not right_fallen  # the correct p0 holds the bottle...
    for p0, (_, res, log, seen, fallen) in runs.items():
        assert not fallen, p0  # ...and so does every other p0
        assert log == right_log, p0  # the very same closings, at the same times
        assert res.grip_added == right.grip_added and res.saturated_at is None, p0
        assert {x[1] for x in log} <= {"close", "stop"}  # no OPEN, no position
        for f in TRIPOD:  # no finger ever moved toward open, at any read
            track = [grasp.positions[f]] + [s[f] for s in seen]
            assert all(b >= a for a, b in zip(track, track[1:])), (p0, f)
        assert "fully closed" not in res.summary()


def _virtual_run(tmp_path, p0, what, duration="1.0"):
    """``slipreflex run`` on the virtual rig; ``what`` starts 0.2 s after the run's safe-start STOP
    reached the hand (however long the run took to start); notes every measured tripod position."""
    sim = SimRig("TX", seed=SEED)
    grasp = sim.grasp()
    track = {f: [grasp.positions[f]] for f in TRIPOD}
    started = []

    def look(dev):
        for f, v in dev.rig.hand.positions().items():
            if f in track:
                track[f].append(v)
        if not started and dev.hand_packets:
            started.append(dev.elapsed)
        elif started and len(started) == 1 and dev.elapsed >= started[0] + 0.2:
            started.append(dev.elapsed)
            dev.rig.perturb(what)

    script = [(k * 0.005, look) for k in range(int(60 / 0.005))]
    sent = []
    with VirtualDevices(sim, script=script) as dev:
        apply = dev._apply_packet

        def note(cmds):   # every command that reached the hand, as the hand received it
            sent.extend(c.command for c in cmds)
            apply(cmds)

        dev._apply_packet = note
        code = main(["run", "--daq", dev.daq_path, "--hand", dev.hand_path, "--p0", str(p0),
                     "--duration", duration, "--no-record"])
        packets = dev.hand_packets
    assert len(started) == 2, "the perturbation never started"
    assert sent and set(sent) <= {HandCommand.CLOSE, HandCommand.STOP}, sorted(set(sent))  # no OPEN, no position
    return code, grasp, track, sim, packets


@pytest.mark.slow
@pytest.mark.parametrize("p0", P0S)
def test_run_on_the_virtual_rig_with_any_p0_never_opens_and_answers_the_drop(tmp_path, capsys, p0):
    code, grasp, track, sim, packets = _virtual_run(tmp_path, p0, "drop")
    out = capsys.readouterr().out
    assert code == 0
    assert not sim.rig.fallen, out
    for f in TRIPOD:
        assert all(b >= a for a, b in zip(track[f], track[f][1:])), (f, track[f][:20])
    assert "grip added: thumb" in out  # the drop was answered with grip, whatever p0 said
    assert max(track[Finger.MIDDLE]) > grasp.positions[Finger.MIDDLE]
    assert "fully closed" not in out and "ceiling" not in out
    # and the bounded grip keeps the force at or under the digits' stall force
    assert sim.rig.normal_force <= sim.rig.hand_params.stall_force_n + 1.0


@pytest.mark.slow
@pytest.mark.parametrize("p0", [0, 500])
def test_a_pour_on_the_virtual_rig_never_opens_the_hand(tmp_path, capsys, p0):
    code, grasp, track, sim, _ = _virtual_run(tmp_path, p0, "pour", duration="2.0")
    assert code == 0 and not sim.rig.fallen
    for f in TRIPOD:
        assert min(track[f]) == grasp.positions[f]
        assert all(b >= a for a, b in zip(track[f], track[f][1:]))


def test_a_finger_given_twice_in_p0_is_one_line_and_nothing_is_sent(tmp_path, capsys):
    class Rig:
        hand = None

        def advance_to(self, t):
            return []

    with VirtualDevices(Rig()) as dev:
        code = main(["run", "--daq", dev.daq_path, "--hand", dev.hand_path, "--no-record",
                     "--p0", "thumb=148,thumb=14,index=147,middle=147"])
        sent = dev.hand.read()
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "thumb is given twice" in err, err
    assert sent == b"" and dev.hand_packets == 0


def _ilimb():
    loop = serial.serial_for_url("loop://", timeout=0)
    return ILimb(loop), loop


def test_the_ilimb_refuses_an_open_or_a_lower_position_while_a_reflex_runs():
    hand, loop = _ilimb()
    hand.set_positions({f: 148 for f in TRIPOD})  # the grasp routine may position the fingers
    hand.reflex_running()
    loop.read(1000)
    with pytest.raises(ParameterError, match="OPEN refused while a reflex runs"):
        hand.send([hw_cmd(Finger.INDEX, HandCommand.OPEN, 100)])
    with pytest.raises(ParameterError, match=r"POSITION 147 refused while a reflex runs \(below its target 148\)"):
        hand.set_positions({Finger.MIDDLE: 147})
    with pytest.raises(ParameterError, match="POSITION 10 refused"):
        hand.send([hw_cmd(Finger.THUMB, HandCommand.POSITION, 10)])
    assert loop.read(1000) == b""  # nothing reached the port
    hand.set_positions({Finger.MIDDLE: 150})  # higher than it was told: allowed
    hand.close_fingers([Finger.MIDDLE], FINGER_SPEED_UNITS_S)
    with pytest.raises(ParameterError, match="a CLOSE moved the finger"):
        hand.set_positions({Finger.MIDDLE: 200})  # where is it now? nobody measured it
    packets = PacketParser().feed(loop.read(1000))
    assert [c.command for p in packets for c in p] == [HandCommand.POSITION, HandCommand.CLOSE]
    assert packets[1][0].value == 297  # the documented speed is full PWM
    hand.reflex_running(False)
    hand.set_positions({Finger.MIDDLE: 100})  # the grasp routine's business again
    hand.close()
    loop.close()


def hw_cmd(finger, command, value):
    from slipreflex.rig.devices.ilimb import FingerCommand

    return FingerCommand(finger, command, value)


def test_the_ilimb_reports_no_positions_and_run_loop_turns_its_guard_on_and_off():
    hand, loop = _ilimb()
    states = []
    original = hand.reflex_running
    hand.reflex_running = lambda running=True: (states.append(running), original(running))

    class Still:
        def read(self, timeout):
            return []

        def close(self):
            pass

    run_loop(Still(), hand, SlipReflex(p0=148.0), duration=0.05, guard=False)
    assert states == [True, False] and hand.positions() == {}
    packets = PacketParser().feed(loop.read(1000))
    assert all(c.command == HandCommand.STOP for p in packets for c in p)  # the safe start's STOP
    hand.close()
    loop.close()


def test_grip_is_the_rise_and_closing_time_accumulates():
    g = Grip(148.0, TRIPOD)
    assert g.rise(140.0) == [0.0] and g.rise(158.0) == [10.0] and g.rise(158.0) == [0.0]
    assert g.added == [10.0]
    start, stop = span(1.0, -math.inf, 12.5)
    assert (start, stop) == (1.0, 1.02)
    assert span(1.01, stop, 6.25) == (1.02, 1.03)  # a rise while closing: closes 10 ms longer
    with pytest.raises(ParameterError, match="finite"):
        g.rise(math.inf)


def test_the_loop_gives_up_the_capability_it_was_given_for_the_scheduler():
    """A non-root process started with CAP_SYS_NICE keeps SCHED_FIFO and drops every capability."""
    import subprocess
    import sys
    import textwrap

    code = textwrap.dedent("""
        import os
        from slipreflex import privileges, runtime
        print(runtime.drop_capabilities())          # as root: says so, keeps its rights
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(5))
        except OSError:
            pass
        policy = os.sched_getscheduler(0)
        os.geteuid = lambda: 1000                   # the path of a user with CAP_SYS_NICE
        print(runtime.drop_capabilities())
        print(privileges._capabilities(), os.sched_getscheduler(0) == policy)
    """)
    if not sys.platform.startswith("linux") or os.geteuid() != 0:
        pytest.skip("needs Linux and root to hand a process capabilities")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         timeout=60).stdout.splitlines()
    assert out[0].startswith("root: not needed, its rights are kept")
    assert out[1].startswith("gave up capabilities") and "CAP_SYS_NICE" in out[1], out
    assert out[2] == "(0, 0) True", out
