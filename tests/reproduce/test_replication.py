"""Replication over master seeds: claims one run's trials leave unresolved are judged on pooled replicate grids."""

import dataclasses

import pytest

from slipreflex.analysis import claims as C
from slipreflex.analysis.outputs import ReproduceResult, judged_claims, replicates_note, write_outputs
from slipreflex.analysis.trial import TrialRow
from slipreflex.files.interrupts import Interrupted
from slipreflex.reproduce import experiments as E
from slipreflex.reproduce import replication as R

BOTTLES = ("TR", "DK", "TX")
#: DATH's responses straddling claim 8's 85 ms on one run of 6 trials, and clearly under it.
CLOSE = [60.0, 116.0, 85.0]
FAST = [70.0, 75.0, 80.0]


@pytest.fixture(autouse=True)
def small_scan(monkeypatch):
    """Claims 1-2 on 8 texture seeds: these tests are about the trials' claims (the full scan costs seconds)."""
    monkeypatch.setattr(C, "scan_ensemble_for", lambda seed, sensor=None, n=None: C._ensemble(int(seed), sensor, 8))


def _rows(seed, methods, tx_ms, other_ms, trials=6):
    """Drop and pour rows: DATH's TX responds ``tx_ms`` (a list cycled over trials), the others ``other_ms``."""
    out = []
    for e in ("drop", "pour"):
        for b in BOTTLES:
            for m in methods:
                for k in range(trials):
                    ms = (tx_ms if b == "TX" else other_ms)[k % len(tx_ms if b == "TX" else other_ms)]
                    out.append(TrialRow.from_dict({
                        "experiment": e, "bottle": b, "method": m, "trial": k, "seed": seed * 1000 + k,
                        "event": 0, "n_events": 1, "response_ms": ms, "total_ms": 300.0, "success": True}))
    return out


def _result(rows, seed=7):
    cfg = E.ReproduceConfig(seed=seed, methods=("dath",), trials=6)
    return ReproduceResult(cfg, rows, [], {}, {}, 0.0, 1, 0.0, 36, 36)


def test_replicate_seeds_are_reproducible_distinct_and_never_the_run_s_own():
    seeds = [C.replicate_seed(20191215, k) for k in range(1, 11)]
    assert seeds == [C.replicate_seed(20191215, k) for k in range(1, 11)]
    assert len(set(seeds)) == 10 and 20191215 not in seeds
    assert not set(seeds) & {C.replicate_seed(4, k) for k in range(1, 11)}
    with pytest.raises(ValueError, match="replicate k: 0"):
        C.replicate_seed(1, 0)


def test_undecided_methods_name_only_the_methods_of_unresolved_claims():
    def res(n, verdict):
        return C.ClaimResult(n, "", verdict, "", 0.0, 0.0, 0.0, "", "", "")

    assert C.undecided_methods([res(10, C.UNRESOLVED), res(3, C.HOLDS)]) == (C.DATH,)
    assert C.undecided_methods([res(3, C.UNRESOLVED), res(5, C.UNRESOLVED)]) == (C.DATH, C.FIXED, C.NMSD)
    assert C.undecided_methods([res(1, C.UNRESOLVED), res(2, C.UNRESOLVED)]) == ()     # the scan: no grid
    assert all(set(c.methods) <= {C.DATH, C.FIXED, C.NMSD, C.SWT} for c in C.CLAIMS)


def test_a_close_comparison_is_replicated_until_pooled_rows_decide_it(monkeypatch):
    # DATH about 87 ms on one run of 6 trials straddles claim 8's 85 ms; pooled with faster grids it resolves
    calls = []

    def grid(config, *, jobs=None, progress=True, plots=True):
        calls.append((config.seed, config.methods))
        return _result(_rows(config.seed, config.methods, FAST, FAST), config.seed)

    monkeypatch.setattr(E, "run_reproduce", grid)
    first = _result(_rows(7, ("dath",), CLOSE, CLOSE))
    assert {r.number: r.verdict for r in judged_claims(first)}[8] == C.UNRESOLVED
    out = R.replicate_undecided(first, jobs=1)
    assert out is first and 1 <= len(out.replicate_seeds) <= C.REPLICATES_MAX
    assert [s for s, _ in calls] == [C.replicate_seed(7, k) for k in range(1, len(calls) + 1)]
    assert all(m == ("dath",) for _, m in calls)                    # only what claim 8 reads
    assert {r.number: r.verdict for r in judged_claims(out)}[8] == C.HOLDS
    assert len(out.replicates) == len(calls) * len(first.rows)
    assert f"{len(calls)} replicate grid(s) of dath" in replicates_note(out)


def test_replication_stops_at_its_cap_and_says_the_claim_stays_unresolved(monkeypatch):
    calls = []

    def grid(config, **kw):
        calls.append(config.seed)
        return _result(_rows(config.seed, config.methods, CLOSE, CLOSE), config.seed)

    monkeypatch.setattr(E, "run_reproduce", grid)
    out = R.replicate_undecided(_result(_rows(7, ("dath",), CLOSE, CLOSE, trials=3)),
                                max_replicates=2)
    assert len(calls) == 2 and len(out.replicate_seeds) == 2


def test_a_decided_run_and_a_partial_run_are_not_replicated(monkeypatch):
    monkeypatch.setattr(E, "run_reproduce", lambda *a, **k: pytest.fail("no replicate was needed"))
    decided = _result(_rows(7, ("dath",), [20.0, 21.0, 22.0], [20.0, 21.0, 22.0]))
    assert R.replicate_undecided(decided).replicate_seeds == ()
    partial = dataclasses.replace(_result(_rows(7, ("dath",), CLOSE[:2], CLOSE[:2])), trials_finished=3)
    assert R.replicate_undecided(partial).replicate_seeds == ()


def test_ctrl_c_in_a_replicate_keeps_the_run_and_the_finished_replicates(monkeypatch):
    n = []

    def grid(config, **kw):
        n.append(1)
        if len(n) == 2:
            raise Interrupted(None, "interrupted after 3 of 36 trials")
        return _result(_rows(config.seed, config.methods, CLOSE, CLOSE), config.seed)

    monkeypatch.setattr(E, "run_reproduce", grid)
    first = _result(_rows(7, ("dath",), CLOSE, CLOSE, trials=3))
    with pytest.raises(Interrupted) as stop:
        R.replicate_undecided(first)
    assert stop.value.partial is first and len(first.replicate_seeds) == 1 and not first.partial_note


@pytest.mark.slow
def test_replicates_csv_is_written_and_the_claims_command_pools_it(tmp_path, capsys, monkeypatch):
    from slipreflex.cli import main

    run = _result(_rows(7, ("dath",), CLOSE, CLOSE))
    run.replicates.extend(_rows(8, ("dath",), FAST, FAST, trials=30))
    run.replicate_seeds = (8,)
    monkeypatch.setattr(E, "trial_plot", lambda *a, **k: None, raising=False)
    paths = write_outputs(run, tmp_path, jobs=1)
    assert paths["replicates"].name == "replicates.csv"
    written = C.read_claims_csv(paths["claims"])
    assert [r["verdict"] for r in written] == [r.verdict for r in judged_claims(run)]
    assert "replicate grid(s) of dath on master seeds 8" in paths["report"].read_text()
    capsys.readouterr()
    assert main(["claims", str(tmp_path / "results.csv"), "--seed", "7", "--out", str(tmp_path / "again.csv")]) == 0
    assert "pooled with" in capsys.readouterr().out
    assert (tmp_path / "again.csv").read_text() == paths["claims"].read_text()
    assert main(["claims", str(tmp_path / "results.csv"), "--seed", "7", "--no-replicates",
                 "--out", str(tmp_path / "alone.csv")]) == 0
    alone = {r["claim"]: r["verdict"] for r in C.read_claims_csv(tmp_path / "alone.csv")}
    assert alone["8"] == C.UNRESOLVED != {r["claim"]: r["verdict"] for r in written}["8"]
