"""The open-loop table of docs/simulator.md ("What the physics gives"), recomputed.

For each paper bottle (nominal plant, seed 0): the normal force per contact after
the grasp routine, the water in the bottle at the first pour slip (seeds 0-2, as
calibrated), how long after that onset the open-loop bottle falls out, and how far
a 10 g drop slides; then the largest static capacity at which a 10 g drop still
ends in complete slippage (``calibration.drop_fall_capacity``, TR and TX).

Run: ``python -m scripts.docs.open_loop_table [--write]`` (``--write``: into docs/simulator.md's markers).
"""

from __future__ import annotations

import sys

from slipreflex.sim import BOTTLES, PAPER_DROP, PAPER_POUR, Rig, simulate_open_loop
from slipreflex.sim.calibration import drop_fall_capacity, first_slip_ml


def main(argv: list[str]) -> int:
    cells: dict[str, list[str]] = {"force": [], "slip": [], "fall": [], "drop": []}
    for b in BOTTLES:
        rig = Rig(b, seed=0)
        g = rig.grasp()
        rig.perturb(PAPER_POUR, at=rig.t + 0.5)
        simulate_open_loop(rig, PAPER_POUR.duration_s + 5.0)
        onset = rig.slip_events()[0].onset
        drop = Rig(b, seed=0)
        drop.grasp()
        drop.perturb(PAPER_DROP, at=drop.t + 0.5)
        simulate_open_loop(drop, 3.0)
        ev = drop.slip_events()
        cells["force"].append(f"{g.force_n:.2f} N")
        cells["slip"].append(f"{first_slip_ml(BOTTLES[b]):.1f} ml (calibrated)")
        cells["fall"].append(f"{rig.fall_time - onset:.2f} s" if rig.fallen else "held")
        cells["drop"].append((f"{ev[0].distance * 1e3:.2f} mm" if ev else "no slip")
                             + (", then falls out" if drop.fallen else ""))
    rows = {"force": "normal force per contact after the grasp routine",
            "slip": "1 L/min pour: water in the bottle at the first slip (as observed)",
            "fall": "... then falls out after (the true onset)",
            "drop": "10 g drop: slide (it then stops by itself unless it falls out)"}
    lines = ["| | " + " | ".join(BOTTLES) + " |", "|---|" + "---|" * len(BOTTLES)]
    lines += [f"| {rows[k]} | " + " | ".join(v) + " |" for k, v in cells.items()]
    for b in ("TR", "TX"):
        r = drop_fall_capacity(BOTTLES[b])
        lines.append(f"| {b}: largest capacity at which a 10 g drop ends in complete slippage | "
                     f"{r['capacity_g']:.1f} g (the calibrated grasp holds {r['bottle_capacity_g']:.0f} g) |"
                     + " |" * (len(BOTTLES) - 1))
    body = "\n".join(lines)
    print(body)
    if "--write" not in argv:
        return 0
    from scripts.docs.splice_report import write_section

    return write_section("open_loop_table", "docs/simulator.md", "open-loop table", body)

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
