"""Study plants with both kernels: how often a plant's claim class or its slips differ from the fixed step.

Runs ``--plants`` plants of the ``slipreflex study --plants 1000`` design (every ``1000 / N``-th) once with
the fixed-step reference and once with the adaptive kernel, each with its calibration, trials and
judging, and prints per plant the claims whose class differs, then the totals: plants accepted by
both, claim classes that differ, plants accepted by one kernel only, and the trial rows whose success
or true slip count differs. A study judges each plant on one trial per cell, so a trial whose
detector grazes its threshold flips a plant's class under any perturbation, a step's as much as a
seed's; the study's fractions, over hundreds of plants, are what it reports. docs/simulator.md
("Time step") quotes the output.

Run: ``python -m scripts.research.stepping_plants --plants 25`` (about 6 CPU-minutes; the fixed step's
plants cost most of it).

Examples
--------
>>> differing(["holds", "unresolved"], ["holds", "fails-plant"])
[(2, 'unresolved', 'fails-plant')]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys


def differing(ref: list[str], new: list[str]) -> list[tuple[int, str, str]]:
    """``(claim, reference class, adaptive class)`` of every claim whose class differs."""
    return [(i + 1, a, b) for i, (a, b) in enumerate(zip(ref, new)) if a != b]


def _plant(index: int, values, config, kind: str):
    from slipreflex.study.runner import run_plant

    o = run_plant(index, values, dataclasses.replace(config, stepping=kind))
    rows = {(r.get("method"), r.get("experiment"), r.get("bottle"), r.get("event")):
            (r.get("success"), r.get("n_true_slips")) for r in o.rows}
    return [c[1] for c in o.claims], rows, bool((o.calibration or {}).get("rejected"))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plants", type=int, default=25, help="plants to compare (default 25)")
    args = ap.parse_args(argv)
    if not 1 <= args.plants <= 1000:
        print(f"stepping_plants: --plants must be in 1..1000, got {args.plants}", file=sys.stderr)
        return 2
    from slipreflex.study.runner import StudyConfig

    config = StudyConfig(plants=1000)
    values = config.plant_values()
    both = flips = one_only = rows = rows_differ = 0
    for index in range(0, 1000, 1000 // args.plants)[:args.plants]:
        (cf, rf, xf), (ca, ra, xa) = (_plant(index, values[index], config, k) for k in ("fixed", "adaptive"))
        if xf != xa:
            one_only += 1
            print(f"plant {index}: accepted by the {'adaptive' if xf else 'fixed-step'} run only")
            continue
        if xf:
            continue
        both += 1
        d = differing(cf, ca)
        flips += len(d)
        if d:
            print(f"plant {index}: " + ", ".join(f"claim {n} {a} -> {b}" for n, a, b in d))
        rows += len(rf)
        rows_differ += sum(1 for k, v in rf.items() if ra.get(k) != v) + len(ra.keys() - rf.keys())
    n_claims = len(cf)
    print(f"plants accepted by both {both}; claim classes that differ {flips} of {both * n_claims}; plants "
          f"accepted by one kernel only {one_only}; trial rows whose success or true slips differ "
          f"{rows_differ} of {rows}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
