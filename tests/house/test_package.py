"""The package checks itself: public names documented with examples, doctests pass."""

import doctest
import importlib
import inspect
import pkgutil

import pytest

import slipreflex


def _modules():
    names = ["slipreflex"]
    for info in pkgutil.walk_packages(slipreflex.__path__, "slipreflex."):
        if info.name.split(".")[-1].startswith("_") or info.name.endswith("__main__"):
            continue
        names.append(info.name)
    return sorted(names)


MODULES = _modules()


@pytest.mark.parametrize("name", MODULES)
def test_public_names_have_numpydoc_docstrings_with_examples(name):
    mod = importlib.import_module(name)
    assert mod.__doc__, f"{name} has no module docstring"
    public = getattr(mod, "__all__", None)
    if public is None:
        assert name.startswith("slipreflex.commands.") or not [
            n for n, o in vars(mod).items()
            if not n.startswith("_") and (inspect.isfunction(o) or inspect.isclass(o))
            and getattr(o, "__module__", None) == name], f"{name} has no __all__"
        return
    for attr in public:
        obj = getattr(mod, attr)
        if not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        doc = inspect.getdoc(obj) or ""
        assert doc, f"{name}.{attr} has no docstring"
        if getattr(obj, "__module__", name) == name and not issubclass_safe(obj, tuple):
            assert "Examples" in doc or ">>>" in doc, f"{name}.{attr} has no example"


def issubclass_safe(obj, cls):
    return inspect.isclass(obj) and issubclass(obj, cls)


@pytest.mark.parametrize("name", MODULES)
def test_doctests_pass(name, monkeypatch):
    monkeypatch.chdir(__import__("pathlib").Path(__file__).resolve().parents[2])
    mod = importlib.import_module(name)
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE, verbose=False)
    assert result.failed == 0, f"{result.failed} doctest(s) failed in {name}"


def test_import_does_not_load_heavy_modules():
    import subprocess
    import sys
    code = ("import sys, slipreflex, slipreflex.cli; "
            "print(sorted(m for m in ('matplotlib', 'numba', 'pywt', 'mcap', 'serial') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
