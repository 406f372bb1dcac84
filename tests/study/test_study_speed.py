"""Work a study no longer repeats: kept tracks and shared calibration pours give the same bits."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from slipreflex.sim import BOTTLES, SURFACES, sensors
from slipreflex.sim.calibration import _mechanics, calibrate_bottle
from slipreflex.sim.sensors import Track


def _fresh(layout, seed, **kw):
    sensors._TRACKS.clear()
    rng = np.random.default_rng(seed)
    return Track.build(layout, rng, **kw), rng.random()


def test_a_kept_track_is_the_built_one_and_leaves_the_generator_alike():
    layout = [(SURFACES["white"], 0.004), (SURFACES["black"], 0.004)]
    built, after_built = _fresh(layout, 11, lead=0.001)
    rng = np.random.default_rng(11)
    kept = Track.build(layout, rng, lead=0.001)
    assert kept.rho is built.rho and rng.random() == after_built
    other = Track.build(layout, np.random.default_rng(12), lead=0.001)
    assert not np.array_equal(other.rho, built.rho)
    again, _ = _fresh(layout, 11, lead=0.001)       # built anew: the same numbers
    assert np.array_equal(again.rho, built.rho) and again.rho is not built.rho


def test_the_cache_is_bounded(monkeypatch):
    monkeypatch.setattr(sensors, "TRACK_CACHE_SIZE", 3)
    sensors._TRACKS.clear()
    for seed in range(5):
        Track.build([(SURFACES["white"], 0.001)], np.random.default_rng(seed))
    assert len(sensors._TRACKS) == 3


def test_a_calibration_pour_depends_on_the_mechanics_not_the_name_or_surface():
    tr, dk = BOTTLES["TR"], BOTTLES["DK"]
    assert tr.surface != dk.surface and _mechanics(tr) == _mechanics(dk)
    assert _mechanics(tr) != _mechanics(dataclasses.replace(tr, mu_s=tr.mu_s * 1.01))


@pytest.mark.slow
def test_shared_pours_give_the_same_calibration():
    memo: dict = {}
    tr = calibrate_bottle(BOTTLES["TR"], 180.0, seeds=(0,), memo=memo)
    pours = len(memo)
    dk = calibrate_bottle(BOTTLES["DK"], 180.0, seeds=(0,), memo=memo)
    assert len(memo) == pours                       # DK ran no pour of its own
    alone = calibrate_bottle(BOTTLES["DK"], 180.0, seeds=(0,))
    assert dk == alone and dk.mu_s == tr.mu_s and dk.bottle.surface == BOTTLES["DK"].surface
