"""The virtual rig: `slipreflex run` over ptys suppresses slip like the in-process simulation."""

from __future__ import annotations

import signal
import subprocess
import threading
import sys
import time

from slipreflex.chain import SlipReflex
from slipreflex.cli import main
from slipreflex.devices.daq import SerialDaq
from slipreflex.devices.ilimb import ILimb
from slipreflex.devices.simrig import SimRig
from slipreflex.devices.virtual import VirtualDevices
from slipreflex.hardware import SLIP_FINGER, TRIPOD
from slipreflex.sim.loop import run_closed_loop
from slipreflex.sim.objects import Pour
from slipreflex.sim.rig import Rig

# A fast pour (150 ml at 4 L/min) that makes the bottle fall out of an unassisted grasp
# in about 2.5 s, short enough for a real-time test.
POUR = Pour(rate_l_min=4.0, volume_ml=150.0)
AT = 0.3
RUN_S = 3.6


class _Hold:
    name, input_kind, fs = "hold", "slip", 333.0

    def step(self, sample, position=None):
        return None

    def reset(self):
        pass


def _in_process(reflex_factory):
    rig = Rig("TR", seed=0)
    g = rig.grasp()
    p0 = g.positions[SLIP_FINGER]
    rig.perturb(POUR, at=rig.t + AT)
    run_closed_loop(rig, reflex_factory(p0), RUN_S)
    return rig


def test_run_over_virtual_devices_suppresses_slip_like_the_in_process_simulation(tmp_path):
    without = _in_process(lambda p0: _Hold())
    assert without.fallen  # the pour is enough to lose the bottle without the reflex
    inproc = _in_process(lambda p0: SlipReflex(dath=True, p0=p0))
    assert not inproc.fallen

    sim = SimRig("TR", seed=0, pour=POUR)
    p0 = sim.grasp().position
    reflex = SlipReflex(dath=True, p0=p0)  # built before the clock starts
    with VirtualDevices(sim, link_dir=str(tmp_path), schedule=[("pour", AT)]) as dev:
        with SerialDaq(dev.daq_path) as daq, ILimb(dev.hand_path) as hand:
            hand.set_positions({f: p0 for f in TRIPOD})
            res = run_loop_for(daq, hand, reflex, RUN_S)
    assert dev.triggered[0][0] == "pour"
    assert res.events > 0 and res.commands_sent == res.commands > 0
    assert res.daq_stats["seq_gaps"] == 0 and res.daq_stats["crc_errors"] == 0
    assert not sim.rig.fallen, sim.status()
    # Same reflex, same physics, through serial ports in real time: the bottle slides about
    # as far as in the in-process run (timing differs by the loop's and the ports' latency,
    # and by the machine's load).
    # (measured: 16.7 mm over ptys, 15.3 mm in-process, 29.8 mm and fallen unassisted)
    assert abs(sim.rig.slip - inproc.slip) < 0.5 * inproc.slip, (sim.rig.slip, inproc.slip)


def run_loop_for(daq, hand, reflex, duration):
    from slipreflex.runtime import run_loop
    return run_loop(daq, hand, reflex, duration=duration)


def _readline(proc, want, deadline_s=120.0):
    deadline = time.monotonic() + deadline_s
    lines = []
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        lines.append(line)
        if line.startswith(want):
            return line, lines
    raise AssertionError(f"no line starting with {want!r}; got {lines}")


def test_virtual_rig_command_keys_signals_schedule_and_run(tmp_path, capsys):
    proc = subprocess.Popen([sys.executable, "-m", "slipreflex", "virtual-rig", "--link-dir", str(tmp_path),
                             "--schedule", "drop@0.2", "--duration", "60"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    killer = threading.Timer(90, proc.kill)  # bounds the test if the child hangs
    killer.start()
    try:
        _, lines = _readline(proc, "keys")
        info = dict(line.split(": ", 1) for line in lines if ": " in line)
        assert info["daq"].strip() == str(tmp_path / "daq") and info["hand"].strip() == str(tmp_path / "hand")
        p0 = info["p0"].strip()
        code = main(["run", "--daq", str(tmp_path / "daq"), "--hand", str(tmp_path / "hand"),
                     "--p0", p0, "--duration", "1.0", "--no-record"])
        assert code == 0
        out = capsys.readouterr().out
        assert "seq_gaps 0" in out and "crc_errors 0" in out
        assert "commands 0 " not in out and "(0 sent)" not in out
        proc.stdin.write("p\n")
        proc.stdin.flush()
        _readline(proc, "pour at")
        proc.send_signal(signal.SIGUSR1)
        _readline(proc, "drop at")
        proc.stdin.write("q\n")
        proc.stdin.flush()
        rest = proc.stdout.read()
        assert proc.wait(timeout=30) == 0
    finally:
        killer.cancel()
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        proc.stdin.close()
        proc.stdout.close()
    assert "perturbations [('drop', 0.2" in rest and "'pour'" in rest and rest.count("'drop'") == 2
    assert "hand packets applied (0 rejected)" in rest


def test_tripod_grasp_routine_on_the_simulated_hand():
    from slipreflex.devices.ilimb import tripod_grasp
    from slipreflex.hardware import CONTACT_FORCE_N, Finger

    rig = Rig("TR", seed=0)

    def contact():  # both tactile arrays (index, thumb) must feel the object
        return min(rig.tactile(Finger.INDEX).sum(), rig.tactile(Finger.THUMB).sum())

    res = tripod_grasp(rig.hand, contact, step=2.0, settle=lambda: rig.advance(0.03))
    assert res.contact and res.force >= CONTACT_FORCE_N
    assert contact() >= CONTACT_FORCE_N
    pos = rig.hand.positions()
    assert all(abs(pos[f] - res.position) <= 2 for f in TRIPOD)
    rig.release_support()
    rig.advance(1.0)
    assert not rig.fallen  # 0.8 N per contact holds the empty bottle
