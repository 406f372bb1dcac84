"""How much NMSD's and SWT-SD's results hang on the choices the paper leaves open.

Usage::

    python -m scripts.docs.threshold_sensitivity [--trials 10] [--jobs 2]

Re-runs the default grid for the two tactile methods (same seeds) with the threshold's
k (sd of the method's statistic at rest) and SWT-SD's persistence changed, one at a
time, and prints docs/reproduce.md's sensitivity table (markdown): per setting and
method, drop slips answered, median drop response, pour success, median pour response,
median closing time, and pour slips the accelerometer found.
"""

from __future__ import annotations

import argparse
import math
import statistics

from slipreflex import methods
from slipreflex.methods.baselines.swt import SWT_PERSIST, SWT_PERSISTENCE, SWT_PERSISTENCE_DEFAULT

#: The default, the threshold's k either side, and every other reading of SWT-SD's persistence rule.
SETTINGS = ((f"default (k = 5, {SWT_PERSISTENCE_DEFAULT}: persist {SWT_PERSIST})", {}),
            ("k = 3", {"rest_k": 3.0}), ("k = 8", {"rest_k": 8.0}),
            *((f"{name}: persist {n}", {"swt_persist": n}) for name, n in SWT_PERSISTENCE.items()
              if name != SWT_PERSISTENCE_DEFAULT))


def _median(values) -> str:
    vals = [v for v in values if not math.isnan(v)]
    return f"{statistics.median(vals):.0f}" if vals else "-"


def row(label: str, method: str, rows) -> str:
    """One line of the table from a run's rows of one method."""
    drop = [r for r in rows if r.experiment == "drop"]
    pour = [r for r in rows if r.experiment == "pour"]
    pour_trials = {(r.bottle, r.trial): r for r in pour if r.event == 0}
    answered = sum(1 for r in drop if not math.isnan(r.response_ms))
    found = sum(1 for r in pour_trials.values() if r.n_events > 0)
    success = sum(1 for r in pour_trials.values() if r.success)
    return (f"| {label} | {methods.label(method)} | {answered}/{len(drop)} | {_median(r.response_ms for r in drop)} | "
            f"{success}/{len(pour_trials)} | {_median(r.response_ms for r in pour)} | "
            f"{_median(r.total_ms for r in rows)} | {found}/{len(pour_trials)} |")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--write", action="store_true", help="put the table between docs/reproduce.md's markers")
    args = ap.parse_args()
    from slipreflex.reproduce.experiments import ReproduceConfig, run_reproduce

    lines = ["| setting | method | drop: slips answered | drop: median response ms | pour: success | "
             "pour: median response ms | median total (closing) ms | slips the accelerometer found in pours |",
             "|---|---|---|---|---|---|---|---|"]
    print("\n".join(lines))
    for label, change in SETTINGS:
        ms = (methods.SWT,) if "swt_persist" in change else (methods.NMSD, methods.SWT)
        res = run_reproduce(ReproduceConfig(trials=args.trials, methods=ms, **change), jobs=args.jobs,
                            progress=False, plots=False)
        for m in ms:
            lines.append(row(label, m, [r for r in res.rows if r.method == m]))
            print(lines[-1], flush=True)
    if not args.write:
        return 0
    from scripts.docs.splice_report import write_section

    return write_section("threshold_sensitivity", "docs/reproduce.md", "threshold sensitivity table",
                         "\n".join(lines))


if __name__ == "__main__":
    raise SystemExit(main())
