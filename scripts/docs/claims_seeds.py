"""The claims' verdicts on several master seeds: do the classes depend on the seed?

Usage::

    python -m scripts.docs.claims_seeds                       # the default grid on seeds 20191215, 1, 2, 3, 4
    python -m scripts.docs.claims_seeds --seeds 5,6,7 --trials 10 --jobs 2
    python -m scripts.docs.claims_seeds --write               # and put the table into docs/reproduce.md

Runs ``slipreflex reproduce``'s grid (in process, no figures) once per master seed, with the
replicate grids ``reproduce`` adds where one run's trials leave a claim unresolved
(:func:`slipreflex.reproduce.replication.replicate_undecided`), judges the claims of each run
(:func:`slipreflex.analysis.outputs.judged_claims`, the scan ensemble from that seed) and
prints one row per claim with its verdict on every seed, then whether the classes agree on
all of them. This is how docs/reproduce.md states that the default run's classes do not
depend on the master seed.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "reproduce.md"
BEGIN, END = "<!-- claims seeds table begins -->", "<!-- claims seeds table ends -->"


def main(argv: list[str] | None = None) -> int:
    from slipreflex.analysis.claims import CLAIMS
    from slipreflex.analysis.outputs import judged_claims
    from slipreflex.reproduce.experiments import DEFAULT_SEED, ReproduceConfig, run_reproduce
    from slipreflex.reproduce.replication import replicate_undecided

    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--seeds", default=f"{DEFAULT_SEED},1,2,3,4")
    ap.add_argument("--trials", type=int, default=None, help="trials per cell (default: reproduce's)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--replicates", type=int, default=None,
                    help="most replicate grids per seed (default: reproduce's; 0: none)")
    ap.add_argument("--write", action="store_true", help=f"write the table between the markers of {DOCS.name}")
    args = ap.parse_args(argv)
    seeds = [int(s) for s in args.seeds.split(",")]
    table: dict[int, list[str]] = {c.number: [] for c in CLAIMS}
    cost: list[str] = []
    for s in seeds:
        t0 = time.perf_counter()
        kw = {} if args.trials is None else {"trials": args.trials}
        res = run_reproduce(ReproduceConfig(seed=s, **kw), jobs=args.jobs, progress=False, plots=False)
        more = {} if args.replicates is None else {"max_replicates": args.replicates}
        replicate_undecided(res, jobs=args.jobs, **more)
        for r in judged_claims(res):
            table[r.number].append(r.verdict)
        cost.append(f"{len(res.replicate_seeds)}")
        print(f"seed {s}: {len(res.rows)} rows and {len(res.replicate_seeds)} replicate grid(s) "
              f"({len(res.replicates)} rows) in {time.perf_counter() - t0:.0f} s", flush=True)
    same = sum(len(set(v)) == 1 for v in table.values())
    lines = ["| claim | " + " | ".join(f"seed {s}" for s in seeds) + " |",
             "|---|" + "---|" * len(seeds)]
    lines += [f"| {n} | " + " | ".join(v) + " |" + ("" if len(set(v)) == 1 else " (differs)")
              for n, v in table.items()]
    lines += ["| replicate grids | " + " | ".join(cost) + " |", "",
              f"{same} of {len(table)} claims have the same class on all {len(seeds)} seeds "
              f"(`python -m scripts.docs.claims_seeds --seeds {args.seeds}`"
              + (f" --trials {args.trials}" if args.trials is not None else "") + "). A master seed changes "
              "the trials' noise (texture draws, sensor noise, onsets), never the plant's physics: the same class "
              "on every seed says the class does not hang on one draw of the noise, not that it holds on other "
              "plants (docs/study.md does that)."]
    body = "\n".join(lines)
    print(body)
    if args.write:
        from scripts.docs.splice_report import write_marked

        return write_marked("claims_seeds", DOCS, BEGIN, END, body)
    return 0


if __name__ == "__main__":
    sys.exit(main())
