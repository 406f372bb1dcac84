"""The linters CI runs: ``ruff check src tests`` and ``pyright src`` (basic) report nothing.

Their settings are in pyproject.toml ([tool.ruff], [tool.pyright]); both come with the
``dev`` extra, which scripts/bootstrap.sh installs (docs/development.md).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _tool(name: str) -> str:
    """The tool beside this interpreter (the venv's), else on PATH; a clear failure when absent."""
    here = Path(sys.executable).parent / name
    found = str(here) if here.exists() else shutil.which(name)
    assert found, f"{name} is not installed: pip install -e '.[dev]' (scripts/bootstrap.sh does)"
    return found


def test_ruff_finds_nothing_in_src_and_tests():
    res = subprocess.run([_tool("ruff"), "check", "--no-cache", "src", "tests"], cwd=ROOT,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr


@pytest.mark.slow
def test_pyright_basic_finds_nothing_in_src():
    res = subprocess.run([_tool("pyright"), "--pythonpath", sys.executable, "src"], cwd=ROOT,
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stdout[-6000:] + res.stderr
    assert "0 errors" in res.stdout, res.stdout[-2000:]
