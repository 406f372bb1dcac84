"""The table of the chain's variants in docs/method.md, from a reproduction's summary.csv.

Usage::

    slipreflex reproduce --methods fixed,dath,nmsd,swt,authors-gui,authors-chain,dath-event,dath-floor,dath-leak \\
        --trials 3 --jobs 2 --no-figures --out /tmp/methods
    python -m scripts.docs.method_table /tmp/methods/summary.csv

Each cell: the response time in ms, mean ± sd (slip events that got a response); then the
success per trial where it is not 100 %; "-" where no slip got a response, "- (no slip)"
where the accelerometer found none.
"""

from __future__ import annotations

import sys
from pathlib import Path

#: The columns, in the docs' order.
ORDER = ("dath", "fixed", "dath-event", "dath-floor", "dath-leak", "authors-gui", "authors-chain", "nmsd", "swt")


def _num(x: str) -> float:
    return float(x) if x not in ("", None) else float("nan")


def cell(s: dict) -> str:
    """One method's cell for one experiment and bottle."""
    mean, sd, n = _num(s["response_mean_ms"]), _num(s["response_sd_ms"]), int(s["response_n"] or 0)
    if n == 0:
        text = "- (no slip)" if int(s["n_events"] or 0) == 0 else "-"
    elif n == 1 or sd != sd:
        text = f"{mean:.0f} ({n})"
    else:
        text = f"{mean:.0f} ± {sd:.0f} ({n})"
    rate = _num(s["trial_success_rate"])
    return text if rate == 1.0 else f"{text}, {100 * rate:.0f} %"


def table(summary: list[dict]) -> str:
    """The markdown table."""
    from slipreflex import methods
    from slipreflex.analysis.paper import BOTTLE_ORDER

    by = {(r["experiment"], r["bottle"], r["method"]): r for r in summary}
    present = [m for m in ORDER if any(k[2] == m for k in by)]
    lines = ["| experiment | bottle | " + " | ".join(methods.label(m) for m in present) + " |",
             "|---|---|" + "---|" * len(present)]
    for e in ("drop", "pour"):
        for b in BOTTLE_ORDER:
            if any(k[:2] == (e, b) for k in by):
                cells = [cell(by[(e, b, m)]) if (e, b, m) in by else "not run" for m in present]
                lines.append(f"| {e} | {b} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    write = "--write" in argv
    argv = [a for a in argv if a != "--write"]
    if len(argv) != 1 or not Path(argv[0]).is_file():
        print("usage: python -m scripts.docs.method_table OUT/summary.csv [--write]", file=sys.stderr)
        return 2
    from slipreflex.analysis.report import read_csv

    body = table(read_csv(argv[0]))
    print(body)
    if not write:
        return 0
    from scripts.docs.splice_report import write_section

    return write_section("method_table", "docs/method.md", "method variants table", body)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
