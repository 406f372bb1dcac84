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

from slipreflex.errors import ParameterError
from slipreflex.sim.calibration import calibrate_bottle, first_slip_ml
from slipreflex.sim.uncertain import nominal_values, plant_from_values
from slipreflex.study import StudyConfig
from slipreflex.study.analyse import claim_fractions, plant_table, study_markdown
from slipreflex.study.runner import run_plant

#: A plausible plant (every constant inside the uncertain table's ranges) with a stick-slipping cuff.
STAIRS = {"cuff_mu_k_ratio": 0.6, "cuff_rate_a": 0.005, "cuff_shear_stiffness": 3000.0, "cuff_mu_s": 0.35}


def _jump(bottle, kw, seeds, mus):
    """The largest jump of the first slip over the grid ``mus``: (volume below, volume above)."""
    r = bottle.mu_k / bottle.mu_s
    v = [first_slip_ml(replace(bottle, mu_s=m, mu_k=m * r), rig_kwargs=kw, seeds=seeds) for m in mus]
    k = int(np.argmax(np.diff(v)))
    return v[k], v[k + 1]


def test_a_target_inside_a_jump_of_the_first_slip_is_reported_or_met_at_the_nearest_edge():
    plant = plant_from_values(STAIRS)
    tr, kw = plant.bottles["TR"], plant.rig_kwargs()
    below, above = _jump(tr, kw, (0,), np.linspace(0.5, 0.9, 21))
    assert above - below > 20.0                                   # a stair, not a slope
    target = 0.5 * (below + above)
    with pytest.raises(ParameterError, match=r"jumps from .* no pad mu_s puts it at"):
        calibrate_bottle(tr, target, rig_kwargs=kw, seeds=(0,))
    with pytest.raises(ParameterError, match=r"nor in"):
        calibrate_bottle(tr, target, rig_kwargs=kw, seeds=(0,), band_ml=(target - 2.0, target + 2.0))
    c = calibrate_bottle(tr, target, rig_kwargs=kw, seeds=(0,), band_ml=(below - 5.0, target))
    assert c.first_slip_ml == pytest.approx(below, abs=1.5) and "nearest edge" in c.note
    assert first_slip_ml(c.bottle, rig_kwargs=kw, seeds=(0,)) == c.first_slip_ml   # what it reports is true
    # a target on a step is met as before, without a note
    on_step = calibrate_bottle(tr, below, rig_kwargs=kw, seeds=(0,))
    assert abs(on_step.first_slip_ml - below) <= 0.02 * below and on_step.note == ""


@pytest.mark.slow
def test_a_study_plant_inside_a_jump_runs_at_the_nearest_edge_or_is_recorded(tmp_path):
    tr = plant_from_values(STAIRS).bottles["TR"]
    kw = plant_from_values(STAIRS).rig_kwargs()
    below, above = _jump(tr, kw, (0, 1, 2), np.linspace(0.66, 0.76, 11))   # the study's fallback seeds
    target = 0.5 * (below + above)
    values = {**nominal_values(), **STAIRS, "first_slip_ml": target}
    grid = dict(trials=1, bottles=("TR",), methods=("dath",), experiments=("drop",), scan=False)
    wide, narrow = tmp_path / "wide.toml", tmp_path / "narrow.toml"
    wide.write_text(f"[first_slip_ml]\nlow = {below - 3.0}\nhigh = {above + 3.0}\nnominal = {target}\n")
    narrow.write_text(f"[first_slip_ml]\nlow = {target - 1.0}\nhigh = {target + 1.0}\nnominal = {target}\n")
    ok = run_plant(0, values, StudyConfig(plants=1, ranges=str(wide), **grid))
    assert ok.error == "" and ok.trials == 1 and "nearest edge" in ok.calibration["calibration_note"]
    got = ok.calibration["calibrated_first_slip_ml_TR"]
    assert min(abs(got - below), abs(got - above)) <= 2.5 and ok.rows[0]["calibrated_first_slip_ml_TR"] == got
    cfg = StudyConfig(plants=1, ranges=str(narrow), **grid)
    bad = run_plant(1, values, cfg)
    assert "jumps from" in bad.error and "nor in" in bad.error and bad.trials == 0
    parts = {o.plant: ({"values": o.values, "error": o.error, "claims": o.claims, "calibration": o.calibration},
                       o.rows) for o in (ok, bad)}
    plants = plant_table(parts)
    assert plants[0]["calibrated_first_slip_ml_TR"] == got

    class Run:   # what study_markdown reads of a StudyRun
        config = cfg
    text = study_markdown(Run(), plants, claim_fractions(plants), [], [])
    assert "1 plant(s): no pad friction meets the target" in text
    assert "1 plant(s): no reachable first slip" in text and "cannot be met" in text
