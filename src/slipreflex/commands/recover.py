"""``slipreflex recover``: rewrite a recording cut by a crash (or damaged) as a complete MCAP file.

A run killed mid-way (SIGKILL, power loss) leaves an MCAP file without its
summary and footer: slipreflex's own reader reads it, but mcap's standard
readers (``mcap.reader.make_reader``, the ``mcap`` command-line tool) need the
footer. ``recover`` reads every readable record (skipping damaged chunks, up
to the last complete one) and writes them to a new, complete file; the
original is never changed, an existing file is never replaced, and a file with no
readable message is an error (exit 2, nothing written).

Examples
--------
>>> from slipreflex.cli import main
>>> main(["recover", "run.mcap"])  # doctest: +SKIP
recovered 41214 messages (metadata: slipreflex, start) to run-recovered.mcap
run.mcap: read 2061 of the 6667 samples it should hold; cut short at byte 101236 (a crash?)
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..files.recording import PART_SUFFIX, recover_recording

NAME = "recover"
HELP = "rewrite a recording cut by a crash as a complete MCAP file that any MCAP reader opens"
ORDER = 34


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex recover``."""
    p.add_argument("recording", type=Path, help="MCAP file written by 'slipreflex run'")
    p.add_argument("-o", "--out", type=Path, default=None,
                   help="complete MCAP file to write (default: REC-recovered.mcap beside it)")


def run(args: argparse.Namespace) -> int:
    """Recover; print what was written and what is missing."""

    out = args.out or default_out(args.recording)
    res = recover_recording(args.recording, out)
    print(f"recovered {res.messages} messages (metadata: {', '.join(res.metadata) or 'none'}) to {out}")
    if res.gaps:
        print(res.gaps)
    return 0


def default_out(recording: Path) -> Path:
    """``REC-recovered.mcap`` beside ``REC`` (for ``REC.mcap.part``, a crashed run's file: ``REC-recovered.mcap``).

    Examples
    --------
    >>> default_out(Path("d/run-1.mcap.part")).as_posix()
    'd/run-1-recovered.mcap'
    """

    name = recording.name[:-len(PART_SUFFIX)] if recording.name.endswith(PART_SUFFIX) else recording.name
    stem = name[:-len(".mcap")] if name.endswith(".mcap") else Path(name).stem
    return recording.with_name(f"{stem}-recovered.mcap")
