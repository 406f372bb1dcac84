"""The bounded grip: the wall's three-piece law and the digit motor's stall, against closed forms."""

import dataclasses
import math

import numpy as np
import pytest

from slipreflex.core import hardware as hw
from slipreflex.core.errors import ParameterError
from slipreflex.core.hardware import Finger, HandCommand
from slipreflex.sim import BOTTLES, Bottle, HandParams, Rig
from slipreflex.sim import kernel as K
from slipreflex.sim.contacts import grip_curve, normal_stiffness


def test_grip_curve_is_the_series_of_linear_contacts_and_the_three_piece_wall():
    hand, b = HandParams(), BOTTLES["TR"]
    c = grip_curve(hand, b)
    # piece one is the old linear law; the pieces meet (continuous) at the wall's range and collapse
    assert c.k1 == pytest.approx(normal_stiffness(hand, b))
    assert c.force(c.pen1) == pytest.approx(b.wall_stiffness_n_m * b.wall_linear_range_m)
    for pen in (c.pen1, c.pen2):
        assert c.force(pen * (1 - 1e-9)) == pytest.approx(c.force(pen * (1 + 1e-9)), rel=1e-6)
    # by hand: the mean travel is N mean(1/k_surface + 1/k_finger) + the wall's dent under N
    ch = (2 / hand.pad_normal_stiffness_n_m + 1 / hand.cuff_normal_stiffness_n_m) / 3 + 1 / hand.finger_stiffness_n_m
    kw, kw2 = b.wall_stiffness_n_m, (1 - b.wall_softening) * b.wall_stiffness_n_m
    for n in (0.5, 3.0, 8.0, 20.0):
        if n <= c.n1:
            dent = n / kw
        elif n <= c.n2:
            dent = b.wall_linear_range_m + (n - c.n1) / kw2
        else:
            dent = b.wall_collapse_m
        assert c.force(n * ch + dent) == pytest.approx(n, rel=1e-9)
    # without softening and with the collapse out of reach, the linear law everywhere
    lin = dataclasses.replace(b, wall_softening=0.0, wall_linear_range_m=0.05, wall_collapse_m=0.06)
    cl = grip_curve(hand, lin)
    assert cl.force(0.03) == pytest.approx(normal_stiffness(hand, lin) * 0.03)


def test_kernel_normal_force_follows_the_grip_curve_and_the_wall_softens():
    rig = Rig("TR", seed=0)
    rig.grasp()
    c = grip_curve(rig.hand_params, rig.bottle)
    lam = rig.hand_params.travel_per_unit_m
    qc = rig._P[K.P_QC]
    seen = []
    for q in (200, 250, 280):
        rig.hand.set_positions({f: q for f in hw.TRIPOD})
        rig.advance(0.8)
        pen = (float(np.mean(rig.finger_q)) - qc) * lam
        assert rig.normal_force == pytest.approx(c.force(pen), rel=1e-9)
        seen.append(rig.normal_force)
    # the linear law would give k1 * pen; the ovalized wall gives less
    assert seen[1] < c.k1 * (250 - qc) * lam * 0.85


def test_a_closing_digit_approaches_its_stall_force_along_the_motor_line():
    """Closed form: beyond the wall's collapse the force grows at k3 lambda v (1 - N / F_stall), so
    N(t) = F_s - (F_s - N_0) exp(-k3 lambda v t / F_s); it never exceeds the stall force, and the
    non-back-drivable digits hold their positions when the load changes."""
    rig = Rig("TR", seed=0)
    rig.grasp()
    hp = rig.hand_params
    c = grip_curve(hp, rig.bottle)
    rig.hand.command(HandCommand.CLOSE, hw.TRIPOD, hw.PWM_MAX)
    rig.advance(0.02)
    t, nf = [], []
    for _ in range(400):
        rig.advance(0.0025)
        t.append(rig.t)
        nf.append(rig.normal_force)
    t, nf = np.array(t), np.array(nf)
    assert nf.max() <= hp.stall_force_n
    assert nf[-1] == pytest.approx(hp.stall_force_n, rel=0.01)
    rigid = np.flatnonzero(nf > c.n2 + 0.5)
    i0 = rigid[0]
    tau = hp.stall_force_n / (c.k3 * hp.travel_per_unit_m * hp.speed_units_s)
    pred = hp.stall_force_n - (hp.stall_force_n - nf[i0]) * np.exp(-(t[i0:] - t[i0]) / tau)
    assert np.max(np.abs(nf[i0:] - pred)) < 0.01 * hp.stall_force_n
    # non-back-drivable: a drop's impact does not move the digits back
    q0 = rig.finger_q.copy()
    rig.hand.command(HandCommand.STOP, hw.TRIPOD)
    rig.advance(0.2)
    assert np.all(rig.finger_q >= q0 - 1.0)


def test_without_droop_the_digit_closes_at_full_speed_up_to_the_stall():
    hp = HandParams(motor_droop=0.0)
    rig = Rig("TR", seed=0, hand=hp)
    rig.grasp()
    rig.hand.command(HandCommand.CLOSE, [Finger.THUMB, Finger.INDEX, Finger.MIDDLE], hw.PWM_MAX)
    rig.advance(1.0)
    # it stops within one step's advance past the stall force
    c = grip_curve(hp, rig.bottle)
    step = c.k3 * hp.travel_per_unit_m * hp.speed_units_s * rig.physics.dt
    assert hp.stall_force_n <= rig.normal_force <= hp.stall_force_n + step + 1e-9


def test_bad_wall_and_motor_constants_are_one_line_errors():
    with pytest.raises(ParameterError, match="wall_collapse_m"):
        Bottle("B", wall_linear_range_m=0.01, wall_collapse_m=0.005)
    with pytest.raises(ParameterError, match="wall_softening"):
        Bottle("B", wall_softening=1.5)
    with pytest.raises(ParameterError, match="motor_droop"):
        HandParams(motor_droop=2.0)
    assert math.isfinite(grip_curve(HandParams(), Bottle("B", wall_softening=0.0)).k2)
