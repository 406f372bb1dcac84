"""scripts/regenerate.py rewrites every generated table the README and docs/ quote: each marker
pair there is written by one of its steps, and each step's script exists."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
try:
    import regenerate
finally:
    sys.path.pop(0)


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
    written = {m for _, markers, _ in regenerate.STEPS for m in markers}
    missing = {name: where for name, where in _markers().items() if name not in written}
    assert not missing, f"tables no step of scripts/regenerate.py writes: {missing}"
    assert _markers(), "no generated table found"
    for name, _, command in regenerate.STEPS:
        for part in command:
            if part.endswith(".py"):
                assert Path(part).exists(), f"step {name!r}: {part} does not exist"


def test_the_dry_run_lists_the_steps_in_order():
    res = subprocess.run([sys.executable, str(ROOT / "scripts" / "regenerate.py"), "--dry-run", "--jobs", "2"],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert [line.split(":")[1].strip() for line in lines] == [name for name, _, _ in regenerate.STEPS]
    assert "--jobs 2" in lines[0] and "(writes: results table, claims table)" in lines[1]


def _script(name: str):
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        return __import__(name)
    finally:
        sys.path.pop(0)


def test_the_dry_run_names_the_opt_in_step_and_only_runs_one_step():
    res = subprocess.run([sys.executable, str(ROOT / "scripts" / "regenerate.py"), "--dry-run"],
                         capture_output=True, text=True, timeout=120)
    tiers = [line for line in res.stdout.splitlines() if line.startswith("regenerate: test tiers:")]
    assert tiers and tiers[0].endswith("(only with --with-tiers)")
    bad = subprocess.run([sys.executable, str(ROOT / "scripts" / "regenerate.py"), "--only", "nope"],
                         capture_output=True, text=True, timeout=120)
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


def test_the_tier_table_says_what_ran_and_what_it_cost():
    tiers = _script("tier_times")
    line = tiers.row("fast", 'python -m pytest -m "not slow" -q', "what", {
        "passed": 1300, "skipped": 2, "wall_s": 130.4, "cpu_s": 44.6, "load": 2.25})
    assert line == ('| fast | `python -m pytest -m "not slow" -q` | what | 1300 passed, 2 skipped | 45 s | '
                    '2 min 10 s at load average 2.2 |')
    assert "<!-- test tiers begins -->" in (ROOT / "docs" / "development.md").read_text()
