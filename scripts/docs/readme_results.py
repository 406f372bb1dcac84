"""The README's "what comes out" table, from a reproduction's summary.csv.

Usage::

    slipreflex reproduce --jobs 2 --out /tmp/repro
    python -m scripts.docs.readme_results /tmp/repro/summary.csv            # print the table
    python -m scripts.docs.readme_results /tmp/repro/summary.csv --write    # put it into README.md

The table goes between the README's two markers; every value comes from the run's
summary (DATH unless the row says otherwise), the paper's column from
:mod:`slipreflex.analysis.paper`, and the open-loop first slip from
:func:`slipreflex.sim.calibration.first_slip_ml` on the paper's bottles. The run's
``claims.csv`` beside the summary gives the claims' verdict table between its own markers.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

README = Path(__file__).resolve().parents[2] / "README.md"
BEGIN, END = "<!-- results table begins -->", "<!-- results table ends -->"
CLAIMS_BEGIN, CLAIMS_END = "<!-- claims table begins -->", "<!-- claims table ends -->"


def claims_table(claims: list[dict]) -> str:
    """The claims' classes as a markdown table (where, class, the parts that hold) from a claims.csv's rows."""
    def short(text: str, most: int = 48) -> str:
        return text if len(text) <= most else text[:most].rsplit(" ", 1)[0] + ' ..."'

    lines = ["| # | the paper says | class | parts that hold (* primary) |", "|---|---|---|---|"]
    for r in claims:
        cls = r["verdict"] + (f" ({r['qualifier']})" if r.get("qualifier") else "")
        parts = [p.rsplit(" ", 1) for p in r.get("parts", "").split("; ") if " " in p]
        held = [name for name, v in parts if v == "holds"]
        lines.append(f"| {r['claim']} | {short(r['text'])} | {cls} | "
                     f"{', '.join(held) or 'none'} ({len(held)} of {len(parts)}) |")
    return "\n".join(lines)


def _cells(summary: list[dict], experiment: str, method: str) -> dict[str, dict]:
    return {r["bottle"]: r for r in summary if r["experiment"] == experiment and r["method"] == method}


def _ms(value: str) -> str:
    return "-" if value in ("", "nan") else f"{float(value):.0f}"


def _pooled_success(summary: list[dict], experiment: str, method: str) -> float:
    rows = [r for r in summary if r["experiment"] == experiment and r["method"] == method and r["event_success_n"]]
    n = sum(int(r["event_success_n"]) for r in rows)
    return sum(float(r["event_success_rate"]) * int(r["event_success_n"]) for r in rows) / n if n else float("nan")


def table(summary: list[dict], first_slip: dict[str, float]) -> str:
    """The markdown table (bottles in the paper's order)."""
    from slipreflex import methods
    from slipreflex.analysis.paper import BOTTLE_ORDER, PAPER_SUCCESS, paper_value

    dath = methods.DATH
    bottles = [b for b in BOTTLE_ORDER if any(r["bottle"] == b for r in summary)]
    names = " / ".join(bottles)
    lines = ["| | ours | paper |", "|---|---|---|"]
    for e, what in (("drop", "response"), ("pour", "response"), ("drop", "total"), ("pour", "total")):
        cells = _cells(summary, e, dath)
        ours = " / ".join(_ms(cells.get(b, {}).get(f"{what}_mean_ms", "")) for b in bottles)
        paper = " / ".join(f"{v.mean:g}" if (v := paper_value(e, f"{what}_ms", b, dath)) and v.mean is not None
                           else "-" for b in bottles)
        label = "response" if what == "response" else "total controller time"
        lines.append(f"| {e} {label}, ms ({names}) | {ours} | {paper} |")
    present = [m for m in methods.names() if any(r["method"] == m for r in summary)]
    for e in ("drop", "pour"):
        rates = " / ".join(f"{100 * _pooled_success(summary, e, m):.0f}" for m in present)
        said = ", ".join(f"{methods.label(m)} {PAPER_SUCCESS[(e, 'all', m)]}" for m in present
                         if (e, "all", m) in PAPER_SUCCESS)
        lines.append(f"| {e} success per slip event, {' / '.join(methods.label(m) for m in present)} (all bottles) | "
                     f"{rates} % | {said or '-'} |")
    slip = " / ".join(f"{first_slip[b]:.0f}" for b in bottles)
    lines.append(f"| open-loop first pour slip, ml ({names}; calibrated, not a result) | {slip} | ~200 |")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    args = [a for a in argv if a != "--write"]
    if len(args) != 1 or not Path(args[0]).is_file():
        print("usage: python -m scripts.docs.readme_results OUT/summary.csv [--write]", file=sys.stderr)
        return 2
    from slipreflex.sim import BOTTLES
    from slipreflex.sim.calibration import first_slip_ml

    with open(args[0], newline="") as fh:
        summary = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    text = table(summary, {b: first_slip_ml(BOTTLES[b]) for b in BOTTLES})
    claims_csv = Path(args[0]).parent / "claims.csv"
    claims = claims_table(list(csv.DictReader(claims_csv.open(newline="")))) if claims_csv.is_file() else None
    if "--write" not in argv:
        print(text + ("\n\n" + claims if claims else ""))
        return 0
    from scripts.docs.splice_report import write_marked

    status = write_marked("readme_results", README, BEGIN, END, text)
    if not status and claims:
        status = write_marked("readme_results", README, CLAIMS_BEGIN, CLAIMS_END, claims)
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
