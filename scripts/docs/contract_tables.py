"""Put the device contracts (``slipreflex.core.interfaces.CONTRACTS``) and the real-time loop's states
(``slipreflex.rig.loop_states``) into docs/runtime.md.

Usage::

    python -m scripts.docs.contract_tables           # print the tables
    python -m scripts.docs.contract_tables --write   # and write them between docs/runtime.md's markers

``tests/core/test_contracts.py`` and ``tests/rig/test_loop_states.py`` fail when the docs' copies differ
from the code's tables.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "runtime.md"


def main(argv: list[str]) -> int:
    from scripts.docs.splice_report import write_marked
    from slipreflex.core.interfaces import contract_markdown
    from slipreflex.rig.loop_states import states_markdown

    status = 0
    for name, table in (("contracts table", contract_markdown()), ("loop states table", states_markdown())):
        print(table, end="\n\n")
        if "--write" in argv:
            status = status or write_marked("contract_tables", DOCS, f"<!-- {name} begins -->",
                                            f"<!-- {name} ends -->", table)
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
