"""Refinement: the two-phase stratified estimator on indicators of known volume, and a refined study's runs."""

from __future__ import annotations

import numpy as np
import pytest

from slipreflex.analysis.claims import proportion_interval
from slipreflex.core.errors import ParameterError
from slipreflex.study import StudyConfig, run_study
from slipreflex.study.analyse import claim_fractions, plant_table, refinement
from slipreflex.study.refine import boundary, candidates, make_plan, ratio_estimate
from slipreflex.study.runner import part_path


def _box(u: np.ndarray) -> np.ndarray:
    """An indicator of known volume: 0.3 x 0.5 = 0.15 of the unit cube."""
    return (u[:, 0] < 0.3) & (u[:, 1] < 0.5)


def _refined_estimate(seed: int, indicator, pilot_n: int = 32, n: int = 48, d: int = 3):
    pilot = candidates(d, pilot_n, 0, seed)
    plan = make_plan(pilot, indicator(pilot, seed, 0)[:, None], n, seed, n_candidates=4096)
    y = indicator(plan.points, seed, 1)
    return ratio_estimate(y, np.ones(len(y), bool), plan.strata, plan.weights, plan.n_candidates)


def _box_indicator(u: np.ndarray, seed: int, stage: int) -> np.ndarray:
    return _box(u)


def _noisy_indicator(u: np.ndarray, seed: int, stage: int) -> np.ndarray:
    """Holds with probability 0.2 anywhere, independently (a claim decided by one noisy trial)."""
    return np.random.default_rng([seed, stage]).random(len(u)) < 0.2


def test_one_stratum_is_the_plain_fraction_and_its_wilson_interval():
    y = np.array([1, 0, 0, 1, 1, 0, 0, 0, 0, 1], bool)
    est, var, lo, hi = ratio_estimate(y, np.ones(10, bool), np.zeros(10, int), [1.0, 0.0], 10**9)
    frac, wlo, whi = proportion_interval(int(y.sum()), 10)
    # the stratified form's variance uses n - 1; with one stratum only the interval's width differs by it
    assert est == pytest.approx(frac) and var == pytest.approx(0.4 * 0.6 / 9)
    assert lo == pytest.approx(wlo, abs=0.02) and hi == pytest.approx(whi, abs=0.02)


def test_rejected_plants_leave_the_denominator():
    est = ratio_estimate([1, 0, 0, 0], [1, 1, 0, 0], [0, 0, 0, 0], [1.0, 0.0], 10**6)[0]
    assert est == pytest.approx(0.5)


def test_boundary_marks_where_neighbours_disagree():
    pilot = candidates(2, 64, 0, seed=3)
    cand = candidates(2, 2048, 64, seed=3)
    edge = boundary(pilot, _box(pilot)[:, None], cand)
    far = (cand[:, 0] > 0.6) & (cand[:, 1] > 0.8)       # far from the box's edges: interior
    assert not edge[far].any() and 0.05 < edge.mean() < 0.8


@pytest.mark.parametrize("n", [4, 5, 9, 33])
def test_plan_has_exactly_the_plants_asked_for(n):
    pilot = candidates(3, 16, 0, seed=2)
    plan = make_plan(pilot, (pilot[:, :1] < 0.1), n, seed=2, n_candidates=512)
    assert len(plan.points) == n and len(set(map(tuple, plan.points))) == n
    assert all((plan.strata == h).sum() >= 2 for h in (0, 1) if plan.weights[h] > 0)


def test_plan_is_deterministic_and_spends_more_on_the_boundary():
    pilot = candidates(3, 32, 0, seed=5)
    a = make_plan(pilot, _box(pilot)[:, None], 40, seed=5, n_candidates=2048)
    b = make_plan(pilot, _box(pilot)[:, None], 40, seed=5, n_candidates=2048)
    assert np.array_equal(a.points, b.points) and np.array_equal(a.strata, b.strata)
    share = a.strata.mean()                 # the share of second-stage plants on the boundary
    assert share > a.weights[1]             # Neyman's allocation: more than the boundary's volume


def test_estimate_is_unbiased_where_pilot_plants_would_not_be():
    """A noisy indicator: the pilot plants in the interior are those whose neighbours agreed with them,
    so reusing them would bias the estimate towards 0; the second stage alone is unbiased."""
    est = np.array([_refined_estimate(s, _noisy_indicator)[0] for s in range(30)])
    assert abs(est.mean() - 0.2) < 3 * est.std(ddof=1) / np.sqrt(len(est)) + 0.01


@pytest.mark.slow
def test_interval_covers_the_true_volume_at_about_its_nominal_rate():
    runs = [_refined_estimate(s, _box_indicator) for s in range(120)]
    est = np.array([r[0] for r in runs])
    covered = np.mean([lo <= 0.15 <= hi for _, _, lo, hi in runs])
    assert abs(est.mean() - 0.15) < 3 * est.std(ddof=1) / np.sqrt(len(est))
    assert 0.88 <= covered <= 1.0
    # the strata pay against independent draws of the same total cost (pilot and second stage): the
    # binomial spread of 80 plants; a smooth box in 3 dimensions is where scrambled Sobol' points alone
    # do better still (docs/study.md, "Refinement")
    assert est.std() < np.sqrt(0.15 * 0.85 / (32 + 48))


def test_refine_needs_sobol_and_counts():
    with pytest.raises(ParameterError, match="needs design 'sobol'"):
        StudyConfig(plants=4, design="lhs", refine=4)
    with pytest.raises(ParameterError, match="refine must be an integer"):
        StudyConfig(plants=4, refine=-1)
    assert StudyConfig(plants=4).fingerprint() != StudyConfig(plants=4, refine=4).fingerprint()
    assert "refine" not in StudyConfig(plants=4).to_dict()


def _tiny(**kw) -> StudyConfig:
    return StudyConfig(plants=4, trials=1, bottles=("TX",), methods=("dath",), experiments=("drop",),
                       calibrate=False, scan=False, refine=4, **kw)


@pytest.mark.slow
def test_refined_study_same_rows_serial_and_local_cluster_and_resumes(tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    from slipreflex.study import runner

    cfg = _tiny()
    serial = run_study(cfg, tmp_path / "a", workers=0, progress=False)
    assert serial.complete and sorted(serial.parts) == list(range(8))
    starts = []
    real = runner._client
    monkeypatch.setattr(runner, "_client", lambda *a: starts.append(a) or real(*a))
    dask = run_study(cfg, tmp_path / "b", workers=2, progress=False)
    assert dask.workers == "LocalCluster(2)" and dask.complete
    assert len(starts) == 1      # one local cluster for the pilot and the refinement
    for i in range(8):      # byte for byte, the second stage's metadata and rows included
        assert part_path(tmp_path / "a", i).read_bytes() == part_path(tmp_path / "b", i).read_bytes()
    again = run_study(cfg, tmp_path / "a", workers=0, progress=False)
    assert again.computed == []
    fr = claim_fractions(plant_table(serial.parts), None, (), refinement(serial))
    assert all(r["low"] <= r["value"] <= r["high"] for r in fr if r["value"] == r["value"])
