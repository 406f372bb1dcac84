"""Put the table of plausible ranges (``slipreflex.core.validation.LIMITS``) into docs/runtime.md.

Usage::

    python -m scripts.docs.limits_table           # print the table
    python -m scripts.docs.limits_table --write   # and write it between docs/runtime.md's markers

``tests/journeys/test_limits.py`` fails when the docs' copy differs from the code's table.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "runtime.md"
BEGIN, END = "<!-- limits table begins -->", "<!-- limits table ends -->"


def main(argv: list[str]) -> int:
    from scripts.docs.splice_report import write_marked
    from slipreflex.core.validation import limits_markdown

    table = limits_markdown()
    print(table)
    return write_marked("limits_table", DOCS, BEGIN, END, table) if "--write" in argv else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
