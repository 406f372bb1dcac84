"""docs/speed.md's block on ``slipreflex study --plants 1000``, from a finished run's folder and its timing.

Usage::

    python -m scripts.docs.large_study FOLDER            # print the block
    python -m scripts.docs.large_study FOLDER --write    # ... and put it between docs/speed.md's markers

FOLDER is the study's ``--out``, holding ``timing.json`` (wall and CPU seconds of the command and its
children, the load before it): ``python -m scripts.regenerate --with-large-study`` runs the study
timed and then this script. The block gives the time against the 15 minutes aimed at on 2 cores, the
plants computed, accepted and rejected (and why), and each claim's holding fraction with its interval,
as the study printed them.

Examples
--------
>>> minutes(662.1)
'11 min 2 s'
"""

from __future__ import annotations

import csv
import datetime
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "speed.md"
BEGIN, END = "<!-- large study begins -->", "<!-- large study ends -->"
#: The command timed (what ``scripts/regenerate.py``'s "large study" step runs) and the time aimed at (s).
COMMAND = "slipreflex study --plants 1000 --workers 2 --no-progress"
TARGET_S = 15 * 60.0


def minutes(s: float) -> str:
    """``"11 min 2 s"``."""
    return f"{int(s // 60)} min {s % 60:.0f} s"


def block(folder: Path, machine: str) -> str:
    """The block's text from ``folder``'s timing.json, plants.csv and claims.csv."""
    timing = json.loads((folder / "timing.json").read_text())
    with open(folder / "plants.csv", newline="") as fh:
        plants = list(csv.DictReader(fh))
    with open(folder / "claims.csv", newline="") as fh:
        claims = list(csv.DictReader(fh))
    from slipreflex.sim.calibration import pinned  # deferred: heavy (numba kernels), for this one block

    errors = sum(1 for p in plants if p.get("error"))
    rejected = [p.get("rejected", "") for p in plants if p.get("rejected")]
    n_pinned = sum(1 for why in rejected if pinned(why))
    accepted = len(plants) - errors - len(rejected)
    cpu = timing["user_s"] + timing["sys_s"]
    verdict = "under" if timing["wall_s"] < TARGET_S else "**over**"
    rows = [f"| {c['claim']} | {c['verdict']} | {100 * float(c['value']):.0f} % | "
            f"{100 * float(c['low']):.0f}-{100 * float(c['high']):.0f} % |" for c in claims]
    return "\n".join([
        f"Measured on {datetime.date.today().isoformat()} by `python -m scripts.regenerate --with-large-study` "
        f"(`scripts/docs/large_study.py`) on {machine}; load {timing['load']:.2f} when it started. "
        f"`{COMMAND}` (figures included) took **{minutes(timing['wall_s'])}** wall, {verdict} the 15 minutes "
        f"aimed at, and {cpu:.0f} CPU-s ({timing['user_s']:.0f} user + {timing['sys_s']:.0f} system). "
        f"{len(plants)} plants, {errors} with errors; {accepted} accepted and {len(rejected)} rejected by their "
        f"calibration ({n_pinned} of them because the accelerometer sees the cuff's slip at the same volume "
        "whatever the pads' friction, the others because no friction puts their observed first slip inside "
        "the paper's range). The claims, as the study printed them (the fraction of accepted plants on which "
        "each holds, with its 95 % Wilson interval):",
        "",
        "| claim | class | holds on | 95 % interval |",
        "|---|---|---|---|",
        *rows,
    ])


def main(argv: list[str]) -> int:
    from benchmarks.machine import describe

    from scripts.docs.splice_report import write_marked

    args = [a for a in argv if not a.startswith("--")]
    if len(args) != 1 or not (Path(args[0]) / "timing.json").is_file():
        print("large_study: give the folder of a finished, timed `slipreflex study --plants 1000` "
              "(python -m scripts.regenerate --with-large-study makes one)", file=sys.stderr)
        return 2
    text = block(Path(args[0]), describe())
    print(text)
    return write_marked("large_study", DOC, BEGIN, END, text) if "--write" in argv else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
