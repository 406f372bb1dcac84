"""Speed of one closed-loop trial, the fixed-step reference beside the adaptive kernel, in one run.

For each method (default: every registered method) and each experiment (the
default reproduction's drop and pour, bottle TR), the trial is set up exactly as
``reproduce`` sets it up (rig, grasp, calibrated thresholds, perturbation) and only
``run_closed_loop`` (the compiled loop) is timed, once with the fixed-step kernel
(``stepping="fixed"``, the reference) and once with the adaptive one, alternately,
so both see the same load on a shared machine; the ratio is the median over the
pairs of adaptive over fixed (the held pour's lines give the pairs' range too).
Each rate is the median over ``--repeat`` runs (``--held-repeat`` for the held
pour) of simulated seconds per CPU second of this process (wall-clock figures
beside it). Then the held pour: the
paper's pour on a grasp squeezed 40 units firmer (it holds throughout), advanced
open loop (physics and sensors alone, also with a 260 Hz and a 380 Hz tactile
stream) and closed by a compiled reflex that never commands, each with both kernels.
``--python`` adds the Python loop (``compiled=False``, fixed steps) for scale.

Run: ``python benchmarks/bench_closed_loop.py`` (``--methods dath,nmsd``,
``--repeat 5``). The README and docs/speed.md quote its output; tests never assert on time.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import numpy as np
from numba import njit

from slipreflex import methods
from slipreflex.core import hardware as hw
from slipreflex.reproduce.experiments import ReproduceConfig, calibrate, method_context, trial_seed
from slipreflex.sim import PAPER_POUR, Rig, run_closed_loop, simulate_open_loop
from slipreflex.sim.variations import VariationSpread, trial_rig


def trial(config: ReproduceConfig, thresholds: dict, method: str, experiment: str, compiled: bool,
          bottle: str = "TR", stepping: str = "adaptive") -> tuple[float, float, float]:
    """(simulated s, wall s, CPU s) of the closed loop of one trial, set up as ``run_trial`` does."""
    seed = trial_seed(config.seed, experiment, bottle, 0)
    rig = trial_rig(bottle, seed, spread=None if config.variations else VariationSpread.none(),
                    rig_kwargs={"stepping": stepping})
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


def held(closed: bool, duration: float = 40.0, tactile_fs: float | None = None,
         stepping: str = "adaptive") -> tuple[float, float, float]:
    """The paper's pour on a grasp squeezed 40 units firmer (it holds throughout), open or closed loop,
    optionally with a tactile stream at ``tactile_fs`` (what a tactile method adds to the physics)."""
    rig = Rig("TR", seed=1, stepping=stepping)
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


def paired_rates(fn, repeat: int, *args) -> dict[str, tuple[float, float]]:
    """Median (per CPU-s, per wall-s) of ``fn(*args, stepping=...)`` for both kernels, run in adjacent pairs, and
    under ``"ratio"`` the median, lowest and highest of the pairs' adaptive-to-fixed CPU ratios.

    The two runs of a pair are adjacent in time (their order alternates from pair to pair), so a pair's ratio
    sees one load; the machine's load moves a kernel's rate by up to a factor of two between pairs.
    """
    for kind in ("fixed", "adaptive"):   # warm-up (compilation, caches)
        fn(*args, stepping=kind)
    runs: dict[str, list] = {"fixed": [], "adaptive": []}
    for i in range(repeat):
        for kind in (("fixed", "adaptive") if i % 2 == 0 else ("adaptive", "fixed")):
            runs[kind].append(fn(*args, stepping=kind))
    pairs = [(sa / ca) / (sf / cf) for (sf, _, cf), (sa, _, ca) in zip(runs["fixed"], runs["adaptive"])]
    out = {k: (statistics.median(s / c for s, _, c in v), statistics.median(s / w for s, w, _ in v))
           for k, v in runs.items()}
    out["ratio"] = (statistics.median(pairs), min(pairs), max(pairs))
    return out


def _ratio(r: dict) -> str:
    med, lo, hi = r["ratio"]
    return f"{med:.2f}x, pairs {lo:.2f}-{hi:.2f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--methods", default=",".join(methods.names()), help="comma-separated (default: all)")
    ap.add_argument("--repeat", type=int, default=3, help="timed pairs per trial figure (median)")
    ap.add_argument("--held-repeat", type=int, default=15, help="timed pairs per held-pour figure (median)")
    ap.add_argument("--python", action="store_true", help="also time the Python loop (fixed steps)")
    args = ap.parse_args()
    for n, flag in ((args.repeat, "--repeat"), (args.held_repeat, "--held-repeat")):
        if not 1 <= n <= 1000:
            ap.error(f"{flag} must be 1-1000, got {n}")
    config = ReproduceConfig(trials=1)
    thresholds = calibrate(config)
    print(f"{'method':14s} {'experiment':10s} {'sim s':>6s}   {'fixed step':>18s}   {'adaptive':>18s}   "
          f"{'ratio':>6s}" + (f"   {'python loop':>18s}" if args.python else ""))
    print(f"{'':33s}   {'per CPU-s (wall)':>18s}   {'per CPU-s (wall)':>18s}")
    for method in args.methods.split(","):
        for experiment in ("drop", "pour"):
            r = paired_rates(trial, args.repeat, config, thresholds, method, experiment, True)
            fx, ad = r["fixed"], r["adaptive"]
            line = (f"{method:14s} {experiment:10s} {config.duration(experiment):6.1f}   "
                    f"{fx[0]:8.0f} ({fx[1]:6.0f})   {ad[0]:8.0f} ({ad[1]:6.0f})   {r['ratio'][0]:5.2f}x")
            if args.python:
                slow = median_rate(trial, args.repeat, config, thresholds, method, experiment, False, "TR", "fixed")
                line += f"   {slow[0]:8.0f} ({slow[1]:6.0f})"
            print(line)
    for fs, what in ((None, ""), (hw.NMSD_FS, ", 260 Hz tactile"), (hw.SWT_FS, ", 380 Hz tactile")):
        phys = paired_rates(held, args.held_repeat, False, 40.0, fs)
        loop = paired_rates(held, args.held_repeat, True, 40.0, fs)
        print(f"held pour{what}: open loop (physics + sensors alone) fixed {phys['fixed'][0]:5.0f} adaptive "
              f"{phys['adaptive'][0]:5.0f} ({_ratio(phys)}) sim-s per CPU-s; closed "
              f"by a compiled reflex that never commands fixed {loop['fixed'][0]:5.0f} adaptive "
              f"{loop['adaptive'][0]:5.0f} ({_ratio(loop)})")


if __name__ == "__main__":
    main()
