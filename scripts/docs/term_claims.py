"""Which physics term moved which claim: the default reproduction with each term switched off in turn.

Runs the default reproduction grid (same master seed and trials per cell as ``slipreflex reproduce``) on the
nominal plant and on the plant with one term at its "absent" value (:mod:`slipreflex.sim.terms`), its pads
calibrated again to the observed open-loop first slip (:meth:`slipreflex.sim.uncertain.Plant.calibrated`, as the
ablation does: a term that moves the grasp's capacity must not move the first slip), judges the paper's claims on
each (:func:`slipreflex.analysis.claims.judge_run`) and prints the verdict classes side by side, with the numbers
of the claims whose verdict or numbers a term changes.

Run: ``python -m scripts.docs.term_claims [--jobs 2] [--terms grip,roll,...]``.

``python -m scripts.docs.term_claims --study DIR`` instead reads a finished study's ``plants.csv`` and prints, for
claims 4, 5 and 7, on how many plants each was decidable (a verdict other than not-decidable) and held, and the
constants whose values go with the claim being decidable (Spearman's rho; Benjamini-Hochberg q < 0.05 over the
constants that can reach the claim).
"""

from __future__ import annotations

import argparse
from typing import Any

from slipreflex.sim.terms import SWITCHES, VERDICT_SWITCHES, absent_values


def decidable(folder: str, claims: tuple[int, ...] = (4, 5, 7)) -> list[str]:
    """Per claim: plants testable and holding, and the constants that go with it being testable."""
    import csv
    from pathlib import Path

    import numpy as np
    from scipy.stats import false_discovery_control, spearmanr

    from slipreflex.analysis.claims import HOLDS, NOT_DECIDABLE
    from slipreflex.sim.uncertain import UNCERTAIN
    from slipreflex.study.analyse import FDR, reaches

    out: list[str] = []
    rows = [r for r in csv.DictReader((Path(folder) / "plants.csv").open())
            if not r.get("error") and r.get("rejected", "") in ("", "False", "0")]
    for n in claims:
        v = [r.get(f"claim_{n}", "") for r in rows]
        testable = np.array([x not in ("", NOT_DECIDABLE) for x in v], dtype=float)
        holds = sum(x == HOLDS for x in v)
        kinds = ", ".join(f"{k} {v.count(k)}" for k in sorted(set(v)))
        out.append(f"claim {n}: decidable on {int(testable.sum())} of {len(rows)} plants, holds on {holds} ({kinds})")
        print(out[-1])
        if 0 < testable.sum() < len(rows):
            tests = []
            for name in UNCERTAIN:
                if name not in rows[0] or not reaches(UNCERTAIN[name], n):
                    continue
                x = np.array([float(r[name]) for r in rows])
                if np.ptp(x) == 0:
                    continue
                res: Any = spearmanr(x, testable)
                tests.append((name, float(res.statistic), float(res.pvalue)))
            q = false_discovery_control([p for _, _, p in tests]) if tests else []
            found = [(abs(rho), name, rho, qv) for (name, rho, _), qv in zip(tests, q) if qv < FDR]
            for _, name, rho, qv in sorted(found, reverse=True):
                out.append(f"  testable with {name}: rho {rho:+.2f} (Benjamini-Hochberg q {qv:.2g})")
                print(out[-1])
    return out


def _write(marker: str, lines: list[str]) -> int:
    from scripts.docs.splice_report import write_section

    return write_section("term_claims", "docs/study.md", marker, "\n".join("    " + x for x in lines))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--terms", default=",".join(VERDICT_SWITCHES),
                    help=f"comma-separated, of: {', '.join(SWITCHES)} (slipreflex.sim.terms; spot and gap: the "
                         "two halves of roll)")
    ap.add_argument("--study", default=None, help="a study's output folder: where claims 4, 5, 7 become testable")
    ap.add_argument("--write", action="store_true", help="put the table between docs/study.md's markers")
    args = ap.parse_args()
    if args.study:
        found = decidable(args.study)
        return _write("study decidable", found) if args.write else 0
    unknown = [x for x in args.terms.split(",") if x not in SWITCHES]
    if unknown:
        ap.error(f"--terms: unknown term {unknown[0]!r} (known: {', '.join(SWITCHES)})")

    from slipreflex.analysis.claims import judge_run
    from slipreflex.reproduce.experiments import ReproduceConfig, run_reproduce
    from slipreflex.sim.uncertain import plant_from_values

    runs = {}
    for label in ("all", *args.terms.split(",")):
        values = {} if label == "all" else absent_values(label)
        plant = plant_from_values(values)
        if values:
            plant = plant.calibrated()
            print(f"without {label}: pads recalibrated, mu_s " + ", ".join(f"{b} {x.mu_s:.4f}"
                                                                              for b, x in plant.bottles.items()))
        cfg = ReproduceConfig(plant=plant)
        rows = run_reproduce(cfg, jobs=args.jobs, progress=False, plots=False).rows
        runs[label] = {c.number: c for c in judge_run(rows, plant=cfg.plant)}
        print(f"ran: {'every term on' if label == 'all' else 'without ' + label}", flush=True)
    labels = list(runs)
    table = ["claim  " + "  ".join(f"{('-' + x) if x != 'all' else 'all':>12s}" for x in labels)]
    table += [f"{n:5d}  " + "  ".join(f"{runs[x][n].verdict[:12]:>12s}" for x in labels) for n in sorted(runs["all"])]
    print("\n".join(table))
    for n in sorted(runs["all"]):
        nums = {x: runs[x][n].numbers for x in labels}
        if len(set(nums.values())) > 1:
            print(f"\nclaim {n}:")
            for x in labels:
                print(f"  {('without ' + x) if x != 'all' else 'all terms':18s} {runs[x][n].verdict}: {nums[x]}")
    return _write("term claims table", table) if args.write else 0


if __name__ == "__main__":
    raise SystemExit(main())
