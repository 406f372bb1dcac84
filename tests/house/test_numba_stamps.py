"""numba's disk cache stays correct across files: a kernel is stamped with every file whose code it compiles in.

numba stamps a cached kernel with its own source file only. A kernel that calls a function
or reads a constant of another module compiles that code into itself, so each module with
cached kernels declares those files (``slipreflex.core._numba_cache.stamped_cache``); these
tests read the kernels' bodies and check the declarations cover them, and that an edit in a
declared file (or a file it declares) changes the stamp.
"""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

from slipreflex.core import _numba_cache as nc

SRC = Path(__file__).resolve().parents[2] / "src"
PKG = SRC / "slipreflex"


def _module_name(path: Path) -> str:
    return ".".join(path.relative_to(SRC).with_suffix("").parts)


def _is_cached_kernel(node: ast.AST) -> bool:
    for d in getattr(node, "decorator_list", []):
        if isinstance(d, ast.Call) and getattr(d.func, "id", "") == "njit":
            if any(k.arg == "cache" for k in d.keywords):
                return True
    return False


def _kernel_modules() -> list[Path]:
    return [p for p in sorted(PKG.rglob("*.py"))
            if any(_is_cached_kernel(n) for n in ast.walk(ast.parse(p.read_text())))]


def _compiled_in(path: Path) -> set[str]:
    """The slipreflex modules whose names the cached kernels of ``path`` use (a star import: always)."""
    tree = ast.parse(path.read_text())
    package = _module_name(path).rpartition(".")[0]
    source: dict[str, str] = {}   # local name -> the module it comes from
    starred: set[str] = set()
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith("slipreflex")):
            base = package.split(".")[:len(package.split(".")) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            for alias in node.names:
                target = f"{module}.{alias.name}"
                is_module = (SRC / target.replace(".", "/")).with_suffix(".py").exists()
                if alias.name == "*":
                    starred.add(module)
                else:
                    source[alias.asname or alias.name] = target if is_module else module
    used = set(starred)
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef) and _is_cached_kernel(node):
            used |= {source[n.id] for n in ast.walk(node) if isinstance(n, ast.Name) and n.id in source}
    used.discard("slipreflex.core._numba_cache")
    used.discard(_module_name(path))
    return used


KERNEL_MODULES = _kernel_modules()


def test_the_cache_module_doctests_pass():
    import doctest

    assert doctest.testmod(nc).failed == 0


def test_the_kernel_modules_are_found():
    names = {_module_name(p) for p in KERNEL_MODULES}
    assert {"slipreflex.sim.kernel_step", "slipreflex.sim.closed", "slipreflex.methods.chain._kernels"} <= names
    assert _compiled_in(PKG / "sim" / "kernel_step.py") >= {"slipreflex.sim._kernel_layout",
                                                             "slipreflex.sim.kernel_contacts"}


@pytest.mark.parametrize("path", KERNEL_MODULES, ids=lambda p: _module_name(p))
def test_every_kernel_is_stamped_with_the_files_it_compiles_in(path):
    """Each module whose cached kernels use another module's names declares it (directly or through a file it
    declares), so an edit there recompiles them instead of running a stale cache."""
    module = importlib.import_module(_module_name(path))
    stamped = set(nc.stamped_files(str(path)))
    needed = {str(Path(importlib.import_module(m).__file__ or "").resolve()) for m in _compiled_in(path)}
    assert not needed - stamped, f"{path.name} compiles in files its stamp does not cover: {needed - stamped}"
    if needed:
        disp = next(v for v in vars(module).values() if hasattr(v, "_cache") and hasattr(v, "py_func"))
        if nc.CACHE:
            assert isinstance(disp._cache._impl.locator, nc._Stamped), f"{path.name}'s kernels are not stamped"


def test_an_edit_in_a_file_a_kernel_compiles_in_changes_its_stamp(tmp_path, monkeypatch):
    """Through two declarations (a module declares b, b declares c): editing c changes a's stamp; no compile."""
    a, b, c = (tmp_path / name for name in ("a.py", "b.py", "c.py"))
    for f in (a, b, c):
        f.write_text(f"# {f.name}\n")
    monkeypatch.setitem(nc._INLINES, str(a), (str(b),))
    monkeypatch.setitem(nc._INLINES, str(b), (str(c),))
    assert nc.stamped_files(str(a)) == [str(a), str(b), str(c)]
    before = nc.source_stamp(str(a))
    c.write_text("# c.py, a constant changed\n")
    assert nc.source_stamp(str(a)) != before


def test_the_step_kernels_stamp_follows_the_contact_laws(tmp_path, monkeypatch):
    """The real declaration: step_until's locator reads the contact laws' file (here a copy, then edited)."""
    from slipreflex.sim import kernel_contacts, kernel_step

    locator = kernel_step.step_until._cache._impl.locator
    if not nc.CACHE:
        pytest.skip("numba's cache is off in this process (no writable folder)")
    copy = tmp_path / "kernel_contacts.py"
    copy.write_text(Path(kernel_contacts.__file__).read_text())
    declared = nc._INLINES[nc._key(kernel_step.__file__)]
    monkeypatch.setitem(nc._INLINES, nc._key(kernel_step.__file__),
                        tuple(str(copy) if p == nc._key(kernel_contacts.__file__) else p for p in declared))
    before = locator.get_source_stamp()
    copy.write_text(copy.read_text().replace("_NEWTON_MAX = 60", "_NEWTON_MAX = 61"))
    assert locator.get_source_stamp() != before


def test_an_undeclared_module_keeps_numbas_own_locator():
    from slipreflex.sim import kernel_step

    assert nc._Stamped.from_function(kernel_step.step_until.py_func, "/nowhere/else.py") is None
