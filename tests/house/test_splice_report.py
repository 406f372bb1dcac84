"""scripts/docs/splice_report.py carries a run's report.md into docs/reproduce.md unedited."""

import runpy
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = runpy.run_path(str(ROOT / "scripts" / "docs" / "splice_report.py"))


def test_sections_drop_title_run_heading_and_figures_and_demote_the_rest():
    report = ("# title\n\n## Run\n\n- seed 1\n\n## Claims\n\nclaim text\n\n## Figures\n\n![a](figures/a.png)\n\n"
              "## Why\n\nbecause\n")
    text = SCRIPT["sections"](report)
    assert text.splitlines()[0] == "- seed 1"
    assert "### Claims" in text and "### Why" in text and "because" in text
    assert "Figures" not in text and "figures/a.png" not in text and "# title" not in text


def test_docs_hold_each_marker_once():
    docs = (ROOT / "docs" / "reproduce.md").read_text()
    assert docs.count(SCRIPT["BEGIN"]) == 1 and docs.count(SCRIPT["END"]) == 1
    assert docs.index(SCRIPT["BEGIN"]) < docs.index(SCRIPT["END"])
