"""The pour's disturbances: the jet's splash (axial) and the water's slosh (sideways), against closed forms."""

import dataclasses
import math

import numpy as np
import pytest

from slipreflex.core import hardware as hw
from slipreflex.core.errors import ParameterError
from slipreflex.sim import BOTTLES, HandParams, Pour, Rig, WaterParams, simulate_open_loop
from slipreflex.sim.objects import WATER_DENSITY

G = hw.GRAVITY


def _held_pour(pour, duration, seed=1, **kw):
    """A grasp squeezed 40 units past the 0.8 N stop (so it holds the whole pour), then the pour."""
    rig = Rig("TR", seed=seed, **kw)
    g = rig.grasp()
    rig.hand.set_positions({f: g.positions[f] + 40 for f in hw.TRIPOD})
    rig.perturb(pour, at=rig.t + 0.5)
    tr = simulate_open_loop(rig, duration)
    assert not tr.fallen
    t_in = tr.t_start + 0.5 + math.sqrt(2.0 * pour.fall_height_m / G)   # the water arrives
    return rig, tr, t_in


def _slosh_hz(ml, radius):
    """First antisymmetric mode of an upright cylinder: k = 1.8412 / R, omega^2 = g k tanh(k h)."""
    k = 1.8412 / radius
    h = ml * 1e-6 / (math.pi * radius ** 2)
    return math.sqrt(G * k * math.tanh(k * h)) / (2.0 * math.pi)


def _jet_n(pour):
    q = pour.rate_l_min / 60.0 * 1e-3 * WATER_DENSITY
    return q * math.sqrt(2.0 * G * pour.fall_height_m)


def test_the_waters_sideways_force_peaks_at_the_slosh_frequency_of_the_fill():
    pour = Pour()
    rig, tr, t_in = _held_pour(pour, 32.0)
    d = tr.daq
    # 200-500 ml: k h = 3.4-8.5, so the mode's frequency is the deep-water one to 0.2 %
    sel = (d.load_mass > rig.bottle.mass_kg + 0.2) & (tr.t < t_in + pour.duration_s - 0.05)
    f_w = d.water_force_lateral[sel]
    spec = np.abs(np.fft.rfft((f_w - f_w.mean()) * np.hanning(f_w.size))) ** 2
    freq = np.fft.rfftfreq(f_w.size, hw.DAQ_PERIOD_S)
    peak = freq[1 + np.argmax(spec[1:])]
    water_ml = (d.load_mass[sel].mean() - rig.bottle.mass_kg) * 1e6 / WATER_DENSITY
    assert peak == pytest.approx(_slosh_hz(water_ml, rig.bottle.diameter_m / 2), rel=0.02)
    # ... and the accelerometer's x axis carries the bottle's sideways shake
    assert np.abs(d.accel_lateral[sel]).max() > 0.0


def test_a_shallow_fill_rings_at_its_own_lower_frequency_after_the_jet_stops():
    pour = Pour(rate_l_min=1.0, volume_ml=30.0)
    rig, tr, t_in = _held_pour(pour, 8.0)
    sel = tr.t > t_in + pour.duration_s + 0.2
    f_w = tr.daq.water_force_lateral[sel]
    up = np.flatnonzero((f_w[:-1] < 0.0) & (f_w[1:] >= 0.0))
    t_up = tr.t[sel][up]
    f_ring = (t_up.size - 1) / (t_up[-1] - t_up[0])
    expected = _slosh_hz(30.0, rig.bottle.diameter_m / 2)
    assert expected < 0.75 * _slosh_hz(300.0, rig.bottle.diameter_m / 2)   # tanh(k h) matters at 9 mm
    assert f_ring == pytest.approx(expected, rel=0.01)
    # lightly damped: after 3 more seconds still more than half the swing (zeta ~ 1 % at 9 mm)
    early = np.abs(f_w[:int(1.0 / hw.DAQ_PERIOD_S)]).max()
    late = np.abs(f_w[int(3.0 / hw.DAQ_PERIOD_S):int(4.0 / hw.DAQ_PERIOD_S)]).max()
    assert 0.3 * early < late < early


def test_no_pour_no_disturbance():
    rig = Rig("DK", seed=2)
    rig.grasp()
    tr = simulate_open_loop(rig, 3.0)
    d = tr.daq
    assert np.all(d.accel_lateral == 0.0) and np.all(d.water_force_lateral == 0.0)
    assert np.array_equal(d.load_force, d.load_mass * G)


def test_a_centred_jet_without_splash_only_pushes_with_its_mean_flux():
    pour = Pour(rate_l_min=2.0, volume_ml=100.0)
    # (and without the digits' motor vibration, which shakes the bottle sideways while the squeeze closes)
    rig, tr, t_in = _held_pour(pour, 4.0, water=WaterParams(splash_rms=0.0, jet_offset_m=0.0),
                               hand=HandParams(motor_vibration_n=0.0))
    d = tr.daq
    flowing = (tr.t > t_in + 0.01) & (tr.t < t_in + pour.duration_s - 0.01)
    assert np.allclose(d.load_force[flowing] - d.load_mass[flowing] * G, _jet_n(pour), rtol=1e-9, atol=1e-12)
    assert np.all(d.accel_lateral == 0.0)


def test_the_splash_has_the_documented_rms_and_is_deterministic():
    pour = Pour(rate_l_min=1.0, volume_ml=150.0)
    runs = [_held_pour(pour, 10.0, seed=s)[1:] for s in (4, 4, 5)]
    (a, t_in), (b, _), (c, _) = runs
    for k in ("load_force", "accel", "accel_lateral", "water_force_lateral", "displacement", "volts"):
        assert np.array_equal(getattr(a.daq, k), getattr(b.daq, k)), k      # same seed, same bits
    assert not np.array_equal(a.daq.load_force, c.daq.load_force)         # another seed, another splash
    flowing = (a.t > t_in + 0.01) & (a.t < t_in + pour.duration_s - 0.01)
    splash = a.daq.load_force[flowing] - a.daq.load_mass[flowing] * G - _jet_n(pour)
    # a one-pole noise sampled on a 1 ms grid and interpolated keeps (2 + rho) / 3 of its variance
    rho = math.exp(-2.0 * math.pi * WaterParams().splash_corner_hz * 1e-3)
    expected = WaterParams().splash_rms * _jet_n(pour) * math.sqrt((2.0 + rho) / 3.0)
    assert splash.std() == pytest.approx(expected, rel=0.1)
    assert abs(splash.mean()) < 0.2 * expected


def test_the_splash_does_not_depend_on_how_the_run_is_cut():
    def run(step):
        rig = Rig("TX", seed=3, stepping="fixed")   # adaptive: a call's end also ends a coarse step
        rig.grasp()
        rig.perturb(Pour(rate_l_min=3.0, volume_ml=100.0), at=rig.t + 0.1)
        end = rig.t + 2.0
        while rig.t < end - 1e-9:
            rig.advance_block(min(end, rig.t + step))
        return rig.daq_history()
    a, b = run(0.0371), run(0.5)
    assert np.array_equal(a.load_force, b.load_force) and np.array_equal(a.accel, b.accel)


def test_water_params_are_checked_before_any_work():
    with pytest.raises(ParameterError, match="WaterParams.splash_rms"):
        WaterParams(splash_rms=-0.1)
    narrow = dataclasses.replace(BOTTLES["TR"], name="NARROW", diameter_m=0.03)
    with pytest.raises(ParameterError, match="jet_offset_m .* inside bottle NARROW"):
        Rig(narrow, water=WaterParams(jet_offset_m=0.018))
