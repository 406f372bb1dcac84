"""Print the longest functions of the package, scripts/ and benchmarks/ (``def`` to last line, docstring excluded).

Numba kernels (functions decorated with ``njit`` / ``jit``) are measured like every other
function: a long kernel is cut into pieces inlined at compile time (``inline="always"``).
Used for the house measure "no function longer than 80 lines", which holds in every folder
of :data:`ROOTS`; ``tests/house/test_house.py`` checks the limit.

Usage: python -m scripts.dev.function_lengths [N] [--root src/slipreflex --root scripts ...] [--with-docstrings]
"""

from __future__ import annotations

import argparse
import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
#: The folders the 80-line rule holds in: the package, the scripts, the benchmarks.
ROOTS: tuple[Path, ...] = (REPO / "src" / "slipreflex", REPO / "scripts", REPO / "benchmarks")


def function_lengths(root: Path, *, docstrings: bool = False) -> list[tuple[int, str]]:
    """(lines, "file:line name") for every function; docstrings not counted unless ``docstrings``."""
    out = []
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                body = node.body
                head = body[0] if body else None
                if (not docstrings and isinstance(head, ast.Expr) and isinstance(head.value, ast.Constant)
                        and isinstance(head.value.value, str)):
                    n -= head.end_lineno - head.lineno + 1
                rel = path.relative_to(root.parent)
                out.append((n, f"{rel}:{node.lineno} {node.name}"))
    return sorted(out, reverse=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n", nargs="?", type=int, default=10)
    ap.add_argument("--root", type=Path, action="append", default=None,
                    help="a folder to measure (repeatable; default: the package, scripts/ and benchmarks/)")
    ap.add_argument("--with-docstrings", action="store_true", help="count docstring lines too")
    args = ap.parse_args()
    roots = args.root or ROOTS
    rows = sorted((row for root in roots for row in function_lengths(root, docstrings=args.with_docstrings)),
                  reverse=True)
    what = "docstring included" if args.with_docstrings else "docstring excluded"
    print(f"longest functions (lines, {what}):")
    for n, where in rows[: args.n]:
        print(f"{n:5d}  {where}")


if __name__ == "__main__":
    main()
