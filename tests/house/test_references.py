"""Every reference in the repository resolves inside it: no outside specification, design note or tracker number."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
# Documents that live outside the repository, and tracker numbers a reader cannot follow.
OUTSIDE = re.compile(r"\bSPEC\b|\bARCHITECTURE\b|shared/|(?i:\bissues?[- ]?[0-9]+)")


def _tracked_text_files() -> list[Path]:
    listed = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True)
    if listed.returncode != 0:  # not a git checkout (an unpacked sdist): every file is the package's
        return [p for p in ROOT.rglob("*") if p.is_file() and ".venv" not in p.parts and ".git" not in p.parts]
    return [ROOT / name for name in listed.stdout.splitlines()]


def test_no_reference_leads_outside_the_repository():
    hits = []
    for path in _tracked_text_files():
        if path.suffix in {".png", ".hex", ".elf", ".mcap", ".pdf"} or not path.is_file():
            continue
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue
        for number, line in enumerate(text.splitlines(), 1):
            if OUTSIDE.search(line) and path.name != "test_references.py":
                hits.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()[:100]}")
    assert not hits, "references that lead outside the repository:\n" + "\n".join(hits)


def test_the_pattern_catches_the_ways_a_tracker_number_is_written():
    for text in ("see issue 12", "the issue-12 count", "issues 19", "Issue 11 item 16: ..."):
        assert OUTSIDE.search(text), text
    assert not OUTSIDE.search("pyserial issue #281 (a public tracker)")


def test_the_specification_sections_cited_exist():
    method = (ROOT / "docs" / "method.md").read_text(encoding="utf-8")
    sections = set(re.findall(r"^#{2,3} (\d+(?:\.\d+)?)[. ]", method, flags=re.M))
    cited = set()
    for path in _tracked_text_files():
        if path.suffix not in {".py", ".md", ".c", ".h", ".toml"} or not path.is_file():
            continue
        text = path.read_text(encoding="utf-8", errors="replace")
        cited |= set(re.findall(r"method\.md,? sections? (\d+(?:\.\d+)?)", text))
    assert cited, "no section of docs/method.md is cited (the pattern no longer matches the citations)"
    assert cited <= sections, f"docs/method.md has no section {sorted(cited - sections)}"
