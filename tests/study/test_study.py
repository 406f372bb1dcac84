"""slipreflex study: reproducible design, resume, errors recorded, same rows serial / LocalCluster / scheduler."""

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from slipreflex.analysis.claims import HOLDS
from slipreflex.cli import main
from slipreflex.core.errors import ParameterError
from slipreflex.sim.uncertain import UNCERTAIN
from slipreflex.study import StudyConfig, draw_design, read_parts, run_study, unit_design, varying
from slipreflex.study.analyse import claim_fractions, plant_table, sensitivity, wilson, write_outputs

TINY = dict(trials=1, bottles=("TX",), methods=("dath",), experiments=("drop",), calibrate=False, scan=False)
CLI_TINY = ["--trials", "1", "--bottles", "TX", "--methods", "dath", "--experiments", "drop",
            "--no-calibration", "--no-figures", "--no-progress"]


@pytest.mark.parametrize("kind", ["sobol", "lhs", "saltelli"])
def test_design_is_reproducible_from_its_seed(kind):
    a = draw_design(UNCERTAIN, 5, kind, seed=11)
    assert a == draw_design(UNCERTAIN, 5, kind, seed=11)
    assert a != draw_design(UNCERTAIN, 5, kind, seed=12)
    for plant in a:
        for k, c in UNCERTAIN.items():
            assert c.low <= plant[k] <= c.high


def test_design_sizes_and_fixed_constants(tmp_path):
    d = len(varying(UNCERTAIN))
    assert unit_design("saltelli", 5, d, 0).shape == (d + 2, d)   # one base sample of B = 1
    assert unit_design("lhs", 7, d, 0).shape == (7, d)
    # a Latin hypercube puts one point in each of the n strata of every dimension
    u = unit_design("lhs", 8, d, 3)
    assert all(sorted(np.floor(u[:, j] * 8).astype(int)) == list(range(8)) for j in range(d))
    p = tmp_path / "r.toml"
    p.write_text("[hand_latency]\nfixed = 0.02\n")
    cfg = StudyConfig(plants=3, ranges=str(p), **TINY)
    assert "hand_latency" not in varying(cfg.table)
    assert {v["hand_latency"] for v in cfg.plant_values()} == {0.02}


def test_a_bad_ranges_file_is_one_line_before_any_work(tmp_path, capsys):
    p = tmp_path / "r.toml"
    p.write_text("[no_such_constant]\nlow = 1\n")
    out = tmp_path / "out"
    assert main(["study", "--plants", "2", "--ranges", str(p), "--out", str(out), *CLI_TINY]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "no_such_constant" in err and str(p) in err
    assert not out.exists()


@pytest.mark.slow
def test_killed_and_resumed_equals_uninterrupted(tmp_path):
    cfg = StudyConfig(plants=3, **TINY)
    full = run_study(cfg, tmp_path / "a", workers=0, progress=False)
    write_outputs(full, figures=False)

    def kill_after_first(outcome):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_study(cfg, tmp_path / "b", workers=0, progress=False, on_plant=kill_after_first)
    assert sorted(read_parts(tmp_path / "b")) == [0]
    resumed = run_study(cfg, tmp_path / "b", workers=0, progress=False)
    assert resumed.computed == [1, 2]            # plant 0 was not computed again
    write_outputs(resumed, figures=False)
    for name in ("results.parquet", "results.csv", "claims.csv", "plants.csv", "sensitivity.csv", "study.md"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name


def test_another_study_in_the_same_out_is_refused(tmp_path):
    run_study(StudyConfig(plants=1, **TINY), tmp_path, workers=0, progress=False)
    with pytest.raises(ParameterError, match="holds another study"):
        run_study(StudyConfig(plants=2, **TINY), tmp_path, workers=0, progress=False)


def test_a_raising_plant_is_recorded_and_the_rest_complete(tmp_path):
    # kinetic over static friction above 1 is rejected by the bottle: a Latin hypercube of 4 puts
    # two plants surely above 1 and one surely below
    p = tmp_path / "r.toml"
    p.write_text("[pad_mu_k_ratio]\nlow = 0.6\nhigh = 1.5\n")
    cfg = StudyConfig(plants=4, design="lhs", ranges=str(p), **TINY)
    run = run_study(cfg, tmp_path / "out", workers=0, progress=False)
    plants = plant_table(run.parts)
    bad = [q for q in plants if q["error"]]
    good = [q for q in plants if not q["error"]]
    assert len(run.parts) == 4 and len(bad) >= 2 and good
    assert all("mu_k" in q["error"] for q in bad)
    assert all(q["pad_mu_k_ratio"] > 1 for q in bad) and all(q["pad_mu_k_ratio"] <= 1 for q in good)
    assert all(run.parts[q["plant"]][1][0].get("experiment") == "drop" for q in good)
    assert claim_fractions(plants)[7]["errors"] == len(bad)


def _rows(path):
    import pyarrow.parquet as pq

    return pq.read_table(path).to_pylist()


@pytest.mark.slow
def test_local_cluster_equals_serial(tmp_path):
    cfg = StudyConfig(plants=2, **TINY)
    serial = run_study(cfg, tmp_path / "s", workers=0, progress=False)
    dask = run_study(cfg, tmp_path / "d", workers=2, progress=False)
    assert dask.workers == "LocalCluster(2)" and sorted(dask.computed) == [0, 1]
    write_outputs(serial, figures=False)
    write_outputs(dask, figures=False)
    assert (tmp_path / "s" / "results.parquet").read_bytes() == (tmp_path / "d" / "results.parquet").read_bytes()
    assert len(_rows(tmp_path / "d" / "results.parquet")) >= 2


def _start(args, env):
    return subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)


def _await_line(proc, needle):
    """Read the process's log until a line holds ``needle``; return that line."""
    for line in proc.stderr:
        if needle in line:
            return line
    raise AssertionError(f"{proc.args[0]} exited before logging {needle!r}")


@pytest.mark.slow
def test_a_scheduler_and_one_worker_give_the_same_rows(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parents[2] / "src")}
    dask = str(Path(sys.executable).with_name("dask"))
    sched = _start([dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard"], env)
    worker = None
    try:
        addr = _await_line(sched, "Scheduler at:").split("Scheduler at:")[1].strip()
        worker = _start([dask, "worker", addr, "--nworkers", "1", "--nthreads", "1", "--no-dashboard"], env)
        _await_line(worker, "Registered to:")
        args = ["study", "--plants", "2", "--seed", "5", *CLI_TINY]
        assert main([*args, "--scheduler", addr, "--out", str(tmp_path / "c")]) == 0
        assert main([*args, "--workers", "0", "--out", str(tmp_path / "s")]) == 0
    finally:
        for p in (worker, sched):
            if p is not None:
                p.terminate()
                p.wait(timeout=30)
                p.stderr.close()
    for name in ("results.parquet", "results.csv", "claims.csv"):
        assert (tmp_path / "c" / name).read_bytes() == (tmp_path / "s" / name).read_bytes(), name
    assert len(_rows(tmp_path / "c" / "results.parquet")) >= 2


def test_claim_fractions_and_wilson():
    from scipy.stats import binomtest

    lo, hi = wilson(5, 10)
    assert (lo, hi) == pytest.approx(tuple(binomtest(5, 10).proportion_ci(method="wilson")))
    assert wilson(0, 10)[0] == 0.0 and wilson(10, 10)[1] == 1.0
    plants = [{"error": "", "claim_3": v} for v in ["holds"] * 3 + ["fails-plant", "unresolved"]]
    plants.append({"error": "ValueError: x"})
    plants.append({"error": "", "rejected": "observed first slip outside 170-230 ml: TR 240 ml", "claim_3": "holds"})
    r = claim_fractions(plants)[2]
    got = (r["plants"], r["errors"], r["rejected"], r["holds"], r["fails_plant"], r["unresolved"])
    assert got == (5, 1, 1, 3, 1, 1)
    assert r["value"] == 0.6 and r["verdict"] == "depends-plant" and "holds on 3 of 5 plants" in r["reason"]


def test_the_study_verdict_of_a_claim_the_equations_decide_is_theirs():
    plants = [{"error": "", "claim_3": "fails-definition", "reason_3": "same encoder"} for _ in range(6)]
    plants += [{"error": "", "claim_3": "holds", "reason_3": ""}]
    r = claim_fractions(plants)[2]
    assert r["verdict"] == "fails-definition" and r["reason"] == "6 of 7 plants: same encoder"
    every = [{"error": "", "claim_5": "fails-plant"} for _ in range(30)]
    assert claim_fractions(every)[4]["verdict"] == "fails-plant"
    # "fails on this plant" only when it fails on every plant: one plant that holds makes it depend on the plant
    r = claim_fractions(every + [{"error": "", "claim_5": "holds"}])[4]
    assert r["verdict"] == "depends-plant" and "holds on 1 of 31 plants" in r["reason"]


def test_depends_on_the_plant_names_the_constants_that_pass_the_false_discovery_control():
    from slipreflex.study.analyse import reaches

    design = draw_design(UNCERTAIN, 48, "sobol", seed=3)
    cut = UNCERTAIN["texture_TX"].nominal
    plants = [{**v, "error": "", "claim_10": HOLDS if v["texture_TX"] < cut else "fails-plant",
               "claim_2": HOLDS if v["wall_stiffness"] < 700 else "fails-plant"} for v in design]
    sens = sensitivity(plants, UNCERTAIN)
    r10 = claim_fractions(plants, None, sens)[9]
    assert r10["verdict"] == "depends-plant" and "texture_TX (rho -0." in r10["decided_by"]
    assert "; decided by " in r10["reason"] and "texture_TX" in r10["reason"] and 0 < r10["value"] < 1
    # a scan claim is never "decided by" a constant that cannot reach a scan (no bottle, no wall)
    assert not reaches(UNCERTAIN["wall_stiffness"], 2) and "wall_stiffness" not in claim_fractions(
        plants, None, sens)[1]["decided_by"]
    assert all(math.isnan(x["bh_q"]) for x in sens if x["claim"] == 2 and x["constant"] == "wall_stiffness")
    # q-values are Benjamini-Hochberg over every reachable (constant, claim)
    from scipy.stats import false_discovery_control
    tested = [x for x in sens if x["reaches"] and x["spearman_p"] == x["spearman_p"]]
    want = false_discovery_control([x["spearman_p"] for x in tested])
    assert [x["bh_q"] for x in tested] == pytest.approx(list(want))


def test_sensitivity_finds_the_deciding_constant_with_sobol_indices():
    design = draw_design(UNCERTAIN, 8 * (len(varying(UNCERTAIN)) + 2), "saltelli", seed=1)
    mid = UNCERTAIN["hand_latency"]
    cut = (mid.low + mid.high) / 2
    plants = [{**v, "error": "", "claim_8": HOLDS if v["hand_latency"] < cut else "fails-plant"} for v in design]
    sens = [r for r in sensitivity(plants, UNCERTAIN, design="saltelli", seed=1) if r["claim"] == 8]
    top = min((r for r in sens if r["rank"] > 0), key=lambda r: r["rank"])
    assert top["constant"] == "hand_latency" and top["sobol_st"] > 0.5 and top["spearman_rho"] < -0.5
    assert all(r["sobol_st"] < 0.3 for r in sens if r["constant"] != "hand_latency")


@pytest.mark.slow
def test_outputs_and_figures(tmp_path):
    run = run_study(StudyConfig(plants=3, **TINY), tmp_path, workers=0, progress=False)
    paths = write_outputs(run, figures=True)
    assert (tmp_path / "figures" / "fractions.png").stat().st_size > 0
    assert len([p for p in paths if p.startswith("claim_")]) == 11
    md = (tmp_path / "study.md").read_text()
    assert '| 8 | "an overall response time of less than 85 ms"' in md and "## What the map says" in md
    header = (tmp_path / "results.csv").read_text().splitlines()[0].split(",")
    assert {"plant", "error", "hand_latency", "response_ms"} <= set(header)


@pytest.mark.slow
def test_every_plant_scans_its_own_texture_seeds_and_the_study_pools_them(tmp_path):
    from slipreflex.study.analyse import pooled_scan
    from slipreflex.study.runner import run_plant

    cfg = StudyConfig(plants=2, **{**TINY, "scan": True})
    a, b = (run_plant(i, v, cfg) for i, v in enumerate(cfg.plant_values()))
    assert len(a.scan["seeds"]) == cfg.scan_seeds and set(a.scan["seeds"]).isdisjoint(b.scan["seeds"])
    run = run_study(cfg, tmp_path, workers=0, progress=False)
    assert len(pooled_scan(run.parts)) == 2 * cfg.scan_seeds
    first = claim_fractions(plant_table(run.parts), pooled_scan(run.parts))[0]
    assert "scans pooled over the plants" in first["reason"]


def test_a_plant_whose_observed_first_slip_leaves_the_band_is_counted_apart(monkeypatch):
    from slipreflex.study import runner

    def off_band(plant, table):
        return plant, {"calibrated_first_slip_ml_TX": 260.0, "calibration_note": "",
                       "rejected": "observed first slip outside the paper's 170-230 ml: TX 260 ml"}

    monkeypatch.setattr(runner, "_calibrated", off_band)
    cfg = StudyConfig(plants=1, **{**TINY, "calibrate": True})
    out = runner.run_plant(0, cfg.plant_values()[0], cfg)
    assert out.error == "" and out.trials == 0 and out.claims == [] and "TX 260 ml" in out.calibration["rejected"]
    rec = plant_table({0: ({"values": out.values, "error": "", "claims": [], "calibration": out.calibration}, [])})
    assert claim_fractions(rec)[0]["rejected"] == 1 and claim_fractions(rec)[0]["plants"] == 0


def test_a_claim_most_plants_cannot_decide_is_unresolved_in_the_study():
    plants = [{"error": "", "claim_6": "unresolved"} for _ in range(30)] + [{"error": "", "claim_6": "fails-plant"}]
    r = claim_fractions(plants)[5]
    assert r["verdict"] == "unresolved" and "fails on 1" in r["reason"] and "do not decide it" in r["reason"]
