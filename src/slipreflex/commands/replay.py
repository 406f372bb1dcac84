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
from pathlib import Path

NAME = "replay"
HELP = "re-run the chain over a recording (MCAP) and compare with the recorded events and commands"
ORDER = 32


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex replay``."""
    p.add_argument("recording", type=Path, help="MCAP file written by 'slipreflex run'")


def run(args: argparse.Namespace) -> int:
    """Replay; exit 0 if identical, 1 if not."""
    from ..recording import replay

    res = replay(args.recording)
    print(res.summary())
    return 0 if res.identical else 1
