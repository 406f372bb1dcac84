"""The trial protocol, seeds, calibration and the parallel grid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipreflex import methods
from slipreflex.core.errors import ParameterError
from slipreflex.methods.baselines import NMSD, SWTSD
from slipreflex.methods.baselines.swt import SWT_PERSIST
from slipreflex.methods.chain import SlipReflex
from slipreflex.reproduce.experiments import (
    RESULTS_CSV_COLUMNS,
    Cell,
    ReproduceConfig,
    calibrate,
    calibration_seed,
    closing_speed,
    method_context,
    run_reproduce,
    run_trial,
    trial_seed,
)
from slipreflex.sim import PAPER_DROP, PAPER_POUR, HandParams


def test_config_defaults_come_from_the_simulator_and_validate():
    c = ReproduceConfig()
    assert (c.trials, c.bottles, c.methods, c.experiments) == (
        20, ("TR", "DK", "TX"), ("dath", "fixed", "nmsd", "swt"), ("drop", "pour"))
    assert c.drop == PAPER_DROP and c.pour == PAPER_POUR
    assert len(c.cells()) == 480
    assert ReproduceConfig(drop_mass_kg=0.02, pour_rate_l_min=2.0).pour.rate_l_min == 2.0
    for bad in (dict(trials=0), dict(methods=("dath", "x")), dict(bottles=()), dict(seed=-1),
                dict(rest_s=0.1), dict(drop_mass_kg=-1.0), dict(experiments=("drop", "drop")),
                dict(rest_k=0.0), dict(swt_persist=-1)):
        with pytest.raises(ParameterError):
            ReproduceConfig(**bad)
    assert closing_speed() == HandParams().speed_units_s
    from slipreflex.reproduce.experiments import BOTTLE_NAMES
    from slipreflex.sim import BOTTLES
    assert set(BOTTLE_NAMES) == set(BOTTLES)


def test_seeds_are_spawned_and_independent_of_the_selection():
    seeds = {trial_seed(7, e, b, k) for e in ("drop", "pour") for b in ("TR", "DK", "TX")
             for k in range(10)}
    assert len(seeds) == 60
    small = ReproduceConfig(trials=3, bottles=("TX",), methods=("nmsd",), seed=7)
    full = ReproduceConfig(trials=10, seed=7)
    pick = {c.key: c.seed for c in full.cells()}
    for c in small.cells():
        assert pick[c.key] == c.seed
    # the methods of one trial share the rig seed (paired comparison)
    by_trial = {}
    for c in full.cells():
        by_trial.setdefault((c.experiment, c.bottle, c.trial), set()).add(c.seed)
    assert all(len(s) == 1 for s in by_trial.values())
    assert calibration_seed(7, "TR") not in seeds
    assert trial_seed(8, "drop", "TR", 0) != trial_seed(7, "drop", "TR", 0)


def _make(name, p0, thresholds, **config):
    """A method's reflex as the trial runner builds it: the registry with the run's context."""
    return methods.make(name, p0=p0, context=method_context(ReproduceConfig(**config), thresholds))


def test_the_runner_swaps_methods_by_name():
    th = {"nmsd": 10.0, "swt": 0.02}
    r = _make("fixed", 150.0, th)
    assert isinstance(r, SlipReflex) and r.name == "fixed" and r.input_kind == "slip"
    assert _make("dath", 150.0, th).name == "dath"
    n = _make("nmsd", 150.0, th)
    s = _make("swt", 150.0, th)
    assert isinstance(n, NMSD) and isinstance(s, SWTSD)
    assert (n.fs, s.fs) == (260.0, 380.0)
    assert n.params.speed == s.params.speed == closing_speed()
    assert s.params.persist == SWT_PERSIST and _make("swt", 1.0, th, swt_persist=3).params.persist == 3
    with pytest.raises(ParameterError):
        _make("nope", 0.0, th)


def test_calibration_gives_one_positive_threshold_per_method():
    th = calibrate(ReproduceConfig(calibration_s=1.0))
    assert set(th) == {"nmsd", "swt"} and th["nmsd"] > 0 and th["swt"] > 0
    assert calibrate(ReproduceConfig(calibration_s=1.0, bottles=("TX",))) == th   # all bottles, always
    th3 = calibrate(ReproduceConfig(calibration_s=1.0, rest_k=3.0))
    assert th3["nmsd"] == pytest.approx(th["nmsd"] * 3 / 5)


def test_a_drop_trial_is_deterministic_and_complete():
    cfg = ReproduceConfig(trials=1)
    cell = Cell("drop", "TX", "dath", 0, trial_seed(cfg.seed, "drop", "TX", 0))
    rows1, plot = run_trial(cell, cfg, {}, keep_plot=True)
    rows2, _ = run_trial(cell, cfg, {})
    assert len(rows1) == 1 and set(RESULTS_CSV_COLUMNS) == set(rows1[0])
    for k in rows1[0]:
        a, b = rows1[0][k], rows2[0][k]
        assert a == b or (isinstance(a, float) and math.isnan(a) and math.isnan(b)), k
    r = rows1[0]
    # the drop makes the bottle slip; the accelerometer finds it close to the truth
    assert r["n_events"] == 1 and abs(r["onset_error_ms"]) < 20.0
    assert r["perturbation_s"] <= r["onset_s"] <= r["perturbation_s"] + 0.5
    assert plot is not None and len(plot.cmd_t) > 0


@pytest.mark.slow
def test_parallel_and_serial_runs_give_the_same_rows():
    cfg = ReproduceConfig(trials=2, bottles=("TR", "TX"), methods=("fixed", "nmsd"),
                          experiments=("drop",), calibration_s=1.0)
    a = run_reproduce(cfg, jobs=1, progress=False, plots=False)
    b = run_reproduce(cfg, jobs=2, progress=False, plots=False)
    assert len(a.rows) == len(b.rows) == 8
    for ra, rb in zip(a.rows, b.rows):
        for k in ra:
            x, y = ra[k], rb[k]
            assert x == y or (isinstance(x, float) and np.isnan(x) and np.isnan(y)), k
    assert a.thresholds == b.thresholds


def test_a_trial_from_a_kept_grasp_equals_one_from_its_own_grasp():
    """The methods of a paired trial start from copies of one grasp: the same bits as their own."""
    from slipreflex.reproduce.experiments import Cell, ReproduceConfig, run_trial, trial_seed
    from slipreflex.sim import variations

    cfg = ReproduceConfig(trials=1)
    cell = Cell("pour", "DK", "dath", 0, trial_seed(cfg.seed, "pour", "DK", 0))
    variations._GRASPED.clear()
    cold = run_trial(cell, cfg, {})[0]
    assert len(variations._GRASPED) == 1
    warm = run_trial(cell, cfg, {})[0]           # from a copy of the kept grasp, which must be untouched
    assert [repr(r) for r in warm] == [repr(r) for r in cold]
    other = run_trial(Cell("pour", "DK", "fixed", 0, cell.seed), cfg, {})[0]
    assert len(variations._GRASPED) == 1 and other[0].grasp_position == cold[0].grasp_position
