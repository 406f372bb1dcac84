"""One uncertain plant constant changed, everything else nominal: what it does to a reproduction.

Usage::

    python -m scripts.research.ablation spot_travel_per_unit 0 --experiments drop --methods dath,nmsd --trials 10
    python -m scripts.research.ablation tilt --experiments drop      # a physics term switched off


Runs the reproduction grid (same seeds) on the nominal plant of :mod:`slipreflex.sim.uncertain`
(``plant_from_values({})``: the built-in plant, bit for bit) and on the plant with NAME set to
VALUE (or, for the name of a physics term or group of :mod:`slipreflex.sim.terms` and no
VALUE, with its constants at their "absent" values), and prints each cell's mean response and
total controller time and its success rate side by side. The changed plant's pads are
calibrated again to the nominal plant's observed open-loop first slip
(:meth:`slipreflex.sim.uncertain.Plant.calibrated`, a minute or two), so a constant that
moves the grasp's capacity does not silently move the first slip too; ``--no-recalibrate``
keeps the nominal pad friction. The constants' names: ``python -c "from
slipreflex.sim.uncertain import UNCERTAIN; print(list(UNCERTAIN))"``. This is how the closing
notes say which physics decided a claim's change.
"""

from __future__ import annotations

import argparse


def _changed(ap: argparse.ArgumentParser, name: str, value: float | None) -> dict[str, float]:
    """The constants to change: NAME=VALUE, or a physics term's absent values; a parser error on a bad name."""
    from slipreflex.sim.terms import SWITCHES, absent_values
    from slipreflex.sim.uncertain import UNCERTAIN

    if value is None:
        if name not in SWITCHES:
            ap.error(f"name: {name!r} is not a physics term (known: {', '.join(SWITCHES)}); give a constant "
                     "and a value")
        return absent_values(name)
    if name not in UNCERTAIN:
        ap.error(f"name: unknown uncertain constant {name!r} (known: {', '.join(UNCERTAIN)})")
    return {name: value}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("name", help="an uncertain constant, or a physics term (slipreflex.sim.terms) without a value")
    ap.add_argument("value", type=float, nargs="?", default=None)
    ap.add_argument("--experiments", default="drop,pour")
    ap.add_argument("--methods", default="dath")
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--no-recalibrate", action="store_true",
                    help="keep the nominal pad friction on the changed plant (default: calibrate it again)")
    args = ap.parse_args()
    changed = _changed(ap, args.name, args.value)

    from slipreflex.reproduce.experiments import ReproduceConfig, run_reproduce
    from slipreflex.sim.uncertain import plant_from_values

    runs = {}
    changed_label = f"{args.name}={args.value:g}" if args.value is not None else f"without {args.name}"
    for label, values in (("nominal", {}), (changed_label, changed)):
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
