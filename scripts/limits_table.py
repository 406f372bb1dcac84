"""Put the table of plausible ranges (``slipreflex.core.validation.LIMITS``) into docs/runtime.md.

Usage::

    python scripts/limits_table.py           # print the table
    python scripts/limits_table.py --write   # and write it between docs/runtime.md's markers

``tests/test_limits.py`` fails when the docs' copy differs from the code's table.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs" / "runtime.md"
BEGIN, END = "<!-- limits table begins -->", "<!-- limits table ends -->"


def main(argv: list[str]) -> int:
    sys.path.insert(0, str(ROOT / "scripts"))
    from splice_report import write_marked

    from slipreflex.core.validation import limits_markdown

    table = limits_markdown()
    print(table)
    return write_marked("limits_table", DOCS, BEGIN, END, table) if "--write" in argv else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
