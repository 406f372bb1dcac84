"""Put a reproduction's report.md into docs/reproduce.md, between its two markers.

Usage::

    slipreflex reproduce --jobs 2 --out /tmp/repro
    python -m scripts.docs.splice_report /tmp/repro/report.md

The report's sections go in one heading level down, without its title, its "Run"
heading (the run's lines stay) and its figure list (the figures are not in the docs).
Nothing of the report is edited: the docs' results are a run's output, regenerated
whenever the code changes.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parents[2] / "docs" / "reproduce.md"
BEGIN, END = "<!-- report.md begins -->", "<!-- report.md ends -->"


def sections(report: str) -> str:
    """The report's text as docs/reproduce.md carries it."""
    out: list[str] = []
    skip = False
    for line in report.splitlines():
        if line.startswith("# "):
            continue
        if line.startswith("## "):
            skip = line.strip() == "## Figures"
            if line.strip() == "## Run":
                continue
        if not skip:
            out.append("#" + line if line.startswith("## ") else line)
    return "\n".join(out).strip("\n")


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print(__doc__.strip().splitlines()[0], "\nusage: python -m scripts.docs.splice_report OUT/report.md",
              file=sys.stderr)
        return 2
    report = Path(argv[0])
    if not report.is_file():
        print(f"splice_report: {report}: no such report", file=sys.stderr)
        return 2
    error = replace_marked(DOCS, BEGIN, END, f"\n{sections(report.read_text())}\n")
    if error:
        print(f"splice_report: {error}", file=sys.stderr)
        return 2
    print(f"splice_report: {DOCS} now carries {report}")
    return 0


def replace_marked(path: Path, begin: str, end: str, body: str) -> str:
    """Put ``body`` between the markers ``begin`` and ``end`` of ``path``; an error message, or "" when done."""
    text = path.read_text()
    if text.count(begin) != 1 or text.count(end) != 1:
        return f"{path} must hold each marker once ({begin}, {end})"
    block = f"{begin}\n{body}\n{end}"
    path.write_text(re.sub(re.escape(begin) + ".*?" + re.escape(end), lambda _: block, text, flags=re.S))
    return ""


def write_marked(tool: str, path: Path, begin: str, end: str, body: str) -> int:
    """What every table script does with ``--write``: splice ``body`` in, say so; the exit status.

    A missing or repeated marker is one line on stderr, prefixed with ``tool``, and status 2.
    """
    error = replace_marked(path, begin, end, body)
    if error:
        print(f"{tool}: {error}", file=sys.stderr)
        return 2
    print(f"{tool}: wrote {path}")
    return 0


def write_section(tool: str, doc: str, name: str, body: str) -> int:
    """:func:`write_marked` for the table called ``name`` in ``doc`` (a path from the repository's top,
    e.g. ``"docs/simulator.md"``), between ``<!-- NAME begins -->`` and ``<!-- NAME ends -->``.

    A table script imports it as ``from scripts.docs.splice_report import write_section``.
    """
    root = Path(__file__).resolve().parents[2]
    return write_marked(tool, root / doc, f"<!-- {name} begins -->", f"<!-- {name} ends -->", body)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
