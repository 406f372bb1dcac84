"""The claims' statistics: cluster bootstrap, censoring, Pocock's boundary and the replication's error rate."""

import math

import numpy as np
import pytest

from slipreflex.analysis import claims as C
from slipreflex.analysis import stats as S


def test_pocock_constants_are_the_published_ones():
    # Pocock (1977), Jennison and Turnbull (2000) table 2.1: two-sided 5 %
    assert S.pocock_z(1) == pytest.approx(1.960, abs=2e-3)
    assert S.pocock_z(2) == pytest.approx(2.178, abs=3e-3)
    assert S.pocock_z(3) == pytest.approx(2.289, abs=3e-3)
    assert S.pocock_z(4) == pytest.approx(2.361, abs=3e-3)
    assert C.looks_level(C.LOOKS) > S.pocock_level(C.LOOKS) > C.looks_level(1) == pytest.approx(0.95)


def test_cluster_interval_resamples_whole_pours():
    # two slips per pour, perfectly correlated inside a pour: the clusters, not the slips, carry the noise
    rng = np.random.default_rng(1)
    pours = rng.normal(0.0, 10.0, 12)
    clustered = S.Sample.of({k: [v, v] for k, v in enumerate(pours)})
    naive = S.Sample.of({(k, e): [v] for k, v in enumerate(pours) for e in range(2)})
    _, lo_c, hi_c = S.cluster_interval(S.MEAN, [clustered])
    _, lo_n, hi_n = S.cluster_interval(S.MEAN, [naive])
    assert hi_c - lo_c > 1.3 * (hi_n - lo_n)
    assert S.cluster_interval(S.MEAN, [clustered]) == (S.cluster_interval(S.MEAN, [clustered]))   # seeded


def test_censored_trials_rank_slowest_and_kaplan_meier_medians():
    fast_but_silent = S.Sample.of({k: [10.0 if k < 4 else math.inf] for k in range(10)})
    slow = S.Sample.of({k: [50.0] for k in range(10)})
    p, lo, hi = S.cluster_interval(S.INDEX, [fast_but_silent, slow], paired=True)
    assert p == pytest.approx(0.4) and lo < 0.4 < hi
    assert S.km_median(fast_but_silent, cutoff=1000.0) == math.inf         # fewer than half answered
    assert S.km_median(S.Sample.of({k: [float(k)] for k in range(1, 6)})) == 3.0
    many_silent = S.Sample.of({k: [10.0 if k < 30 else math.inf] for k in range(100)})
    many_slow = S.Sample.of({k: [50.0] for k in range(100)})
    assert S.rank_p(many_slow, many_silent) < 0.05 < S.rank_p(many_silent, many_slow)


def test_newcombe_interval_of_two_rates():
    d, lo, hi = S.newcombe_interval(56, 70, 48, 80)        # Newcombe (1998), example (a), method 10
    assert (d, lo, hi) == pytest.approx((0.2, 0.0524, 0.3339), abs=1e-4)


def _draw_pour(rng, n_pours, shift):
    """A pour grid of two methods: two slips per pour sharing the pour's effect (correlated), paired seeds."""
    rows = []
    for k in range(n_pours):
        pour = rng.normal(0.0, 20.0)
        for m, extra in (("dath", shift), ("fixed", 0.0)):
            for e in range(2):
                rows.append({"experiment": "pour", "bottle": "TX", "method": m, "trial": k, "seed": k,
                             "event": e, "n_events": 2, "response_ms": 80.0 + pour + extra + rng.normal(0.0, 10.0)})
    return rows


def _sequential_class(rng, looks, design_looks, shift=0.0, n_pours=10):
    """The rule as coded: judge; while unresolved and looks remain, add a replicate grid and judge the pool.

    ``design_looks`` sets every look's level (the design's); ``looks`` is how often it may look.
    """
    rows = []
    for k in range(looks):
        rows += [{**r, "seed": f"{k}-{r['seed']}"} for r in _draw_pour(rng, n_pours, shift)]
        ci = C.ClaimInput(rows, reading=C.Reading(looks=design_looks))
        part = C._compare(ci, "pour", ["TX"], "dath", "fixed", label="TX", physics="-")
        if part.verdict != C.UNRESOLVED:
            return part.verdict
    return C.UNRESOLVED


@pytest.mark.slow
def test_replication_keeps_its_error_rate_at_the_criterion():
    rng = np.random.default_rng(20191215)
    reps = 600
    decisive = sum(_sequential_class(rng, C.LOOKS, C.LOOKS) in C.DECISIVE for _ in range(reps))
    assert decisive / reps <= 1.0 - C.CONFIDENCE, decisive
    # 95 % at every look, looking until it decides (the old rule: up to 11 looks), does not keep it
    rng = np.random.default_rng(20191215)
    naive = sum(_sequential_class(rng, 11, 1) in C.DECISIVE for _ in range(200))
    assert naive / 200 > 2 * (1.0 - C.CONFIDENCE), naive
    # and with a real difference the design still decides
    rng = np.random.default_rng(1)
    assert sum(_sequential_class(rng, C.LOOKS, C.LOOKS, shift=-30.0) == C.HOLDS for _ in range(40)) > 30
