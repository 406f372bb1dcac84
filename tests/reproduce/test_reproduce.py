"""A small ``slipreflex reproduce`` run end to end: files, columns, every method and bottle."""

from __future__ import annotations

import re

import pytest

from slipreflex.analysis.report import SUMMARY_COLUMNS, read_csv
from slipreflex.cli import main
from slipreflex.reproduce.experiments import BOTTLE_NAMES, EXPERIMENTS, METHODS, RESULTS_CSV_COLUMNS


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("reproduce")
    status = main(["reproduce", "--trials", "2", "--out", str(out), "--jobs", "2", "--pour-volume", "200",
                   "--after", "1.0", "--calibration", "1.0", "--no-progress", "--seed", "11"])
    assert status == 0
    return out


@pytest.mark.slow
def test_files_and_columns(run_dir, capsys):
    for name in ("results.csv", "summary.csv", "report.md"):
        assert (run_dir / name).stat().st_size > 0
    rows = read_csv(run_dir / "results.csv")
    assert tuple(rows[0]) == RESULTS_CSV_COLUMNS
    summary = read_csv(run_dir / "summary.csv")
    assert tuple(summary[0]) == SUMMARY_COLUMNS
    assert len(summary) == len(EXPERIMENTS) * len(BOTTLE_NAMES) * len(METHODS)


@pytest.mark.slow
def test_every_method_bottle_and_experiment_ran(run_dir):
    rows = read_csv(run_dir / "results.csv")
    ran = {(r["experiment"], r["bottle"], r["method"], r["trial"]) for r in rows}
    assert ran == {(e, b, m, str(k)) for e in EXPERIMENTS for b in BOTTLE_NAMES for m in METHODS
                   for k in range(2)}
    assert all(r["seed"] and int(r["seed"]) >= 0 for r in rows)
    assert {r["success"] for r in rows} <= {"True", "False"}
    # drops always show their slip in the accelerometer
    drops = [r for r in rows if r["experiment"] == "drop"]
    assert all(r["onset_s"] != "" for r in drops)


@pytest.mark.slow
def test_report_has_the_paper_table_ours_and_the_figures(run_dir):
    md = (run_dir / "report.md").read_text()
    assert "| drop, response ms | TR | 50 ± 6.48 |" in md
    assert "## Where we differ from the paper, and why" in md
    for rel in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", md):
        assert (run_dir / rel).stat().st_size > 1000, rel
    figs = {p.name for p in (run_dir / "figures").iterdir()}
    assert {f"trial_{e}_{b}_dath.png" for e in EXPERIMENTS for b in BOTTLE_NAMES} <= figs
    assert {"bars_drop_response.png", "bars_drop_total.png", "bars_pour_response.png",
            "bars_pour_total.png", "success.png"} <= figs


def test_bad_arguments_are_one_line_errors(tmp_path, capsys):
    assert main(["reproduce", "--trials", "0", "--out", str(tmp_path), "--no-progress"]) == 2
    assert "trials" in capsys.readouterr().err
    # Bottles are checked once --objects is read (it may add some), still before any trial.
    assert main(["reproduce", "--bottles", "TR,XX", "--out", str(tmp_path)]) == 2
    assert "bottles: unknown 'XX'" in capsys.readouterr().err
