"""``slipreflex replay``: re-run a recorded run's chain offline and check it reproduces the run.

Examples
--------
>>> from slipreflex.cli import main
>>> main(["replay", "run.mcap"])  # doctest: +SKIP
samples 19998
events: recorded 112, replayed 112 - identical
commands: recorded 1249, replayed 1249 - identical
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import DataError
from ..recording import read_recording, replay

NAME = "replay"
HELP = "re-run the chain over a recording (MCAP) and compare with the recorded events and commands"
ORDER = 32


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex replay``."""
    add_recording_arguments(p, "replay a recording cut by a crash or with damaged chunks up to its first gap")


def run(args: argparse.Namespace) -> int:
    """Replay; exit 0 if identical, 1 if not, 2 for a partial recording without --allow-partial."""

    res = replay(read_checked(args))
    print(res.summary())
    return 0 if res.identical else 1


def add_recording_arguments(p: argparse.ArgumentParser, partial_help: str) -> None:
    """The recording to read and ``--allow-partial`` (what the command does with a partial one)."""
    p.add_argument("recording", type=Path, help="MCAP file written by 'slipreflex run'")
    p.add_argument("--allow-partial", action="store_true",
                   help=f"{partial_help} (without it, such a recording is an error naming every gap)")


def read_checked(args: argparse.Namespace):
    """The recording ``args.recording``, partial ones refused unless ``args.allow_partial``."""

    rec = read_recording(args.recording)
    check_partial(rec, args.allow_partial)
    return rec


def check_partial(rec, allow: bool) -> None:
    """A recording with gaps is an error naming them, or with ``allow`` a warning on stderr."""


    gaps = rec.gaps()
    if gaps and not allow:
        raise DataError(f"{gaps} (--allow-partial uses what was read)")
    if gaps:
        print(f"slipreflex: warning: {gaps}", file=sys.stderr, flush=True)
