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


def run(args: argparse.Namespace) -> int:
    """Export; print the files written."""
    from ..recording import export_csv

    for name in export_csv(args.recording, args.out, all_streams=args.all):
        print(f"wrote {name}")
    return 0
