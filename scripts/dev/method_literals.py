"""Count the method names written as string literals in the package.

A literal counts when the whole string is exactly the name of a method the package registers
(``slipreflex.methods.names()`` at import), outside docstrings. The names' one home,
``slipreflex/methods.py``, is listed apart. Used to report the count
"method names stop being string literals scattered over the package".

Usage: python -m scripts.dev.method_literals [--root src/slipreflex] [--list]
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections import Counter
from pathlib import Path


def _docstring_nodes(tree: ast.AST) -> set[int]:
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                out.add(id(body[0].value))
    return out


def method_literals(root: Path, names: set[str]) -> list[tuple[str, int, str]]:
    """(file relative to ``root``'s parent, line, literal) for every method-name literal."""
    out = []
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(), filename=str(path))
        docs = _docstring_nodes(tree)
        for node in ast.walk(tree):
            if (isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs
                    and node.value in names):
                out.append((str(path.relative_to(root.parent)), node.lineno, node.value))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", type=Path, default=Path(__file__).resolve().parents[2] / "src" / "slipreflex")
    ap.add_argument("--list", action="store_true", help="print every literal, not only the counts per file")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(args.root.parent))
    from slipreflex import methods

    found = method_literals(args.root, set(methods.names()))
    home = [f for f in found if f[0].endswith("slipreflex/methods.py")]
    rest = [f for f in found if f not in home]
    if args.list:
        for f, line, s in rest:
            print(f"{f}:{line}: {s!r}")
    for f, n in Counter(f for f, _, _ in rest).most_common():
        print(f"{n:4d} {f}")
    print(f"{len(rest)} method-name literals outside slipreflex/methods.py ({len(home)} in it)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
