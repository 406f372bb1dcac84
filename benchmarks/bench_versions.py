"""The held pour's closed loop in two versions of the code, processes alternating: a ratio across versions.

Two versions cannot share a process, so each round runs one process per side, one after the other. Each
process times ``held(True)`` of that version's ``benchmarks/bench_closed_loop.py`` (the paper's pour on a
grasp squeezed firmer, closed by a compiled reflex that never commands) ``--runs`` times after a warm-up and
prints its median simulated seconds per CPU second. Each round's ratio is this side over the other side,
and the script prints every round's and their median. A side is a checkout's folder (its ``src`` goes first
on ``PYTHONPATH``) with a stepping (``fixed``, ``adaptive``, or ``-`` for a version without the choice).

Across processes a kernel's rate moves more than within one (docs/speed.md), so these ratios are the
noisier ones: ``bench_closed_loop.py``'s in-process pairs measure one version's two kernels.

Run: ``python benchmarks/bench_versions.py --other DIR --other-stepping - --stepping adaptive --rounds 6``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
from pathlib import Path

# that version's own held() and median_rate() (warm-up, then the median): held(closed, duration, tactile_fs[, stepping])
_CHILD = """
import sys
sys.path.insert(0, sys.argv[1] + "/benchmarks")
from bench_closed_loop import held, median_rate
args = (True,) if sys.argv[2] == "-" else (True, 40.0, None, sys.argv[2])
print(median_rate(held, int(sys.argv[3]), *args)[0])
"""


def rate(folder: Path, stepping: str, runs: int) -> float:
    """The median held-pour rate (sim-s per CPU-s) of the version in ``folder``, in a process of its own."""
    env = dict(os.environ, PYTHONPATH=str(folder / "src"))
    out = subprocess.run([sys.executable, "-c", _CHILD, str(folder), stepping, str(runs)], env=env,
                         capture_output=True, text=True, check=True)
    return float(out.stdout.split()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--other", type=Path, required=True, help="the other version's checkout")
    ap.add_argument("--other-stepping", default="-", help="fixed, adaptive or - (default: -, no choice)")
    ap.add_argument("--stepping", default="adaptive", help="this version's stepping (default: adaptive)")
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--runs", type=int, default=9, help="timed runs per process (median)")
    args = ap.parse_args()
    here = Path(__file__).resolve().parents[1]
    if not (args.other / "benchmarks" / "bench_closed_loop.py").is_file():
        ap.error(f"--other {args.other}: no benchmarks/bench_closed_loop.py there")
    for n, flag in ((args.rounds, "--rounds"), (args.runs, "--runs")):
        if not 1 <= n <= 1000:
            ap.error(f"{flag} must be 1-1000, got {n}")
    for s, flag in ((args.other_stepping, "--other-stepping"), (args.stepping, "--stepping")):
        if s not in ("fixed", "adaptive", "-"):
            ap.error(f"{flag} {s!r}: not fixed, adaptive or -")
    ratios = []
    for i in range(args.rounds):
        other = rate(args.other, args.other_stepping, args.runs)
        this = rate(here, args.stepping, args.runs)
        ratios.append(this / other)
        print(f"round {i + 1}: other ({args.other_stepping}) {other:6.0f}, this ({args.stepping}) {this:6.0f} "
              f"sim-s per CPU-s: {this / other:.2f}x", flush=True)
    print(f"median of {len(ratios)} rounds: {statistics.median(ratios):.2f}x "
          f"(rounds {min(ratios):.2f}-{max(ratios):.2f})")


if __name__ == "__main__":
    main()
