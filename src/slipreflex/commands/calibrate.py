"""``slipreflex calibrate``: the plant's open-loop calibration, bottle by bottle.

For every bottle it prints the open-loop first pour slip (ml of water in the
bottle when it first slips with the 0.8 N grasp and no reflex) twice: as the
paper's instruments observe it (the accelerometer-onset recipe that analyses
the trials, the flow sensor's volume: the number calibrated) and the
simulator's true onset (all contacts sliding, creep included, earlier); then
the pads' and the cuff's friction, the grasp's normal force per contact, its static
capacity and its grip gain per position unit. The paper's bottles are
calibrated to the paper's 200 ml (their built-in pad friction is the result
of this calibration); a user's bottle from ``--objects`` keeps the friction
its file gives, unless ``--first-slip-ml`` asks for a first slip of its own,
in which case its pad friction is calibrated to it.

Examples (shell)::

    slipreflex calibrate
    slipreflex calibrate --objects my.toml --bottles JAR TR
    slipreflex calibrate --objects my.toml --bottles JAR --first-slip-ml 150
"""

from __future__ import annotations

import argparse
from pathlib import Path

NAME = "calibrate"
HELP = "open-loop calibration: first pour slip and friction per bottle (paper: first slip near 200 ml)"
ORDER = 45


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Command-line options of ``slipreflex calibrate``."""
    parser.add_argument("--objects", type=Path, default=None, help="TOML file of your own bottles and surfaces")
    parser.add_argument("--bottles", nargs="+", default=None,
                        help="bottles to calibrate (default: the paper's TR DK TX, plus every bottle of --objects)")
    parser.add_argument("--first-slip-ml", type=float, default=None,
                        help="calibrate every listed bottle's pad friction so that its open-loop first slip comes "
                             "at this volume (default: the paper's bottles are calibrated to 200 ml, yours kept)")


def run(args: argparse.Namespace) -> int:
    """Calibrate or check each bottle and print one line per bottle."""
    from .. import hardware as hw
    from ..errors import ParameterError
    from ..sim import BOTTLES, HandParams, load_objects
    from ..sim.calibration import PAPER_FIRST_SLIP_ML, calibrate_bottle, first_slip
    from ..sim.contacts import grip_gain, static_capacity

    own = load_objects(args.objects).bottles if args.objects is not None else {}
    known = {**BOTTLES, **own}
    names = args.bottles or [*BOTTLES, *own]
    for n in names:
        if n not in known:
            raise ParameterError(f"--bottles: unknown bottle {n!r} (known: {', '.join(known)})")
    target = args.first_slip_ml
    if target is not None and not 0 < target < 500:
        raise ParameterError(f"--first-slip-ml must be in (0, 500) ml, got {target!r}")
    hand = HandParams()
    print(f"open-loop calibration: {hw.CONTACT_FORCE_N} N grasp, 500 ml at 1 L/min, no reflex "
          f"(paper: first slip near {PAPER_FIRST_SLIP_ML:g} ml, as its accelerometer and flow sensor saw it)")
    print("bottle  observed   true      pad mu_s/mu_k   cuff mu_s/mu_k  law          N/contact  capacity  gain")
    from ..sim import Rig

    for n in names:
        bottle = known[n]
        goal = target if target is not None else (PAPER_FIRST_SLIP_ML if n in BOTTLES and n not in own else None)
        note = "kept"
        if goal is not None and not (n in BOTTLES and n not in own and target is None):
            bottle = calibrate_bottle(bottle, goal).bottle
            note = f"calibrated to {goal:g} ml"
        elif goal is not None:
            note = f"built-in, calibrated to {goal:g} ml"
        fs = first_slip(bottle)
        ml, true_ml = fs.observed_ml, fs.true_ml
        rig = Rig(bottle, seed=0)
        g = rig.grasp()
        cap = static_capacity(bottle, g.force_n)
        law = bottle.friction_law if bottle.friction_law == bottle.cuff_friction_law else \
            f"{bottle.friction_law}/{bottle.cuff_friction_law}"
        slip = "none" if ml != ml else ("falls at grasp" if ml == 0 else f"{ml:6.1f} ml")
        true = "none" if true_ml != true_ml else ("-" if true_ml == 0 else f"{true_ml:6.1f} ml")
        print(f"{n:7s} {slip:>9s} {true:>9s}   {bottle.mu_s:5.3f}/{bottle.mu_k:5.3f}     {bottle.cuff_mu_s:5.3f}/"
              f"{bottle.cuff_mu_k:5.3f}     {law:12s} {g.force_n:5.2f} N  {cap:5.2f} N   "
              f"{grip_gain(hand, bottle):.3f} N/unit  ({note})")
    return 0
