"""``slipreflex study``: which of the paper's claims hold across every plausible plant (on Dask).

Draws ``--plants`` plants from the uncertain constants, runs the reproduce
grid on each (a local Dask cluster by default, ``--scheduler`` for a running
one, ``--workers 0`` in this process) and writes, to ``--out``: one Parquet
part per plant as it finishes, results.parquet / results.csv, plants.csv,
claims.csv, sensitivity.csv, figures/ and study.md. Started again with the
same arguments it resumes; Ctrl-C keeps every finished plant (exit 130).
See docs/study.md.

Examples
--------
>>> from slipreflex.cli import main
>>> main(["study", "--plants", "2", "--trials", "1", "--workers", "0", "--out", "/tmp/s"])  # doctest: +SKIP
claim  class             holds (95% CI)     the paper says (decided by)
    1  not-decidable        0% (    0-66%)  "oscillated around a low value (300 to 500 mV)"; ...
...
   11  fails-paper          0% (    0-66%)  "DATH performed consistently better than the NMSD and ...
...
2 plants (2 computed now, 0 with errors) in 6.2 s on serial; wrote /tmp/s/{results.parquet, ...}
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import shlex
import sys
from pathlib import Path
from typing import Any

from .. import methods
from ..analysis.claims import DEPENDS_PLANT
from ..core import experiment_specs
from ..core.errors import SlipreflexError
from ..core.validation import within
from ..files.paths import OutputSet
from ..reproduce.experiments import BOTTLE_NAMES, EXPERIMENTS
from ..reproduce.experiments import DEFAULT_SEED as seed
from ..study import DEFAULT_PLANTS, DEFAULT_TRIALS, DESIGNS, StudyConfig, read_parts, run_study
from ..study.analyse import claim_fractions, plant_table, pooled_scan, refinement, sensitivity, write_outputs
from ..study.runner import probe_scheduler

NAME = "study"
HELP = "map where the paper's claims hold across plausible plants (Dask; resumable)"
ORDER = 35


def _list(kind: str, known: Any):
    def parse(text: str) -> tuple[str, ...]:
        items = tuple(x.strip() for x in text.split(",") if x.strip())
        listed: Any = known() if callable(known) else known
        names = tuple(listed)
        if kind == "methods":   # method names match in any case (the registry's rule)
            items = tuple(x.lower() for x in items)
        bad = [x for x in items if x not in names]
        if bad or not items:
            raise argparse.ArgumentTypeError(
                f"{kind}: unknown {', '.join(map(repr, bad)) or 'empty list'} (known: {', '.join(names)})")
        return items
    return parse


#: The tables and figures ``study`` writes into ``--out``, replaced as one set (the Parquet parts
#: and study.json are the study's resumable state, kept across runs).
OUTPUT_NAMES: tuple[str, ...] = ("results.parquet", "results.csv", "plants.csv", "claims.csv", "sensitivity.csv",
                                 "study.md", "figures")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex study``."""
    p.add_argument("--plants", type=int, default=DEFAULT_PLANTS,
                   help=f"plants to draw (default {DEFAULT_PLANTS}; saltelli rounds up to B(D+2))")
    p.add_argument("--refine", type=int, default=0, metavar="N",
                   help="after the --plants pilot, N more plants where a claim's class changes between "
                        "neighbours, and a stratified estimate of each claim's fraction (default 0: none; "
                        "sobol design only)")
    p.add_argument("--design", choices=DESIGNS, default="sobol", help="design over the constants (default sobol)")
    p.add_argument("--trials", type=int, default=DEFAULT_TRIALS,
                   help=f"trials per bottle, experiment and method on each plant (default {DEFAULT_TRIALS})")
    p.add_argument("--bottles", type=_list("bottles", BOTTLE_NAMES), default=BOTTLE_NAMES,
                   help=f"comma-separated bottles (default {','.join(BOTTLE_NAMES)})")
    p.add_argument("--methods", type=_list("methods", methods.names), default=methods.names(paper=True),
                   help=f"comma-separated methods (default {','.join(methods.names(paper=True))})")
    p.add_argument("--experiments", type=_list("experiments", experiment_specs.names), default=EXPERIMENTS,
                   help=f"comma-separated experiments (default {','.join(EXPERIMENTS)})")
    p.add_argument("--seed", type=int, default=seed, help=f"design and trial master seed (default {seed})")
    p.add_argument("--out", type=Path, default=Path("out/study"), help="output directory (default out/study)")
    p.add_argument("--ranges", type=Path, default=None, metavar="FILE",
                   help="TOML file narrowing, widening or fixing uncertain constants")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="a running Dask scheduler, tcp://HOST:PORT (default: a local cluster)")
    p.add_argument("--dashboard", default=None, metavar="HOST:PORT",
                   help="serve the local cluster's Dask dashboard there, e.g. 127.0.0.1:8787 (default: no "
                        "dashboard; it has no authentication, so keep it on 127.0.0.1)")
    p.add_argument("--workers", type=int, default=None,
                   help="local Dask worker processes (default: all cores; 0: no Dask, this process)")
    p.add_argument("--no-calibration", action="store_true",
                   help="keep each plant's pad friction (default: calibrate it to the 200 ml first slip)")
    p.add_argument("--no-figures", action="store_true", help="skip the figures")
    p.add_argument("--no-progress", action="store_true", help="no progress output")


#: What ``pip install 'slipreflex[study]'`` adds; the base install never imports them.
STUDY_EXTRA = ("dask", "distributed", "pyarrow", "SALib")


def require_study_extra() -> None:
    """Raise a one-line error naming the ``study`` extra when any of its packages is missing.

    Raises
    ------
    SlipreflexError
        ``needs the optional 'study' extra (not installed: ...)``, before any work starts.

    Examples
    --------
    >>> require_study_extra()  # doctest: +SKIP
    """


    missing = [name for name in STUDY_EXTRA if importlib.util.find_spec(name) is None]
    if missing:
        raise SlipreflexError(f"needs the optional 'study' extra (not installed: {', '.join(missing)}); "
                              "install it with: pip install 'slipreflex[study]'")


def run(args: argparse.Namespace) -> int:
    """Run the study, write the outputs, print the claims' fractions."""
    require_study_extra()

    within("trials", args.trials, "--trials")
    within("plants", args.plants, "--plants")
    if args.workers:
        within("jobs", args.workers, "--workers")
    config = StudyConfig(plants=args.plants, design=args.design, trials=args.trials, bottles=tuple(args.bottles),
                         methods=tuple(args.methods), experiments=tuple(args.experiments), seed=args.seed,
                         ranges=args.ranges, calibrate=not args.no_calibration, refine=args.refine)
    claimed: OutputSet | None = None
    if args.out.is_dir():   # a file of the user's where the study writes its tables: refused before any work
        claimed = OutputSet(args.out, NAME)
        claimed.claim()     # held to the commit: one study writing into --out at a time
        claimed.check(OUTPUT_NAMES)
    if args.scheduler:      # an address that is not a Dask scheduler costs one line, before the folder is touched
        probe_scheduler(args.scheduler)
    try:
        result = run_study(config, args.out, workers=args.workers, scheduler=args.scheduler,
                           progress=not args.no_progress, dashboard=args.dashboard)
    except KeyboardInterrupt:

        done = len(read_parts(args.out, config.fingerprint()))
        print(f"slipreflex study: interrupted; {done} finished plant(s) kept in {args.out}/parts, "
              "run the same command again to resume" if done else
              "slipreflex study: interrupted before any plant finished; nothing kept", file=sys.stderr)
        return 130
    command = "slipreflex " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv[1:] else None
    outputs = claimed or OutputSet(args.out, NAME)
    staged = outputs.stage()
    try:
        write_outputs(dataclasses.replace(result, out=staged), figures=not args.no_figures, command=command)
        outputs.commit(staged)
    except KeyboardInterrupt:
        outputs.abort(staged)
        print(f"slipreflex study: interrupted while writing the tables; {args.out}/ keeps the previous ones and "
              "every finished plant (run the same command again)", file=sys.stderr)
        return 130
    except BaseException:
        outputs.abort(staged)
        raise
    paths = {"study_md": outputs.folder / "study.md"}
    plants = plant_table(result.parts)

    sens = sensitivity(plants, result.config.table, design=result.config.design, seed=result.config.seed)
    print("claim  class             holds (95% CI)     the paper says (decided by)")
    for r in claim_fractions(plants, pooled_scan(result.parts), sens, refinement(result)):
        ci = f"{100 * r['low']:.0f}-{100 * r['high']:.0f}%" if r["plants"] else "-"
        frac = f"{100 * r['value']:.0f}%" if r["plants"] else "-"
        dec = f" (decided by {r['decided_by']})" if r["verdict"] == DEPENDS_PLANT and r["decided_by"] else ""
        print(f"{r['claim']:>5}  {r['verdict']:16}  {frac:>5} ({ci:>9})  {r['text']}{dec}")
    errors = sum(1 for p in plants if p.get("error"))
    files = "results.parquet, results.csv, plants.csv, claims.csv, sensitivity.csv, study.md"
    files += "" if args.no_figures else ", figures/"
    print(f"{len(result.parts)} plants ({len(result.computed)} computed now, {errors} with errors) in "
          f"{result.wall_s:.1f} s on {result.workers}; wrote {paths['study_md'].parent}/{{{files}}}")
    return 0
