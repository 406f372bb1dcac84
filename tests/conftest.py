"""Helpers shared by the test modules (fixtures; pytest finds them by name).

Tiers: ``pytest -m "not slow"`` is the fast tier (docs/development.md); the slow tier
(``-m slow``) is what a full run adds. Tests that build or run the firmware declare the
tools they need with ``@pytest.mark.needs_tools("make", "avr-gcc", ...)`` or, in a
fixture, ``require_tools(...)``: where a tool is absent they skip, naming it, unless
``SLIPREFLEX_REQUIRE_TOOLS=1`` (``scripts/bootstrap.sh test`` sets it, so CI, which
installs the tools, fails instead of skipping). Real-time tests (``@pytest.mark.realtime``:
the loop against the wall clock) skip, saying so, on a machine loaded past
``REALTIME_LOAD_PER_CORE`` runnable processes per core, except under that same variable.
"""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

#: The test modules live in folders that mirror the package (plus journeys/ and house/); a module
#: imports another's helpers by its name, as pytest's default import mode imports it.
for _folder in sorted(Path(__file__).resolve().parent.iterdir()):
    if _folder.is_dir() and _folder.name not in ("data", "__pycache__") and str(_folder) not in sys.path:
        sys.path.insert(0, str(_folder))

#: How each tool a test may need is found. ``simavr`` is the library and headers the
#: firmware's harness links against (libsimavr-dev, libelf-dev), found by pkg-config.
TOOLS = {
    "make": "make", "cc": "cc", "avr-gcc": "avr-gcc", "avrdude": "avrdude", "pkg-config": "pkg-config",
}


@functools.cache
def missing_tool(name: str) -> str | None:
    """Why ``name`` is unusable here (a one-line reason), or None when it is present."""
    if name == "simavr":
        if shutil.which("pkg-config") is None:
            return "pkg-config is not on PATH (needed to find simavr)"
        ok = subprocess.run(["pkg-config", "--exists", "simavr"], capture_output=True).returncode == 0
        return None if ok else "simavr (libsimavr-dev) is not known to pkg-config"
    if name == "avr-libc":
        return None if os.path.exists("/usr/lib/avr/include/avr/io.h") else "avr-libc is not installed"
    if name not in TOOLS:
        raise ValueError(f"unknown tool {name!r} (known: {', '.join([*TOOLS, 'simavr', 'avr-libc'])})")
    return None if shutil.which(TOOLS[name]) else f"{TOOLS[name]} is not on PATH"


def require_tools(*names: str) -> None:
    """Skip the calling test or fixture, naming what is missing, when a tool is absent.

    With ``SLIPREFLEX_REQUIRE_TOOLS=1`` a missing tool fails the test instead.
    """
    reasons = [r for r in map(missing_tool, names) if r]
    if not reasons:
        return
    message = "needs " + ", ".join(names) + ": " + "; ".join(reasons) + " (scripts/bootstrap.sh installs them)"
    if os.environ.get("SLIPREFLEX_REQUIRE_TOOLS") == "1":
        pytest.fail(message)
    pytest.skip(message)


#: The firmware's tool sets, for ``needs_tools`` and ``require_tools``.
HOST_C = ("make", "cc")
AVR = ("make", "avr-gcc", "avr-libc")
SIMAVR = ("make", "cc", "avr-gcc", "avr-libc", "simavr")


#: A real-time test (the loop against the wall clock, over virtual devices) skips when the
#: 1-minute load average is above this many runnable processes per core: its deadlines would
#: measure the machine's other work, not the code.
REALTIME_LOAD_PER_CORE = 2.0


def realtime_overload() -> str | None:
    """Why the machine is too busy for a real-time test (a one-line reason), or None."""
    cores = os.cpu_count() or 1
    load = os.getloadavg()[0]
    if load <= REALTIME_LOAD_PER_CORE * cores:
        return None
    return (f"real-time test: load average {load:.1f} on {cores} cores (over {REALTIME_LOAD_PER_CORE:g} per core) "
            "would make it miss deadlines; run it on a quieter machine (CI: SLIPREFLEX_REQUIRE_TOOLS=1 runs it anyway)")


def pytest_runtest_setup(item):
    for mark in item.iter_markers("needs_tools"):
        require_tools(*mark.args)
    if item.get_closest_marker("realtime") and os.environ.get("SLIPREFLEX_REQUIRE_TOOLS") != "1":
        reason = realtime_overload()
        if reason:
            pytest.skip(reason)


@pytest.fixture(scope="session")
def tools():
    """``tools(*names)``: skip (or, under ``SLIPREFLEX_REQUIRE_TOOLS=1``, fail) unless every tool is here."""
    return require_tools


def _stream(reflex, samples, positions=None) -> np.ndarray:
    """Feed ``samples`` to ``reflex`` one by one; the commands, NaN where ``step`` gave None."""
    out = []
    for k, x in enumerate(samples):
        p = None if positions is None or np.isnan(positions[k]) else float(positions[k])
        v = reflex.step(x, position=p)
        out.append(np.nan if v is None else v)
    return np.array(out, dtype=float)


@pytest.fixture
def stream():
    """``stream(reflex, samples, positions=None)``: a streaming reflex's commands over a recording.

    Positions are fed where they are not NaN; the result has NaN where ``step``
    returned None, so it compares directly with the batch functions' output.
    """
    return _stream


@pytest.fixture
def assert_same_commands():
    """``assert_same_commands(a, b)``: equal where set, NaN in the same places, bit for bit."""
    def check(a, b):
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
        np.testing.assert_array_equal(a[~np.isnan(a)], b[~np.isnan(b)])
    return check


def reap_child(proc: subprocess.Popen, killer=None) -> None:
    """After a test's child process: stop its time-out timer, kill it if it still runs, reap it, close its pipes."""
    if killer is not None:
        killer.cancel()
    if proc.poll() is None:
        proc.kill()
        proc.wait(timeout=10)
    for pipe in (proc.stdin, proc.stdout, proc.stderr):
        if pipe is not None:
            pipe.close()


#: Simulated rigs built while the tests were being collected (by ``pytest_collection`` below); a
#: calibration or simulation a module needs belongs in a fixture or a cached function, not in a
#: module-level constant, so the count stays 0 and a one-line change pays only for its tests.
COLLECTION_RIGS: list[str] = []


@pytest.hookimpl(hookwrapper=True)
def pytest_collection(session):
    """Count the simulated rigs built during collection (pytest_collection_finish refuses a nonzero count)."""
    from slipreflex.sim.rig import Rig

    real = Rig.__init__

    def counting(self, *args, **kwargs):
        COLLECTION_RIGS.append(f"Rig{args[:1]!r}")
        real(self, *args, **kwargs)

    Rig.__init__ = counting
    try:
        yield
    finally:
        Rig.__init__ = real


def pytest_collection_finish(session):
    if COLLECTION_RIGS:
        raise pytest.UsageError(f"{len(COLLECTION_RIGS)} simulated rig(s) built while collecting the tests "
                                f"({', '.join(COLLECTION_RIGS[:3])}): move the simulation into a fixture")
