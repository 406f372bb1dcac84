"""Speed of the simulated rig: simulated seconds per wall-clock second.

Prints, after a warm-up run that loads the numba cache (or compiles):

1. physics + sensors alone (open loop: a 40 s pour that drops the bottle,
   DAQ + IMU streams, plus a 260 Hz tactile stream; then the same pour with the
   grasp squeezed so that it holds throughout, the case a closed loop is in), and
   the set-up + grasp routine separately (texture generation, 100 Hz tactile polling);
2. one closed-loop trial with the paper's chain (SlipReflex, DATH) on a pour;
3. one closed-loop trial with a tactile baseline (NMSD at 260 Hz) on a pour;
4. a batch of trials (3 bottles x drop/pour x fixed/DATH) run one after the
   other on one core, and the same batch spread over all cores.

Run: ``python benchmarks/bench_sim.py`` (add ``--quick`` for a shorter batch).
The README / docs/simulator.md quote its output; tests never assert on time.
"""

from __future__ import annotations

import argparse
import os
import time
from concurrent.futures import ProcessPoolExecutor

import slipreflex
from slipreflex.core import hardware as hw
from slipreflex.sim import PAPER_DROP, PAPER_POUR, Rig, run_closed_loop, simulate_open_loop


def open_loop(seed: int = 0, duration: float = 40.0, tactile: bool = False,
              held: bool = False) -> tuple[float, float, float]:
    """Simulated, wall and CPU seconds of the open-loop stretch alone (set-up and grasp excluded).

    The paper's pour drops the open-loop bottle after ~16 s, and a fallen bottle is
    cheap to simulate; ``held=True`` squeezes 40 units past the grasp first, so the
    contacts hold (and compute) through the whole pour, as in a closed-loop trial.
    """
    rig = Rig("TR", seed=seed)
    g = rig.grasp()
    if held:
        rig.hand.set_positions({f: g.positions[f] + 40 for f in hw.TRIPOD})
    rig.perturb(PAPER_POUR, at=rig.t + 0.5)
    t0, w0, c0 = rig.t, time.perf_counter(), time.process_time()
    simulate_open_loop(rig, duration, tactile_fs=hw.NMSD_FS if tactile else None)
    return rig.t - t0, time.perf_counter() - w0, time.process_time() - c0


def setup(seed: int = 0) -> tuple[float, float]:
    """Rig construction (texture generation) and the grasp routine."""
    w0 = time.perf_counter()
    rig = Rig("TR", seed=seed)
    rig.grasp()
    return rig.t, time.perf_counter() - w0


def trial(args: tuple[str, str, str, int]) -> float:
    bottle, method, kind, seed = args
    rig = Rig(bottle, seed=seed)
    g = rig.grasp()
    p0 = g.positions[hw.SLIP_FINGER]
    if method == "nmsd":
        from slipreflex.methods.baselines import NMSD, rest_threshold

        s = rig.tactile_sampler(hw.NMSD_FS, keep=True)
        rig.advance(0.5)
        _, frames = s.history
        s.close()
        reflex = NMSD(threshold=rest_threshold(frames, "nmsd"), speed=rig.hand_params.speed_units_s, p0=p0)
    else:
        reflex = slipreflex.SlipReflex(fs=hw.DAQ_FS, dath=method == "dath", p0=p0)
    pert = PAPER_POUR if kind == "pour" else PAPER_DROP
    rig.perturb(pert, at=rig.t + 0.5)
    duration = pert.duration_s + 2.0 if kind == "pour" else 3.0
    t0 = rig.t
    run_closed_loop(rig, reflex, duration)
    return rig.t - t0


def rate(fn, *args) -> tuple[float, float]:
    t0 = time.perf_counter()
    sim = fn(*args)
    wall = time.perf_counter() - t0
    return sim, sim / wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer trials in the batch")
    args = ap.parse_args()
    t0 = time.perf_counter()
    open_loop(duration=1.0)
    trial(("TR", "dath", "drop", 0))
    trial(("TR", "nmsd", "drop", 0))
    print(f"warm-up (numba cache load or compile): {time.perf_counter() - t0:.1f} s")

    # on a shared machine the CPU time of this process is the steadier measure of one core
    sim, wall, cpu = open_loop(1, 40.0)
    print(f"physics + sensors (open loop, DAQ + IMU):       {sim / wall:8.0f} sim-s per wall-s  ({sim:.1f} sim-s; "
          f"{sim / cpu:.0f} per CPU-s)")
    sim, wall, cpu = open_loop(1, 40.0, True)
    print(f"  ... plus a 260 Hz tactile stream:             {sim / wall:8.0f} sim-s per wall-s  ({sim:.1f} sim-s; "
          f"{sim / cpu:.0f} per CPU-s)")
    sim, wall, cpu = open_loop(1, 40.0, held=True)
    print(f"  held through the pour (40 units firmer):     {sim / wall:8.0f} sim-s per wall-s  ({sim:.1f} sim-s; "
          f"{sim / cpu:.0f} per CPU-s)")
    sim, wall, cpu = open_loop(1, 40.0, True, held=True)
    print(f"  held, plus a 260 Hz tactile stream:          {sim / wall:8.0f} sim-s per wall-s  ({sim:.1f} sim-s; "
          f"{sim / cpu:.0f} per CPU-s)")
    sim, wall = setup(1)
    print(f"rig set-up + grasp routine (100 Hz polling):    {sim / wall:8.0f} sim-s per wall-s  ({sim:.1f} sim-s)")
    sim, r = rate(trial, ("TR", "dath", "pour", 1))
    print(f"one closed-loop trial, SlipReflex (DATH), pour: {r:8.0f} sim-s per wall-s  ({sim:.1f} sim-s)")
    sim, r = rate(trial, ("TR", "nmsd", "pour", 1))
    print(f"one closed-loop trial, NMSD (260 Hz), pour:     {r:8.0f} sim-s per wall-s  ({sim:.1f} sim-s)")

    reps = 1 if args.quick else 3
    jobs = [(b, m, k, s) for b in ("TR", "DK", "TX") for m in ("fixed", "dath") for k in ("drop", "pour")
            for s in range(reps)]
    t0 = time.perf_counter()
    total = sum(trial(j) for j in jobs)
    wall = time.perf_counter() - t0
    print(f"batch of {len(jobs)} trials, one core:              {total / wall:8.0f} sim-s per wall-s  "
          f"({total:.0f} sim-s in {wall:.1f} s)")
    ncpu = os.cpu_count() or 1
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=ncpu) as pool:
        total = sum(pool.map(trial, jobs))
    wall = time.perf_counter() - t0
    print(f"same batch over {ncpu} processes:                  {total / wall:8.0f} sim-s per wall-s  "
          f"({total:.0f} sim-s in {wall:.1f} s, includes worker start-up)")


if __name__ == "__main__":
    main()
