"""Grasp physics of the simulated rig against closed forms."""

import dataclasses
import math

import numpy as np
import pytest

from slipreflex.core import hardware as hw
from slipreflex.sim import Bottle, Drop, PhysicsParams, Pour, Rig, simulate_open_loop
from slipreflex.sim import kernel as K

G = hw.GRAVITY


def _capacity(rig, mu):
    """Friction capacity mu * 3 N_c (N) of the current grasp."""
    return mu * 3.0 * rig.normal_force


#: Coulomb-Stribeck contacts, the cuff with the pads' friction, so the closed forms are the textbook ones.
COULOMB = Bottle("C", mu_s=0.6, mu_k=0.45, cuff_mu_s=0.6, cuff_mu_k=0.6, friction_law="coulomb",
                 cuff_friction_law="coulomb")


def test_grasp_stops_near_contact_force_and_holds_the_empty_bottle():
    rig = Rig("TR", seed=0)
    g = rig.grasp()
    assert g.stable and not rig.fallen
    # the 0.8 N stop overshoots by (poll period + latency) x closing speed, no more
    hp = rig.hand_params
    kn = rig._P[K.P_KN] * hp.travel_per_unit_m
    overshoot = (1.0 / hp.grasp_poll_fs + hp.latency_s + 0.03) * hp.grasp_speed_units_s * kn
    assert hw.CONTACT_FORCE_N <= g.force_n <= hw.CONTACT_FORCE_N + overshoot
    # thumb and index stop on their own sensors, so they may differ by a unit
    assert max(g.positions[f] for f in hw.TRIPOD) - min(g.positions[f] for f in hw.TRIPOD) <= 1
    # held: the weight is below static friction capacity
    assert rig.bottle.mass_kg * G < _capacity(rig, rig.bottle.mu_s)


def test_slip_starts_at_mu_s_times_normal_force():
    rig = Rig(COULOMB, seed=0)
    rig.grasp()
    pour = Pour(rate_l_min=0.3, volume_ml=400, fall_height_m=0.0)   # slow, no jet force
    t_start = rig.t + 0.1
    rig.perturb(pour, at=t_start)
    tr = simulate_open_loop(rig, 60.0)
    assert tr.onsets.size >= 1
    t_on = tr.onsets[0]
    load = (rig.bottle.mass_kg + pour.rate_l_min / 60.0 * (t_on - t_start)) * G
    cap = rig.bottle.mu_s * 3.0 * tr.daq.normal_force[np.searchsorted(tr.t, t_on)]
    assert load == pytest.approx(cap, rel=0.02)


def test_sliding_acceleration_matches_kinetic_friction():
    heavy = dataclasses.replace(COULOMB, name="heavy", mass_kg=0.3, grip_travel_m=0.08, cuff_mu_k=0.45)
    rig = Rig(heavy, seed=0)
    g = rig.grasp()
    assert not g.stable      # 0.3 kg is far above what 3 x ~1 N at mu_s 0.6 holds
    h = rig.daq_history()
    on = rig.onsets[0]
    n = h.normal_force[np.searchsorted(h.t, on)]
    sel = (h.t > on + 0.03) & ~h.fallen & (h.t < on + 0.12)
    assert sel.sum() > 10
    a = np.polyfit(h.t[sel], h.velocity[sel], 1)[0]
    expected = G - heavy.mu_k * 3.0 * n / heavy.mass_kg
    assert a == pytest.approx(expected, rel=0.03)
    # once out of the grip it falls freely
    later = simulate_open_loop(rig, 0.3)
    assert later.fallen
    f = later.daq.fallen
    a_free = np.polyfit(later.t[f][5:], later.daq.velocity[f][5:], 1)[0]
    assert a_free == pytest.approx(G, rel=1e-3)


def test_no_drift_while_stuck_over_10_s():
    rig = Rig("DK", seed=3)
    rig.grasp()
    x0, s0 = rig.displacement, rig.slip
    n_on = rig.onsets.size
    tr = simulate_open_loop(rig, 10.0)
    assert rig.slip == s0                        # the contact anchor does not move at all
    assert abs(rig.displacement - x0) < 1e-9     # the pad shear is settled
    assert np.abs(tr.daq.velocity).max() < 1e-6
    assert rig.onsets.size == n_on and tr.daq.stuck.all()


def test_drop_lands_after_free_fall_and_the_bottle_slips():
    rig = Rig("TR", seed=0)
    rig.grasp()
    d = Drop()
    t_rel = rig.t + 0.2
    rig.perturb(d, at=t_rel)
    tr = simulate_open_loop(rig, 1.0)
    ev = rig.events()
    landed = ev[ev[:, 1] == K.E_LANDED, 0]
    fall = math.sqrt(2.0 * (rig.bottle.height_m + d.height_m) / G)
    assert landed.size == 1 and landed[0] - t_rel == pytest.approx(fall, abs=1e-3)
    assert tr.onsets.size >= 1 and tr.onsets[0] >= landed[0] - 1e-9
    # the landed mass is carried: load = bottle + drop
    assert tr.daq.load_mass[-1] == pytest.approx(rig.bottle.mass_kg + d.mass_kg)
    # momentum: the impact's impulse accelerates the bottle at most like a perfectly plastic collision
    v_imp = math.sqrt(2 * G * (rig.bottle.height_m + d.height_m))
    assert tr.daq.velocity.max() <= d.mass_kg * v_imp / rig.bottle.mass_kg * (1 + 0.3) + 0.05


def test_pour_fills_the_bottle_at_the_set_rate():
    rig = Rig("TR", seed=0)
    rig.grasp()
    p = Pour(rate_l_min=2.0, volume_ml=100)
    rig.perturb(p, at=rig.t)
    # keep the bottle from slipping: squeeze harder first
    rig.hand.set_positions({f: 300 for f in hw.TRIPOD})
    tr = simulate_open_loop(rig, 5.0)
    assert not tr.fallen
    water = tr.daq.load_mass - rig.bottle.mass_kg
    assert water[-1] == pytest.approx(0.1, abs=1e-9)
    delay = math.sqrt(2 * p.fall_height_m / G)
    mid = np.searchsorted(tr.t, tr.t_start + delay + 1.0)
    assert water[mid] == pytest.approx(2.0 / 60.0 * (tr.t[mid] - tr.t_start - delay), abs=2e-4)


def _trial(dt, pert):
    rig = Rig("TR", seed=7, physics=PhysicsParams(dt=dt))
    rig.grasp()
    rig.perturb(pert, at=rig.t + 0.1)
    tr = simulate_open_loop(rig, 25.0 if isinstance(pert, Pour) else 1.0)
    return rig, tr


def test_halving_the_time_step_does_not_change_the_results():
    for pert in (Pour(), Drop()):
        r1, t1 = _trial(1e-4, pert)
        r2, t2 = _trial(5e-5, pert)
        e1, e2 = r1.slip_events(), r2.slip_events()
        assert len(e1) >= 1 and len(e2) >= 1
        assert e1[0].onset == pytest.approx(e2[0].onset, abs=2e-3)
        assert r1.fallen == r2.fallen
        if r1.fallen:
            assert r1.fall_time == pytest.approx(r2.fall_time, abs=3e-3)
        else:
            assert e1[0].distance == pytest.approx(e2[0].distance, rel=0.03)
        # the same trace at the shared DAQ instants
        n = min(t1.t.size, t2.t.size)
        held = ~t1.daq.fallen[:n] & ~t2.daq.fallen[:n]
        assert held.sum() > 100
        assert np.allclose(t1.daq.displacement[:n][held], t2.daq.displacement[:n][held], atol=3e-4)
