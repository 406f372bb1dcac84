"""Speed of the comparison methods: NMSD and SWT-SD streaming objects and their compiled step.

Prints frames per second (one core) of:

* the streaming objects ``NMSD.step`` / ``SWTSD.step`` called from Python once per
  4 x 4 frame (with a measured position), as the Python closed loop calls them;
* the compiled step ``tactile_step(S, P, frame, position)`` called from an @njit
  loop over the same frames, as a compiled closed loop calls it (``reflex.compiled()``);

and checks on the way that both give the same commands bit for bit.

``--stream-only`` times the streaming objects alone through the public API, so the
same script measures an older version of the package for a before/after figure:

    git worktree add /tmp/before <commit> && \\
        PYTHONPATH=/tmp/before/src python benchmarks/bench_baselines.py --stream-only

Run: python benchmarks/bench_baselines.py [--frames N] [--repeats R] [--stream-only]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from machine import describe  # benchmarks/machine.py: run as python benchmarks/NAME.py


def _frames(n: int, fs: float) -> np.ndarray:
    """Noisy 4 x 4 frames with a slow slide and sudden drops every second (the methods act)."""
    rng = np.random.default_rng(0)
    t = np.arange(n) / fs
    f = 0.5 + rng.normal(0.0, 0.004, (n, 4, 4))
    f[:, 1, :] -= 5.0 * np.clip(t % 1.0 - 0.5, 0.0, 0.2)[:, None]
    f[:, 0, 0] -= np.where(t % 1.0 > 0.3, 0.3, 0.0)
    return f


def _reflexes():
    from slipreflex.methods.baselines import NMSD, SWTSD

    return (("NMSD", lambda: NMSD(threshold=40.0, speed=500.0, p0=100.0)),
            ("SWT-SD", lambda: SWTSD(threshold=0.03, speed=500.0, p0=100.0)))


def _time_stream(make, frames, positions, repeats):
    reflex = make()
    rates, out = [], None
    for _ in range(repeats):
        reflex.reset()
        step = reflex.step
        t0 = time.perf_counter()
        res = [step(f, p) for f, p in zip(frames, positions)]
        rates.append(len(frames) / (time.perf_counter() - t0))
        out = np.array([np.nan if u is None else u for u in res])
    return rates, out


def _time_compiled(make, frames, positions, repeats):
    from numba import njit

    @njit(cache=False)
    def loop(step, S, P, flat, pos, out):
        for k in range(flat.shape[0]):
            out[k] = step(S, P, flat[k], pos[k])

    reflex = make()
    step, S, P = reflex.compiled()
    flat = np.ascontiguousarray(frames.reshape(len(frames), -1))
    out = np.empty(len(frames))
    loop(step, S, P, flat[:10], positions[:10], out[:10])        # compile outside the timing
    rates = []
    for _ in range(repeats):
        reflex.reset()
        t0 = time.perf_counter()
        loop(step, S, P, flat, positions, out)
        rates.append(len(frames) / (time.perf_counter() - t0))
    return rates, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=50_000, help="frames per streaming repeat")
    ap.add_argument("--compiled-frames", type=int, default=2_000_000, help="frames per compiled repeat")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--stream-only", action="store_true", help="time the streaming objects only")
    args = ap.parse_args()
    print(f"machine: {describe()}")
    for label, make in _reflexes():
        fs = make().fs
        frames = _frames(max(args.frames, args.compiled_frames), fs)
        positions = np.where(np.arange(len(frames)) % 3 == 0, 100.0, np.nan)
        pos_py = [None if np.isnan(p) else float(p) for p in positions[:args.frames]]
        rates, stream = _time_stream(make, frames[:args.frames], pos_py, args.repeats)
        print(f"{label} streaming object .step: median {statistics.median(rates) / 1e3:.0f} k frames/s "
              f"(best {max(rates) / 1e3:.0f} k; {args.repeats} x {args.frames} frames; "
              f"{np.isfinite(stream).sum()} commands)")
        if args.stream_only:
            continue
        rates, compiled = _time_compiled(make, frames[:args.compiled_frames], positions[:args.compiled_frames],
                                         args.repeats)
        print(f"{label} compiled step in an @njit loop: median {statistics.median(rates) / 1e6:.2f} M frames/s "
              f"(best {max(rates) / 1e6:.2f} M; {args.repeats} x {args.compiled_frames} frames)")
        same = np.array_equal(compiled[:args.frames], stream, equal_nan=True)
        print(f"{label} compiled == streaming on the first {args.frames} frames: {same}")
        if not same:
            raise SystemExit(f"{label}: the compiled step and the streaming object disagree")


if __name__ == "__main__":
    main()
