"""Fuzz: every command's options with hostile values, and hostile objects/ranges TOML files.

Nothing may end in a traceback: an option or a file is refused with exit 2 (one line), or the
command gets as far as its work, where a stand-in stops it (no simulation runs here). The
examples are bounded and derandomized, so the test is fast and the same on every run.
"""

from __future__ import annotations

import argparse
import json
import math
import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from slipreflex.cli import build_parser, main
from slipreflex.core.errors import SlipreflexError

#: Examples per test: 150 in CI (seconds); FUZZ_EXAMPLES=1500 for a longer look (1500 found nothing either).
SETTINGS = settings(max_examples=int(os.environ.get("FUZZ_EXAMPLES", "150")), deadline=None, derandomize=True,
                    database=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


class Reached(Exception):
    """The command passed its checks and reached its work (a stand-in stopped it there)."""


def _stop(*a, **k):
    raise Reached


#: Where each command's work starts, named where it is called: replaced by _stop.
WORK = [("slipreflex.commands.reproduce", "run_reproduce"), ("slipreflex.commands.study", "run_study"),
        ("slipreflex.sim", "scan"), ("slipreflex.commands.virtual_rig", "SimRig"),
        ("slipreflex.commands.run", "SerialDaq"), ("slipreflex.commands.detect", "run_chain"),
        ("slipreflex.commands.detect", "run_board_chain"), ("slipreflex.sim.calibration", "first_slip_ml"),
        ("slipreflex.sim.calibration", "calibrate_bottle"), ("slipreflex.sim.uncertain", "calibrate_bottle"),
        ("slipreflex.commands.claims", "judge_run"), ("slipreflex.commands.nir", "measure"),
        ("slipreflex.commands.spikes", "simulated_trial")]

NUMBERS = ["nan", "inf", "-inf", "-1", "0", "1", "0.5", "1e300", "1e9", "-1e-300", "3", "100000000",
           "9" * 400, "1e8", "0x10", ""]
TEXTS = ["", ",", ",,", "x", "é", "a:b", "stand:5,white:-1", "drop@nan", "thumb=148,thumb=14", "TR,TR",
         "dath,DATH", "tcp://", "fixed", "[]", " "]


def _files(root: Path) -> list[str]:
    """Hostile and valid input files, made once per test."""
    from slipreflex.files.recording import METADATA_NAME, Recorder
    from slipreflex.methods.chain import ReflexParams

    (root / "bin.toml").write_bytes(bytes(range(256)) * 4)
    (root / "latin1.toml").write_bytes(b'[bottles.B]\nname = "caf\xe9"\n')
    (root / "five.toml").write_text("bottles = 5\n")
    (root / "ok.toml").write_text('[bottles.B]\nmass_kg = 0.05\ndiameter_m = 0.06\nmu_s = 1.0\nmu_k = 0.8\n'
                                  'surface = "DK"\n')
    (root / "ranges.toml").write_text("[hand_latency]\nfixed = 1e30\n")
    (root / "long.csv").write_text("t,x\n" + "1" * 2_000_000 + "\n")
    (root / "ok.csv").write_text("t,x\n" + "".join(f"{k * 0.003:.3f},0.4\n" for k in range(64)))
    (root / "adc.csv").write_text("adc\n" + "300\n" * 64)
    with Recorder(root / "ok.mcap", metadata={METADATA_NAME: {
            "reflex_params": json.dumps(ReflexParams().to_dict())}}) as rec:
        for k in range(20):
            rec.write("/daq/samples", {"seq": k, "t": k * 0.003, "slip_volts": 0.4, "flow_pulses": 0,
                                       "arrival": 0.0, "position": None}, k)
    (root / "junk.mcap").write_bytes(b"\x89MCAP0\r\n" + bytes(range(256)) * 8)
    (root / "dir").mkdir()
    return [str(root / n) for n in ("bin.toml", "latin1.toml", "five.toml", "ok.toml", "ranges.toml",
                                     "long.csv", "ok.csv", "adc.csv", "ok.mcap", "junk.mcap", "dir")] + [
        "/dev/zero", "/nonexistent/file", "out-new"]


def _commands() -> dict[str, list[argparse.Action]]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {name: [a for a in p._actions if not isinstance(a, argparse._HelpAction)]
            for name, p in sub.choices.items()}


COMMANDS = _commands()


def _value(action: argparse.Action, files: list[str]):
    if action.choices:
        return st.sampled_from([*map(str, action.choices), "nope"])
    if action.type in (float, int):
        return st.sampled_from(NUMBERS)
    if action.type is Path or any(w in (action.dest or "") for w in ("out", "objects", "ranges", "record",
                                                                        "recording", "results", "dir")):
        return st.sampled_from(files)
    return st.sampled_from(TEXTS + files[:3])


@st.composite
def _argv(draw, files):
    name = draw(st.sampled_from(sorted(COMMANDS)))
    actions = COMMANDS[name]
    argv = [name]
    for a in actions:
        if not a.option_strings:             # positionals: always given, a valid one half the time
            good = files[6] if name in ("detect", "claims") else files[8]
            argv.append(draw(st.sampled_from([good, good, good, *files])))
    optional = [a for a in actions if a.option_strings]
    for a in draw(st.lists(st.sampled_from(optional), max_size=4, unique_by=lambda a: a.dest)):
        opt = a.option_strings[-1]
        if a.nargs == 0:
            argv.append(opt)
        elif a.nargs in ("+", "*"):
            argv += [opt, *draw(st.lists(_value(a, files), min_size=1, max_size=3))]
        else:
            argv += [opt, draw(_value(a, files))]
    return argv


@pytest.fixture
def sandbox(tmp_path, monkeypatch):
    import importlib

    for mod, name in WORK:
        monkeypatch.setattr(importlib.import_module(mod), name, _stop)
    monkeypatch.chdir(tmp_path)
    return _files(tmp_path)


@pytest.mark.slow
def test_every_option_value_is_refused_in_one_line_or_reaches_the_work(sandbox, capsys):
    @SETTINGS
    @given(_argv(sandbox))
    def check(argv):
        try:
            code = main(argv)
        except SystemExit as stop:             # argparse: usage and one error line
            code = stop.code
        except Reached:
            code = "reached"
        err = capsys.readouterr().err
        assert "Traceback" not in err, (argv, err)
        assert code in (0, 1, 2, 130, "reached"), (argv, code, err)
        if code == 2 and "usage:" not in err:
            lines = [x for x in err.splitlines() if x.strip() and "warning" not in x]
            assert len(lines) == 1, (argv, err)

    check()


# --- objects and ranges TOML files ---------------------------------------------------------------

_FIELDS = {"bottles": ["mass_kg", "diameter_m", "mu_s", "mu_k", "surface", "height_m", "wall_stiffness_n_m",
                       "stribeck_velocity_m_s", "heal_s", "name", "friction_law", "grip_travel_m", "rate_a"],
           "surfaces": ["reflectance", "texture", "texture_exponent", "texture_min_wavelength_m",
                        "texture_max_wavelength_m"],
           "drops": ["mass_kg", "height_m", "contact_stiffness_n_m", "restitution"],
           "pours": ["rate_l_min", "volume_ml", "fall_height_m"]}

_SCALARS = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**30, 10**30),
                     st.sampled_from([1e30, -1e30, 1e-30, 0.0, 0.05, 0.8, 5e-324]), st.booleans(),
                     st.text(max_size=8), st.sampled_from(["DK", "white", "coulomb", ""]))
_VALUES = st.one_of(_SCALARS, st.lists(_SCALARS, max_size=3), st.dictionaries(st.text(max_size=4), _SCALARS,
                                                                                max_size=2))


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {_toml_value(x)}" for k, x in v.items()) + "}"


@st.composite
def _objects_doc(draw):
    lines = []
    for kind in draw(st.lists(st.sampled_from([*_FIELDS, "other"]), max_size=3, unique=True)):
        if draw(st.booleans()):
            lines.append(f"{kind} = {_toml_value(draw(_SCALARS))}")
            continue
        for name in draw(st.lists(st.sampled_from(["A", "B", "TR"]), min_size=1, max_size=2, unique=True)):
            lines.append(f"[{kind}.{name}]")
            for f in draw(st.lists(st.sampled_from(_FIELDS.get(kind, ["x"]) + ["unknown"]), max_size=6,
                                   unique=True)):
                lines.append(f"{f} = {_toml_value(draw(_VALUES))}")
    return "\n".join(lines) + "\n"


@st.composite
def _ranges_doc(draw):
    from slipreflex.sim.uncertain import UNCERTAIN

    lines = []
    for name in draw(st.lists(st.sampled_from([*list(UNCERTAIN)[:8], "hand_latency", "wall_stiffness", "nope"]),
                              max_size=3, unique=True)):
        lines.append(f"[{name}]")
        for key in draw(st.lists(st.sampled_from(["low", "high", "nominal", "fixed", "distribution", "x"]),
                                 max_size=3, unique=True)):
            lines.append(f"{key} = {_toml_value(draw(_VALUES))}")
    return "\n".join(lines) + "\n"


def _load_is_clean(load, path: Path) -> None:
    try:
        load(path)
    except SlipreflexError as err:
        assert "\n" not in str(err) and str(path) in str(err), err


@pytest.mark.slow
def test_objects_files_load_or_are_refused_in_one_line(tmp_path):
    from slipreflex.sim import load_objects

    @SETTINGS
    @given(st.one_of(_objects_doc(), st.binary(max_size=64).map(lambda b: b)))
    def check(doc):
        p = tmp_path / "o.toml"
        p.write_bytes(doc if isinstance(doc, bytes) else doc.encode())
        _load_is_clean(load_objects, p)

    check()


@pytest.mark.slow
def test_ranges_files_load_or_are_refused_in_one_line(tmp_path):
    from slipreflex.sim.uncertain import load_ranges

    @SETTINGS
    @given(st.one_of(_ranges_doc(), st.binary(max_size=64)))
    def check(doc):
        p = tmp_path / "r.toml"
        p.write_bytes(doc if isinstance(doc, bytes) else doc.encode())
        _load_is_clean(load_ranges, p)

    check()


def test_the_fuzzed_commands_cover_every_command():
    assert {"detect", "reproduce", "study", "scan", "virtual-rig", "run", "export", "replay", "recover",
            "claims", "calibrate"} <= set(COMMANDS)
