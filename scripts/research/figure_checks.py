"""DATH trials on the nominal plant beside the paper's Fig. 10 (drop) and Fig. 15 (pour).

Usage::

    python -m scripts.research.figure_checks [--trials 4] [--bottles DK,TR]

For each bottle, experiment and trial seed of the default run (the nominal plant: no
trial-to-trial variation), prints every slip the simulator had (its onset, the water in
the bottle then, how far it slid) and every burst of the DATH controller's rises (when,
the water then, units added). docs/simulator.md ("The plant against the paper's
figures") quotes these numbers; tests/sim/test_sim_figures.py checks what they must show.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np


def dath_trial(experiment: str, bottle: str, trial: int):
    """One DATH trial on the nominal plant: (trace, grasp position p0, perturbation time)."""
    from slipreflex import methods
    from slipreflex.core import experiment_specs
    from slipreflex.core.hardware import SLIP_FINGER
    from slipreflex.reproduce.experiments import ReproduceConfig, method_context, trial_seed
    from slipreflex.sim import run_closed_loop
    from slipreflex.sim.variations import VariationSpread, grasped_rig

    cfg = ReproduceConfig(trials=1)
    rig, grasp = grasped_rig(bottle, trial_seed(cfg.seed, experiment, bottle, trial), cfg.grasp_force_n,
                             spread=VariationSpread.none())
    p0 = float(round(grasp.positions[SLIP_FINGER]))
    spec = methods.get(methods.DATH)
    reflex = spec.build(p0, dataclasses.replace(method_context(cfg, {}), method=spec.name))
    t_pert = rig.t + cfg.rest_s
    rig.perturb(experiment_specs.get(experiment).perturbation(cfg), at=t_pert)
    return run_closed_loop(rig, reflex, cfg.duration(experiment)), p0, t_pert


def bursts(cmd_t, cmd_v, p0: float, gap_s: float = 0.1) -> list[tuple[float, float, float]]:
    """The command's rises grouped into bursts: (start s, end s, units added); a pause > gap_s ends one."""
    t = np.asarray(cmd_t, dtype=float)
    rise = np.diff(np.concatenate(([p0], np.asarray(cmd_v, dtype=float))))
    out: list[list[float]] = []
    for i in np.flatnonzero(rise > 0):
        if out and t[i] - out[-1][1] <= gap_s:
            out[-1][1] = t[i]
            out[-1][2] += rise[i]
        else:
            out.append([t[i], t[i], rise[i]])
    return [(a, b, c) for a, b, c in out]


def _water(trace, experiment: str, t: float) -> str:
    return f"{np.interp(t, trace.t, trace.water_ml):.0f} ml" if experiment == "pour" else "-"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=4)
    ap.add_argument("--bottles", default="DK,TR")
    args = ap.parse_args()
    for bottle in args.bottles.split(","):
        for experiment in ("drop", "pour"):
            for trial in range(args.trials):
                tr, p0, t0 = dath_trial(experiment, bottle, trial)
                slips = "; ".join(f"{e.onset - t0:.2f} s ({_water(tr, experiment, e.onset)}) "
                                  f"{1e3 * e.distance:.1f} mm" for e in tr.slip_events) or "none"
                rises = "; ".join(f"{a - t0:.2f}-{b - t0:.2f} s ({_water(tr, experiment, a)}) +{n:.0f}"
                                  for a, b, n in bursts(tr.cmd_t, tr.cmd_value, p0)) or "none"
                print(f"{bottle} {experiment} trial {trial}: fallen {tr.fallen}; slips: {slips}; DATH rises: {rises}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
