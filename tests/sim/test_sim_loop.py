"""Closed loops on the simulated rig: the paper's chain catches a slow pour that drops the bottle without it."""

import numpy as np
import pytest

import slipreflex
from slipreflex.core import hardware as hw
from slipreflex.core.interfaces import Reflex
from slipreflex.sim import HandParams, Pour, Rig, run_closed_loop, simulate_open_loop

SLOW_POUR = Pour(rate_l_min=0.5, volume_ml=300)


def _pour_rig(seed=2):
    rig = Rig("TR", seed=seed)
    g = rig.grasp()
    rig.perturb(SLOW_POUR, at=rig.t + 0.5)
    return rig, g


def test_without_the_reflex_the_slow_pour_drops_the_bottle():
    rig, _ = _pour_rig()
    tr = simulate_open_loop(rig, SLOW_POUR.duration_s + 2.0)
    assert tr.fallen and tr.fall_time is not None


@pytest.mark.parametrize("dath", [False, True])
def test_slip_reflex_catches_the_slow_pour(dath):
    rig, g = _pour_rig()
    reflex = slipreflex.SlipReflex(fs=hw.DAQ_FS, dath=dath, p0=g.positions[hw.SLIP_FINGER])
    assert isinstance(reflex, Reflex)
    tr = run_closed_loop(rig, reflex, SLOW_POUR.duration_s + 2.0)
    assert not tr.fallen
    x = tr.daq.displacement
    # the bottle moves: a gross slip, or (the reflex closing first) the pads creeping 20 um and more while the
    # cuff still holds
    moved = tr.t[np.argmax(x - x[0] > 20e-6)] if (x - x[0] > 20e-6).any() else np.nan
    onset = tr.slip_events[0].onset if tr.slip_events else moved
    assert np.isfinite(onset), "the pour must move the bottle"
    # the controller answered that motion by closing the fingers within its first 2 mm (a slowly
    # loaded rate-state contact creeps for a while before it runs, so time from onset is not the test)
    up = tr.cmd_t[(tr.cmd_t >= onset) & (tr.cmd_value > g.positions[hw.SLIP_FINGER])]
    assert up.size and not (tr.cmd_value[tr.cmd_t < onset] > g.positions[hw.SLIP_FINGER]).any()
    assert x[np.searchsorted(tr.t, up[0])] - x[np.searchsorted(tr.t, onset)] < 2e-3
    assert np.all(np.diff(tr.cmd_value) >= 0)              # MPI: monotonic
    assert tr.daq.fingers[-1, 2] > g.positions[hw.SLIP_FINGER]
    assert tr.daq.load_mass[-1] == pytest.approx(rig.bottle.mass_kg + 0.3)
    # every DAQ sample was fed: one command per 16-sample window at most
    assert tr.cmd_t.size <= tr.t.size // hw.WINDOW_N + 1


class _Probe:
    """Stand-in tactile reflex: records what it is fed, squeezes once after 0.1 s."""

    name, input_kind = "probe", "tactile"

    def __init__(self, fs):
        self.fs = fs
        self.frames, self.positions = [], []

    def step(self, sample, position=None):
        self.frames.append(np.array(sample))
        self.positions.append(position)
        return position + 50 if len(self.frames) == int(0.1 * self.fs) else None

    def reset(self):
        self.frames.clear()


@pytest.mark.parametrize("fs", [hw.NMSD_FS, hw.SWT_FS])
def test_tactile_reflex_is_fed_frames_at_its_rate_and_moves_the_tripod(fs):
    rig = Rig("TX", seed=1)
    g = rig.grasp()
    probe = _Probe(fs)
    tr = run_closed_loop(rig, probe, 0.5)
    assert len(probe.frames) == pytest.approx(0.5 * fs, abs=1)
    assert probe.frames[0].shape == hw.TACTILE_SHAPE
    assert tr.tactile.shape == (len(probe.frames),) + hw.TACTILE_SHAPE
    assert probe.positions[0] == g.positions[hw.SLIP_FINGER]
    # the command reaches all three tripod fingers after the latency, then the servo moves them
    t_cmd = tr.cmd_t[0]
    lat = rig.hand.latency
    before = tr.t < t_cmd + lat - 1e-9
    assert np.all(tr.daq.fingers[before] == tr.daq.fingers[0])
    # the grip-only rule closes for rise / full speed seconds; loaded, the digit motors run slower (their
    # torque-speed line), so they close most, not all, of the rise
    rise = tr.cmd_value[0] - g.positions[hw.SLIP_FINGER]
    assert np.all(tr.daq.fingers[-1] <= tr.cmd_value[0] + 1.0)
    assert np.all(tr.daq.fingers[-1] >= g.positions[hw.SLIP_FINGER] + 0.8 * rise)
    assert tr.daq.normal_force[-1] > g.force_n + 2.0
    # without the droop they close the whole rise
    rig = Rig("TX", seed=1, hand=HandParams(motor_droop=0.0))
    g = rig.grasp()
    tr = run_closed_loop(rig, _Probe(fs), 0.5)
    assert np.allclose(tr.daq.fingers[-1], tr.cmd_value[0], atol=1.0)


def test_trace_export(tmp_path):
    rig, g = _pour_rig()
    reflex = slipreflex.SlipReflex(fs=hw.DAQ_FS, p0=g.positions[hw.SLIP_FINGER])
    tr = run_closed_loop(rig, reflex, 1.0)
    frame = tr.to_frame()
    assert {len(v) for v in frame.values()} == {tr.t.size}
    p = tr.write_csv(tmp_path / "trace.csv")
    lines = p.read_text().splitlines()
    assert lines[0].split(",")[:2] == ["t", "volts"] and len(lines) == tr.t.size + 1
    assert tr.perturbations and tr.perturbations[0][1] == SLOW_POUR
