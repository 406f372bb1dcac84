"""``slipreflex claims``: the paper's claims judged on a results table.

Reads a ``results.csv`` (written by ``slipreflex reproduce``, by an older version of it,
or by your own analysis with the same columns: see
:data:`slipreflex.analysis.trial.RESULT_COLUMNS`), prints the claims table that
``reproduce`` prints (each of the paper's claims with its verdict class: holds,
fails-definition, fails-paper, fails-plant, unresolved or not-decidable, its reason and
the interval behind it) and writes it as ``claims.csv`` beside the results (or to
``--out``; new files: ``claims-2.csv`` where the name, or its parts file's, is taken).
A ``replicates.csv`` beside the results (the replicate grids ``reproduce``
ran where one run's trials left a claim unresolved) is pooled with them, so the
table is the one ``reproduce`` wrote; every part of every claim goes to ``claim_parts.csv``
beside the claims table. Claim 2 is judged on the characterization scan of the simulated
slip sensor over texture seeds from ``--seed``. Claim 1 (the scan's levels) is an input the
simulator was calibrated to, so it is not decidable on a simulation; ``--scan scan.csv``
judges it on a real or replayed scan (columns ``t``, ``position_mm``, ``volts``, as
``slipreflex scan`` writes them, over the paper's layout). ``--explain N`` prints claim N
whole: the paper's sentence, the reading, every part and why.

Examples (shell)::

    slipreflex claims out/reproduce/results.csv
    slipreflex claims out/reproduce/results.csv --scan bench/scan.csv --explain 1
    slipreflex claims old-run/results.csv --seed 20191215 --out old-run/claims-now.csv
"""

from __future__ import annotations

import argparse
import csv
import itertools
import os
from pathlib import Path

from ..analysis.claims import (
    CLAIMS,
    claims_terminal,
    explain,
    judge_run,
    measured_scan,
    write_claims_csv,
    write_parts_csv,
)
from ..analysis.outputs import scored
from ..analysis.trial import TrialRow
from ..core.errors import ParameterError
from ..files.paths import read_text
from ..reproduce.experiments import ReproduceConfig

NAME = "claims"
HELP = "judge the paper's claims on a results.csv (yours, or an earlier run's)"
ORDER = 47

#: Columns the claims read; a table without them cannot be judged.
NEEDED = ("experiment", "bottle", "method", "trial", "event", "n_events", "response_ms", "total_ms", "success")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Command-line options of ``slipreflex claims``."""

    parser.add_argument("results", type=Path, help="a results.csv (one row per trial and slip event)")
    parser.add_argument("--seed", type=int, default=ReproduceConfig().seed,
                        help="first texture seed of the slip-sensor scans behind claims 1-2 (default: reproduce's "
                             "master seed)")
    parser.add_argument("--no-replicates", action="store_true",
                        help="judge RESULTS.csv alone, without a replicates.csv beside it")
    parser.add_argument("--scan", type=Path, default=None, metavar="SCAN.csv",
                        help="a real or replayed characterization scan (t, position_mm, volts): judges claim 1")
    parser.add_argument("--explain", type=int, default=None, metavar="N",
                        help="also print claim N whole: the paper's sentence, the reading, every part")
    parser.add_argument("--out", type=Path, default=None, metavar="CLAIMS.csv",
                        help="where to write the claims table (default: claims.csv beside RESULTS.csv)")


def read_rows(path: Path) -> list:
    """The rows of a results table as :class:`~slipreflex.analysis.trial.TrialRow` s.

    Raises :class:`~slipreflex.core.errors.ParameterError` naming the file (and line) when it
    is missing, lacks a column the claims read, or holds a value that does not parse.
    """

    if not path.exists():
        raise ParameterError(f"{path}: no such results file")
    lines = [line for line in read_text(path, "").splitlines(keepends=True) if not line.startswith("#")]
    reader = csv.DictReader(lines)
    rows = []
    try:
        missing = [c for c in NEEDED if c not in (reader.fieldnames or ())]
        if missing:
            raise ParameterError(f"{path}: not a results table: no column {', '.join(missing)}")
        for i, d in enumerate(reader, start=2):
            try:
                rows.append(TrialRow.from_dict(d))
            except (ValueError, TypeError) as e:
                raise ParameterError(f"{path}, data line {i}: {e}") from None
    except csv.Error as e:
        raise ParameterError(f"{path}: not a results table ({e})") from None
    return rows


def run(args: argparse.Namespace) -> int:
    """Print the claims table of ``args.results`` and write it as claims.csv."""

    out = args.out if args.out is not None else args.results.parent / "claims.csv"
    if out.resolve() == args.results.resolve():
        raise ParameterError(f"--out {out}: would overwrite the results table it judges")
    if not out.parent.is_dir():
        raise ParameterError(f"--out {out}: no such directory {out.parent}")
    out, parts_path = _free_pair(out)
    numbers = [c.number for c in CLAIMS]
    if args.explain is not None and args.explain not in numbers:
        raise ParameterError(f"--explain {args.explain}: no such claim (1-{numbers[-1]})")
    try:
        measured = None if args.scan is None else measured_scan(args.scan)
    except ValueError as err:
        raise ParameterError(f"--scan {err}") from None
    rows = read_rows(args.results)
    print(f"{len(rows)} rows of {args.results}")
    replicates = args.results.parent / "replicates.csv"
    if replicates.is_file() and not args.no_replicates:
        more = read_rows(replicates)
        print(f"pooled with {len(more)} rows of {replicates} (replicate grids; --no-replicates: without)")
        rows += more
    rows = scored(rows)
    results = judge_run(rows, seed=args.seed, measured=measured)
    print(claims_terminal(results))
    if args.explain is not None:
        print(explain(results[numbers.index(args.explain)]))
    write_claims_csv(out, results)
    parts = write_parts_csv(parts_path, results)
    print(f"wrote {out} and {parts}")
    return 0


def _parts_name(out: Path) -> Path:
    return out.with_name(out.stem.replace("claims", "claim_parts") if "claims" in out.stem
                         else out.stem + "_parts").with_suffix(".csv")


def _free_pair(out: Path) -> tuple[Path, Path]:
    """``out`` and its parts file, or ``NAME-2``... where either is taken: outputs are new files,
    never written over (nor through a symlink), chosen before any work."""
    for k in itertools.count(1):
        name = out if k == 1 else out.with_name(f"{out.stem}-{k}{out.suffix}")
        pair = (name, _parts_name(name))
        if not any(os.path.lexists(p) for p in pair):
            if k > 1:
                print(f"{out.name} or its parts file exists: writing {pair[0].name} and {pair[1].name}")
            return pair
    raise AssertionError("unreachable")  # pragma: no cover
