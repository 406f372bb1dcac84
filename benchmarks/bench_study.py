"""Throughput of ``slipreflex study``: trials per second with 1 and 2 workers, and core-hours, printed.

Runs a small study (``--plants`` plants of the default per-plant grid:
``--trials`` x 3 bottles x 2 experiments x 4 methods, calibration and scan
included) in this process (serial), then on a Dask LocalCluster of 1 and of
2 worker processes, each into a fresh temporary directory: once as a user
runs it (the cluster's start and the workers' first imports included), and
once on a cluster already started and warmed (every worker has imported the
package and loaded the compiled kernels), which is the throughput a long
study sees. Prints wall time, plants and trials per second, core-seconds per
plant, and what the default study and a large one (``--large`` plants) cost
in core-hours at the measured serial rate.

Usage::

    python benchmarks/bench_study.py [--plants N] [--trials T] [--workers 1,2] [--large N]
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time


def _run(config, workers):
    from slipreflex.study import run_study

    with tempfile.TemporaryDirectory() as out:
        t0, c0 = time.perf_counter(), time.process_time()
        run = run_study(config, out, workers=workers, progress=False)
        return time.perf_counter() - t0, time.process_time() - c0


def _warm() -> None:
    """On a worker: import the package and load the compiled kernels (the serial run's warm-up plant)."""
    from slipreflex.study.runner import run_plant

    cfg = _warm_up_config()
    run_plant(0, cfg.plant_values()[0], cfg)


def _warm_up_config():
    from slipreflex.study import StudyConfig

    return StudyConfig(plants=1, trials=1, bottles=("TX",), experiments=("drop",))


def _run_warm(config, workers):
    """Wall time of the study on a LocalCluster of ``workers`` started and warmed beforehand."""
    from dask.distributed import Client, LocalCluster

    from slipreflex.study import run_study

    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
            Client(cluster) as client, tempfile.TemporaryDirectory() as out:
        client.run(_warm)
        t0 = time.perf_counter()
        run_study(config, out, scheduler=cluster.scheduler_address, progress=False)
        return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plants", type=int, default=4, help="plants per measured run (default 4)")
    ap.add_argument("--trials", type=int, default=None, help="trials per cell (default: the study's)")
    ap.add_argument("--workers", default="1,2", help="LocalCluster sizes to measure (default 1,2)")
    ap.add_argument("--large", type=int, default=4096, help="plants of the 'large study' estimate")
    args = ap.parse_args()

    from slipreflex.study import DEFAULT_PLANTS, DEFAULT_TRIALS, StudyConfig

    trials = args.trials or DEFAULT_TRIALS
    config = StudyConfig(plants=args.plants, trials=trials)
    per_plant = config.trials_per_plant
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"python {platform.python_version()}; {args.plants} plants x {per_plant} trials")
    _run(_warm_up_config(), 0)   # numba cache, imports
    wall, cpu = _run(config, 0)
    core_s = cpu / args.plants   # CPU time: the cost on an idle core, whatever else the machine runs
    print(f"serial: {wall:.1f} s wall, {cpu:.1f} s CPU, {args.plants / wall:.3f} plants/s, "
          f"{args.plants * per_plant / wall:.1f} trials/s; {core_s:.2f} CPU-s per plant, "
          f"{cpu / (args.plants * per_plant):.3f} CPU-s per trial (calibration and scan included)")
    for w in (int(x) for x in args.workers.split(",") if x.strip()):
        wall_w, _ = _run(config, w)   # the workers' CPU is not this process's
        print(f"LocalCluster({w}): {wall_w:.1f} s (cluster start included), {args.plants / wall_w:.3f} plants/s, "
              f"{args.plants * per_plant / wall_w:.1f} trials/s")
        warm = _run_warm(config, w)
        print(f"LocalCluster({w}), started and warmed: {warm:.1f} s, {args.plants / warm:.3f} plants/s, "
              f"{args.plants * per_plant / warm:.1f} trials/s")
    default = StudyConfig(plants=DEFAULT_PLANTS, trials=DEFAULT_TRIALS)
    d_core_s = core_s * default.trials_per_plant / per_plant
    print(f"default study ({DEFAULT_PLANTS} plants x {default.trials_per_plant} trials): "
          f"{DEFAULT_PLANTS * d_core_s / 3600:.3f} core-hours, {DEFAULT_PLANTS * d_core_s / 2 / 60:.1f} min "
          "on 2 cores (plus cluster start)")
    print(f"large study ({args.large} plants x {per_plant} trials): {args.large * core_s / 3600:.2f} "
          f"core-hours, {args.large * core_s / 64 / 60:.1f} min on 64 cores")


if __name__ == "__main__":
    main()
