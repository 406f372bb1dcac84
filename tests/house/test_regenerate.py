"""scripts/regenerate.py rewrites every generated table the README and docs/ quote: each marker
pair there is written by one of its steps, each step's script exists, and each step declares the
steps whose outputs it reads (no circle; ``--only`` plans them first)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
import scripts.regenerate as regenerate  # noqa: E402  (the repository's top is on pytest's path)


def _markers() -> dict[str, str]:
    """``{marker name: file}`` of every ``<!-- NAME begins -->`` in README.md and docs/*.md."""
    out = {}
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = path.read_text()
        for name in re.findall(r"<!-- (.+?) begins -->", text):
            assert f"<!-- {name} ends -->" in text, f"{path.name}: '{name}' begins but never ends"
            out[name] = path.name
    return out


def test_every_generated_table_has_a_step_and_every_step_a_script():
    written = {m for step in regenerate.STEPS for m in step.writes}
    missing = {name: where for name, where in _markers().items() if name not in written}
    assert not missing, f"tables no step of scripts/regenerate.py writes: {missing}"
    assert _markers(), "no generated table found"
    for step in regenerate.STEPS:
        for part in step.command:
            if part.endswith(".py"):
                assert Path(part).exists(), f"step {step.name!r}: {part} does not exist"


def test_the_dry_run_lists_the_steps_in_order():
    res = subprocess.run([sys.executable, "-m", "scripts.regenerate", "--dry-run", "--jobs", "2"],
                         capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert [line.split(":")[1].strip() for line in lines] == [step.name for step in regenerate.STEPS]
    assert "--jobs 2" in lines[0] and "(writes: results table, claims table)" in lines[1]


def _circle(needs: dict[str, tuple[str, ...]]) -> list[str] | None:
    """One circle of the ``needs`` graph (step names, the first repeated last), or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(v: str) -> list[str] | None:
        state[v] = 1
        stack.append(v)
        for w in needs.get(v, ()):
            if state.get(w) == 1:
                return stack[stack.index(w):] + [w]
            if w not in state and (found := visit(w)):
                return found
        stack.pop()
        state[v] = 2
        return None

    for v in needs:
        if v not in state and (found := visit(v)):
            return found
    return None


def _producer(path: str) -> str:
    """The step whose folder (``--out``) holds ``path`` (a "{out}..." argument of a command)."""
    found = [s.name for s in regenerate.STEPS
             if (folder := s.folder()) and (path == folder or path.startswith(folder + "/"))]
    assert len(found) == 1, f"{path}: written by {found or 'no step'}"
    return found[0]


def test_the_steps_needs_name_steps_listed_before_them_and_form_no_circle():
    names = [s.name for s in regenerate.STEPS]
    needs = {s.name: s.needs for s in regenerate.STEPS}
    assert len(set(names)) == len(names)
    assert _circle(needs) is None, f"a circle of needs: {_circle(needs)}"
    for i, step in enumerate(regenerate.STEPS):
        for need in step.needs:
            assert need in names[:i], f"step {step.name!r} needs {need!r}, which is not a step listed before it"
    assert any(needs.values()), "no step declares a need"


def test_the_circle_finder_finds_a_circle():
    assert _circle({"a": ("b",), "b": ("c",), "c": ("a",)}) == ["a", "b", "c", "a"]
    assert _circle({"a": ("b",), "b": (), "c": ("a", "b")}) is None


def test_every_step_needs_exactly_the_steps_whose_folders_its_command_reads():
    """A folder a command reads ("{out}/summary.csv", "{out}-study") is the --out of one step, and
    that step is among the reader's needs; a need is there because its folder is read."""
    for step in regenerate.STEPS:
        read = {_producer(path) for path in step.reads()}
        assert read == set(step.needs), f"step {step.name!r} reads the folders of {read}, declares {step.needs}"
    readers = [s for s in regenerate.STEPS if s.reads()]
    assert len(readers) >= 6 and {"reproduce", "study"} <= {n for s in readers for n in s.needs}


def test_only_plans_what_a_step_needs_first_and_nothing_else():
    plan = regenerate.plan
    assert [s.name for s in plan("speed table")] == ["reproduce", "study", "speed table"]
    assert [s.name for s in plan("README results and claims tables")] == ["reproduce",
                                                                          "README results and claims tables"]
    assert [s.name for s in plan("NIR loop table")] == ["NIR loop", "NIR loop table"]
    assert [s.name for s in plan("limits table")] == ["limits table"]
    assert [s.name for s in plan()] == [s.name for s in regenerate.STEPS]
    for step in regenerate.STEPS:       # every need of a planned step is planned before it
        names = [s.name for s in plan(step.name)]
        assert names[-1] == step.name
        for i, planned in enumerate(plan(step.name)):
            assert set(planned.needs) <= set(names[:i]), (step.name, planned.name)
    chained = [regenerate.Step("a", (), ["x", "--out", "{out}-a"]),
               regenerate.Step("b", (), ["x", "{out}-a", "--out", "{out}-b"], needs=("a",)),
               regenerate.Step("c", (), ["x"]),
               regenerate.Step("d", ("d",), ["x", "{out}-b/f.csv"], needs=("b",))]
    assert [s.name for s in plan("d", chained)] == ["a", "b", "d"]


def test_the_dry_run_of_only_a_dependent_step_prints_its_plan():
    res = subprocess.run([sys.executable, "-m", "scripts.regenerate", "--dry-run", "--only",
                          "study claims table"], capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert [line.split(":")[1].strip() for line in lines] == ["study", "study claims table"]
    assert lines[1].endswith("(needs: study)")
    study_out = lines[0].split("--out ")[1].split()[0]
    assert f"scripts.docs.study_table {study_out} --write" in lines[1]


def _script(name: str):
    import importlib

    return importlib.import_module(f"scripts.docs.{name}")


def test_the_dry_run_names_the_opt_in_step_and_only_runs_one_step():
    res = subprocess.run([sys.executable, "-m", "scripts.regenerate", "--dry-run"],
                         capture_output=True, text=True, timeout=120, cwd=ROOT)
    tiers = [line for line in res.stdout.splitlines() if line.startswith("regenerate: test tiers:")]
    assert tiers and tiers[0].endswith("(only with --with-tiers)")
    bad = subprocess.run([sys.executable, "-m", "scripts.regenerate", "--only", "nope"],
                         capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--only 'nope': no such step" in bad.stderr


def test_every_speed_row_reads_its_benchmark_and_a_missing_line_is_an_error_naming_it():
    speed = _script("speed_table")
    assert len({what for what, *_ in speed.ROWS}) == len(speed.ROWS)
    for _, _, script, _, _ in speed.ROWS:
        assert (ROOT / "benchmarks" / script).is_file(), script
    chain = ("SlipReflex.step (dath): median 0.329 us/sample (min 0.3, 7 x 200000 samples)\n"
             "SlipReflex.step (authors-gui): median 0.461 us/sample (min 0.4, 7 x 200000 samples)\n"
             "SlipReflex.step (dath-event): median 0.343 us/sample (min 0.3, 7 x 200000 samples)\n"
             "run_chain (filter+encode+windows+MPI, dath): median 21.5 M samples/s (best 35.5) over 20 samples\n")
    assert speed.chain_step(chain) == "0.329 / 0.461 / 0.343 us"
    assert speed.chain_batch(chain) == "21.5 M samples/s median (best 35.5)"
    with pytest.raises(speed.Missing, match="bench_chain: no line matching"):
        speed.sosfilt(chain)
    assert speed.whole_run("480 trials", {"wall_s": 150.0, "user_s": 60.0, "sys_s": 4.0, "load": 1.5}) == (
        "480 trials: 2 min 30 s wall at load average 1.5, 64 CPU s (60 user + 4 system), so at least 32 s on "
        "2 free cores")


def test_the_tier_table_says_what_ran_and_what_it_cost(monkeypatch):
    tiers = _script("tier_times")
    monkeypatch.setenv("PYTHONDONTWRITEBYTECODE", "1")
    env = tiers._developer_env()
    assert "PYTHONDONTWRITEBYTECODE" not in env and env["PATH"] == os.environ["PATH"]
    line = tiers.row("fast", 'python -m pytest -m "not slow" -q', "what", {
        "passed": 1300, "skipped": 2, "wall_s": 130.4, "cpu_s": 44.6, "load": 2.25})
    assert line == ('| fast | `python -m pytest -m "not slow" -q` | what | 1300 passed, 2 skipped | 45 s | '
                    '2 min 10 s at load average 2.2 |')
    assert "<!-- test tiers begins -->" in (ROOT / "docs" / "development.md").read_text()


def test_the_large_study_block_says_its_time_against_the_target_and_why_plants_were_rejected(tmp_path):
    import csv
    import json

    large = _script("large_study")
    (tmp_path / "timing.json").write_text(json.dumps({"wall_s": 1000.0, "user_s": 1800.0, "sys_s": 40.0,
                                                      "load": 0.5}))
    pinned = "calibration: ... observed at 4.4 ml at pad mu_s 0.8 and 1.2 alike, before its true onsets (200 ml) ..."
    with open(tmp_path / "plants.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, ["plant", "error", "rejected"])
        w.writeheader()
        w.writerows([{"plant": 0, "error": "", "rejected": ""}, {"plant": 1, "error": "", "rejected": pinned},
                     {"plant": 2, "error": "", "rejected": "observed first slip outside the paper's 170-230 ml"},
                     {"plant": 3, "error": "ValueError: x", "rejected": ""}])
    with open(tmp_path / "claims.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, ["claim", "verdict", "value", "low", "high"])
        w.writeheader()
        w.writerow({"claim": 2, "verdict": "holds", "value": 0.59, "low": 0.55, "high": 0.62})
    text = large.block(tmp_path, "a machine")
    assert "**16 min 40 s** wall, **over** the 15 minutes aimed at" in text and "1840 CPU-s" in text
    assert "4 plants, 1 with errors; 1 accepted and 2 rejected by their calibration (1 of them because" in text
    assert "| 2 | holds | 59 % | 55-62 % |" in text
    assert "<!-- large study begins -->" in (ROOT / "docs" / "speed.md").read_text()
