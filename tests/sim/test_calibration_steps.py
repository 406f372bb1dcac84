"""A plant whose open-loop first slip grows in steps: the calibration finds the jump and says so.

With a soft, velocity-weakening cuff on the middle finger (low kinetic/static ratio, little rate
strengthening, soft shear spring) the cuff sticks and slips in its own cycle as the water comes
in, and the bottle can slip grossly only at one of the cuff's slips: the first pour slip against
the pads' mu_s is a staircase. About 6 % of the default study's plants drew a target volume
inside one of its jumps.
"""

from dataclasses import replace

import numpy as np
import pytest

from slipreflex.core.errors import ParameterError
from slipreflex.sim.calibration import calibrate_bottle, first_slip_ml
from slipreflex.sim.uncertain import nominal_values, plant_from_values
from slipreflex.study import StudyConfig
from slipreflex.study.analyse import claim_fractions, plant_table
from slipreflex.study.runner import run_plant

#: A plausible plant (every constant inside the uncertain table's ranges) with a stick-slipping cuff.
STAIRS = {"cuff_mu_k_ratio": 0.6, "cuff_rate_a": 0.005, "cuff_shear_stiffness": 3000.0, "cuff_mu_s": 0.35}


def _jump(bottle, kw, seeds, mus):
    """The largest jump of the true first slip over the grid ``mus``: (volume below, volume above)."""
    r = bottle.mu_k / bottle.mu_s
    v = [first_slip_ml(replace(bottle, mu_s=m, mu_k=m * r), rig_kwargs=kw, seeds=seeds, observed=False)
         for m in mus]
    k = int(np.argmax(np.diff(v)))
    return v[k], v[k + 1]


@pytest.mark.slow
def test_a_target_inside_a_jump_of_the_first_slip_is_reported_or_met_at_the_nearest_edge():
    plant = plant_from_values(STAIRS)
    tr, kw = plant.bottles["TR"], plant.rig_kwargs()
    below, above = _jump(tr, kw, (0,), np.linspace(0.5, 0.9, 21))
    assert above - below > 20.0                                   # a stair, not a slope
    target = 0.5 * (below + above)
    cal = dict(rig_kwargs=kw, seeds=(0,), observed=False)      # the jump logic, on the true first slip
    with pytest.raises(ParameterError, match=r"jumps from .* no pad mu_s puts it at"):
        calibrate_bottle(tr, target, **cal)
    with pytest.raises(ParameterError, match=r"nor in"):
        calibrate_bottle(tr, target, band_ml=(target - 2.0, target + 2.0), **cal)
    c = calibrate_bottle(tr, target, band_ml=(below - 5.0, target), **cal)
    assert c.first_slip_ml == pytest.approx(below, abs=1.5) and "nearest edge" in c.note
    assert first_slip_ml(c.bottle, rig_kwargs=kw, seeds=(0,), observed=False) == c.first_slip_ml
    # a target on a step is met as before, without a note
    on_step = calibrate_bottle(tr, below, **cal)
    assert abs(on_step.first_slip_ml - below) <= 0.02 * below and on_step.note == ""
    # what the paper's accelerometer sees on this plant: the cuff's first slip, long before the bottle's
    assert first_slip_ml(c.bottle, rig_kwargs=kw, seeds=(0,)) < 0.5 * below


@pytest.mark.slow
def test_a_study_plant_whose_accelerometer_sees_the_cuff_slip_cannot_meet_the_paper_s_fact(tmp_path):
    values = {**nominal_values(), **STAIRS, "first_slip_ml": 200.0}
    grid = dict(trials=1, bottles=("TR",), methods=("dath",), experiments=("drop",), scan=False)
    out = run_plant(0, values, StudyConfig(plants=1, **grid))
    assert out.trials == 0 and out.claims == []
    assert "first slip" in out.error or out.calibration.get("rejected")
    plants = plant_table({0: ({"values": out.values, "error": out.error, "claims": [],
                               "calibration": out.calibration}, out.rows)})
    assert claim_fractions(plants)[0]["plants"] == 0


@pytest.mark.slow
def test_a_first_slip_pinned_at_the_cuff_s_slip_is_refused_after_two_frictions():
    plant = plant_from_values({**nominal_values(), **STAIRS})
    tr, kw = plant.bottles["TR"], plant.rig_kwargs()
    memo: dict = {}
    with pytest.raises(ParameterError, match=r"observed at [0-9.]+ ml at pad mu_s .* alike, before its true onsets"):
        calibrate_bottle(tr, 200.0, rig_kwargs=kw, seeds=(0,), memo=memo)
    assert len(memo) == 2                     # two pours, not a search onto the friction where the slip leaves the pour
    # the seeds' fallback reuses seed 0's pours and stops after the same two frictions
    with pytest.raises(ParameterError, match=r"alike.*nor in 170-230 ml"):
        calibrate_bottle(tr, 200.0, rig_kwargs=kw, seeds=(0, 1, 2), band_ml=(170.0, 230.0), memo=memo)
    assert len(memo) == 6
    # a plant whose accelerometer sees the bottle's own slip is searched as before
    c = calibrate_bottle(plant_from_values(nominal_values()).bottles["TR"], 200.0, seeds=(0,))
    assert abs(c.first_slip_ml - 200.0) <= 4.0 and c.first_slip_ml >= c.true_first_slip_ml


def test_the_stairs_plant_sets_uncertain_constants_only():
    from slipreflex.sim.uncertain import UNCERTAIN

    assert set(STAIRS) <= set(UNCERTAIN) and plant_from_values(STAIRS).bottles["TR"].cuff_mu_s == 0.35
