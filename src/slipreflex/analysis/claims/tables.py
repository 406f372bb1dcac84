"""The claims' files and tables: claims.csv, claim_parts.csv, Markdown, the terminal, one claim explained.

Re-exported by :mod:`slipreflex.analysis.claims`.

Examples
--------
>>> CLAIMS_CSV_COLUMNS[:3]
('claim', 'verdict', 'qualifier')
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ...files.paths import new_file
from .judging import CLAIMS
from .verdicts import VERDICTS, ClaimResult

__all__ = [
    "CLAIMS_CSV_COLUMNS", "PARTS_CSV_COLUMNS", "write_claims_csv", "write_parts_csv", "read_claims_csv",
    "claims_markdown", "parts_markdown", "claims_terminal", "explain"
]


#: Columns of claims.csv (``reproduce``, ``claims`` and, with a study's counts, ``study``).
CLAIMS_CSV_COLUMNS: tuple[str, ...] = ("claim", "verdict", "qualifier", "parts", "reason", "value", "criterion",
                                       "low", "high", "text", "where", "numbers")
#: Columns of claim_parts.csv: one row per part of every claim.
PARTS_CSV_COLUMNS: tuple[str, ...] = ("claim", "part", "primary", "verdict", "qualifier", "value", "low", "high",
                                      "criterion", "reason")


def _cell(v: Any) -> str:
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    return "" if v is None else str(v)


def write_claims_csv(path: str | Path, results: Sequence[Any], columns: Sequence[str] = CLAIMS_CSV_COLUMNS
                     ) -> Path:
    """Write the claims table as CSV (one row per claim; NaN as an empty cell).

    The file appears under its name only when complete (an earlier one is replaced, a symlink of
    that name replaced, not followed: :func:`slipreflex.files.paths.new_file`).

    ``results`` holds :class:`ClaimResult` s or mappings with the columns.

    Examples
    --------
    >>> from slipreflex.analysis.claims import judge
    >>> import tempfile, pathlib
    >>> p = write_claims_csv(pathlib.Path(tempfile.mkdtemp()) / "claims.csv", judge([]))
    >>> p.read_text().splitlines()[0]
    'claim,verdict,qualifier,parts,reason,value,criterion,low,high,text,where,numbers'
    """
    path = Path(path)
    with new_file(path, "w", replace=True) as fh:   # complete or not there, never through a link
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(columns)
        for r in results:
            if isinstance(r, Mapping):
                d = r
            else:
                d = {c: getattr(r, "number" if c == "claim" else c, "") for c in columns if c != "parts"}
                d["parts"] = r.parts_text()
            w.writerow([_cell(d.get(c, "")) for c in columns])
    return path


def write_parts_csv(path: str | Path, results: Sequence[ClaimResult]) -> Path:
    """Write claim_parts.csv: every part of every claim with its class, interval and reason.

    Examples
    --------
    >>> from slipreflex.analysis.claims import judge
    >>> import tempfile, pathlib
    >>> p = write_parts_csv(pathlib.Path(tempfile.mkdtemp()) / "claim_parts.csv", judge([]))
    >>> p.read_text().splitlines()[1].split(",")[:4]
    ['1', 'scan levels', 'True', 'not-decidable']
    """
    path = Path(path)
    with new_file(path, "w", replace=True) as fh:   # complete or not there, never through a link
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(PARTS_CSV_COLUMNS)
        for r in results:
            for p in r.parts:
                w.writerow([_cell(x) for x in (r.number, p.label, str(p.primary), p.verdict, p.qualifier, p.value,
                                               p.low, p.high, p.criterion, p.reason)])
    return path


def read_claims_csv(path: str | Path) -> list[dict[str, str]]:
    """The rows of a claims.csv as dicts of strings.

    Examples
    --------
    >>> from slipreflex.analysis.claims import judge
    >>> import tempfile, pathlib
    >>> p = write_claims_csv(pathlib.Path(tempfile.mkdtemp()) / "c.csv", judge([]))
    >>> read_claims_csv(p)[0]["verdict"]
    'not-decidable'
    """
    with Path(path).open(newline="") as fh:
        return list(csv.DictReader(fh))


def _value(r: Any) -> str:
    if r.value != r.value:
        return "-"
    v = f"{r.value:.3g}"
    return v if r.low != r.low else f"{v} [{r.low:.3g}, {r.high:.3g}]"


def claims_markdown(results: Sequence[ClaimResult]) -> str:
    """The claims table as markdown (claim, where, class, parts, reason, value and interval, criterion).

    Examples
    --------
    >>> from slipreflex.analysis.claims import judge
    >>> claims_markdown(judge([])).splitlines()[2].startswith('| 1 | "oscillated around')
    True
    """
    lines = ["| # | the paper says | where | class | parts (* primary) | reason | value [interval] | criterion |",
             "|---|---|---|---|---|---|---|---|"]
    for r in results:
        lines.append(f"| {r.number} | {r.text} | {r.where} | **{r.class_text}** | {r.parts_text()} | {r.reason} | "
                     f"{_value(r)} | {r.criterion or '-'} |")
    return "\n".join(lines)


def parts_markdown(results: Sequence[ClaimResult]) -> str:
    """Every part of every claim as markdown (claim, part, primary, class, value, reason).

    Examples
    --------
    >>> from slipreflex.analysis.claims import judge
    >>> parts_markdown(judge([])).splitlines()[2].startswith("| 1 | scan levels | yes | not-decidable")
    True
    """
    lines = ["| # | part | primary | class | value [interval] | reason |", "|---|---|---|---|---|---|"]
    for r in results:
        for p in r.parts:
            lines.append(f"| {r.number} | {p.label or '-'} | {'yes' if p.primary else 'no'} | "
                         f"{p.verdict}{f' ({p.qualifier})' if p.qualifier else ''} | {_value(p)} | {p.reason} |")
    return "\n".join(lines)


def _counts(results: Sequence[ClaimResult]) -> str:
    n = {v: sum(r.verdict == v for r in results) for v in VERDICTS}
    return ", ".join(f"{n[v]} {v}" for v in VERDICTS if n[v]) or "none"


def claims_terminal(results: Sequence[ClaimResult]) -> str:
    """The claims table for the terminal: per claim, its class and short quote, its parts, its reason.

    Examples
    --------
    >>> from slipreflex.analysis.claims import judge
    >>> print(claims_terminal(judge([])).splitlines()[0])
    paper's claims: 1 fails-paper, 10 not-decidable
    """
    lines = [f"paper's claims: {_counts(results)}"]
    for r in results:
        lines += [f"{r.number:>3} {r.class_text:18} {r.text} ({r.where})", f"{'':22}parts: {r.parts_text()}",
                  f"{'':22}{r.reason}"]
    return "\n".join(lines)


def explain(result: ClaimResult) -> str:
    """One claim in full: the paper's whole sentence, where, the reading, the tolerance, every part.

    Examples
    --------
    >>> from slipreflex.analysis.claims import judge
    >>> print(explain(judge([])[10]).splitlines()[0])
    claim 11 (III-B, III-C, Figs. 14, 17): fails-paper
    """
    claim = {c.number: c for c in CLAIMS}[result.number]
    lines = [f"claim {result.number} ({result.where}): {result.class_text}", f"  the paper: {claim.quote}",
             f"  judged: {claim.reading}", f"  tolerance: {claim.tolerance}",
             "  class: the first, in the order " + ", ".join(VERDICTS) + ", among the primary parts", "  parts:"]
    for p in result.parts:
        lines.append(f"    [{p.label or '-'}]{' (primary)' if p.primary else ''} "
                     f"{p.verdict}{f' ({p.qualifier})' if p.qualifier else ''}: {p.reason}")
    return "\n".join(lines)


