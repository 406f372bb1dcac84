"""The bottle's tilt in the grasp: small-angle statics and ringing, an eccentric impact's angular momentum,
the friction couple's limit (the tilt can make the bottle slip out), and no tilt without an eccentric load."""

import dataclasses
import math

import numpy as np
import pytest

from slipreflex.sim import BOTTLES, PAPER_DROP, PAPER_POUR, Drop, HandParams, PhysicsParams, Rig
from slipreflex.sim import kernel as K


def _inertia(b):
    """The empty bottle about the tilt axis, by hand: a thin-walled cylinder, m (R^2 / 2 + H^2 / 12 + d^2)."""
    r, h, zg = b.diameter_m / 2, b.height_m, b.grasp_height_m
    return b.mass_kg * (r * r / 2 + h * h / 12 + (zg - h / 2) ** 2)


def _stiffness(b, hand, m_land=0.0):
    """Small-angle restoring stiffness (N m / rad) with the contacts stuck: the pads' shear stiffness at their
    levers (thumb and index 120 degrees either side of the axis through the cuff: R sin 60), gravity on the
    centre of mass below the axis and on a mass resting on the bottom z_g below it."""
    r, zg = b.diameter_m / 2, b.grasp_height_m
    lever = r * math.sqrt(3) / 2
    g = 9.81
    return 2 * hand.pad_shear_stiffness_n_m * lever ** 2 + g * b.mass_kg * (zg - b.height_m / 2) + g * m_land * zg


def _rig(e, **kw):
    b = dataclasses.replace(BOTTLES["TR"], drop_eccentricity_m=e)
    rig = Rig(b, seed=0, **kw)
    rig.grasp()
    return rig


def test_a_small_mass_resting_off_the_axis_tilts_the_bottle_by_the_closed_form_and_rings_at_its_frequency():
    e, m = 0.01, 0.002
    rig = _rig(e)
    b, hand = rig.bottle, rig.hand_params
    rig.perturb(Drop(mass_kg=m, height_m=0.0), at=rig.t)
    th = []
    for _ in range(3000):                               # 1.5 s in 0.5 ms blocks
        rig.advance_block(rig.t + 5e-4)
        th.append(rig._S[K.S_TH])
    th = np.array(th)
    assert not rig.fallen and all(rig._S[K.S_C0 + i * K.SC_SIZE + K.SC_STUCK] == 1.0 for i in range(3))
    kth = _stiffness(b, hand, m)
    g = 9.81
    # statics: the resting mass's moment m g (e - z_g th) against the stiffness
    want = m * g * e / kth
    assert th[-1] == pytest.approx(want, rel=0.01)
    # the ringing after the landing: the damped frequency of K over the bottle's inertia plus the mass's at
    # its lever (the mass rides up and down with the bottom, its contact spring ringing at 1.6 kHz, far above
    # the tilt's 25 Hz; the contact carries no sideways force, so the bottom's sideways swing does not move it)
    inertia = _inertia(b) + m * e ** 2
    c = 2 * hand.pad_shear_damping_n_s_m * (b.diameter_m / 2 * math.sqrt(3) / 2) ** 2
    zeta = c / (2 * math.sqrt(kth * inertia))
    f_want = math.sqrt(kth / inertia) * math.sqrt(1 - zeta ** 2) / (2 * math.pi)
    land = int(np.argmax(th != 0))
    y = th[land:land + 400] - want                      # 0.2 s of ringing
    up = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    assert len(up) >= 4
    f_got = (len(up) - 1) / ((up[-1] - up[0]) * 5e-4)
    assert f_got == pytest.approx(f_want, rel=0.03)


def test_an_eccentric_impact_gives_the_bottle_the_angular_momentum_of_its_impulse():
    # a stiff, short impact (0.2 ms, 20 steps of 10 us): the contacts' moment has no time to act, so the
    # bottle's angular momentum right after it is the impulse times its lever
    e, m = 0.015, 0.005
    rig = _rig(e, physics=PhysicsParams(dt=1e-5))
    drop = Drop(mass_kg=m, height_m=0.02, contact_stiffness_n_m=1e6, restitution=0.3)
    rig.perturb(drop, at=rig.t)
    t_fall = math.sqrt(2 * (rig.bottle.height_m + drop.height_m) / 9.81)
    rig.advance_block(rig.t + t_fall - 2e-3)
    assert rig._S[K.S_TH] == 0.0
    vz0 = rig._D[0, K.D_VZ]
    om = []
    for _ in range(400):                              # 4 ms in steps of 10 us
        rig.advance_block(rig.t + 1e-5)
        om.append((rig._S[K.S_OM], rig._D[0, K.D_VZ], rig._S[K.S_TH]))
    om = np.array(om)
    hit = int(np.argmax(om[:, 0] != 0))
    # the impact ends where the mass's velocity stops changing but for gravity
    dv = np.diff(om[:, 1])
    end = hit + int(np.argmax(np.abs(dv[hit:] - 9.81e-5) < 1e-6 * 9.81)) + 1
    assert 10 <= end - hit <= 40
    impulse = m * (vz0 + 9.81 * (hit - 1) * 1e-5 - om[end, 1])      # gravity's own impulse over the fall removed
    assert impulse > 0
    got = _inertia(rig.bottle) * om[end, 0]
    assert got == pytest.approx(impulse * (e - rig.bottle.grasp_height_m * om[end, 2]), rel=0.02)


def test_the_tilt_makes_the_bottle_slip_out_where_the_friction_couple_cannot_hold_it():
    # a 45 g drop, held when it lands on the axis; off the axis its moment exceeds the pads' friction couple
    # (2 mu N R sin 60, about 0.05 N m), the pads slide the bottle round and it falls out
    drop = Drop(mass_kg=0.045, height_m=0.02)
    centred = _rig(0.0)
    centred.perturb(drop, at=centred.t + 0.1)
    centred.advance_block(centred.t + 1.0)
    assert not centred.fallen and centred.tilt == 0.0
    off = _rig(0.02)
    n = off.normal_force
    off.perturb(drop, at=off.t + 0.1)
    peak = 0.0
    for _ in range(100):
        off.advance_block(off.t + 0.01)
        peak = max(peak, abs(off.tilt))
    assert off.fallen
    couple = 2 * off.bottle.mu_s * n * off.bottle.diameter_m / 2 * math.sqrt(3) / 2
    k = _stiffness(off.bottle, HandParams())
    assert peak > couple / k                             # the tilt went past what the stuck pads hold


def test_no_eccentric_load_no_tilt():
    for e, what in ((0.0, PAPER_DROP), (0.01, PAPER_POUR)):
        rig = _rig(e)
        rig.perturb(what, at=rig.t + 0.1)
        rig.advance_block(rig.t + 3.0)
        assert rig._S[K.S_TH] == 0.0 and rig._S[K.S_OM] == 0.0


@pytest.mark.parametrize("e, mass", [(0.01, 0.01), (0.02, 0.03)])
def test_halving_dt_moves_the_drop_s_slide_and_tilt_by_under_one_percent(e, mass):
    out = []
    for dt in (1e-4, 5e-5):
        rig = _rig(e, physics=PhysicsParams(dt=dt))
        rig.perturb(Drop(mass_kg=mass), at=rig.t + 0.1)
        rig.advance_block(rig.t + 1.0)
        out.append((rig._S[K.S_X], rig._S[K.S_TH]))
    (x1, th1), (x2, th2) = out
    assert th1 != 0.0
    assert x1 == pytest.approx(x2, rel=0.01) and th1 == pytest.approx(th2, rel=0.01)
