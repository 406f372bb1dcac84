"""Wall time of the default reproduction (``slipreflex reproduce``), printed, not asserted.

Runs the paper's full grid (10 trials x 3 bottles x 2 experiments x 4 methods)
with the outputs written to a temporary directory, once to warm the numba
cache if it is cold, then ``--repeat`` times measured.

Usage::

    python benchmarks/bench_reproduce.py [--jobs N] [--repeat R] [--trials T]
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import tempfile
import time


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    ap.add_argument("--repeat", type=int, default=1, help="measured runs (default 1)")
    ap.add_argument("--trials", type=int, default=10, help="trials per cell (default: the paper's 10)")
    ap.add_argument("--no-warmup", action="store_true", help="measure the first (possibly cold) run too")
    args = ap.parse_args()

    from slipreflex.reproduce.experiments import TRIAL_SIM_SPEED, ReproduceConfig, run_reproduce, write_outputs

    config = ReproduceConfig(trials=args.trials)
    jobs = args.jobs or os.cpu_count() or 1
    print(f"machine: {_cpu_name()}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}, "
          f"python {platform.python_version()}; jobs={jobs}; {len(config.cells())} trials")
    if not args.no_warmup:
        t0 = time.perf_counter()
        run_reproduce(ReproduceConfig(trials=1, experiments=("drop",)), jobs=jobs, progress=False,
                      plots=False)
        print(f"warm-up (numba cache, worker start): {time.perf_counter() - t0:.1f} s")
    sim_s = sum(config.duration(c.experiment) for c in config.cells())
    for i in range(args.repeat):
        with tempfile.TemporaryDirectory() as out:
            cpu0 = _cpu_s()
            t0 = time.perf_counter()
            result = run_reproduce(config, jobs=jobs, progress=False)
            t_run = time.perf_counter() - t0
            cpu = _cpu_s() - cpu0
            write_outputs(result, out)
            t_all = time.perf_counter() - t0
        print(f"run {i + 1}: trials + analysis {t_run:.1f} s (calibration {result.calibration_wall_s:.1f} s), "
              f"with CSV/figures/report {t_all:.1f} s wall")
        print(f"  {sim_s:.0f} simulated s in {cpu:.1f} CPU s (all processes): {sim_s / cpu:.0f} simulated s "
              f"per CPU s (the run-time estimate assumes TRIAL_SIM_SPEED = {TRIAL_SIM_SPEED:g} per worker)")


def _cpu_name() -> str:
    """The CPU's model name as /proc/cpuinfo gives it (else what platform knows)."""
    try:
        with open("/proc/cpuinfo") as fh:
            return next(line.split(":", 1)[1].strip() for line in fh if line.startswith("model name"))
    except (OSError, StopIteration):
        return platform.processor() or platform.machine()


def _cpu_s() -> float:
    """User + system CPU seconds of this process and its finished children (the workers)."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


if __name__ == "__main__":
    main()
