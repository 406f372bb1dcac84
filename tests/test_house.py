"""The package's own house rules: checked over every public name, so new code is covered."""

from __future__ import annotations

import enum
import importlib
import inspect
import re
import sys
from pathlib import Path

import pytest

from slipreflex.errors import ParameterError
from test_package import MODULES

ROOT = Path(__file__).resolve().parents[1]
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
    from slipreflex.baselines import NMSD, SWTSD, NMSDParams, SWTParams

    for cls, params in ((NMSD, NMSDParams(threshold=1.0, speed=2.0)), (SWTSD, SWTParams(threshold=1.0, speed=2.0))):
        with pytest.raises(ParameterError, match=UNKNOWN):
            cls(params, **{UNKNOWN: 1})
        assert cls(params, threshold=3.0).params.threshold == 3.0


def test_no_function_outside_the_numba_kernels_is_longer_than_80_lines():
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        from function_lengths import function_lengths
    finally:
        sys.path.pop(0)
    rows = function_lengths(ROOT / "src" / "slipreflex")
    assert any(kernel for _, _, kernel in rows), "the numba kernels were not recognised"
    long = [(n, where) for n, where, kernel in rows if not kernel and n > 80]
    assert not long, f"functions over 80 lines (docstring excluded): {long}"


def test_experiments_keeps_to_its_job_in_at_most_500_lines():
    """Issue 12: configuration, seeds, the trial and the grid; running the grid is grid.py's,
    the report's prose analysis/report.py's. Its public names stay importable from it."""
    from slipreflex import experiments, grid

    lines = (ROOT / "src" / "slipreflex" / "experiments.py").read_text().count("\n")
    assert lines <= 500, f"experiments.py has {lines} lines (at most 500)"
    assert experiments.Cell is grid.Cell
    assert all(hasattr(experiments, name) for name in experiments.__all__)


def test_the_default_sampling_rate_is_the_daq_s_everywhere():
    import slipreflex as sr
    from slipreflex import hardware as hw
    from slipreflex import methods
    from slipreflex.board import BoardReflex
    from slipreflex.chain import FilterParams, ReflexParams

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
    import ast
    import tomllib

    without = []
    for path in sorted((ROOT / "tests").glob("test_*.py")):
        tree = ast.parse(path.read_text())
        if any(isinstance(n, ast.Assign) and any(getattr(t, "id", "") == "pytestmark" for t in n.targets)
               and "slow" in ast.unparse(n.value) for n in tree.body):
            without.append(path.name)
            continue
        tests = [n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name.startswith("test_")]
        if tests and all(_marked_slow(n) for n in tests):
            without.append(path.name)
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
    readme = Path(__file__).resolve().parent.parent / "README.md"
    size = len(readme.read_bytes())
    assert size <= 10 * 1024, f"README.md is {size} bytes; move the long parts to docs/"
    for link in re.findall(r"\]\((docs/[^)#]+)", readme.read_text(encoding="utf-8")):
        assert (readme.parent / link).is_file(), f"README links to {link}, which does not exist"
