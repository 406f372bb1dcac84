"""Put the device contracts (``slipreflex.core.interfaces.CONTRACTS``) and the real-time loop's states
(``slipreflex.rig.loop_states``) into docs/runtime.md.

Usage::

    python scripts/contract_tables.py           # print the tables
    python scripts/contract_tables.py --write   # and write them between docs/runtime.md's markers

``tests/test_contracts.py`` and ``tests/test_loop_states.py`` fail when the docs' copies differ
from the code's tables.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs" / "runtime.md"


def main(argv: list[str]) -> int:
    sys.path.insert(0, str(ROOT / "scripts"))
    from splice_report import write_marked

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
