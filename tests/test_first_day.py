"""A researcher's first day: advice that holds, figures from what the controller saw, commands that
do what they say."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from slipreflex.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]


# -- one list syntax ---------------------------------------------------------------------------

def test_calibrate_takes_the_comma_list_the_readme_shows(capsys):
    assert build_parser().parse_args(["calibrate", "--bottles", "TR,DK,TX"]).bottles == ("TR", "DK", "TX")
    assert main(["calibrate", "--bottles", "TR,XX"]) == 2           # checked before any work
    assert "unknown bottle 'XX'" in capsys.readouterr().err


@pytest.mark.parametrize("argv, option, right", [
    (["calibrate", "--bottles", "TR", "DK", "TX"], "--bottles", "--bottles TR,DK,TX"),
    (["reproduce", "--methods", "dath", "fixed", "--trials", "1"], "--methods", "--methods dath,fixed"),
    (["study", "--experiments", "drop", "pour"], "--experiments", "--experiments drop,pour"),
])
def test_space_separated_names_are_refused_with_the_right_form(capsys, argv, option, right):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and option in err[0] and right in err[0] and "comma-separated" in err[0]


# -- scan --------------------------------------------------------------------------------------

@pytest.mark.parametrize("argv, says", [
    (["--layout", "stand:5,white:10,black:15"], "longer than --layout 'stand:5,white:10,black:15' (30 mm)"),
    (["--distance", "60"], "longer than the paper's layout (50 mm)"),
    (["--objects", "MISSING.toml"], "--objects MISSING.toml: no such file"),
])
def test_scan_refuses_what_it_cannot_do_before_any_work(tmp_path, capsys, argv, says):
    out = tmp_path / "scan"
    assert main(["scan", "--out", str(out), *argv]) == 2
    assert says in capsys.readouterr().err
    assert not out.exists()
