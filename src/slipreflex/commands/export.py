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

NAME = "export"
HELP = "write a recording's samples as CSV (t in s, x in V) that 'slipreflex detect' reads"
ORDER = 33


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex export``."""
    p.add_argument("recording", type=Path, help="MCAP file written by 'slipreflex run'")
    p.add_argument("-o", "--out", type=Path, default=None, help="CSV to write (default: REC.csv)")
    p.add_argument("--all", action="store_true",
                   help="also write REC-imu/-flow/-events/-windows/-commands/-faults.csv")
    p.add_argument("--allow-partial", action="store_true",
                   help="export what was read from a recording cut by a crash or with damaged chunks "
                        "(without it, such a recording is an error naming every gap)")


def run(args: argparse.Namespace) -> int:
    """Export; print the files written (exit 2 for a partial recording without --allow-partial)."""
    from ..recording import export_csv, read_recording
    from .replay import check_partial

    rec = read_recording(args.recording)
    check_partial(rec, args.allow_partial)
    for name in export_csv(rec, args.out, all_streams=args.all):
        print(f"wrote {name}")
    return 0
