"""Imports flow one way: no circle between the package's modules, nor between its subpackages.

The graph is read from the source (the AST of every module under src/slipreflex), so an
import inside a function counts as much as one at the top; imports under ``if TYPE_CHECKING:``
do not run and do not count. A registry names what sits above it by entry point
(``slipreflex.core.registry.EntryPoint``), which is not an import.
"""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

import pytest

from slipreflex import methods

SRC = Path(__file__).resolve().parents[2] / "src"
PKG = SRC / "slipreflex"


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in PKG.rglob("*.py")}


@functools.cache
def _imports(name: str, path: Path) -> list[tuple[str, int]]:
    """(imported slipreflex module, line) for every import that can run, at any depth."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: list[tuple[str, int]] = []

    def visit(node: ast.AST) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and "TYPE_CHECKING" in ast.unparse(child.test):
                for other in child.orelse:
                    visit(other)
                continue
            if isinstance(child, ast.Import):
                out.extend((a.name, child.lineno) for a in child.names)
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    base = package.split(".")
                    base = base[:len(base) - child.level + 1]
                    target = ".".join(base + ([child.module] if child.module else []))
                else:
                    target = child.module or ""
                for a in child.names:   # `from . import hardware` imports the module slipreflex.core.hardware
                    out.append((f"{target}.{a.name}" if f"{target}.{a.name}" in MODULES else target, child.lineno))
            visit(child)

    visit(ast.parse(path.read_text()))
    resolved = []
    for target, line in out:
        while target not in MODULES and "." in target:
            target = target.rpartition(".")[0]
        if target in MODULES and target != name:
            resolved.append((target, line))
    return resolved


def _graph(unit=lambda m: m) -> dict[str, dict[str, str]]:
    """``{a: {b: "a.py:line"}}``: a imports b (both mapped through ``unit``)."""
    edges: dict[str, dict[str, str]] = {}
    for name, path in MODULES.items():
        for target, line in _imports(name, path):
            a, b = unit(name), unit(target)
            if a != b:
                edges.setdefault(a, {}).setdefault(b, f"{path.relative_to(SRC)}:{line}")
    return edges


def _subpackage(module: str) -> str:
    """slipreflex.sim.rig -> slipreflex.sim; slipreflex.methods -> slipreflex.methods."""
    return ".".join(module.split(".")[:2])


def _cycle(edges: dict[str, dict[str, str]]) -> list[str] | None:
    """One circle of ``edges`` as its arrows ("a -> b (where)"), or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def dfs(v: str) -> list[str] | None:
        state[v] = 1
        stack.append(v)
        for w in sorted(edges.get(v, {})):
            if state.get(w) == 1:
                loop = stack[stack.index(w):] + [w]
                return [f"{a} -> {b} ({edges[a][b]})" for a, b in zip(loop, loop[1:])]
            if w not in state and (found := dfs(w)):
                return found
        stack.pop()
        state[v] = 2
        return None

    for v in sorted(edges):
        if v not in state and (found := dfs(v)):
            return found
    return None


# Why an import may sit inside a function, as a trailing comment on the statement: it keeps a heavy or
# optional dependency out of `import slipreflex`; or moving it up would close a cycle (to fix later).
# A test that replaces a name patches it where it is used (the importing module), never at its source,
# so no import has to stay late for a test's sake.
DEFERRED = re.compile(r"#\s*deferred: (heavy|optional extra|would close a cycle) \(?\S")


def _unmarked_function_imports(source: str, where: str) -> list[str]:
    """``"where:line: statement"`` for each import inside a def or lambda without a ``# deferred:`` reason."""
    lines = source.splitlines()
    found: list[str] = []

    def visit(node: ast.AST, inside: bool) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and "TYPE_CHECKING" in ast.unparse(child.test):
                continue
            if inside and isinstance(child, ast.Import | ast.ImportFrom):
                text = "\n".join(lines[child.lineno - 1:child.end_lineno])
                if not DEFERRED.search(text):
                    found.append(f"{where}:{child.lineno}: {ast.unparse(child)}")
            visit(child, inside or isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda))

    visit(ast.parse(source), False)
    return found


def test_every_function_level_import_says_why_it_is_deferred():
    unmarked = [hit for name, path in sorted(MODULES.items())
                for hit in _unmarked_function_imports(path.read_text(), str(path.relative_to(SRC)))]
    assert not unmarked, ("imports inside functions must sit at the module top unless marked "
                          "'# deferred: heavy (NAME)' or '# deferred: optional extra (NAME)':\n" + "\n".join(unmarked))


def test_the_marker_check_finds_an_unmarked_import():
    source = (
        "import json\n"
        "def f():\n"
        "    import pywt  # deferred: heavy (pywt)\n"
        "    from .paths import (  # deferred: optional extra (study: pyarrow)\n"
        "        new_file)\n"
        "    import csv\n"
        "    g = lambda: __import__('x')\n"
        "    class C:\n"
        "        def m(self):\n"
        "            from . import hardware  # just because\n"
        "    from .runtime import run_loop  # deferred: late-bound (tests patch it)\n")
    assert _unmarked_function_imports(source, "m.py") == ["m.py:6: import csv", "m.py:10: from . import hardware",
                                                          "m.py:11: from .runtime import run_loop"]


def test_the_graph_is_read_from_every_module():
    edges = _graph()
    assert len(MODULES) > 80
    assert "slipreflex.core.hardware" in edges["slipreflex.methods"]          # a top-level import
    assert "slipreflex.methods.chain.reflex" in edges["slipreflex.methods.chain.builders"]
    assert "slipreflex.sim.kernel" in edges["slipreflex.sim.rig"]


@pytest.mark.parametrize("level, unit", [("module", lambda m: m), ("subpackage", _subpackage)])
def test_no_import_circle(level, unit):
    assert _cycle(_graph(unit)) is None, f"an import circle between {level}s: {_cycle(_graph(unit))}"


def test_the_cycle_finder_finds_a_circle():
    assert _cycle({"a": {"b": "x:1"}, "b": {"c": "x:2"}, "c": {"a": "x:3"}}) == [
        "a -> b (x:1)", "b -> c (x:2)", "c -> a (x:3)"]
    assert _cycle({"a": {"b": "x:1"}, "b": {"c": "x:2"}}) is None


def test_the_registry_sits_below_the_implementations_it_lists():
    """The registry (slipreflex.methods' own module) imports none of chain, baselines, board, sim; its built-ins
    resolve by entry point."""
    below = set(_graph().get("slipreflex.methods", {}))
    assert not {m for m in below if m.startswith(("slipreflex.methods.", "slipreflex.sim"))}, below
    for name in methods.names():
        spec = methods.get(name)
        for part in (spec.build, spec.detections, spec.rest_statistic):
            if isinstance(part, methods.EntryPoint):
                module, _, attr = part.target.partition(":")
                assert module in MODULES and attr in ast.unparse(ast.parse(MODULES[module].read_text())), part


#: The declared layers, bottom first. A unit (a package directly below slipreflex, or a top-level module;
#: "slipreflex" is the package's own __init__) imports only units declared at or below it, so the tree
#: reads bottom-up in this order. A new top-level package or module is placed here (and in docs/design.md).
LAYERS: tuple[str, ...] = (
    "slipreflex.core",        # facts and contracts: hardware, errors, protocols, the grip rule, registries' machinery
    "slipreflex.files",       # files and processes: output sets, CSV, recordings, Ctrl-C, progress
    "slipreflex.methods",     # the method registry and its implementations: the chain, the baselines, the board twin
    "slipreflex",             # the package: the chain's public names
    "slipreflex.sim",         # the simulator
    "slipreflex.analysis",    # a trial's metrics, the claims, the report
    "slipreflex.benchmark",   # every method on recorded labelled slip
    "slipreflex.rig",         # devices, the real-time loop, the live view, LSL
    "slipreflex.reproduce",   # the trial, the grid, thresholds, replication
    "slipreflex.neuro",       # NIR export and neuromorphic back-ends
    "slipreflex.study",       # the claims over plausible plants
    "slipreflex.testing",     # the conformance checkers
    "slipreflex.commands",    # one module per subcommand
    "slipreflex.cli",         # the console script
    "slipreflex.__main__",    # python -m slipreflex
)


def _upward(edges: dict[str, dict[str, str]], layers: tuple[str, ...]) -> list[str]:
    """Every import of a unit declared above the importer ("a -> b (where)")."""
    return [f"{a} -> {b} ({where})" for a, targets in sorted(edges.items()) for b, where in sorted(targets.items())
            if layers.index(b) > layers.index(a)]


def test_every_unit_of_the_tree_has_its_declared_layer():
    units = {_subpackage(m) for m in MODULES}
    assert units == set(LAYERS), f"undeclared: {sorted(units - set(LAYERS))}; gone: {sorted(set(LAYERS) - units)}"


def test_imports_only_go_down_the_declared_layers():
    up = _upward(_graph(_subpackage), LAYERS)
    assert not up, "imports of a layer above the importer:\n" + "\n".join(up)


def test_the_layer_check_finds_an_upward_import():
    assert _upward({"a": {"b": "a.py:3"}, "b": {}}, ("a", "b")) == ["a -> b (a.py:3)"]
    assert _upward({"b": {"a": "b.py:1"}}, ("a", "b")) == []


def _named_targets(name: str, path: Path) -> list[str]:
    """Every module path an import of ``name`` names, as written (before any resolution)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: list[str] = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            parts = package.split(".")
            base = ".".join(parts[:len(parts) - node.level + 1] + ([node.module] if node.module else [])) \
                if node.level else (node.module or "")
            out += [base] + [f"{base}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            out += [a.name for a in node.names]
    return out


def test_every_old_import_path_is_the_module_at_its_new_place():
    import importlib

    from slipreflex.core._moved import MOVED, new_name

    for old, new in MOVED.items():
        assert importlib.import_module(f"slipreflex.{old}") is importlib.import_module(f"slipreflex.{new}"), old
        assert importlib.import_module(f"slipreflex.{old}").__spec__.name == f"slipreflex.{new}", old  # its own
    internal = [f"{p.relative_to(SRC)}: {t}" for name, p in sorted(MODULES.items())
                for t in _named_targets(name, p) if new_name(t) is not None]
    assert not internal, "old import paths inside the package:\n" + "\n".join(internal)
