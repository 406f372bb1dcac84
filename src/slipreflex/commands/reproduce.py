"""``slipreflex reproduce``: the paper's drop and pour experiments on the simulated rig.

Runs every trial (by default 20 trials x 3 bottles x 2 experiments x 4
methods) in parallel, analyses them as the paper does, and writes
``results.csv``, ``summary.csv``, ``report.md``, ``claims.csv`` (the paper's claims, each
with its verdict class, reason and interval) and PNG figures to ``--out``.

Examples
--------
>>> from slipreflex.cli import main
>>> main(["reproduce", "--trials", "1", "--out", "/tmp/r"])  # doctest: +SKIP
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import shlex
import sys
from pathlib import Path

from .. import methods
from ..analysis.claims import claims_terminal
from ..analysis.outputs import judged_claims, paper_part, replicates_note, write_outputs
from ..analysis.report import terminal_table
from ..core import experiment_specs
from ..core.errors import ParameterError
from ..core.validation import choices, within
from ..files.interrupts import Interrupted, signals_ignored, sigterm_interrupts
from ..files.paths import OutputSet
from ..files.progress import format_duration
from ..reproduce.experiments import BOTTLE_NAMES, EXPERIMENTS, METHODS, ReproduceConfig, grasp_seeds, run_reproduce
from ..reproduce.grasping import check_run_grasp
from ..reproduce.replication import replicate_undecided
from ..reproduce.warmup import COLD_COMPILE_S, cold_kernels, estimate_wall_s
from ._lists import names_list
from .nir import add_graph_option, apply_graph_option

NAME = "reproduce"
HELP = "run the paper's drop and pour experiments on the simulated rig and write a report"
ORDER = 30


def _csv_list(kind: str, known, *, any_case: bool = False):
    """An argparse type: a comma-separated list of ``known()`` names (checked when parsed)."""
    def parse(text: str) -> tuple[str, ...]:

        try:
            return choices(kind, list(_names(text)), known(),
                           any_case=any_case)
        except ParameterError as err:
            raise argparse.ArgumentTypeError(str(err)) from None
    return parse


def _names(text: str) -> tuple[str, ...]:
    """A comma-separated list of names, checked later against the run's objects."""

    return names_list(text)


def own_objects(args: argparse.Namespace) -> dict:
    """The ReproduceConfig fields for ``--objects``, ``--drop``, ``--pour`` (empty: the paper's).

    Every name is checked here, before any work: an unknown one is one line naming the
    option, the file and the names it has.
    """
    from ..sim import load_objects  # deferred: heavy (numba kernels)

    objs = load_objects(args.objects) if args.objects is not None else None
    out: dict = {}
    for option, kind in (("--drop", "drops"), ("--pour", "pours")):
        name = getattr(args, option[2:])
        if name is None:
            continue
        table = getattr(objs, kind) if objs is not None else {}
        if name not in table:
            where = f"{args.objects} has {', '.join(table) or 'none'}" if objs else "give --objects FILE.toml"
            raise ParameterError(f"{option} {name}: no such {kind[:-1]} ({where})")
        out[f"{option[2:]}_object"] = table[name]
    if objs is not None and objs.bottles:
        from ..sim import BOTTLES  # deferred: heavy (numba kernels)
        from ..sim.uncertain import Plant  # deferred: heavy (numba kernels)

        out["plant"] = Plant(bottles={**BOTTLES, **objs.bottles})
    return out


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex reproduce``: every count and load parameter."""


    d = {f.name: f.default for f in dataclasses.fields(ReproduceConfig)}
    p.add_argument("--out", type=Path, default=Path("out/reproduce"),
                   help="output directory (default: ./out/reproduce)")
    p.add_argument("--trials", type=int, default=d["trials"],
                   help=f"trials per bottle, experiment and method (default {d['trials']})")
    p.add_argument("--bottles", type=_names, default=BOTTLE_NAMES,
                   help=f"comma-separated bottles: the paper's ({','.join(BOTTLE_NAMES)}, the default) "
                        "and those of --objects")
    p.add_argument("--objects", type=Path, default=None, metavar="FILE.toml",
                   help="your own bottles, surfaces, drops and pours (slipreflex.sim.load_objects); "
                        "then --bottles, --drop and --pour take their names")
    p.add_argument("--drop", default=None, metavar="NAME",
                   help="the sudden load: a drop of --objects (default: the paper's, 10 g from 2 cm)")
    p.add_argument("--pour", default=None, metavar="NAME",
                   help="the gradual load: a pour of --objects (default: the paper's, 500 ml at 1 L/min)")
    p.add_argument("--grasp-force", type=float, default=d["grasp_force_n"], metavar="N",
                   help=f"contact force at which the grasp stops closing, N (default: the paper's "
                        f"{d['grasp_force_n']:g})")
    p.add_argument("--methods", type=_csv_list("methods", methods.names, any_case=True), default=METHODS,
                   help=f"comma-separated methods, any case (registered: {','.join(methods.names())}; "
                        f"default: {','.join(METHODS)})")
    p.add_argument("--experiments", type=_csv_list("experiments", experiment_specs.names),
                   default=EXPERIMENTS,
                   help=f"comma-separated experiments (default: {','.join(EXPERIMENTS)})")
    p.add_argument("--seed", type=int, default=d["seed"], help=f"master seed (default {d['seed']})")
    from ..sim import PAPER_DROP, PAPER_POUR  # deferred: heavy (numba kernels)

    p.add_argument("--drop-mass", type=float, default=None, metavar="KG",
                   help=f"dropped mass in kg (default {PAPER_DROP.mass_kg:g}, the paper's)")
    p.add_argument("--drop-height", type=float, default=None, metavar="M",
                   help=f"drop height above the opening in m (default {PAPER_DROP.height_m:g}, the paper's)")
    p.add_argument("--pour-rate", type=float, default=None, metavar="L_MIN",
                   help=f"pour rate in L/min (default {PAPER_POUR.rate_l_min:g}, the paper's)")
    p.add_argument("--pour-volume", type=float, default=None, metavar="ML",
                   help=f"poured volume in ml (default {PAPER_POUR.volume_ml:g}, the paper's)")
    p.add_argument("--rest", type=float, default=d["rest_s"], metavar="S",
                   help=f"rest recorded before the perturbation, s (default {d['rest_s']:g})")
    p.add_argument("--after", type=float, default=d["after_s"], metavar="S",
                   help=f"recording after the drop / the pour's end, s (default {d['after_s']:g})")
    p.add_argument("--calibration", type=float, default=d["calibration_s"], metavar="S",
                   help="length of each at-rest calibration recording for the NMSD/SWT-SD "
                        f"thresholds, s (default {d['calibration_s']:g})")
    p.add_argument("--rest-k", type=float, default=d["rest_k"], metavar="K",
                   help="NMSD/SWT-SD thresholds: K sd of the statistic at rest, for sensitivity "
                        f"studies (default {d['rest_k']:g}, the same for every bottle)")
    p.add_argument("--swt-persist", type=int, default=d["swt_persist"], metavar="N",
                   help=f"SWT-SD persistence after the crossing, samples (default {d['swt_persist']})")
    p.add_argument("--independent-seeds", action="store_true",
                   help="each method gets its own trials (default: paired, every method faces the same trials)")
    p.add_argument("--no-variations", action="store_true",
                   help="every repeat is the nominal plant (default: placement, grip height and friction vary "
                        "from each trial's seed as real repeats do)")
    p.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--no-figures", action="store_true", help="skip the example-trial figures")
    add_graph_option(p)


def run(args: argparse.Namespace) -> int:
    """Check the outputs, estimate, run the grid, write the outputs, print a compact table.

    Ctrl-C or SIGTERM stops the run within about two seconds and writes what finished,
    marked partial; exit status 130.
    """
    check_limits(args, _LIMITED)
    apply_graph_option(args)
    config = ReproduceConfig(
        trials=args.trials, bottles=tuple(args.bottles), methods=tuple(args.methods),
        experiments=tuple(args.experiments), seed=args.seed, drop_mass_kg=args.drop_mass,
        drop_height_m=args.drop_height, pour_rate_l_min=args.pour_rate, pour_volume_ml=args.pour_volume,
        rest_s=args.rest, after_s=args.after, calibration_s=args.calibration, rest_k=args.rest_k,
        swt_persist=args.swt_persist, variations=not args.no_variations,
        independent_seeds=args.independent_seeds, grasp_force_n=args.grasp_force, **own_objects(args))
    outputs = OutputSet(args.out, NAME)             # before the first trial, not after the last
    outputs.claim()                                 # one command writing into --out at a time
    outputs.check(OUTPUT_NAMES)

    for b in config.bottles:                         # a grasp that cannot hold: one line, before the estimate
        check_run_grasp(config, b, grasp_seeds(config, b))
    jobs = int(args.jobs or os.cpu_count() or 1)
    cold = bool(cold_kernels())
    n, estimate = len(config.cells()), estimate_wall_s(config, jobs, cold=cold)
    print(f"{n} trials on {jobs} worker(s): about {format_duration(estimate)}"
          + (f" (first run: about {COLD_COMPILE_S:g} s of it compiles the kernels once; later runs "
             "load them from numba's cache)" if cold else "")
          + (" (a long run: fewer --trials, --bottles or --methods shorten it)" if estimate > LONG_RUN_S else ""),
          file=sys.stderr, flush=True)
    command = "slipreflex " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv[1:] else None
    try:
        with sigterm_interrupts():
            result = run_reproduce(config, jobs=jobs, progress=not args.no_progress,
                                   plots=not args.no_figures)
            replicate_undecided(result, jobs=jobs, progress=not args.no_progress, on_replicate=_announce)
    except Interrupted as stop:
        with signals_ignored():
            paths = _write(stop.partial, outputs, command)
        if paths is None:
            return 130
        what = stop.partial.partial_note or str(stop)
        print(f"slipreflex reproduce: {what}; wrote the finished trials to {outputs.folder}/ "
              + ("(results.csv, summary.csv, report.md marked partial)" if stop.partial.partial_note else
                 "(the whole grid; claims judged with the replicates that finished)"),
              file=sys.stderr)
        return 130
    return 0 if _write(result, outputs, command) is not None else 130


#: Everything ``reproduce`` writes into ``--out``; replaced as one set (slipreflex.files.paths.OutputSet).
OUTPUT_NAMES: tuple[str, ...] = ("results.csv", "summary.csv", "report.md", "figures")

#: Options bounded by slipreflex.core.validation.LIMITS: (option, its dest, the limit's name).
_LIMITED = (("--trials", "trials", "trials"), ("--rest", "rest", "rest_s"), ("--after", "after", "after_s"),
            ("--calibration", "calibration", "calibration_s"), ("--rest-k", "rest_k", "rest_k"),
            ("--swt-persist", "swt_persist", "swt_persist"), ("--grasp-force", "grasp_force", "grasp_force_n"),
            ("--jobs", "jobs", "jobs"))


def check_limits(args: argparse.Namespace, limited) -> None:
    """Every bounded option within its plausible range (before any work), named by its option."""

    for option, dest, limit in limited:
        value = getattr(args, dest, None)
        if value is not None:
            within(limit, value, option)


def _announce(k: int, seed: int, methods: tuple[str, ...]) -> None:
    print(f"replicate {k}: one run's trials leave a claim unresolved; the grid of {', '.join(methods)} again on "
          f"master seed {seed}", file=sys.stderr, flush=True)


#: A run estimated longer than this (s) says how to shorten it before it starts.
LONG_RUN_S: float = 600.0


def _write(result, outputs, command: str | None) -> dict | None:
    """Write the outputs into a fresh staging folder, then swap them in as one set.

    Ctrl-C while writing leaves the previous outputs untouched: one "interrupted" line,
    and None (the caller exits 130).
    """
    staged = outputs.stage()
    try:
        write_outputs(result, staged, command=command)
        outputs.commit(staged)
    except KeyboardInterrupt:
        outputs.abort(staged)
        print(f"slipreflex reproduce: interrupted while writing the outputs; {outputs.folder}/ holds the "
              "previous run's outputs, untouched", file=sys.stderr, flush=True)
        return None
    except BaseException:
        outputs.abort(staged)
        raise
    paths = {name: outputs.folder / name for name in ("results.csv", "summary.csv", "report.md")}
    paper, _, notice = paper_part(result)
    if notice:
        print(notice)
    print(terminal_table(result.summary))
    if not result.partial_note and paper.rows:
        if result.replicate_seeds:
            print(replicates_note(result))
        print(claims_terminal(judged_claims(result)))
    claims = "" if result.partial_note or not paper.rows else ", claims.csv"
    claims += ", replicates.csv" if result.replicates else ""
    print(f"{len(result.rows)} rows from {result.trials_finished} trials in {result.wall_s:.1f} s "
          f"({result.jobs} jobs); wrote {outputs.folder}/"
          "{results.csv, summary.csv, report.md" + claims + ("" if result.partial_note else ", figures/") + "}")
    return paths
