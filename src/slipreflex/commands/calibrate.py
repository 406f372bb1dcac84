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
    slipreflex calibrate --objects my.toml --bottles JAR,TR
    slipreflex calibrate --objects my.toml --bottles JAR --first-slip-ml 150
    slipreflex calibrate --figure out/calibration.png
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis.figures import _plt, check_figure_path
from ..core import hardware as hw
from ..core.errors import ParameterError
from ..files.paths import new_file, output_dir, unique_name
from ._lists import names_list

NAME = "calibrate"
HELP = "open-loop calibration: first pour slip and friction per bottle (paper: first slip near 200 ml)"
ORDER = 45


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Command-line options of ``slipreflex calibrate``."""
    parser.add_argument("--objects", type=Path, default=None, help="TOML file of your own bottles and surfaces")

    parser.add_argument("--bottles", type=names_list, default=None,
                        help="comma-separated bottles to calibrate (default: the paper's TR,DK,TX, plus every "
                             "bottle of --objects)")
    parser.add_argument("--figure", type=Path, default=None, metavar="PNG",
                        help="also draw the open-loop pours behind the numbers: the bottle's slide against "
                             "the water in it, each calibration seed's first slip and the paper's ~200 ml")
    parser.add_argument("--first-slip-ml", type=float, default=None,
                        help="calibrate every listed bottle's pad friction so that its open-loop first slip comes "
                             "at this volume (default: the paper's bottles are calibrated to 200 ml, yours kept)")


def run(args: argparse.Namespace) -> int:
    """Calibrate or check each bottle and print one line per bottle."""
    from ..sim import BOTTLES, HandParams, load_objects  # deferred: heavy (numba kernels)
    from ..sim.calibration import (  # deferred: heavy (llvmlite, numba, scipy)
        PAPER_FIRST_SLIP_ML,
        calibrate_bottle,
        first_slip,
    )
    from ..sim.contacts import grip_gain, static_capacity  # deferred: heavy (numba kernels)

    own = load_objects(args.objects).bottles if args.objects is not None else {}
    known = {**BOTTLES, **own}
    names = args.bottles or [*BOTTLES, *own]
    for n in names:
        if n not in known:
            raise ParameterError(f"--bottles: unknown bottle {n!r} (known: {', '.join(known)})")
    target = args.first_slip_ml
    if target is not None and not 0 < target < 500:
        raise ParameterError(f"--first-slip-ml must be in (0, 500) ml, got {target!r}")
    if args.figure is not None:
        output_dir(args.figure.parent, "--figure")      # before the work: a bad folder costs one line
        check_figure_path(args.figure, "--figure")
    hand = HandParams()
    drawn: dict = {}
    print(f"open-loop calibration: {hw.CONTACT_FORCE_N} N grasp, 500 ml at 1 L/min, no reflex "
          f"(paper: first slip near {PAPER_FIRST_SLIP_ML:g} ml, as its accelerometer and flow sensor saw it)")
    print("bottle  observed   true      pad mu_s/mu_k   cuff mu_s/mu_k  law          N/contact  capacity  gain")
    from ..sim import Rig  # deferred: heavy (numba kernels)

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
        drawn[n] = (bottle, ml)
    if args.figure is not None:
        wrote = calibration_figure(drawn, args.figure)
        print(f"wrote {wrote}" + (f" ({args.figure} exists and is kept)" if wrote != args.figure else ""))
    return 0


def open_loop_pour(bottle, seed: int, *, rest_s: float = 0.5, after_s: float = 3.0):
    """One open-loop pour of the paper's calibration: (water in the bottle ml, slide mm, first slip ml).

    The 0.8 N grasp, ``rest_s`` of rest, then the paper's pour with no reflex, until
    ``after_s`` after the first gross slip (or the pour's end); the slide is the truth's
    displacement of the bottle from where it was grasped.

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> ml, mm, first = open_loop_pour(BOTTLES["TR"], 0)
    >>> 150 < first < 250 and ml.shape == mm.shape
    True
    """


    from ..sim import PAPER_POUR, Rig, simulate_open_loop  # deferred: heavy (numba kernels)

    rig = Rig(bottle, seed=seed)
    rig.grasp(hw.CONTACT_FORCE_N)
    t0 = rig.t + rest_s
    rig.perturb(PAPER_POUR, at=t0)
    n0 = rig.onsets.size
    end = t0 + PAPER_POUR.duration_s + 1.0
    parts = []
    while rig.t < end and not rig.fallen:
        parts.append(simulate_open_loop(rig, min(0.5, end - rig.t)))
        if rig.onsets.size > n0:
            end = min(end, float(rig.onsets[n0]) + after_s)
    t = np.concatenate([p.t for p in parts])
    x = np.concatenate([p.daq.displacement for p in parts])
    delay = math.sqrt(2.0 * PAPER_POUR.fall_height_m / hw.GRAVITY)

    def ml(tt):
        return np.clip(np.asarray(tt) - t0 - delay, 0.0, PAPER_POUR.duration_s) * PAPER_POUR.rate_l_min / 60.0 * 1e3

    first = float(ml(rig.onsets[n0])) if rig.onsets.size > n0 else float("nan")
    return ml(t), 1e3 * (x - x[0]), first


def calibration_figure(drawn: dict, path: Path) -> Path:
    """The open-loop calibration as a figure: per bottle, each seed's slide against the water in it.

    ``drawn`` maps a bottle's name to (Bottle, its first slip in ml as printed).
    """

    from ..sim.calibration import CALIBRATION_SEEDS, PAPER_FIRST_SLIP_ML  # deferred: heavy (numba kernels)

    plt = _plt()
    names = list(drawn)
    fig, axes = plt.subplots(1, len(names), figsize=(3.6 * len(names) + 0.6, 3.4), squeeze=False, sharey=True)
    for ax, n in zip(axes[0], names):
        bottle, ml = drawn[n]
        travel = bottle.grip_travel_m * 1e3
        ax.axhline(travel, color="0.5", ls=":", lw=0.8, label=f"falls out ({travel:g} mm)")
        ax.axvspan(PAPER_FIRST_SLIP_ML - 20, PAPER_FIRST_SLIP_ML + 20, color="tab:red", alpha=0.15, lw=0,
                   label=f"paper: first slip near {PAPER_FIRST_SLIP_ML:g} ml")
        for k, seed in enumerate(CALIBRATION_SEEDS):
            water, mm, first = open_loop_pour(bottle, seed)
            keep = np.cumsum(mm > travel) <= 1           # up to the fall-out travel: the free fall is no slide
            ax.plot(water[keep], np.minimum(mm[keep], travel), lw=0.9, color=f"C{k}", label=f"seed {seed}")
            if first == first:
                ax.plot([first], [float(mm[min(int((water <= first).sum()), mm.size - 1)])], "o", color=f"C{k}", ms=4)
        if ml == ml:
            ax.axvline(ml, color="k", ls="--", lw=0.9, label=f"first slip {ml:.0f} ml (mean of seeds)")
        ax.set_title(f"{n}: pad mu_s {bottle.mu_s:.3f}, {bottle.mass_kg * 1e3:.0f} g", fontsize=8)
        ax.set_xlabel("water in the bottle (ml)")
        ax.set_xlim(0, 500)
        ax.set_ylim(-1, travel * 1.12)
        ax.legend(fontsize=6, loc="upper left")
    axes[0][0].set_ylabel("slide of the bottle (mm)")
    fig.suptitle("Open-loop calibration: the paper's pour (500 ml at 1 L/min), 0.8 N grasp, no reflex; "
                 "dots: each seed's first gross slip", fontsize=8)
    fig.tight_layout()
    return _save_new(plt, fig, Path(path))


def _save_new(plt: Any, fig: Any, path: Path) -> Path:
    """Save ``fig`` as a new file: ``path``, or ``NAME-2.png``... when the name is taken (a file, a
    symlink: never written through, never replaced). The figure appears whole or not at all."""
    try:
        for _ in range(100):  # another process may take the free name first: take the next one
            target = unique_name(path.parent, path.stem, path.suffix)
            try:
                with new_file(target, "wb") as fh:
                    fig.savefig(fh, dpi=110, format=path.suffix.lstrip(".").lower() or "png")
                return target
            except FileExistsError:
                continue
        raise ParameterError(f"--figure {path}: no free name {path.stem}-N{path.suffix} in {path.parent}")
    finally:
        plt.close(fig)
