"""Compare two reproductions row by row: the fixed-step reference against the adaptive kernel.

Reads the ``results.csv`` and ``claims.csv`` of two ``slipreflex reproduce`` output folders and prints
whether every claim is in the same class, whether both have the same slips event by event, the largest
difference of each timed or measured field, and the trials outside the declared tolerance of a row
(``ROW_TOLERANCE``: the one ``tests/sim/test_sim_stepping.py`` holds every default trial to).
docs/simulator.md ("Time step") quotes its output.

Run::

    SLIPREFLEX_STEPPING=fixed slipreflex reproduce --jobs 2 --no-figures --out out/fixed
    slipreflex reproduce --jobs 2 --no-figures --out out/adaptive
    python -m scripts.research.stepping_rows out/fixed out/adaptive

Examples
--------
>>> compare([{"experiment": "drop", "bottle": "TR", "method": "dath", "trial": "0", "event": "0",
...           "onset_s": "1.0", "success": "1"}],
...         [{"experiment": "drop", "bottle": "TR", "method": "dath", "trial": "0", "event": "0",
...           "onset_s": "1.003", "success": "1"}])["outside"]
[]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from slipreflex.analysis.report import read_csv

#: The declared tolerance of a trial's row (docs/simulator.md, "Time step"): times in s or ms, distances in mm.
ROW_TOLERANCE = {"onset_s": 2e-3, "true_onset_s": 2e-3, "response_ms": 3.0, "total_ms": 3.0, "fell_out_s": 2e-3,
                 "true_slip_mm": 0.05, "true_slip_ms": 1.0}
#: Fields that must be equal event by event.
SAME = ("n_events", "success", "fell_out", "n_true_slips")
KEY = ("experiment", "bottle", "method", "trial", "event")


def _number(v: str | None) -> float:
    try:
        return float(v) if v not in (None, "") else math.nan
    except ValueError:
        return math.nan


def compare(ref: list[dict], new: list[dict]) -> dict:
    """Row-by-row differences of two reproductions' results (rows as read from results.csv)."""
    a = {tuple(r[k] for k in KEY): r for r in ref}
    b = {tuple(r[k] for k in KEY): r for r in new}
    largest: dict[str, tuple[float, tuple]] = {}
    outside: list[tuple[tuple, str, str, str]] = []
    for key in sorted(a.keys() & b.keys()):
        r, n = a[key], b[key]
        for f in SAME:
            if f in r and r.get(f) != n.get(f):
                outside.append((key, f, r.get(f, ""), n.get(f, "")))
        for f, tol in ROW_TOLERANCE.items():
            x, y = _number(r.get(f)), _number(n.get(f))
            if math.isnan(x) and math.isnan(y):
                continue
            d = abs(x - y) if not (math.isnan(x) or math.isnan(y)) else math.inf
            if d > largest.get(f, (-1.0, ()))[0]:
                largest[f] = (d, key)
            if d > tol:
                outside.append((key, f, r.get(f, ""), n.get(f, "")))
    return {"rows": (len(a), len(b)), "only_ref": sorted(a.keys() - b.keys()), "only_new": sorted(b.keys() - a.keys()),
            "largest": largest, "outside": outside}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("reference", type=Path, help="the fixed-step reproduction's output folder")
    ap.add_argument("adaptive", type=Path, help="the adaptive reproduction's output folder")
    args = ap.parse_args(argv)
    for d in (args.reference, args.adaptive):
        for name in ("results.csv", "claims.csv"):
            if not (d / name).is_file():
                print(f"stepping_rows: {d / name}: no such file (run slipreflex reproduce first)", file=sys.stderr)
                return 2
    ref, new = (read_csv(d / "results.csv") for d in (args.reference, args.adaptive))
    out = compare(ref, new)
    ca, cb = ([(c["claim"], c["verdict"]) for c in read_csv(d / "claims.csv")]
              for d in (args.reference, args.adaptive))
    trials = len({tuple(r[k] for k in KEY[:4]) for r in ref})
    print(f"trials {trials}, rows {out['rows'][0]} (reference) / {out['rows'][1]} (adaptive); "
          f"every claim in the same class: {ca == cb}")
    if ca != cb:
        print("  classes differ: " + ", ".join(f"claim {x[0]} {x[1]} -> {y[1]}" for x, y in zip(ca, cb) if x != y))
    print(f"rows only in the reference: {len(out['only_ref'])}; only in the adaptive run: {len(out['only_new'])}")
    for f, (d, key) in sorted(out["largest"].items()):
        print(f"  largest |difference| of {f}: {d:.4g} (tolerance {ROW_TOLERANCE[f]:g}) at {'/'.join(key)}")
    print(f"row fields outside the tolerance: {len(out['outside'])}")
    for key, f, x, y in out["outside"]:
        print(f"  {'/'.join(key)} {f}: {x or 'none'} -> {y or 'none'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
