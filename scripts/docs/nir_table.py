"""The NIR graphs' distance to Eq. 1-9 (docs/method.md) and per backend (docs/neuromorphic.md).

Usage::

    python -m scripts.docs.nir_table                 # print both agreement tables
    python -m scripts.docs.nir_table --write         # and write them between the docs' markers
    slipreflex reproduce --methods fixed,nir --trials 3 --jobs 2 --no-figures --out /tmp/nir
    python -m scripts.docs.nir_table --loop /tmp/nir/summary.csv --write   # the closed-loop table

The agreement tables run ``slipreflex.neuro.agreement`` on the shipped recordings and the
simulated drops and pours, in every backend installed (the package's executor, Spyx, Nengo).
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _loop_table(summary: Path) -> str:
    from scripts.docs.method_table import cell

    rows = list(csv.DictReader(summary.read_text().splitlines()))
    keys = sorted({(r["experiment"], r["bottle"]) for r in rows})
    by = {(r["experiment"], r["bottle"], r["method"]): r for r in rows}
    lines = ["| experiment | bottle | fixed (chain) | nir (graph) |", "|---|---|---|---|"]
    for exp, bottle in keys:
        cells = [cell(by[(exp, bottle, m)]) if (exp, bottle, m) in by else "-" for m in ("fixed", "nir")]
        lines.append(f"| {exp} | {bottle} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    from scripts.docs.splice_report import write_section

    write = "--write" in argv
    if "--loop" in argv:
        table = _loop_table(Path(argv[argv.index("--loop") + 1]))
        print(table)
        return write_section("nir_table", "docs/neuromorphic.md", "nir loop table", table) if write else 0

    from slipreflex.neuro import agreement as ag
    from slipreflex.neuro.backends import BACKENDS, available

    backends = [b for b in BACKENDS if available(b)]
    sigs = ag.signals()
    rows = [ag.compare(s, g, b) for g in ag.GRAPHS for b in backends for s in sigs]
    stages, per_backend = ag.stage_table(rows), ag.table(rows)
    print(stages, per_backend, sep="\n\n")
    if not write:
        return 0
    return (write_section("nir_table", "docs/method.md", "nir stages table", stages)
            or write_section("nir_table", "docs/neuromorphic.md", "nir backends table", per_backend))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
