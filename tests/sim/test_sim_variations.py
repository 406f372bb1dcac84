"""Trials that differ physically: variations drawn from each trial's seed, and independent seeds."""

import numpy as np
import pytest

from slipreflex.core.errors import ParameterError
from slipreflex.core.hardware import SLIP_FINGER
from slipreflex.reproduce.experiments import ReproduceConfig, trial_seed
from slipreflex.sim import BOTTLES, HandParams
from slipreflex.sim.variations import TrialVariation, VariationSpread, apply_variation, draw_variation, trial_rig


def test_same_seed_same_variation_and_rig_bits():
    assert draw_variation(11) == draw_variation(11)
    a, b = trial_rig("TX", 11), trial_rig("TX", 11)
    assert a.bottle == b.bottle and a.hand_params == b.hand_params
    assert np.array_equal(a.advance_block(0.2).volts, b.advance_block(0.2).volts)


def test_variations_spread_as_documented():
    spread = VariationSpread()
    v = [draw_variation(s, spread) for s in range(400)]
    assert np.std([x.placement_m for x in v]) == pytest.approx(spread.placement_m, rel=0.15)
    assert np.std([x.grip_height_m for x in v]) == pytest.approx(spread.grip_height_m, rel=0.15)
    pads = np.array([x.pad_friction for x in v])
    assert np.mean(pads) == pytest.approx(1.0, abs=0.01) and np.std(pads) == pytest.approx(0.05, rel=0.15)
    assert abs(np.corrcoef(pads, [x.cuff_friction for x in v])[0, 1]) < 0.15
    assert draw_variation(5, VariationSpread.none()) == TrialVariation(0.0, 0.0, 1.0, 1.0)


def test_repeats_differ_physically_where_the_grasp_stops():
    stops = {trial_rig("TR", s).grasp().positions[SLIP_FINGER] for s in range(6)}
    assert len(stops) >= 3                       # not the same position in every trial
    nominal = {trial_rig("TR", s, spread=VariationSpread.none()).grasp().positions[SLIP_FINGER]
               for s in range(6)}
    assert len(nominal) < len(stops)


def test_apply_variation_keeps_ratios_and_moves_the_contact():
    b, h = apply_variation(BOTTLES["TR"], HandParams(), TrialVariation(2e-3, -1e-3, 0.9, 1.2))
    assert b.mu_k / b.mu_s == pytest.approx(BOTTLES["TR"].mu_k / BOTTLES["TR"].mu_s)
    assert b.cuff_mu_s == pytest.approx(1.2 * BOTTLES["TR"].cuff_mu_s)
    assert b.grip_travel_m == pytest.approx(BOTTLES["TR"].grip_travel_m - 1e-3)
    assert h.aperture_radius_m == pytest.approx(HandParams().aperture_radius_m - 2e-3)


def test_bad_input():
    with pytest.raises(ParameterError, match="seed"):
        draw_variation(-1)
    with pytest.raises(ParameterError, match="friction_rel"):
        VariationSpread(friction_rel=-0.1)
    with pytest.raises(ParameterError, match="unknown bottle"):
        trial_rig("XX", 1)


def test_paired_by_default_and_independent_seeds_on_request():
    paired = ReproduceConfig(trials=2, bottles=("TR",), experiments=("drop",)).cells()
    assert len({c.seed for c in paired}) == 2          # one seed per trial, shared by the methods
    own = ReproduceConfig(trials=2, bottles=("TR",), experiments=("drop",), independent_seeds=True).cells()
    assert len({c.seed for c in own}) == len(own)
    assert trial_seed(1, "drop", "TR", 0, method="dath") == trial_seed(1, "drop", "TR", 0, method="DATH")
    assert trial_seed(1, "drop", "TR", 0, method="dath") != trial_seed(1, "drop", "TR", 0)
    with pytest.raises(ParameterError, match="variations"):
        ReproduceConfig(variations="yes")


def test_a_grasp_that_cannot_hold_is_an_error_before_any_trial(monkeypatch):
    import dataclasses

    from slipreflex.reproduce import experiments
    from slipreflex.sim.calibration import GraspFailed, check_grasp

    jar = dataclasses.replace(BOTTLES["TR"], name="JAR", mass_kg=0.25, mu_s=0.4, mu_k=0.3)
    with pytest.raises(GraspFailed) as err:
        check_grasp(jar)
    msg = str(err.value)
    assert "--grasp-force" in msg and "mu_s 0.4 -> about" in msg
    advised = float(msg.split("grasp force of about ")[1].split(" N")[0])
    check_grasp(jar, advised)                                     # the advice holds it
    # reproduce checks every bottle before the first trial
    ran = []
    monkeypatch.setattr(experiments, "run_trial", lambda *a, **k: ran.append(1))
    with pytest.raises(GraspFailed, match="0.05 N grasp cannot hold"):
        experiments.run_reproduce(ReproduceConfig(trials=1, bottles=("TR",), grasp_force_n=0.05,
                                                  methods=("dath",)), jobs=1, progress=False, plots=False)
    assert not ran
