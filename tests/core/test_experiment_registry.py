"""Experiments as registered data (slipreflex.core.experiment_specs): the drop and the pour are two
registrations, a new experiment registered from a file outside the package runs through
``reproduce``, its outputs and its figures, and the paper's rows do not move."""

from __future__ import annotations

import ast
import csv
import importlib.util
import sys
import textwrap
from pathlib import Path

import pytest

from slipreflex.cli import main
from slipreflex.core import experiment_specs
from slipreflex.core.errors import ParameterError
from slipreflex.reproduce.experiments import ReproduceConfig, trial_seed
from slipreflex.testing import ContractError, check_experiment

SRC = Path(__file__).resolve().parents[2] / "src" / "slipreflex"

# A user's experiment, in a file of its own: a heavier, higher drop (30 g from 5 cm).
PLUGIN = textwrap.dedent('''
    from slipreflex import experiment_specs
    from slipreflex.sim import Drop

    def heavy_drop(config):
        return Drop(mass_kg=0.03, height_m=0.05)

    def describe(drop):
        return f"{1e3 * drop.mass_kg:g} g from {1e2 * drop.height_m:g} cm"

    experiment_specs.register(experiment_specs.ExperimentSpec(
        name="heavy-drop", title="heavy sudden load", perturbation=heavy_drop, describe=describe,
        slip_events="single", zoom_s=(0.3, 1.5)))
''')


@pytest.fixture
def heavy_drop(tmp_path):
    """The plugin file imported from outside the package; unregistered afterwards."""
    path = tmp_path / "my_experiments.py"
    path.write_text(PLUGIN)
    spec = importlib.util.spec_from_file_location("my_experiments", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["my_experiments"] = module
    spec.loader.exec_module(module)
    yield "heavy-drop"
    experiment_specs.unregister("heavy-drop")
    sys.modules.pop("my_experiments", None)


def _rows(path: Path) -> list[dict[str, str]]:
    return list(csv.DictReader(line for line in path.read_text().splitlines() if not line.startswith("#")))


def test_the_paper_experiments_are_two_registrations():
    assert experiment_specs.names()[:2] == ("drop", "pour")
    drop, pour = experiment_specs.get("drop"), experiment_specs.get("pour")
    assert (drop.slip_events, pour.slip_events) == ("single", "segmented")
    assert pour.records_load and not drop.records_load
    cfg = ReproduceConfig(pour_volume_ml=100.0)
    assert pour.load_s(pour.perturbation(cfg)) == pytest.approx(6.0) and drop.load_s(drop.perturbation(cfg)) == 0
    assert cfg.duration("pour") == cfg.rest_s + 6.0 + cfg.after_s


def test_a_spec_is_validated_and_the_registry_names_what_it_knows():
    with pytest.raises(ParameterError, match="slip_events"):
        experiment_specs.ExperimentSpec(name="x", title="x", perturbation=len, describe=str, slip_events="many")
    with pytest.raises(ParameterError, match="name"):
        experiment_specs.ExperimentSpec(name="Bad Name", title="x", perturbation=len, describe=str)
    with pytest.raises(ParameterError, match="experiment: unknown 'shake' \\(known: drop, pour"):
        experiment_specs.get("shake")
    with pytest.raises(ParameterError, match="cannot be unregistered"):
        experiment_specs.unregister("pour")


def test_the_conformance_check_passes_the_papers_and_names_a_broken_rule():
    assert [r.experiment for r in check_experiment("drop")] == ["drop"]
    broken = experiment_specs.ExperimentSpec(
        name="broken", title="a load that settles after the recording ends",
        perturbation=experiment_specs.get("drop").perturbation, describe=experiment_specs.get("drop").describe,
        settle_s=lambda what: 99.0)
    experiment_specs.register(broken)
    try:
        with pytest.raises(ContractError, match="experiment 'broken': settle_s"):
            check_experiment("broken")
    finally:
        experiment_specs.unregister("broken")


def test_registering_an_experiment_moves_no_other_seed(heavy_drop):
    assert experiment_specs.seed_branch(heavy_drop) == experiment_specs.CALIBRATION_BRANCH + 1
    before = trial_seed(7, "pour", "TX", 3), trial_seed(7, "drop", "DK", 0)
    spec = experiment_specs.get(heavy_drop)
    experiment_specs.unregister(heavy_drop)
    assert (trial_seed(7, "pour", "TX", 3), trial_seed(7, "drop", "DK", 0)) == before
    experiment_specs.register(spec)


@pytest.mark.slow
def test_an_experiment_from_a_file_runs_through_reproduce_its_outputs_and_figures(heavy_drop, tmp_path):
    rows = check_experiment(heavy_drop)
    assert rows[0].experiment == heavy_drop and rows[0].n_events == 1
    common = ["reproduce", "--bottles", "TX", "--methods", "dath", "--trials", "2", "--jobs", "1", "--no-progress"]
    assert main([*common, "--experiments", "drop", "--out", str(tmp_path / "paper")]) == 0
    assert main([*common, "--experiments", f"drop,{heavy_drop}", "--out", str(tmp_path / "both")]) == 0
    both = _rows(tmp_path / "both" / "results.csv")
    mine = [r for r in both if r["experiment"] == heavy_drop]
    assert len({r["trial"] for r in mine}) == 2 and all(r["n_events"] == "1" for r in mine)
    # the paper's rows are the same bits with or without the new experiment beside them
    assert [r for r in both if r["experiment"] == "drop"] == _rows(tmp_path / "paper" / "results.csv")
    figures = {p.name for p in (tmp_path / "both" / "figures").iterdir()}
    assert {f"trial_{heavy_drop}_TX_dath.png", f"bars_{heavy_drop}_response.png",
            f"bars_{heavy_drop}_total.png"} <= figures
    report = (tmp_path / "both" / "report.md").read_text()
    assert f"bars_{heavy_drop}_total.png" in report and f"{heavy_drop} (30 g from 5 cm)" in report
    summary = _rows(tmp_path / "both" / "summary.csv")
    assert any(s["experiment"] == heavy_drop for s in summary)


# The run's own modules: what happens in a trial and what its outputs show is read from the
# experiment's specification, never decided by comparing its name with "drop" or "pour".
PIPELINE = ["reproduce/experiments.py", "reproduce/grid.py", "reproduce/paper_experiments.py",
            "analysis/outputs.py", "analysis/figures.py",
            "analysis/trial.py", "analysis/report/tables.py", "analysis/report/prose.py", "rig/devices/simrig.py",
            "rig/devices/virtual.py"]


@pytest.mark.parametrize("module", PIPELINE)
def test_no_drop_or_pour_branch_outside_their_specs(module):
    tree = ast.parse((SRC / module).read_text())
    branches = [f"{module}:{n.lineno}: {ast.unparse(n)}" for n in ast.walk(tree) if isinstance(n, ast.Compare)
                and any(isinstance(c, ast.Constant) and c.value in ("drop", "pour") for c in ast.walk(n))]
    assert not branches, branches
