"""scripts/docs/readme_results.py builds the README's results table from a run's summary."""

import runpy
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = runpy.run_path(str(ROOT / "scripts" / "docs" / "readme_results.py"))


def _row(e, b, m, resp, total, rate, n):
    return {"experiment": e, "bottle": b, "method": m, "response_mean_ms": resp, "total_mean_ms": total,
            "event_success_rate": rate, "event_success_n": n}


def test_table_reads_dath_cells_and_pools_success_over_bottles():
    summary = [_row("drop", "TR", "dath", "61.4", "80", "1.0", "10"),
               _row("drop", "TX", "dath", "40", "", "0.5", "10"),
               _row("drop", "TR", "fixed", "70", "90", "0.0", "5"),
               _row("drop", "TX", "fixed", "70", "90", "1.0", "15")]
    text = SCRIPT["table"](summary, {"TR": 199.6, "TX": 201.2})
    assert "| drop response, ms (TR / TX) | 61 / 40 | 50 / 31.3 |" in text
    assert "| drop total controller time, ms (TR / TX) | 80 / - |" in text
    assert "| 75 / 75 % |" in text                      # DATH 15 of 20, fixed 15 of 20 pooled
    assert "| 200 / 201 | ~200 |" in text


def test_readme_holds_each_marker_once():
    readme = (ROOT / "README.md").read_text()
    assert readme.count(SCRIPT["BEGIN"]) == 1 and readme.count(SCRIPT["END"]) == 1


def test_claims_table_from_a_claims_csv():
    rows = [{"claim": "3", "text": '"decreased"', "where": "III-B", "verdict": "fails-definition", "qualifier": "",
             "parts": "TR* holds", "value": "0.0", "low": "0.0", "high": "0.0"},
            {"claim": "1", "text": '"300 to 500 mV"', "where": "III-A", "verdict": "not-decidable",
             "qualifier": "calibrated input", "parts": "scan levels* not-decidable", "value": "", "low": "",
             "high": ""},
            {"claim": "5", "text": "twice", "verdict": "fails-plant", "value": "0.4213", "low": "0.28", "high": "0.65"}]
    text = SCRIPT["claims_table"](rows)
    assert '| 3 | "decreased" | fails-definition | TR* (1 of 1) |' in text
    assert '| 1 | "300 to 500 mV" | not-decidable (calibrated input) | none (0 of 1) |' in text
    readme = (ROOT / "README.md").read_text()
    assert readme.count(SCRIPT["CLAIMS_BEGIN"]) == 1 and readme.count(SCRIPT["CLAIMS_END"]) == 1
