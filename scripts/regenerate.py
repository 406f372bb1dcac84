"""Rewrite every generated table the README and docs/ quote, in one command.

Usage::

    python -m scripts.regenerate              # run every default step (a default reproduction first)
    python -m scripts.regenerate --with-tiers # ... and time both test tiers (the whole suite: minutes)
    python -m scripts.regenerate --with-large-study   # ... and time the 1000-plant study (over ten minutes)
    python -m scripts.regenerate --dry-run    # list the steps and the markers each one writes
    python -m scripts.regenerate --only "speed table"   # one step and the steps it needs, first
    python -m scripts.regenerate --jobs 4     # worker processes of the reproduction (default 2)

Each table sits between two markers, ``<!-- NAME begins -->`` and ``<!-- NAME ends -->``, and
each marker pair is written by exactly one step below; ``tests/house/test_regenerate.py`` fails when
a marker in README.md or docs/*.md has no step, so a physics change updates every table the
docs quote in one commit. Steps:

1. ``slipreflex reproduce --jobs 2 --out TMP/repro --no-progress`` into a fresh temporary
   folder (the default run; the command docs/reproduce.md records, so a rerun changes only
   what the code changes);
2. ``scripts/docs/readme_results.py SUMMARY --write``: README's results and claims tables;
3. ``scripts/docs/splice_report.py REPORT``: the run's report in docs/reproduce.md;
4. ``scripts/docs/benchmark_table.py --write``: the real-data benchmark tables of README.md and
   docs/benchmark.md;
5. ``scripts/docs/limits_table.py --write``: the plausible ranges in docs/runtime.md;
6. ``scripts/docs/claims_seeds.py --write``: the claims' classes on five master seeds in
   docs/reproduce.md (about five default grids, plus their replicates);
7. ``scripts/docs/open_loop_table.py --write`` and ``scripts/docs/physics_terms.py --write``: docs/simulator.md's
   open-loop table and the physics terms one by one (and their figure);
8. ``scripts/docs/term_claims.py --write``: the claims with each physics term switched off in turn
   (docs/study.md; one default grid per term, each plant recalibrated: the longest step);
9. ``slipreflex study`` into a temporary folder (timed, for the speed table's row), then
   ``scripts/docs/study_table.py`` and
   ``scripts/docs/term_claims.py --study``: the default study's claims and where claims 4, 5 and 7
   become decidable (docs/study.md);
10. ``scripts/docs/threshold_sensitivity.py --write``: the tactile methods' thresholds (docs/reproduce.md);
11. ``slipreflex reproduce`` of the chain's variants (3 trials) and ``scripts/docs/method_table.py``:
    docs/method.md's table;
12. ``scripts/docs/speed_table.py --write``: docs/speed.md's table, every benchmark run now, the
   reproduction's and the study's rows from steps 1 and 9's timings (their wall and CPU time,
   written to ``timing.json`` in each one's folder);
13. only with ``--with-tiers``: ``scripts/docs/tier_times.py --write``, docs/development.md's test
   tiers (it runs the fast tier and then the whole suite);
14. only with ``--with-large-study``: ``slipreflex study --plants 1000 --workers 2`` timed, then
   ``scripts/docs/large_study.py --write``: docs/speed.md's block on it (over ten minutes on 2 cores).

**What a step needs.** Each step names the steps whose outputs it reads (:attr:`Step.needs`):
the README tables and the report read the default reproduction's folder, the study tables the
study's, the speed table both runs' timings, and so on. ``--only STEP`` runs STEP's needs first
(and theirs), in the order of the list, then STEP (:func:`plan`). A need is always run again,
never taken from an earlier regeneration: every run writes into a new temporary folder, and the
speed table's timings must be this run's (a timing of another session on another load would
make the table lie). ``--dry-run`` prints the plan, each step with what it writes and needs;
``tests/house/test_regenerate.py`` checks that the needs form no circle and cover every folder a
step's command reads.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCRIPTS = ROOT / "scripts"

#: The methods of docs/method.md's table of the chain's variants (three trials each).
METHOD_VARIANTS = ("fixed", "dath", "nmsd", "swt", "authors-gui", "authors-chain", "dath-event", "dath-floor",
                   "dath-leak")


@dataclass(frozen=True)
class Step:
    """One step: its name, the markers it writes, its command ("{out}" is the run's folder), its needs.

    Examples
    --------
    >>> step = Step("table", ("t",), ["python", "t.py", "{out}-study/plants.csv"], needs=("study",))
    >>> step.reads(), Step("study", (), ["x", "--out", "{out}-study"]).folder()
    (['{out}-study/plants.csv'], '{out}-study')
    """

    name: str
    writes: tuple[str, ...]
    command: list[str]
    needs: tuple[str, ...] = ()

    def folder(self) -> str | None:
        """The folder this step's command writes (after ``--out``), or None."""
        return self.command[self.command.index("--out") + 1] if "--out" in self.command else None

    def reads(self) -> list[str]:
        """The paths under a step's folder this step's command reads (every "{out}" argument but its own --out)."""
        own = self.folder()
        return [c for c in self.command if c.startswith("{out}") and c != own]


STEPS: list[Step] = [
    Step("reproduce", (), [sys.executable, "-m", "slipreflex", "reproduce", "--jobs", "{jobs}", "--out", "{out}",
                           "--no-progress"]),
    Step("README results and claims tables", ("results table", "claims table"),
         [sys.executable, "-m", "scripts.docs.readme_results", "{out}/summary.csv", "--write"], needs=("reproduce",)),
    Step("docs/reproduce.md report", ("report.md",),
         [sys.executable, "-m", "scripts.docs.splice_report", "{out}/report.md"], needs=("reproduce",)),
    Step("benchmark tables", ("benchmark table", "operating points", "ranking", "benchmark summary", "vs-sim table",
                              "chain rule", "k sensitivity", "why"),
         [sys.executable, "-m", "scripts.docs.benchmark_table", "--write"]),
    Step("contracts and loop states tables", ("contracts table", "loop states table"),
         [sys.executable, "-m", "scripts.docs.contract_tables", "--write"]),
    Step("limits table", ("limits table",), [sys.executable, "-m", "scripts.docs.limits_table", "--write"]),
    Step("claims over five master seeds", ("claims seeds table",),
         [sys.executable, "-m", "scripts.docs.claims_seeds", "--jobs", "{jobs}", "--write"]),
    Step("open-loop table", ("open-loop table",), [sys.executable, "-m", "scripts.docs.open_loop_table", "--write"]),
    Step("physics terms table", ("physics terms table",),
         [sys.executable, "-m", "scripts.docs.physics_terms", "--figure", str(ROOT / "docs" / "physics_terms.png"),
          "--write"]),
    Step("term claims table", ("term claims table",),
         [sys.executable, "-m", "scripts.docs.term_claims", "--jobs", "{jobs}", "--write"]),
    Step("study", (), [sys.executable, "-m", "slipreflex", "study", "--out", "{out}-study", "--no-progress"]),
    Step("study claims table", ("study claims table",),
         [sys.executable, "-m", "scripts.docs.study_table", "{out}-study", "--write"], needs=("study",)),
    Step("study decidable", ("study decidable",),
         [sys.executable, "-m", "scripts.docs.term_claims", "--study", "{out}-study", "--write"], needs=("study",)),
    Step("threshold sensitivity table", ("threshold sensitivity table",),
         [sys.executable, "-m", "scripts.docs.threshold_sensitivity", "--jobs", "{jobs}", "--write"]),
    Step("method variants", (), [sys.executable, "-m", "slipreflex", "reproduce", "--methods",
                                 ",".join(METHOD_VARIANTS), "--trials", "3", "--jobs", "{jobs}", "--no-figures",
                                 "--no-progress", "--out", "{out}-methods"]),
    Step("method variants table", ("method variants table",),
         [sys.executable, "-m", "scripts.docs.method_table", "{out}-methods/summary.csv", "--write"],
         needs=("method variants",)),
    Step("NIR agreement tables", ("nir stages table", "nir backends table"),
         [sys.executable, "-m", "scripts.docs.nir_table", "--write"]),
    Step("NIR loop", (), [sys.executable, "-m", "slipreflex", "reproduce", "--methods", "fixed,nir", "--trials", "3",
                          "--jobs", "{jobs}", "--no-figures", "--no-progress", "--out", "{out}-nir"]),
    Step("NIR loop table", ("nir loop table",),
         [sys.executable, "-m", "scripts.docs.nir_table", "--loop", "{out}-nir/summary.csv", "--write"],
         needs=("NIR loop",)),
    Step("speed table", ("speed table",), [sys.executable, "-m", "scripts.docs.speed_table", "--write",
                                           "--reproduce-timing", "{out}/timing.json",
                                           "--study-timing", "{out}-study/timing.json"],
         needs=("reproduce", "study")),
    Step("test tiers", ("test tiers",), [sys.executable, "-m", "scripts.docs.tier_times", "--write"]),
    Step("large study", (), [sys.executable, "-m", "slipreflex", "study", "--plants", "1000", "--workers", "2",
                             "--out", "{out}-study1000", "--no-progress"]),
    Step("large study block", ("large study",),
         [sys.executable, "-m", "scripts.docs.large_study", "{out}-study1000", "--write"], needs=("large study",)),
]

#: Steps timed as they run: step -> the speed table's option for its timing (None: the step's own block reads it).
TIMED: dict[str, str | None] = {"reproduce": "--reproduce-timing", "study": "--study-timing",
                                "large study": None}   # (its block reads the timing.json in its folder)

#: Steps run only when their flag is given (too slow for the default).
OPT_IN: dict[str, str] = {"test tiers": "--with-tiers", "large study": "--with-large-study",
                          "large study block": "--with-large-study"}


def plan(only: str | None = None, steps: list[Step] = STEPS) -> list[Step]:
    """The steps to run, in the list's order: every step, or ``only`` after everything it needs (transitively).

    Examples
    --------
    >>> [s.name for s in plan("speed table")]
    ['reproduce', 'study', 'speed table']
    >>> [s.name for s in plan("limits table")]
    ['limits table']
    """
    if only is None:
        return list(steps)
    by_name = {s.name: s for s in steps}
    wanted, todo = set(), [only]
    while todo:
        name = todo.pop()
        if name not in wanted:
            wanted.add(name)
            todo.extend(by_name[name].needs)
    return [s for s in steps if s.name in wanted]


def _command(step: Step, out: str, jobs: str, timed_here: set[str]) -> list[str]:
    """The step's command for this run; a timing option only where this run timed that step."""
    cmd = [c.replace("{out}", out).replace("{jobs}", jobs) for c in step.command]
    for timed_step, option in TIMED.items():     # only this run's timings, never an older file's
        if option is not None and option in cmd and timed_step not in timed_here:
            cmd = cmd[:cmd.index(option)] + cmd[cmd.index(option) + 2:]
    return cmd


def _run(step: Step, cmd: list[str], timed_here: set[str]) -> int:
    """Run one step (timed when it is one of :data:`TIMED`); its exit code, with a line on failure."""
    if step.name in TIMED:      # timed: the speed table's row of this default job (not run twice)
        from scripts.docs.speed_table import Missing, timed
        try:
            timing = timed(cmd)
        except Missing as err:
            print(f"regenerate: step '{step.name}' failed: {err}; later steps not run", file=sys.stderr)
            return 1
        Path(cmd[cmd.index("--out") + 1], "timing.json").write_text(json.dumps(timing))
        timed_here.add(step.name)
        return 0
    done = subprocess.run(cmd, cwd=ROOT)
    if done.returncode != 0:
        print(f"regenerate: step '{step.name}' failed (exit {done.returncode}); later steps not run",
              file=sys.stderr)
    return done.returncode


def main(argv: list[str]) -> int:
    dry = "--dry-run" in argv
    only = argv[argv.index("--only") + 1] if "--only" in argv else None
    if only is not None and only not in [s.name for s in STEPS]:
        print(f"regenerate: --only {only!r}: no such step (steps: {', '.join(s.name for s in STEPS)})",
              file=sys.stderr)
        return 2
    jobs = argv[argv.index("--jobs") + 1] if "--jobs" in argv else "2"
    out = str(Path(tempfile.mkdtemp(prefix="slipreflex-regenerate-")) / "repro")
    timed_here: set[str] = set()
    for step in plan(only):
        flag = OPT_IN.get(step.name)
        # the timings are left in: a dry run prints the command of a run that times its steps
        cmd = _command(step, out, jobs, set(TIMED) if dry else timed_here)
        print(f"regenerate: {step.name}: {' '.join(cmd)}"
              + (f"  (writes: {', '.join(step.writes)})" if step.writes else "")
              + (f"  (needs: {', '.join(step.needs)})" if step.needs else "")
              + (f"  (only with {flag})" if flag else ""), flush=True)
        if dry or (flag and flag not in argv and only != step.name):
            continue
        code = _run(step, cmd, timed_here)
        if code != 0:
            return code
    return 0


if __name__ == "__main__":
    if not __package__:   # run as a file, the scripts package is not importable
        sys.exit("regenerate: run it from the repository's top as: python -m scripts.regenerate")
    sys.exit(main(sys.argv[1:]))
