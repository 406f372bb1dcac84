"""``slipreflex scan``: the simulated characterization scan of the slip sensor (paper Fig. 4-9).

The sensor moves 5 cm down the white/black test surface at 1 mm/s, 3 mm
away (:func:`slipreflex.sim.scan`), or over ``--layout``; ``--distance`` longer than the
layout is an error (the scan never runs past its surfaces). The command writes the trace as CSV and
a figure like the paper's Fig. 6-9 (filtered signal; accumulator with the
threshold; spikes; fixed threshold and DATH), and prints the voltage range
on white and on black, the spike count of each method and the smallest
spike spacing in mm.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis.paper import PAPER_SCAN_VOLTS
from ..core.errors import ParameterError
from ..core.hardware import DAQ_FS
from ..core.validation import number, within
from ..files.paths import OutputSet
from ..methods import DATH, FIXED

NAME = "scan"
HELP = "simulate the slip sensor's characterization scan (paper Fig. 4-9): CSV, figure, numbers"
ORDER = 40


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Command-line options of ``slipreflex scan``."""
    parser.add_argument("--seed", type=int, default=0, help="texture and noise seed (default 0)")
    parser.add_argument("--speed", type=float, default=1.0, help="scan speed in mm/s (default 1, the paper's)")
    parser.add_argument("--distance", type=float, default=50.0,
                        help="scan length in mm (default 50, the paper's layout; at most the layout's length)")
    parser.add_argument("--threshold", type=float, default=0.008, help="base threshold in V (default 0.008)")
    parser.add_argument("--out", type=Path, default=Path("out/scan"), help="output directory (default out/scan)")
    parser.add_argument("--no-figure", action="store_true", help="skip the PNG figure")
    parser.add_argument("--objects", type=Path, default=None, metavar="FILE.toml",
                        help="your own surfaces and bottles (slipreflex.sim.load_objects) for --layout")
    parser.add_argument("--layout", default=None, metavar="NAME:MM,...",
                        help="the test surface top to bottom, e.g. 'stand:5,foil:10,black:30,stand:5'; a "
                             "name is a surface (built-in or of --objects) or a bottle of --objects (its "
                             "surface); default the paper's stand:5,white:10,black:30,stand:5")


def run(args: argparse.Namespace) -> int:
    """Run the scan, write the files, print the numbers."""
    from ..sim import scan  # deferred: heavy (numba kernels)
    from ..sim.scan import PAPER_LAYOUT  # deferred: heavy (numba kernels)

    within("scan_speed_mm_s", args.speed, "--speed")
    within("scan_distance_mm", args.distance, "--distance")
    within("scan_samples", int(args.distance / args.speed * DAQ_FS) + 1, "--distance / --speed x the DAQ rate")
    number("--threshold", args.threshold, lo=0.0, hi=10.0)
    if args.objects is not None and not args.objects.is_file():
        raise ParameterError(f"--objects {args.objects}: no such file")
    layout = _layout(args) if args.layout is not None else list(PAPER_LAYOUT)
    if args.objects is not None and args.layout is None:
        _layout_names(args)         # the file is read and checked even when no layout uses it
    length_mm = 1e3 * sum(length for _, length in layout)
    if args.distance > length_mm + 1e-9:
        what = f"--layout {args.layout!r}" if args.layout is not None else "the paper's layout"
        raise ParameterError(f"--distance {args.distance:g} mm is longer than {what} ({length_mm:g} mm): "
                             f"give --distance {length_mm:g} or less, or a longer --layout")
    outputs = OutputSet(args.out, NAME)
    outputs.claim()                                  # one scan writing into --out at a time, before the work
    outputs.check(OUTPUT_NAMES)
    kw: dict[str, Any] = {"layout": layout} if args.layout is not None else {}
    result = scan(seed=args.seed, speed=args.speed * 1e-3, distance=args.distance * 1e-3, **kw)
    summary = result.analyse(threshold=args.threshold)
    staged = outputs.stage()
    try:
        frame = result.to_frame()
        with (staged / "scan.csv").open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(list(frame))
            cols = [np.asarray(v) for v in frame.values()]
            for i in range(result.t.size):
                w.writerow([repr(float(c[i])) if c.dtype.kind == "f" else str(int(c[i])) for c in cols])
        if not args.no_figure:
            _figure(result, summary, staged / "scan.png", args.threshold)
        outputs.commit(staged)
    except BaseException:
        outputs.abort(staged)
        raise
    out = outputs.folder
    csv_path = out / "scan.csv"
    print(f"scan: {args.distance:g} mm at {args.speed:g} mm/s, seed {args.seed}, {result.t.size} samples")
    shown = _shown(summary)
    for region in shown:
        lo, hi = summary.ranges[region]
        print(f"  {region:5s} filtered volts {lo:.3f} .. {hi:.3f} V")
    print(f"  spikes over the whole scan: fixed {summary.spikes[FIXED]}, DATH {summary.spikes[DATH]}")
    for region in shown:
        parts = []
        for meth in (FIXED, DATH):
            sp = summary.min_spacing_mm[(meth, region)]
            parts.append(f"{meth} {summary.spikes_in[(meth, region)]} spikes, smallest spacing "
                         + ("-" if sp is None else f"{sp:.3f} mm"))
        print(f"  on {region}: " + "; ".join(parts))
    print(f"  wrote {csv_path}")
    if not args.no_figure:
        print(f"  wrote {out / 'scan.png'}")
    return 0


#: What ``scan`` writes into ``--out``, replaced as one set (slipreflex.files.paths.OutputSet).
OUTPUT_NAMES: tuple[str, ...] = ("scan.csv", "scan.png")


def _layout_names(args: argparse.Namespace) -> dict:
    """The surfaces ``--objects`` adds (its surfaces, and its bottles' surfaces by bottle name)."""
    from ..sim import load_objects  # deferred: heavy (numba kernels)

    objs = load_objects(args.objects) if args.objects is not None else None
    extra: dict[str, Any] = dict(objs.surfaces) if objs else {}
    if objs:
        extra.update({n: b.surface for n, b in objs.bottles.items()})
    return extra


def _layout(args: argparse.Namespace) -> list:
    """``--layout`` as (Surface, length_m) pairs; names from the built-ins or ``--objects``."""
    from ..sim.objects import resolve_surface  # deferred: heavy (numba kernels)

    extra = _layout_names(args)
    out = []
    if not args.layout.replace(",", "").strip():
        raise ParameterError("--layout: empty; give NAME:MM parts, e.g. 'stand:5,white:10,black:30,stand:5'")
    for i, part in enumerate(p.strip() for p in args.layout.split(",") if p.strip()):
        name, sep, mm = part.partition(":")
        try:
            length = float(mm) * 1e-3
        except ValueError:
            length = float("nan")
        if not sep or not length > 0:
            raise ParameterError(f"--layout part {i + 1} {part!r}: expected NAME:MM with MM > 0")
        surf = resolve_surface(name.strip(), extra, where=f"--layout part {i + 1}")
        # A bottle's surface is shown under the bottle's name.
        out.append((dataclasses.replace(surf, name=name.strip()) if surf.name != name.strip() else surf, length))
    return out


def _shown(summary) -> list[str]:
    """The regions to print and draw: every one but the stand, in layout order."""
    return [r for r in summary.ranges if not r.startswith("stand")]


def _figure(result, summary, path: Path, threshold: float) -> None:
    import matplotlib  # deferred: heavy (matplotlib)

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # deferred: heavy (matplotlib)

    pos = result.position * 1000.0
    x = result.analysis["filtered"]
    shown = _shown(summary)[:3]
    fig = plt.figure(figsize=(5.5 * max(2, len(shown)), 9), constrained_layout=True)
    gs = fig.add_gridspec(4, max(2, len(shown)))
    ax = fig.add_subplot(gs[0, :])
    ax.plot(pos, x, lw=0.8)
    regions: dict = {}
    for name, a, b in result.regions:
        key = name if name not in regions else f"{name}@{a * 1000:g}mm"
        if key in shown:
            regions[key] = (a * 1000, b * 1000)
    shade = {"white": "0.97", "black": "0.80", "stand": "#e8dcc8"}
    for name, a, b in result.regions:         # every region named where it lies, the stand too
        ax.axvspan(a * 1000, b * 1000, color=shade.get(name, "0.9"), zorder=0)
        ax.axvline(a * 1000, ls="--", c="grey", lw=0.6)
        ax.text((a + b) * 500, 0.97, name, transform=ax.get_xaxis_transform(), ha="center", va="top",
                fontsize=8, bbox={"fc": "white", "ec": "0.6", "lw": 0.5, "pad": 1.5})

    banded = False
    for name, a, b in result.regions:         # the paper's level on white and on black, where they lie
        if name in PAPER_SCAN_VOLTS:
            lo, hi = PAPER_SCAN_VOLTS[name]
            ax.fill_between([a * 1000, b * 1000], lo - 0.01, hi + 0.01, color="tab:red", alpha=0.25, lw=0,
                            label=None if banded else "paper's level (Figs. 6-9)", zorder=1)
            low = lo < 0.5 * float(np.nanmax(x))     # the label inside the axes: above a low band, below a high one
            ax.text(b * 1000 - 0.5, hi + 0.03 if low else lo - 0.06, f"paper {lo:g}-{hi:g} V", ha="right",
                    va="bottom" if low else "top", fontsize=7, color="tab:red")
            banded = True
    if banded:
        ax.legend(fontsize=7, loc="center right")
    ax.set(title="A  filtered slip-sensor output over the scan (shaded: the test surface's regions; red: "
                 "the paper's levels)", xlabel="position (mm)", ylabel="V")
    for col, name in enumerate(shown):
        a, b = regions[name]
        sel = (pos >= a + 2.5) & (pos <= b - 2.5)
        axb = fig.add_subplot(gs[1, col])
        axb.plot(pos[sel], x[sel], lw=0.8)
        base = name.split("@")[0]
        if base in PAPER_SCAN_VOLTS:
            lo, hi = PAPER_SCAN_VOLTS[base]
            axb.axhspan(lo, hi, color="tab:red", alpha=0.2, lw=0)
            seen = lo <= x[sel].max() and hi >= x[sel].min()
            axb.text(0.99, 0.02, f"paper {lo:g}-{hi:g} V (red band{'' if seen else ', off this scale'})",
                     transform=axb.transAxes, ha="right", va="bottom", fontsize=7, color="tab:red")
        axb.set(title=f"B  {name}: filtered output", ylabel="V")
        axc = fig.add_subplot(gs[2, col], sharex=axb)
        for meth, color in ((FIXED, "C0"), (DATH, "C2")):
            tr = result.analysis[meth]
            axc.plot(pos[sel], np.abs(tr.accumulator[sel]), lw=0.7, c=color, label=f"|acc| {meth}")
        # Both thresholds stay visible where they coincide (DATH rests at the fixed one):
        # DATH's as a wide pale band, the fixed one as a dashed line on top.
        axc.plot(pos[sel], result.analysis[DATH].threshold[sel], lw=3.0, c="C1", alpha=0.45,
                 label=f"threshold {DATH}", zorder=3)
        axc.plot(pos[sel], result.analysis[FIXED].threshold[sel], lw=1.0, c="C3", ls=(0, (4, 2)),
                 label=f"threshold {FIXED}", zorder=4)
        axc.set(ylabel="V")
        axc.set_title(f"C  {name}: |accumulator| and threshold (base {threshold * 1000:g} mV)", fontsize=9)
        axc.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=4, frameon=False)
        axd = fig.add_subplot(gs[3, col], sharex=axb)
        for row, meth in enumerate((FIXED, DATH)):
            ev = result.analysis[meth].events & sel
            axd.vlines(pos[ev], row + 0.1, row + 0.9, lw=0.7, color=f"C{2 * row}")
        axd.set_yticks([0.5, 1.5], ["fixed", "DATH"])
        sp = summary.min_spacing_mm
        gap = sp[(FIXED, name)]
        axd.set(xlabel="position (mm)")
        axd.set_title(f"D  {name}: spikes, fixed {summary.spikes_in[(FIXED, name)]} "
                      f"(min spacing {'-' if gap is None else format(gap, '.3f')} mm), "
                      f"DATH {summary.spikes_in[(DATH, name)]}", fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)
