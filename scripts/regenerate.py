"""Rewrite every generated table the README and docs/ quote, in one command.

Usage::

    python scripts/regenerate.py              # run every step (a default reproduction first)
    python scripts/regenerate.py --dry-run    # list the steps and the markers each one writes
    python scripts/regenerate.py --jobs 4     # worker processes of the reproduction (default 2)

Each table sits between two markers, ``<!-- NAME begins -->`` and ``<!-- NAME ends -->``, and
each marker pair is written by exactly one step below; ``tests/test_regenerate.py`` fails when
a marker in README.md or docs/*.md has no step, so a physics change updates every table the
docs quote in one commit. Steps:

1. ``slipreflex reproduce --jobs 2 --out TMP/repro --no-progress`` into a fresh temporary
   folder (the default run; the command docs/reproduce.md records, so a rerun changes only
   what the code changes);
2. ``scripts/readme_results.py SUMMARY --write``: README's results and claims tables;
3. ``scripts/splice_report.py REPORT``: the run's report in docs/reproduce.md;
4. ``scripts/benchmark_table.py --write``: the real-data benchmark tables of README.md and
   docs/benchmark.md;
5. ``scripts/limits_table.py --write``: the plausible ranges in docs/runtime.md;
6. ``scripts/claims_seeds.py --write``: the claims' classes on five master seeds in
   docs/reproduce.md (about five default grids, plus their replicates).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCRIPTS = ROOT / "scripts"

#: (step name, markers it writes, command; "{out}" is the reproduction's directory).
STEPS: list[tuple[str, tuple[str, ...], list[str]]] = [
    ("reproduce", (), [sys.executable, "-m", "slipreflex", "reproduce", "--jobs", "{jobs}", "--out", "{out}",
                       "--no-progress"]),
    ("README results and claims tables", ("results table", "claims table"),
     [sys.executable, str(SCRIPTS / "readme_results.py"), "{out}/summary.csv", "--write"]),
    ("docs/reproduce.md report", ("report.md",),
     [sys.executable, str(SCRIPTS / "splice_report.py"), "{out}/report.md"]),
    ("benchmark tables", ("benchmark table", "benchmark summary", "vs-sim table", "chain rule",
                          "k sensitivity", "why"),
     [sys.executable, str(SCRIPTS / "benchmark_table.py"), "--write"]),
    ("limits table", ("limits table",), [sys.executable, str(SCRIPTS / "limits_table.py"), "--write"]),
    ("claims over five master seeds", ("claims seeds table",),
     [sys.executable, str(SCRIPTS / "claims_seeds.py"), "--jobs", "{jobs}", "--write"]),
]


def main(argv: list[str]) -> int:
    dry = "--dry-run" in argv
    jobs = argv[argv.index("--jobs") + 1] if "--jobs" in argv else "2"
    out = str(Path(tempfile.mkdtemp(prefix="slipreflex-regenerate-")) / "repro")
    for name, markers, command in STEPS:
        cmd = [c.replace("{out}", out).replace("{jobs}", jobs) for c in command]
        print(f"regenerate: {name}: {' '.join(cmd)}" + (f"  (writes: {', '.join(markers)})" if markers else ""),
              flush=True)
        if dry:
            continue
        done = subprocess.run(cmd, cwd=ROOT)
        if done.returncode != 0:
            print(f"regenerate: step '{name}' failed (exit {done.returncode}); later steps not run",
                  file=sys.stderr)
            return done.returncode
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
