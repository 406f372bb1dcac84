"""The claims' verdicts on several master seeds: do the classes depend on the seed?

Usage::

    python scripts/claims_seeds.py                       # the default grid on seeds 20191215, 1, 2, 3, 4
    python scripts/claims_seeds.py --seeds 5,6,7 --trials 10 --jobs 2

Runs ``slipreflex reproduce``'s grid (in process, no figures) once per master seed, judges
the claims of each run (:func:`slipreflex.analysis.claims.judge_run`, the scan ensemble from
that seed) and prints one line per claim with its verdict on every seed, then whether the
classes agree on all of them. This is how docs/reproduce.md states that the default run's
classes do not depend on the master seed.
"""

from __future__ import annotations

import argparse
import time


def main() -> None:
    from slipreflex.analysis.claims import CLAIMS, judge_run
    from slipreflex.experiments import DEFAULT_SEED, ReproduceConfig, run_reproduce

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default=f"{DEFAULT_SEED},1,2,3,4")
    ap.add_argument("--trials", type=int, default=None, help="trials per cell (default: reproduce's)")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    table: dict[int, list[str]] = {c.number: [] for c in CLAIMS}
    for s in seeds:
        t0 = time.perf_counter()
        kw = {} if args.trials is None else {"trials": args.trials}
        res = run_reproduce(ReproduceConfig(seed=s, **kw), jobs=args.jobs, progress=False, plots=False)
        for r in judge_run(res.rows, seed=s):
            table[r.number].append(r.verdict)
        print(f"seed {s}: {len(res.rows)} rows in {time.perf_counter() - t0:.0f} s", flush=True)
    print("claim  " + "  ".join(f"{s:>16}" for s in seeds))
    for n, v in table.items():
        print(f"{n:>5}  " + "  ".join(f"{x:>16}" for x in v) + ("" if len(set(v)) == 1 else "   <- differs"))
    same = sum(len(set(v)) == 1 for v in table.values())
    print(f"{same} of {len(table)} claims have the same class on all {len(seeds)} seeds")


if __name__ == "__main__":
    main()
