"""Seconds a reproduction's first run spends compiling its numba kernels (an empty numba cache).

Each measurement is a fresh process whose ``NUMBA_CACHE_DIR`` is a new empty folder, so every kernel
compiles: it times, as ``slipreflex reproduce`` runs them before its trials, the threshold calibration
(``slipreflex.reproduce.thresholds.calibrate`` of the default grid) and the warm-up of the closed loops
(``slipreflex.reproduce.warmup.warm_kernels`` for one slip-sensor and one tactile method), then the same
two again in a second fresh process on the cache the first one filled, which is what a later run pays.
``slipreflex.reproduce.warmup.COLD_COMPILE_S``, the estimate printed before a first run, comes from the
cold total. A speed figure lives here, never in a test.

Usage::

    python benchmarks/bench_cold_compile.py [--repeat 1]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent

_STAGES = """
import json, time
t0 = time.perf_counter()
from slipreflex import methods
from slipreflex.reproduce.experiments import ReproduceConfig, method_context
from slipreflex.reproduce.thresholds import calibrate
from slipreflex.reproduce.warmup import warm_kernels
cfg = ReproduceConfig()
t1 = time.perf_counter()
context = method_context(cfg, calibrate(cfg))
t2 = time.perf_counter()
warm_kernels(cfg, context, {"dath": methods.get("dath")}, 1)
t3 = time.perf_counter()
warm_kernels(cfg, context, {"nmsd": methods.get("nmsd")}, 1)
t4 = time.perf_counter()
print(json.dumps({"imports": t1 - t0, "thresholds": t2 - t1, "slip loop": t3 - t2, "tactile loop": t4 - t3}))
"""


def stages(cache: str) -> dict[str, float]:
    """Wall seconds of each stage in a fresh process whose numba cache is ``cache``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    out = subprocess.run([sys.executable, "-c", _STAGES], env=env, check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    sys.path.insert(0, str(HERE))
    from machine import describe

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1, help="cold caches measured (median; default 1)")
    args = ap.parse_args()
    print(describe())
    cold, warm = [], []
    for _ in range(args.repeat):
        with tempfile.TemporaryDirectory(prefix="slipreflex-cold-") as cache:
            cold.append(stages(cache))
            warm.append(stages(cache))
    for name, runs in (("cold cache", cold), ("warm cache", warm)):
        parts = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
        compiled = parts["thresholds"] + parts["slip loop"] + parts["tactile loop"]
        print(f"{name}: thresholds {parts['thresholds']:.1f} s, slip closed loop {parts['slip loop']:.1f} s, "
              f"tactile closed loop {parts['tactile loop']:.1f} s, together {compiled:.1f} s "
              f"(imports {parts['imports']:.1f} s)")


if __name__ == "__main__":
    main()
