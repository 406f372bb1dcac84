"""The open-loop table of docs/simulator.md ("What the physics gives"), recomputed.

For each paper bottle (nominal plant, seed 0): the normal force per contact after
the grasp routine, the water in the bottle at the first pour slip (seeds 0-2, as
calibrated), how long after that onset the open-loop bottle falls out, and how far
a 10 g drop slides; then the largest static capacity at which a 10 g drop still
ends in complete slippage (``calibration.drop_fall_capacity``, TR and TX).

Run: ``python scripts/open_loop_table.py``.
"""

from __future__ import annotations

from slipreflex.sim import BOTTLES, PAPER_DROP, PAPER_POUR, Rig, simulate_open_loop
from slipreflex.sim.calibration import drop_fall_capacity, first_slip_ml


def main() -> None:
    for b in BOTTLES:
        rig = Rig(b, seed=0)
        g = rig.grasp()
        rig.perturb(PAPER_POUR, at=rig.t + 0.5)
        simulate_open_loop(rig, PAPER_POUR.duration_s + 5.0)
        onset = rig.slip_events()[0].onset
        fall = f"falls out {rig.fall_time - onset:.2f} s after the onset" if rig.fallen else "held"
        drop = Rig(b, seed=0)
        drop.grasp()
        drop.perturb(PAPER_DROP, at=drop.t + 0.5)
        simulate_open_loop(drop, 3.0)
        ev = drop.slip_events()
        slide = f"{ev[0].distance * 1e3:.2f} mm" if ev else "no slip"
        print(f"{b}: {g.force_n:.2f} N per contact; first pour slip at {first_slip_ml(BOTTLES[b]):.1f} ml, {fall}; "
              f"10 g drop slides {slide}{' and falls' if drop.fallen else ''}")
    for b in ("TR", "TX"):
        r = drop_fall_capacity(BOTTLES[b])
        print(f"{b}: a 10 g drop ends in complete slippage up to a capacity of {r['capacity_g']:.1f} g "
              f"(the calibrated grasp holds {r['bottle_capacity_g']:.0f} g)")


if __name__ == "__main__":
    main()
