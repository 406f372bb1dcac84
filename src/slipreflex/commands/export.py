"""``slipreflex export``: a recording's slip-sensor samples as CSV (columns t, x) for ``detect``.

Examples
--------
>>> from slipreflex.cli import main
>>> main(["export", "run.mcap"])  # doctest: +SKIP
wrote run.csv
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..files.recording import export_csv
from .replay import add_recording_arguments, read_checked

NAME = "export"
HELP = "write a recording's samples as CSV (t in s, x in V) that 'slipreflex detect' reads"
ORDER = 33


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex export``."""
    p.add_argument("-o", "--out", type=Path, default=None, help="CSV to write (default: REC.csv)")
    p.add_argument("--all", action="store_true",
                   help="also write REC-imu/-flow/-events/-windows/-commands/-faults.csv")
    add_recording_arguments(p, "export what was read from a recording cut by a crash or with damaged chunks")


def run(args: argparse.Namespace) -> int:
    """Export; print the files written (exit 2 for a partial recording without --allow-partial)."""

    rec = read_checked(args)
    for name in export_csv(rec, args.out, all_streams=args.all):
        print(f"wrote {name}")
    return 0
