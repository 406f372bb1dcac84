"""The bottle's shoulder: past grip_travel the normal force falls with the radius, and the contacts are lost where
the shoulder has taken up the fingertips' travel (closed forms)."""

import dataclasses

import numpy as np
import pytest

from slipreflex.sim import BOTTLES, PAPER_POUR, Rig, simulate_open_loop
from slipreflex.sim import kernel as K
from slipreflex.sim.contacts import grip_curve


def _pour(bottle):
    rig = Rig(bottle, seed=2)
    rig.grasp()
    rig.perturb(PAPER_POUR, at=rig.t + 0.1)
    tr = simulate_open_loop(rig, 25.0)
    assert rig.fallen
    return rig, tr


def test_on_the_shoulder_the_normal_force_follows_the_shrinking_radius():
    b = BOTTLES["TR"]
    rig, tr = _pour(b)
    d = tr.daq
    c = grip_curve(rig.hand_params, b)
    lam, qc = rig.hand_params.travel_per_unit_m, rig._P[K.P_QC]
    pen = (float(np.mean(rig.finger_q)) - qc) * lam + np.zeros(len(tr.t))   # open loop: the fingers hold
    on = (d.displacement > b.grip_travel_m) & ~d.fallen
    assert on.sum() >= 3
    want = np.array([c.force(p - b.shoulder_slope * (x - b.grip_travel_m)) for p, x in zip(pen[on], d.displacement[on],
                                                                                              strict=True)])
    tol = b.shoulder_slope * np.abs(d.velocity[on]) * rig.physics.dt * c.k1 + 1e-9
    assert np.all(np.abs(d.normal_force[on] - want) <= tol)
    assert d.normal_force[on][-1] < d.normal_force[~on & ~d.fallen][-1]
    # the contacts are lost where the shoulder has taken up the fingertips' whole travel
    ev = rig.events()
    x_fall = float(ev[ev[:, 1] == K.E_FALLEN][0, 2])
    assert x_fall == pytest.approx(b.grip_travel_m + pen[0] / b.shoulder_slope, abs=2e-4)


def test_without_a_taper_the_contacts_are_lost_at_grip_travel():
    b = dataclasses.replace(BOTTLES["TR"], shoulder_slope=0.0)
    rig, tr = _pour(b)
    ev = rig.events()
    x_fall = float(ev[ev[:, 1] == K.E_FALLEN][0, 2])
    assert b.grip_travel_m < x_fall < b.grip_travel_m + 2e-4
