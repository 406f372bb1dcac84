"""The optional ``study`` extra: the base install never imports Dask, pyarrow or SALib.

Each check runs in a fresh interpreter, so what an earlier test imported cannot hide a load.
"""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
STUDY_ONLY = ("dask", "distributed", "pyarrow", "SALib")
# What `import slipreflex` alone must not load: the study extra and every heavy or device-only
# dependency its modules import inside functions (marked `# deferred:`).
NOT_ON_IMPORT = STUDY_ONLY + ("matplotlib", "pywt", "foxglove", "pylsl")

# Import every module of the package (the study's too: its heavy imports sit inside its
# functions), build the CLI and run `detect` on the shipped example; then list what loaded.
IMPORT_ALL = f"""
import importlib, pkgutil, sys
import slipreflex
for info in pkgutil.walk_packages(slipreflex.__path__, "slipreflex."):
    if not info.name.endswith("__main__"):
        importlib.import_module(info.name)
from slipreflex.cli import main
assert main(["detect", {str(ROOT / "examples" / "slip_example.csv")!r}, "--out", sys.argv[1]]) == 0
print("LOADED:", " ".join(sorted({{m.split(".")[0] for m in sys.modules}} & set({STUDY_ONLY!r}))))
"""

# The study extra made to look uninstalled: find_spec answers None and importing fails.
WITHOUT_EXTRA = f"""
import importlib.abc, importlib.util, sys
_find_spec = importlib.util.find_spec
def _absent(name):
    return name.split(".")[0] in {STUDY_ONLY!r}
class Absent(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if _absent(name):
            raise ModuleNotFoundError(name)
        return None
sys.meta_path.insert(0, Absent())
importlib.util.find_spec = lambda name, package=None: None if _absent(name) else _find_spec(name, package)
"""


def _python(code: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300,
                          cwd=ROOT)


def test_the_study_packages_are_an_extra_not_a_dependency():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    base = " ".join(project["dependencies"]).lower()
    study = " ".join(project["optional-dependencies"]["study"]).lower()
    for name in ("dask", "pyarrow", "salib"):
        assert name not in base, f"{name} is still a base dependency"
        assert name in study, f"{name} is missing from the study extra"


def test_import_slipreflex_loads_no_heavy_or_optional_package():
    code = ("import sys, slipreflex\n"
            f"print('LOADED:', ' '.join(sorted({{m.split('.')[0] for m in sys.modules}} & set({NOT_ON_IMPORT!r}))))")
    res = _python(code)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "LOADED:", f"`import slipreflex` loaded {res.stdout.strip()}"


@pytest.mark.slow
def test_the_base_install_and_the_other_commands_load_no_study_package(tmp_path):
    res = _python(IMPORT_ALL, str(tmp_path))
    assert res.returncode == 0, res.stderr
    loaded = [line for line in res.stdout.splitlines() if line.startswith("LOADED:")]
    assert loaded == ["LOADED: "], f"importing slipreflex or running detect loaded {loaded}"


@pytest.mark.slow
def test_study_without_its_extra_is_a_one_line_error_naming_it(tmp_path):
    code = WITHOUT_EXTRA + (
        "from slipreflex.cli import main\n"
        "sys.exit(main(['study', '--plants', '2', '--trials', '1', '--workers', '0', "
        f"'--out', {str(tmp_path / 's')!r}]))\n")
    res = _python(code)
    assert res.returncode == 2, res.stdout + res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert "'study' extra" in lines[0] and "slipreflex[study]" in lines[0] and "dask" in lines[0]
    assert not (tmp_path / "s").exists(), "the study started before it found its extra missing"


def test_bootstrap_installs_every_extra_pyproject_declares():
    text = (ROOT / "scripts" / "bootstrap.sh").read_text()
    assert 'optional-dependencies' in text and '-e ".${extras:+[$extras]}"' in text
