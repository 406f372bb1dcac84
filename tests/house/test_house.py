"""The package's own house rules: checked over every public name, so new code is covered."""

from __future__ import annotations

import enum
import functools
import importlib
import inspect
import re
import sys
from pathlib import Path

import pytest
from test_package import MODULES

from slipreflex.core.errors import ParameterError

ROOT = Path(__file__).resolve().parents[2]
UNKNOWN = "no_such_option_xyz"


def _public_classes():
    out = []
    for name in MODULES:
        mod = importlib.import_module(name)
        for attr in getattr(mod, "__all__", ()):
            obj = getattr(mod, attr)
            if (inspect.isclass(obj) and obj.__module__ == name and not inspect.isabstract(obj)
                    and not issubclass(obj, (BaseException, enum.Enum))
                    and not getattr(obj, "_is_protocol", False)):
                out.append(obj)
    return out


CLASSES = _public_classes()


def test_the_constructor_list_is_found_automatically():
    names = {c.__qualname__ for c in CLASSES}
    assert {"NMSD", "SWTSD", "SlipReflex", "MethodSpec", "ReproduceConfig", "TrialRow"} <= names
    assert len(CLASSES) > 50


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: f"{c.__module__}.{c.__qualname__}")
def test_every_public_constructor_rejects_an_unknown_keyword(cls):
    """Like python-control's kwargs_test: a misspelt option is an error naming it, never ignored."""
    with pytest.raises((TypeError, ParameterError)) as err:
        cls(**{UNKNOWN: 1})
    assert UNKNOWN in str(err.value), f"{cls.__qualname__}: {err.value}"


def test_the_params_and_overrides_contract_names_the_unknown_keyword():
    from slipreflex.methods.baselines import NMSD, SWTSD, NMSDParams, SWTParams

    for cls, params in ((NMSD, NMSDParams(threshold=1.0, speed=2.0)), (SWTSD, SWTParams(threshold=1.0, speed=2.0))):
        with pytest.raises(ParameterError, match=UNKNOWN):
            cls(params, **{UNKNOWN: 1})
        assert cls(params, threshold=3.0).params.threshold == 3.0


def test_no_function_is_longer_than_80_lines():
    """In the package, the scripts and the benchmarks alike, numba kernels included (a long kernel is cut
    into pieces numba inlines)."""
    from scripts.dev.function_lengths import ROOTS, function_lengths
    assert {root.relative_to(ROOT).as_posix() for root in ROOTS} == {"src/slipreflex", "scripts", "benchmarks"}
    rows = [row for root in ROOTS for row in function_lengths(root)]
    assert any(where.endswith(" step_until") for _, where in rows), "the numba kernels were not measured"
    assert any(where.startswith("scripts/") for _, where in rows), "the scripts were not measured"
    assert any(where.startswith("benchmarks/") for _, where in rows), "the benchmarks were not measured"
    long = [(n, where) for n, where in rows if n > 80]
    assert not long, f"functions over 80 lines (docstring excluded): {long}"


def test_no_module_is_longer_than_800_lines():
    """Every module of the package, numba kernels' included: a module that outgrows 800 lines becomes a
    package of the same name re-exporting its public names."""
    pkg = ROOT / "src" / "slipreflex"
    sizes = {path.relative_to(pkg).as_posix(): len(path.read_text().splitlines()) for path in pkg.rglob("*.py")}
    assert len(sizes) > 80 and max(sizes.values()) > 400, "the package's modules were not read"
    over = {name: n for name, n in sizes.items() if n > 800}
    assert not over, f"modules over 800 lines (split each into a package of the same name): {over}"


def test_experiments_keeps_to_its_job_in_at_most_500_lines():
    """Configuration, seeds, the trial and the grid; running the grid is grid.py's,
    the report's prose analysis/report's. Its public names stay importable from it."""
    from slipreflex.reproduce import experiments, grid

    lines = (ROOT / "src" / "slipreflex" / "reproduce" / "experiments.py").read_text().count("\n")
    assert lines <= 500, f"experiments.py has {lines} lines (at most 500)"
    assert experiments.Cell is grid.Cell
    assert all(hasattr(experiments, name) for name in experiments.__all__)


def test_the_default_sampling_rate_is_the_daq_s_everywhere():
    import slipreflex as sr
    from slipreflex import methods
    from slipreflex.core import hardware as hw
    from slipreflex.methods.board import BoardReflex
    from slipreflex.methods.chain import FilterParams, ReflexParams

    assert hw.DAQ_FS == pytest.approx(333.333, abs=1e-3)
    rates = {"ReflexParams": ReflexParams().fs, "FilterParams": FilterParams().fs,
             "SlipReflex": sr.SlipReflex().fs, "BoardReflex": BoardReflex().fs,
             "dath": methods.make("dath").fs, "fixed": methods.get("fixed").fs,
             "LowPass": inspect.signature(sr.LowPass).parameters["fs"].default,
             "lowpass": inspect.signature(sr.lowpass).parameters["fs"].default}
    assert rates == dict.fromkeys(rates, hw.DAQ_FS)


def _marked_slow(node) -> bool:
    import ast

    return any("mark.slow" in ast.unparse(d) for d in node.decorator_list)


def test_every_test_module_keeps_a_fast_test_and_the_tier_markers_are_registered():
    """The fast tier (`pytest -m "not slow"`, docs/development.md) covers every test module."""
    import tomllib

    without = [path.name for path, _, tests, fast in _test_files() if tests and not fast]
    assert not without, f"test modules with no test in the fast tier: {without}"
    markers = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]["markers"]
    assert {m.split(":")[0].split("(")[0] for m in markers} >= {"slow", "needs_tools"}


def test_a_realtime_test_skips_only_on_an_overloaded_machine_and_says_why(monkeypatch):
    import os

    from conftest import realtime_overload

    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    monkeypatch.setattr(os, "getloadavg", lambda: (3.9, 0.0, 0.0))
    assert realtime_overload() is None
    monkeypatch.setattr(os, "getloadavg", lambda: (7.3, 0.0, 0.0))
    assert "load average 7.3 on 2 cores" in realtime_overload()


def test_the_readme_is_a_five_minute_read():
    """README.md stays under 10 KB: long explanations belong in docs/, which it links."""
    readme = Path(__file__).resolve().parents[2] / "README.md"
    size = len(readme.read_bytes())
    assert size <= 10 * 1024, f"README.md is {size} bytes; move the long parts to docs/"
    for link in re.findall(r"\]\((docs/[^)#]+)", readme.read_text(encoding="utf-8")):
        assert (readme.parent / link).is_file(), f"README links to {link}, which does not exist"


@functools.cache
def _test_files():
    """(path, syntax tree, its tests, its fast tests) of every test module (a module-wide slow mark: none fast)."""
    import ast

    out = []
    for path in sorted((ROOT / "tests").rglob("test_*.py")):
        tree = ast.parse(path.read_text())
        tests = [n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name.startswith("test_")]
        all_slow = any(isinstance(n, ast.Assign) and any(getattr(t, "id", "") == "pytestmark" for t in n.targets)
                       and "slow" in ast.unparse(n.value) for n in tree.body)
        out.append((path, tree, tests, [] if all_slow else [n for n in tests if not _marked_slow(n)]))
    return out


def _fast_test_files():
    """(path, syntax tree, its fast tests) of every test module that keeps a test in the fast tier."""
    return [(path, tree, fast) for path, tree, _, fast in _test_files() if fast]


def _fast_tier_reaches(modules: dict[str, Path]) -> set[str]:
    """The modules the fast tier exercises, read from the tests' source.

    A module counts when a test module that keeps a fast test imports it; when its doctests run
    (test_package runs every public module's examples in the fast tier); when it is a command
    that a fast test runs by name (``main(["reproduce", ...])``, ``python -m slipreflex scan``);
    or when it is a private module or a package that a counted module imports at its top.
    """
    import ast

    named, commands = set(), set()
    for path, tree, fast in _fast_test_files():
        for n in ast.walk(tree):
            if isinstance(n, ast.Import):
                named.update(a.name for a in n.names)
            elif isinstance(n, ast.ImportFrom) and n.module:
                named.add(n.module)
                named.update(f"{n.module}.{a.name}" for a in n.names)
        for test in fast:
            for n in ast.walk(test):
                if isinstance(n, ast.List) and n.elts and isinstance(n.elts[0], ast.Constant):
                    commands.add(str(n.elts[0].value))
        commands.update(re.findall(r'"slipreflex", "([a-z-]+)"', path.read_text()))
    reached = set()
    for name, path in modules.items():
        last = name.rpartition(".")[2]
        if (name in named or (name in MODULES and ">>>" in path.read_text())
                or (name.startswith("slipreflex.commands.") and last.replace("_", "-") in commands)):
            reached.add(name)
    todo = sorted(reached)
    while todo:                  # private helpers and packages, through the counted modules' top-level imports
        name = todo.pop()
        package = name if modules[name].name == "__init__.py" else name.rpartition(".")[0]
        for n in ast.parse(modules[name].read_text()).body:
            if isinstance(n, ast.ImportFrom) and n.level:
                base = ".".join(package.split(".")[:len(package.split(".")) - n.level + 1])
                first = f"{base}.{n.module}" if n.module else base
                for t in [first, *(f"{first}.{a.name}" for a in n.names)]:
                    if t in modules and t not in reached and (t.rpartition(".")[2].startswith("_")
                                                              or modules[t].name == "__init__.py"):
                        reached.add(t)
                        todo.append(t)
    return reached


def test_every_module_in_src_is_exercised_by_the_fast_tier():
    """`pytest -m "not slow"` reaches every module of the package (so a fast run checks each)."""
    src = ROOT / "src"
    modules = {}
    for path in (src / "slipreflex").rglob("*.py"):
        parts = list(path.relative_to(src).with_suffix("").parts)
        if parts[-1] != "__main__":
            modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    missing = sorted(set(modules) - _fast_tier_reaches(modules))
    assert not missing, f"modules no fast test exercises (import one in a fast test, or give it doctests): {missing}"


def test_the_fast_tier_check_sees_a_module_no_fast_test_reaches(tmp_path):
    lonely = tmp_path / "lonely.py"
    lonely.write_text("def f():\n    return 1\n")
    modules = {"slipreflex.core.errors": ROOT / "src" / "slipreflex" / "core" / "errors.py",
               "slipreflex.lonely": lonely}
    assert _fast_tier_reaches(modules) == {"slipreflex.core.errors"}


@pytest.mark.slow
def test_a_simulation_at_collection_time_stops_the_run(tmp_path):
    """conftest counts the rigs built while collecting: a module-level simulation is a one-line error."""
    import shutil
    import subprocess

    probe = tmp_path / "tests"
    probe.mkdir()
    shutil.copy(ROOT / "tests" / "conftest.py", probe / "conftest.py")
    (probe / "test_probe.py").write_text('from slipreflex.sim import Rig\nRIG = Rig("TR")\n\n\n'
                                         "def test_nothing():\n    pass\n")
    # outside the project's config: its addopts' "-p no:nengo" (the neuro extra's plugin breaks pytest 9) given here
    res = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:nengo", str(probe)],
                         capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert res.returncode != 0
    assert "1 simulated rig(s) built while collecting the tests (Rig('TR',))" in res.stdout + res.stderr


def _layout_blocks() -> dict[str, str]:
    """docs/design.md's map: ``{package path ("" for the top): the text of its entry}``."""
    text = (ROOT / "docs" / "design.md").read_text()
    body = text.split("    src/slipreflex/\n", 1)[1].split("\n    firmware/", 1)[0]
    blocks: dict[str, str] = {"": ""}
    current = ""
    for line in body.splitlines():
        first = line.split()[0] if line.split() else ""
        indent = len(line) - len(line.lstrip())
        if first.endswith("/") and indent == 6:
            current = first.rstrip("/")
            blocks[current] = line
        elif indent == 6:           # a top-level module's line
            current = ""
            blocks[""] += line + "\n"
        else:
            blocks[current] += "\n" + line
    return blocks


def test_the_design_map_lists_every_module_of_the_tree():
    """docs/design.md's layout names every package and every module in it (an __init__.py speaks for its package)."""
    import re

    pkg = ROOT / "src" / "slipreflex"
    blocks = _layout_blocks()
    missing = []
    for path in sorted(pkg.rglob("*.py")):
        rel = path.relative_to(pkg)
        where = rel.parent.as_posix() if rel.parent.as_posix() != "." else ""
        if path.name == "__init__.py":
            if where and where not in blocks:
                missing.append(f"{where}/")
        elif path.name not in re.findall(r"[\w]+\.py", blocks.get(where, "")):
            missing.append(rel.as_posix())
    stale = [f"{b}/" for b in blocks if b and not (pkg / b).is_dir()]
    assert not missing and not stale, f"docs/design.md's map: missing {missing}; not in the tree {stale}"
