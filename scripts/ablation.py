"""One uncertain plant constant changed, everything else nominal: what it does to a reproduction.

Usage::

    python scripts/ablation.py spot_travel_per_unit 0 --experiments drop --methods dath,nmsd --trials 10

Runs the reproduction grid (same seeds) on the nominal plant of :mod:`slipreflex.sim.uncertain`
(``plant_from_values({})``: the built-in plant, bit for bit) and on the plant with NAME set to
VALUE, and prints each cell's mean response and total controller time and its success rate
side by side. The changed plant's pads are calibrated again to the nominal plant's observed
open-loop first slip (:meth:`slipreflex.sim.uncertain.Plant.calibrated`, a minute or two), so a
constant that moves the grasp's capacity does not silently move the first slip too;
``--no-recalibrate`` keeps the nominal pad friction. The constants' names: ``python -c "from
slipreflex.sim.uncertain import UNCERTAIN; print(list(UNCERTAIN))"``. This is how the closing
notes say which physics decided a claim's change.
"""

from __future__ import annotations

import argparse


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("name")
    ap.add_argument("value", type=float)
    ap.add_argument("--experiments", default="drop,pour")
    ap.add_argument("--methods", default="dath")
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--no-recalibrate", action="store_true",
                    help="keep the nominal pad friction on the changed plant (default: calibrate it again)")
    args = ap.parse_args()

    from slipreflex.experiments import ReproduceConfig, run_reproduce
    from slipreflex.sim.uncertain import plant_from_values

    runs = {}
    for label, values in (("nominal", {}), (f"{args.name}={args.value:g}", {args.name: args.value})):
        plant = plant_from_values(values)
        if values and not args.no_recalibrate:
            plant = plant.calibrated()
            print(f"{label}: pads recalibrated, mu_s " + ", ".join(f"{b} {x.mu_s:.4f}"
                                                                   for b, x in plant.bottles.items()))
        cfg = ReproduceConfig(trials=args.trials, experiments=tuple(args.experiments.split(",")),
                              methods=tuple(args.methods.split(",")), plant=plant)
        runs[label] = {(s["experiment"], s["bottle"], s["method"]): s
                       for s in run_reproduce(cfg, jobs=args.jobs, progress=False, plots=False).summary}
    (a, ra), (b, rb) = runs.items()
    print(f"{'cell':24s} {'response ms':>24s} {'total ms':>22s} {'success':>14s}")
    print(f"{'':24s} {a:>11s} {b[:12]:>12s} {a:>10s} {b[:11]:>11s}")
    for key in ra:
        x, y = ra[key], rb.get(key, {})
        fmt = lambda d, k: f"{float(d.get(k, 'nan')):.0f}"           # noqa: E731
        print(f"{' '.join(key):24s} {fmt(x, 'response_mean_ms'):>11s} {fmt(y, 'response_mean_ms'):>12s} "
              f"{fmt(x, 'total_mean_ms'):>10s} {fmt(y, 'total_mean_ms'):>11s} "
              f"{100 * float(x['event_success_rate']):5.0f}% {100 * float(y.get('event_success_rate', 'nan')):5.0f}%")


if __name__ == "__main__":
    main()
