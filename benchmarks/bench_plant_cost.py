"""CPU seconds of one study plant in one process: this checkout, and optionally another, measured in turns.

Each measurement is a fresh process that builds ``StudyConfig(plants=--design)`` (the plants of the
1000-plant study by default), runs a warm-up plant (0: imports, compiled kernels, caches), then times
:func:`slipreflex.study.runner.run_plant` on each plant asked for with ``time.process_time``. With
``--other PATH`` (another checkout's top folder, e.g. the version before a change) the two checkouts
are measured in alternating rounds, so a machine whose load changes affects both alike; the ratio is
the cost after over the cost before. With ``--dask`` the plants run instead in a one-worker Dask
``LocalCluster`` (the worker's CPU seconds), with Dask's statistical profiler on and off in alternating
rounds: what a study's worker pays for the profiler. A speed figure lives here, never in a test.

Usage::

    python benchmarks/bench_plant_cost.py [--plants 1-8] [--rounds 2] [--design 1000] [--other PATH | --dask]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent


def measure(plants: list[int], design: int) -> dict:
    """In this process: CPU seconds of each plant after a warm-up plant."""
    from slipreflex.study.runner import StudyConfig, run_plant

    cfg = StudyConfig(plants=design)
    values = cfg.plant_values()
    run_plant(0, values[0], cfg)
    cpu = {}
    for i in plants:
        t0 = time.process_time()
        run_plant(i, values[i], cfg)
        cpu[i] = time.process_time() - t0
    return cpu


def _in_checkout(top: Path, plants: list[int], design: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(top / "src"))
    code = (f"import json, sys; sys.path.insert(0, {str(HERE / 'benchmarks')!r}); "
            f"from bench_plant_cost import measure; print(json.dumps(measure({plants!r}, {design})))")
    out = subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True, text=True)
    return {int(k): v for k, v in json.loads(out.stdout.strip().splitlines()[-1]).items()}


def _in_dask(profiler: bool, plants: list[int], design: int) -> dict:
    import logging

    import dask.config
    from dask.distributed import Client, LocalCluster

    with dask.config.set({"distributed.worker.profile.enabled": profiler}):
        cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                               dashboard_address=None, silence_logs=logging.ERROR)
    with cluster, Client(cluster) as client:
        client.run(sys.path.insert, 0, str(HERE / "benchmarks"))
        from bench_plant_cost import measure as remote  # the worker imports it by name, from the path set
        return client.submit(remote, plants, design, pure=False).result()


def _plants(text: str) -> list[int]:
    lo, _, hi = text.partition("-")
    return list(range(int(lo), int(hi or lo) + 1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plants", default="1-8", help="plants to time, e.g. 1-8 (default; plant 0 warms up)")
    ap.add_argument("--rounds", type=int, default=2, help="alternating rounds (default 2)")
    ap.add_argument("--design", type=int, default=1000, help="plants of the study whose plants are timed")
    ap.add_argument("--other", type=Path, help="another checkout to measure in turns with this one")
    ap.add_argument("--dask", action="store_true", help="in a one-worker LocalCluster, profiler on and off")
    args = ap.parse_args()
    plants = _plants(args.plants)
    if args.dask:
        sides = [("profiler-on", True), ("profiler-off", False)]
    else:
        sides = [("this", HERE)] + ([("other", args.other.resolve())] if args.other else [])
    mean: dict[str, list[float]] = {name: [] for name, _ in sides}
    for r in range(args.rounds):
        for name, top in (sides if r % 2 == 0 else sides[::-1]):
            cpu = (_in_dask(bool(top), plants, args.design) if args.dask
                   else _in_checkout(Path(str(top)), plants, args.design))
            m = sum(cpu.values()) / len(cpu)
            mean[name].append(m)
            print(f"round {r + 1} {name:5s} ({top}): {m:.3f} CPU-s per plant over plants {args.plants} "
                  f"(each: {', '.join(f'{v:.2f}' for v in cpu.values())})", flush=True)
    line = {name: sum(v) / len(v) for name, v in mean.items()}
    print("mean CPU-s per plant: " + ", ".join(f"{k} {v:.3f}" for k, v in line.items()))
    if len(line) == 2:
        (a, x), (b, y) = line.items()
        print(f"{a} / {b}: {x / y:.3f}")


if __name__ == "__main__":
    sys.path.insert(0, str(HERE / "benchmarks"))
    main()
