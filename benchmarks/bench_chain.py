"""Speed of the reflex chain: streaming SlipReflex.step and the fused batch chain.

Prints the median time per SlipReflex.step (one core) for the paper's DATH chain
and the variants (authors-gui, dath-event), the batch chain's throughput
(filter + encode + windows + MPI) over a long array, and scipy.signal.sosfilt on
the same array for scale. Checks on the way that the batch result equals the
streaming one bit for bit. Both run the same compiled step
(slipreflex.methods.chain._kernels.chain_step) over a state vector.

Run: python benchmarks/bench_chain.py [--samples N] [--repeats R]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from machine import describe  # benchmarks/machine.py: run as python benchmarks/NAME.py


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=20_000_000, help="batch array length")
    ap.add_argument("--stream-samples", type=int, default=200_000, help="samples per streaming repeat")
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()

    import scipy.signal as ss

    import slipreflex as sr

    rng = np.random.default_rng(0)
    raw = 0.4 + np.cumsum(rng.normal(0, 0.002, args.samples))
    print(f"machine: {describe()}")

    # Streaming: the object a real-time loop calls once per sample.
    chunk = raw[: args.stream_samples].tolist()
    for label in ("dath", "authors-gui", "dath-event"):
        reflex = sr.SlipReflex.from_preset(label)
        per_sample = []
        for _ in range(args.repeats):
            reflex.reset()
            step = reflex.step
            t0 = time.perf_counter()
            for r in chunk:
                step(r)
            per_sample.append((time.perf_counter() - t0) / len(chunk))
        print(f"SlipReflex.step ({label}): median {statistics.median(per_sample) * 1e6:.3f} us/sample "
              f"(min {min(per_sample) * 1e6:.3f}, {args.repeats} x {len(chunk)} samples)")
    reflex = sr.SlipReflex(dath=True)

    # Batch: one fused numba pass; warm the JIT first.
    sr.run_chain(raw[:1000], dath=True)
    times = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        res = sr.run_chain(raw, dath=True)
        times.append(time.perf_counter() - t0)
    best, med = min(times), statistics.median(times)
    print(f"run_chain (filter+encode+windows+MPI, dath): median {args.samples / med / 1e6:.1f} M samples/s "
          f"(best {args.samples / best / 1e6:.1f}) over {args.samples} samples")

    sos = sr.design_lowpass()
    zi = ss.sosfilt_zi(sos) * raw[0]
    stimes = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        ss.sosfilt(sos, raw, zi=zi)
        stimes.append(time.perf_counter() - t0)
    print(f"scipy.signal.sosfilt alone, for scale: median {args.samples / statistics.median(stimes) / 1e6:.1f} "
          f"M samples/s")

    reflex.reset()
    n_check = 100_000
    cmds = [u for u in map(reflex.step, raw[:n_check].tolist()) if u is not None]
    same = cmds == sr.run_chain(raw[:n_check], dath=True).commands.tolist()
    print(f"batch == streaming on the first {n_check} samples: {same}")
    if not same:
        raise SystemExit("batch and streaming disagree")


if __name__ == "__main__":
    main()
