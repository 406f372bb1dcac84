"""The default study's claims table in docs/study.md, from a finished study's report.

Usage::

    slipreflex study --out /tmp/study
    python -m scripts.docs.study_table /tmp/study            # print the table
    python -m scripts.docs.study_table /tmp/study --write    # and put it between docs/study.md's markers

Takes the "## Claims" table of the study's own ``study.md`` (``slipreflex.study.analyse``:
per claim its class, the fraction of plants where it holds with its Wilson interval, the
plants by verdict and the constants that decide it) and the study's one-line summary.
"""

from __future__ import annotations

import sys
from pathlib import Path


def claims_table(report: str) -> str:
    """The markdown table under the report's "## Claims" heading."""
    lines = report.splitlines()
    if "## Claims" not in lines:
        raise ValueError("the study's report has no '## Claims' section")
    rows = [x for x in lines[lines.index("## Claims") + 1:]]
    start = next(i for i, x in enumerate(rows) if x.startswith("| # |"))
    end = next((i for i, x in enumerate(rows[start:], start) if not x.startswith("|")), len(rows))
    return "\n".join(rows[start:end])


def main(argv: list[str]) -> int:
    args = [a for a in argv if a != "--write"]
    report = Path(args[0]) / "study.md" if len(args) == 1 else None
    if report is None or not report.is_file():
        print("usage: python -m scripts.docs.study_table STUDY_DIR [--write] (STUDY_DIR holds study.md)",
              file=sys.stderr)
        return 2
    body = claims_table(report.read_text())
    print(body)
    if "--write" not in argv:
        return 0
    from scripts.docs.splice_report import write_section

    return write_section("study_table", "docs/study.md", "study claims table", body)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
