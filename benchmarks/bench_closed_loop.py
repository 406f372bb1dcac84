"""Speed of one closed-loop trial: simulated seconds per second of one core, compiled loop and Python loop.

For each method (default: every registered method) and each experiment (the
default reproduction's drop and pour, bottle TR), the trial is set up exactly as
``reproduce`` sets it up (rig, grasp, calibrated thresholds, perturbation) and only
``run_closed_loop`` is timed: with the compiled loop (``compiled=True``, what
``reproduce`` runs) and with the Python loop (``compiled=False``). Each figure is
the median over ``--repeat`` runs of simulated seconds per CPU second of this
process (the steadier measure of one core on a shared machine; wall-clock figures
beside it). Then the loop's own cost: the same held grasp through the paper's pour
advanced open loop (physics and sensors alone, also with a 260 Hz and a 380 Hz
tactile stream, the tactile methods' floor) and closed by a compiled reflex that
never commands (the compiled loop's overhead is the difference).

Run: ``python benchmarks/bench_closed_loop.py`` (``--methods dath,nmsd``,
``--repeat 5``). Issue 10's target: 1500 simulated s per CPU s or more for every
method (at least 1000). The README quotes its output; tests never assert on time.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import numpy as np
from numba import njit

from slipreflex import hardware as hw
from slipreflex import methods
from slipreflex.experiments import ReproduceConfig, calibrate, method_context, trial_seed
from slipreflex.sim import PAPER_POUR, Rig, run_closed_loop, simulate_open_loop
from slipreflex.sim.variations import VariationSpread, trial_rig


def trial(config: ReproduceConfig, thresholds: dict, method: str, experiment: str, compiled: bool,
          bottle: str = "TR") -> tuple[float, float, float]:
    """(simulated s, wall s, CPU s) of the closed loop of one trial, set up as ``run_trial`` does."""
    seed = trial_seed(config.seed, experiment, bottle, 0)
    rig = trial_rig(bottle, seed, spread=None if config.variations else VariationSpread.none())
    g = rig.grasp(config.grasp_force_n)
    spec = methods.get(method)
    reflex = spec.build(float(round(g.positions[hw.SLIP_FINGER])),
                        dataclasses.replace(method_context(config, thresholds), method=spec.name))
    rig.perturb(config.pour if experiment == "pour" else config.drop, at=rig.t + config.rest_s)
    duration = config.duration(experiment)
    w0, c0 = time.perf_counter(), time.process_time()
    run_closed_loop(rig, reflex, duration, compiled=compiled)
    return duration, time.perf_counter() - w0, time.process_time() - c0


@njit(cache=True)
def _never(S, P, raw, position):
    S[0] += 1.0
    return np.nan


class Never:
    """A compiled slip reflex that never commands: the loop's cost without a reflex's."""

    name, input_kind, fs = "never", "slip", hw.DAQ_FS

    def __init__(self) -> None:
        self.S, self.P = np.zeros(1), np.zeros(1)

    def compiled(self):
        return _never, self.S, self.P

    def step(self, sample, position=None):
        return None

    def reset(self) -> None:
        self.S[:] = 0.0


def held(closed: bool, duration: float = 40.0, tactile_fs: float | None = None) -> tuple[float, float, float]:
    """The paper's pour on a grasp squeezed 40 units firmer (it holds throughout), open or closed loop,
    optionally with a tactile stream at ``tactile_fs`` (what a tactile method adds to the physics)."""
    rig = Rig("TR", seed=1)
    g = rig.grasp()
    rig.hand.set_positions({f: g.positions[f] + 40 for f in hw.TRIPOD})
    rig.perturb(PAPER_POUR, at=rig.t + 0.5)
    w0, c0 = time.perf_counter(), time.process_time()
    if closed:
        run_closed_loop(rig, Never(), duration, tactile_fs=tactile_fs)
    else:
        simulate_open_loop(rig, duration, tactile_fs=tactile_fs)
    return duration, time.perf_counter() - w0, time.process_time() - c0


def median_rate(fn, repeat: int, *args) -> tuple[float, float]:
    """Median simulated s per CPU s and per wall s over ``repeat`` runs (after one warm-up)."""
    fn(*args)
    runs = [fn(*args) for _ in range(repeat)]
    return statistics.median(s / c for s, _, c in runs), statistics.median(s / w for s, w, _ in runs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--methods", default=",".join(methods.names()), help="comma-separated (default: all)")
    ap.add_argument("--repeat", type=int, default=3, help="timed runs per figure (median)")
    args = ap.parse_args()
    config = ReproduceConfig(trials=1)
    thresholds = calibrate(config)
    print(f"{'method':14s} {'experiment':10s} {'sim s':>6s}   {'compiled':>18s}   {'python':>18s}   "
          f"{'speed-up':>8s}")
    print(f"{'':33s}   {'per CPU-s (wall)':>18s}   {'per CPU-s (wall)':>18s}")
    for method in args.methods.split(","):
        for experiment in ("drop", "pour"):
            fast = median_rate(trial, args.repeat, config, thresholds, method, experiment, True)
            slow = median_rate(trial, args.repeat, config, thresholds, method, experiment, False)
            print(f"{method:14s} {experiment:10s} {config.duration(experiment):6.1f}   "
                  f"{fast[0]:8.0f} ({fast[1]:6.0f})   {slow[0]:8.0f} ({slow[1]:6.0f})   {fast[0] / slow[0]:7.1f}x")
    for fs, what in ((None, ""), (hw.NMSD_FS, ", 260 Hz tactile"), (hw.SWT_FS, ", 380 Hz tactile")):
        phys = median_rate(held, args.repeat, False, 40.0, fs)
        loop = median_rate(held, args.repeat, True, 40.0, fs)
        print(f"held pour{what}: open loop (physics + sensors alone) {phys[0]:5.0f} sim-s per CPU-s; closed by a "
              f"compiled reflex that never commands {loop[0]:5.0f} (the loop's own cost: "
              f"{100 * (phys[0] / loop[0] - 1):.0f}%)")


if __name__ == "__main__":
    main()
