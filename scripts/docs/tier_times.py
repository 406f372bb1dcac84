"""docs/development.md's table of the two test tiers, measured now (both tiers run: minutes).

Usage::

    python -m scripts.docs.tier_times            # run the fast tier, then the whole suite; print the table
    python -m scripts.docs.tier_times --write    # ... and put it between docs/development.md's markers

``python -m scripts.regenerate --with-tiers`` runs it with ``--write`` (not by default: the full suite
takes minutes). Each row says the tests that passed, the CPU time (user + system, the run's cost
whatever else the machine does) and the wall time with the load average when it started.
"""

from __future__ import annotations

import datetime
import os
import re
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "development.md"
BEGIN, END = "<!-- test tiers begins -->", "<!-- test tiers ends -->"

#: (tier, the command as the table shows it, the argument lists of its ``python -m pytest`` runs, what it holds).
TIERS = [
    ("fast", 'python -m pytest -m "not slow" -q -n auto', [["-m", "not slow", "-n", "auto"]],
     "every test module keeps at least one test here, every module's doctests run here, and every module of "
     "`src/` is reached (`tests/house/test_house.py` checks both)"),
    ("full", 'python -m pytest -q -n auto -m "not realtime"; python -m pytest -q -m realtime',
     [["-n", "auto", "-m", "not realtime"], ["-m", "realtime"]],
     "adds the slow tier: whole reproduce runs, the firmware under simavr, the bootstrap script, the Dask "
     "study; then the real-time loop against the wall clock, alone (what `bash scripts/bootstrap.sh test` runs)"),
]


def _developer_env() -> dict[str, str]:
    """The environment with Python's bytecode caches on: a developer's pytest rewrites a test module's asserts
    once and reads the cached module after (an environment with ``PYTHONDONTWRITEBYTECODE`` set redoes it in
    every worker on every run: 8-19 s of a fast tier's collection here)."""
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def warm_bytecode() -> None:
    """Collect every test once, which writes the bytecode caches a developer's second run reads."""
    subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider"], cwd=ROOT,
                   env=_developer_env(), capture_output=True, text=True)


def run_tier(runs: list[list[str]]) -> dict[str, object]:
    """Run pytest once per argument list; the summed counts, wall and CPU seconds (children included),
    the load before the first."""
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    counts: dict[str, int] = {}
    for args in runs:
        done = subprocess.run([sys.executable, "-m", "pytest", *args, "-q", "-rfE", "-p", "no:cacheprovider"],
                              cwd=ROOT, env=_developer_env(), capture_output=True, text=True)
        last = done.stdout.strip().splitlines()[-1] if done.stdout.strip() else ""
        if done.returncode != 0:
            failed = [ln for ln in done.stdout.splitlines() if ln.startswith(("FAILED ", "ERROR "))]
            raise SystemExit(f"tier_times: pytest {' '.join(args)} failed (exit {done.returncode}): {last}\n"
                             + "\n".join(failed))
        for n, k in re.findall(r"(\d+) (passed|skipped|deselected)", last):
            counts[k] = counts.get(k, 0) + int(n)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return {"passed": counts.get("passed", 0), "skipped": counts.get("skipped", 0), "wall_s": wall,
            "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), "load": load}


def _duration(s: float) -> str:
    return f"{s:.0f} s" if s < 120 else f"{int(s // 60)} min {s % 60:.0f} s"


def row(tier: str, command: str, what: str, got: dict) -> str:
    skipped = f", {got['skipped']} skipped" if got["skipped"] else ""
    return (f"| {tier} | `{command}` | {what} | {got['passed']} passed{skipped} | {_duration(got['cpu_s'])} | "
            f"{_duration(got['wall_s'])} at load average {got['load']:.1f} |")


def table(rows: list[str], machine: str) -> str:
    return "\n".join([
        "| tier | command | what | tests | CPU time | wall time, 2 shared cores |", "|---|---|---|---|---|---|",
        *rows, "",
        f"Measured on {datetime.date.today().isoformat()} by `python -m scripts.regenerate --with-tiers` "
        f"(`scripts/docs/tier_times.py`) on {machine}, with numba's cache and Python's bytecode caches warm, as a "
        "developer's second run has them (a first run on a fresh checkout also compiles the kernels and rewrites "
        "the tests' asserts, and takes longer). The CPU time (user + system) is what a run costs; the wall time "
        "depends on what else the 2 cores run."])


def main(argv: list[str]) -> int:
    from benchmarks.machine import describe

    from scripts.docs.splice_report import write_marked

    rows = []
    warm_bytecode()
    for tier, command, runs, what in TIERS:
        print(f"tier_times: {command}", flush=True)
        rows.append(row(tier, command, what, run_tier(runs)))
    text = table(rows, describe())
    print(text)
    return write_marked("tier_times", DOC, BEGIN, END, text) if "--write" in argv else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
