"""Load kinds as a registry, and plugin files: a shake and a hand twin, each one file outside the package."""

from __future__ import annotations

import csv
import json
import math
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from slipreflex.cli import main
from slipreflex.core.errors import ParameterError
from slipreflex.core.experiment_specs import EXPERIMENTS
from slipreflex.core.registry import PLUGIN_ENV
from slipreflex.rig.hands import HANDS
from slipreflex.sim import kernel as K
from slipreflex.sim.loads import LOAD_KINDS, LoadKind, kind_of, load_names

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"


def _cli(*argv: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """The console script in a fresh process (a plugin registers for the whole process)."""
    env = {k: v for k, v in os.environ.items() if k != PLUGIN_ENV}
    return subprocess.run([sys.executable, "-m", "slipreflex", *argv], capture_output=True, text=True, env=env,
                          cwd=ROOT, timeout=timeout)


@pytest.mark.parametrize("body, says", [
    (None, "no such file"),
    ("raise ValueError('no rig here')\n", "ValueError: no rig here"),
    ("x = (\n", "line 1: SyntaxError"),
])
def test_a_bad_plugin_file_is_one_line_and_exit_2_before_any_work(tmp_path, capsys, body, says):
    plugin = tmp_path / "broken.py"
    if body is not None:
        plugin.write_text(body)
    out = tmp_path / "out"
    before = (EXPERIMENTS.names(), HANDS.names(), load_names())
    assert main(["reproduce", "--plugin", str(plugin), "--trials", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"plugin {plugin}" in err and says in err
    assert not out.exists()
    assert (EXPERIMENTS.names(), HANDS.names(), load_names()) == before


def test_a_perturbation_finds_its_kind_and_a_class_has_one_kind():
    from slipreflex.sim import Drop, Pour

    assert kind_of(Drop()).table == "drops" and kind_of(Pour()).table == "timed"
    with pytest.raises(ParameterError, match="no load kind takes a str"):
        kind_of("drop")
    with pytest.raises(ParameterError, match="Pour is already load kind 'pour'"):
        LOAD_KINDS.register(LoadKind("water", Pour, "timed", lambda what, at, rig: K.POUR.new()))
    with pytest.raises(ParameterError, match="table"):
        LoadKind("lift", Drop, "lifts", lambda what, at, rig: K.DROP.new())  # type: ignore[arg-type]


@dataclass(frozen=True)
class _Jolt:
    accel: float


def _jolt_row(what: _Jolt, at: float, rig) -> np.ndarray:
    row = K.POUR.new()
    row[[K.W_RATE_KG_S, K.W_TOTAL_KG, K.W_DELAY, K.W_JET_N, K.W_RATE_L_S]] = 0.0
    row[K.W_START], row[K.W_DUR] = at, 0.5
    row[K.W_ACC], row[K.W_ACC_W] = -what.accel, 2.0 * math.pi * 2.0
    return row


@pytest.mark.slow        # two rigs grasp and are shaken (the kernels loaded)
def test_a_registered_kind_moves_the_grip_and_the_imu_reads_it():
    from slipreflex.sim import Rig

    LOAD_KINDS.register(LoadKind("jolt", _Jolt, "timed", _jolt_row))
    try:
        peaks = []
        for accel, stepping in ((0.0, "adaptive"), (9.80665, "adaptive"), (9.80665, "fixed")):
            rig = Rig("TR", seed=3, stepping=stepping)
            rig.grasp()
            rig.perturb(_Jolt(accel) if accel else _Jolt(1e-300), at=rig.t + 0.05)
            samples = rig.advance(0.6)
            peaks.append(max(abs(s.accel_g[1]) for s in samples))
            assert rig.perturbations[-1][1] == _Jolt(accel or 1e-300) and not rig.fallen
    finally:
        LOAD_KINDS.unregister("jolt")
    # the accelerometer's vertical axis reads gravity alone, then gravity plus a 1 g shake of the grip
    assert peaks[0] < 1.2 < 1.6 < peaks[1]
    # the adaptive stepping follows the shake as the fixed-step reference does
    assert abs(peaks[1] - peaks[2]) < 0.02


@pytest.mark.slow        # a fresh interpreter, the kernels loaded and 3 trials run
def test_the_shake_example_runs_as_an_experiment_from_the_command_line(tmp_path):
    out = tmp_path / "shake"
    r = _cli("reproduce", "--plugin", str(EXAMPLES / "shake.py"), "--experiments", "shake", "--trials", "1",
             "--bottles", "TR", "--methods", "dath,fixed,nmsd", "--no-figures", "--no-progress", "--jobs", "1",
             "--out", str(out))
    assert r.returncode == 0, r.stderr
    with (out / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert {row["experiment"] for row in rows} == {"shake"}
    assert {row["method"] for row in rows} == {"dath", "fixed", "nmsd"}
    # the shake starts after the rest and the grasp holds through it (3 x 3 Hz at 0.72 g, an empty bottle)
    assert all(float(row["perturbation_s"]) > 1.0 and row["fell_out"] == "False" for row in rows)
    assert "shake (3 x 3 Hz at 0.72 g)" in r.stdout


@pytest.mark.slow        # real time: a virtual rig, then 'slipreflex run' for 3 s
def test_the_hand_twin_example_gets_the_reflexs_close_commands(tmp_path):
    from slipreflex.rig.devices.simrig import SimRig
    from slipreflex.rig.devices.virtual import VirtualDevices

    rig = SimRig("TR", seed=1)
    rig.grasp()
    log = tmp_path / "twin.jsonl"
    env = {k: v for k, v in os.environ.items() if k != PLUGIN_ENV}
    with VirtualDevices(rig) as dev:
        run = subprocess.Popen([sys.executable, "-m", "slipreflex", "run", "--plugin", str(EXAMPLES / "hand_twin.py"),
                                "--hand-type", "twin", "--hand", str(log), "--daq", dev.daq_path, "--p0", "150",
                                "--duration", "3", "--no-record"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, env=env, cwd=ROOT)
        # the loop starts with STOP: the twin's first line; then the bottle gets the paper's drop
        deadline = time.monotonic() + 300
        while not (log.exists() and log.read_text()) and run.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        dev.trigger("drop", "signal")
        out, err = run.communicate(timeout=300)
    assert run.returncode == 0, err
    assert "hand twin on" in out
    commands = [json.loads(line) for line in log.read_text().splitlines()]
    assert commands[0]["command"] == "hold"
    closes = [c for c in commands if c["command"] == "close"]
    assert closes and all(c["speed"] > 0 and c["fingers"] for c in closes)
    assert {c["command"] for c in commands} <= {"close", "hold"}    # a reflex never sets positions


class _EntryPoint:
    def __init__(self, name, obj):
        self.name, self.value, self._obj = name, f"pkg.mod:{name}", obj

    def load(self):
        if isinstance(self._obj, Exception):
            raise self._obj
        return self._obj


def test_an_installed_package_adds_a_hand_through_its_entry_point_group(monkeypatch):
    import importlib.metadata

    from slipreflex.core.registry import Registry
    from slipreflex.rig.hands import HandSpec

    twin = HandSpec("twin", "hand twin", dict)
    groups = {"slipreflex.hands": [_EntryPoint("twin", lambda: [twin])]}
    monkeypatch.setattr(importlib.metadata, "entry_points", lambda group: groups.get(group, []))
    hands = Registry("hand", HandSpec, group="slipreflex.hands")
    assert hands.names() == ("twin",) and hands.get("twin") is twin
    assert hands.load_entry_points() == ()          # read once
    groups["slipreflex.hands"] = [_EntryPoint("broken", ImportError("no module named pkg"))]
    with pytest.raises(ParameterError, match=r"hand plugin 'broken' \(pkg.mod:broken\): cannot load: no module"):
        Registry("hand", HandSpec, group="slipreflex.hands").names()
    groups["slipreflex.hands"] = [_EntryPoint("odd", 42)]
    with pytest.raises(ParameterError, match="hand plugin 'odd'"):
        Registry("hand", HandSpec, group="slipreflex.hands").names()
