"""``slipreflex spikes``: the spikes of a recording, a CSV, a trial file or a simulated trial, as event files.

Formats: AEDAT4 (``--format aedat4``), a tonic-readable ``.npy`` of tonic's ``events_struct``
(``--format tonic``), NIR event data (``--format nir``); several at once with commas.

Examples
--------
>>> from slipreflex.cli import main
>>> main(["spikes", "examples/slip_example.csv", "--format", "tonic", "-o", "slip"])   # doctest: +SKIP
wrote slip.npy (44 events, 1 x 1 pixels)
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from ..benchmark import read_trial
from ..core.errors import ParameterError
from ..files.csvfiles import read_preamble, read_slip_csv
from ..files.recording import read_recording
from ..neuro import events as ev
from ..neuro.events import FORMATS, sensor_size, write_events
from ..rig.replay import chain_params_of

NAME = "spikes"
HELP = "write spikes as AEDAT4, tonic's events_struct (.npy) or NIR event data"
ORDER = 34


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex spikes``."""
    p.add_argument("source", type=Path, nargs="?", default=None,
                   help="a CSV of slip-sensor volts (what 'detect' reads), an MCAP recording of 'run' (its "
                        "samples replayed through its own chain), or a recorded tactile trial (a CSV with a "
                        "'# layout' line: every taxel encoded)")
    p.add_argument("--simulate", choices=("drop", "pour"), default=None,
                   help="instead of SOURCE: an open-loop simulated trial with the paper's drop or pour")
    p.add_argument("--bottle", default="TR", help="--simulate: the bottle (TR, DK, TX; default TR)")
    p.add_argument("--seed", type=int, default=0, help="--simulate: the seed (0)")
    p.add_argument("--format", default="aedat4,tonic,nir",
                   help="comma-separated: aedat4, tonic, nir (default: all three)")
    p.add_argument("-o", "--out", type=Path, required=True,
                   help="output path without suffix; each format adds its own (.aedat4, .npy, .nir-events.h5)")
    p.add_argument("--dath", action="store_true", help="a CSV or simulated trial: the DATH chain (default fixed)")
    p.add_argument("--threshold", type=float, default=None,
                   help="the encoder's threshold: V for the slip sensor (default 0.008), the trial's unit "
                        "for taxels (needed for a tactile trial)")


def _formats(text: str) -> list[str]:
    names = [f.strip() for f in text.split(",") if f.strip()]
    bad = [f for f in names if f not in FORMATS]
    if bad or not names:
        raise ParameterError(f"--format: {', '.join(bad) or 'none given'} (known: {', '.join(FORMATS)})")
    return names


def _events(args: argparse.Namespace) -> np.ndarray:
    if (args.source is None) == (args.simulate is None):
        raise ParameterError("give a SOURCE file or --simulate drop|pour (one of them)")
    chain = {"dath": args.dath, **({"threshold": args.threshold} if args.threshold is not None else {})}
    if args.simulate is not None:
        t, volts = simulated_trial(args.simulate, args.bottle, args.seed)
        return ev.chain_events(volts, t, **chain)
    src: Path = args.source
    if not src.is_file():
        raise ParameterError(f"{src}: no such file")
    if src.suffix == ".mcap":
        rec = read_recording(src)
        samples = rec.topic("/daq/samples")
        raw = np.array([np.nan if s["slip_volts"] is None else s["slip_volts"] for s in samples], dtype=float)
        return ev.chain_events(raw, [s["t"] for s in samples], chain_params_of(rec))
    if "layout" in read_preamble(src):
        if args.threshold is None:
            raise ParameterError(f"{src} is a tactile trial: give --threshold in its unit (its taxels' counts)")
        trial = read_trial(src)
        return ev.taxel_events(trial.normal_frames(), trial.t, args.threshold)
    t, x = read_slip_csv(src)
    return ev.chain_events(x, t, **chain)


def simulated_trial(kind: str, bottle: str, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """An open-loop simulated trial: the grasp, 1 s at rest, the paper's drop or pour, 3 s after; (t, volts)."""
    from ..sim import PAPER_DROP, PAPER_POUR, Rig, simulate_open_loop  # deferred: heavy (numba kernels)

    rig = Rig(bottle, seed=seed)
    rig.grasp()
    what = PAPER_DROP if kind == "drop" else PAPER_POUR
    rig.perturb(what, at=rig.t + 1.0)
    length = 3.0 if kind == "drop" else PAPER_POUR.volume_ml / 1000 / PAPER_POUR.rate_l_min * 60 + 3.0
    tr = simulate_open_loop(rig, length)
    return np.asarray(tr.t), np.asarray(tr.volts)


def run(args: argparse.Namespace) -> int:
    """Check every output first, then read, encode and write."""
    fmts = _formats(args.format)
    targets = {f: args.out.with_name(args.out.name + FORMATS[f]) for f in fmts}
    for target in targets.values():              # every destination checked before any work
        if os.path.lexists(target):  # a dangling symlink too: the writers would follow it
            raise ParameterError(f"{target}: exists; spikes writes new files (give another -o)")
        if not target.parent.is_dir():
            raise ParameterError(f"{target.parent}: no such folder")
    events = _events(args)
    size = sensor_size(events)
    for fmt, target in targets.items():
        write_events(events, target, fmt)
        print(f"wrote {target} ({events.size} events, {size[0]} x {size[1]} pixels)")
    return 0
