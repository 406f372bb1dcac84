"""Cost of one physics step and of one tactile frame in the numba kernel (ns), in the states that matter.

Prints the thread-CPU time per step of ``kernel.step_until`` (DAQ and IMU included, no
tactile sampler), best of 7 repeats of 100 000 steps started from the same saved state:

1. a grasp held at rest (no perturbation; 5 s after the grasp);
2. a pour, the grasp squeezed 40 units so that it holds, 5 s into the pour (contacts stuck);
3. the same pour 20 s in, where the middle finger's cuff creeps (the rate-state solve runs
   every step);

and the time per frame of ``kernel.tactile_frames`` (20 000 frames of one contact).

The rigs take the fixed step (``stepping="fixed"``): this is the fine step's cost (the adaptive
kernel's coarse steps are timed per simulated second by ``bench_closed_loop.py``).

Run: ``python benchmarks/bench_kernel_steps.py``. docs/simulator.md ("Speed") quotes it; it
uses the rig's internal arrays, so it runs against older versions of the kernel too.
"""

from __future__ import annotations

import time

import numpy as np

from slipreflex.core import hardware as hw
from slipreflex.sim import PAPER_POUR, Rig
from slipreflex.sim import kernel as K


def held_rig(pour: bool, after_s: float) -> Rig:
    """Grasp, squeeze 40 units, optionally start the paper's pour, advance ``after_s``."""
    rig = Rig("TR", seed=1, stepping="fixed")
    g = rig.grasp()
    rig.hand.set_positions({f: g.positions[f] + 40 for f in hw.TRIPOD})
    if pour:
        rig.perturb(PAPER_POUR, at=rig.t + 0.5)
    rig.advance_block(rig.t + after_s)
    return rig


def ns_per_step(rig: Rig, steps: int = 100_000, repeats: int = 7) -> float:
    """Best thread-CPU time per step over ``repeats`` runs from the rig's current state."""
    daq = np.empty((int(steps * rig.physics.dt / hw.DAQ_PERIOD_S) + 16, K.O_SIZE))
    tac = np.empty((0, K.T_SIZE))
    ev = np.empty((4 * steps + 16, 3))
    counts = np.zeros(3, np.int64)
    best = float("inf")
    for _ in range(repeats):
        S, C, D = rig._S.copy(), rig._C.copy(), rig._D.copy()
        end = int(C[K.C_N]) + steps
        t0 = time.thread_time()
        while C[K.C_N] < end:
            K.step_until(S, C, rig._P, rig._keys, D, rig._W, rig.track.rho, rig._tac_rates, rig._tac_next,
                         rig._tac_contact, end, daq, tac, ev, counts)
        best = min(best, time.thread_time() - t0)
    return best / steps * 1e9


def ns_per_frame(frames: int = 20_000, repeats: int = 5) -> float:
    """Best thread-CPU time per tactile frame (one contact, 260 Hz snapshots)."""
    snap = np.zeros((frames, K.T_SIZE))
    snap[:, K.T_IDX] = np.arange(frames)
    snap[:, K.T_T] = np.arange(frames) / hw.NMSD_FS
    snap[:, K.T_NC] = 1.0
    snap[:, K.T_FT] = 0.3
    out = np.empty((frames, 4, 4))
    args = (snap, np.uint64(99), 1.0, 0.9, 0.7, 0.005, 0.002, 0.9, 0.005, 0.02)
    K.tactile_frames(*args, np.full((2, 4, 4), np.nan), out)
    best = float("inf")
    for _ in range(repeats):
        state = np.full((2, 4, 4), np.nan)
        t0 = time.thread_time()
        K.tactile_frames(*args, state, out)
        best = min(best, time.thread_time() - t0)
    return best / frames * 1e9


def main() -> None:
    print(f"held grasp at rest:                     {ns_per_step(held_rig(False, 5.0)):6.1f} ns per step")
    print(f"held pour, contacts stuck (5 s in):     {ns_per_step(held_rig(True, 5.0)):6.1f} ns per step")
    print(f"held pour, cuff creeping (20 s in):     {ns_per_step(held_rig(True, 20.0)):6.1f} ns per step")
    print(f"tactile frame:                          {ns_per_frame():6.1f} ns per frame")


if __name__ == "__main__":
    main()
