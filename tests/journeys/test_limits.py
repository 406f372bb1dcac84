"""Bounded work and one line for every bad input (docs/runtime.md "Limits" and "Files").

Each case of the list that used to run for days, eat the memory or end in a traceback:
refused before any work with one line and exit status 2.
"""

from __future__ import annotations

import pytest

from slipreflex.cli import main
from slipreflex.core.validation import LIMITS, limits_markdown, within


def _one_line(capsys, *needles):
    err = capsys.readouterr().err
    lines = [x for x in err.splitlines() if x.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    for n in needles:
        assert n in lines[0], err
    return lines[0]


@pytest.fixture
def no_work(monkeypatch):
    """Any command that gets past its checks fails the test (nothing may start)."""
    import slipreflex.commands.reproduce as reproduce
    import slipreflex.commands.study as study
    import slipreflex.sim as sim

    def started(*a, **k):
        raise AssertionError("work started")

    # each where its command calls it (scan's command imports it when it runs: numba stays out of the CLI)
    for mod, name in ((reproduce, "run_reproduce"), (sim, "scan"), (study, "run_study")):
        monkeypatch.setattr(mod, name, started)


@pytest.mark.parametrize("argv, option", [
    (["reproduce", "--rest", "1e9"], "--rest"),
    (["reproduce", "--trials", "100000000"], "--trials"),
    (["reproduce", "--after", "nan"], "--after"),
    (["reproduce", "--jobs", "0"], "--jobs"),
    (["study", "--plants", "1000000000"], "--plants"),
    (["study", "--trials", "0"], "--trials"),
    (["scan", "--distance", "1e9"], "--distance"),
    (["scan", "--speed", "1e-9"], "--speed"),
    (["virtual-rig", "--duration", "nan"], "--duration"),
    (["virtual-rig", "--duration", "-1"], "--duration"),
    (["detect", "examples/slip_example.csv", "--fs", "1e300"], "--fs"),
    (["detect", "--board", "examples/slip_example.csv", "--p0", "nan"], "--p0"),
])
def test_an_unbounded_option_is_one_line_before_any_work(argv, option, no_work, capsys, tmp_path):
    assert main([*argv, *(["--out", str(tmp_path / "o")] if argv[0] in ("reproduce", "study", "scan") else [])]) == 2
    _one_line(capsys, option)


@pytest.mark.parametrize("command", [["replay"], ["export"], ["recover"], ["detect"], ["claims"]])
def test_readers_given_dev_zero_say_so_in_one_line(command, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main([*command, "/dev/zero"]) == 2
    _one_line(capsys, "/dev/zero")


def _files(tmp_path, argv=("long.csv",)):
    (tmp_path / "bin.toml").write_bytes(bytes(range(256)))
    (tmp_path / "latin1.toml").write_bytes(b'[bottles.B]\nname = "caf\xe9"\n')
    (tmp_path / "five.toml").write_text("bottles = 5\n")
    (tmp_path / "wall.toml").write_text('[bottles.B]\nmass_kg = 0.05\ndiameter_m = 0.06\nmu_s = 1.0\n'
                                        'mu_k = 0.8\nsurface = "DK"\nwall_stiffness_n_m = 1e30\n')
    (tmp_path / "latency.toml").write_text("[hand_latency]\nfixed = 1e30\n")
    if "long.csv" in argv:      # 50 MB: written only for the case that reads it
        (tmp_path / "long.csv").write_text("t,x\n" + "1" * 50_000_000 + "\n")
    return tmp_path


@pytest.mark.parametrize("argv, says", [
    (["reproduce", "--objects", "bin.toml"], "not UTF-8"),
    (["reproduce", "--objects", "latin1.toml"], "not UTF-8"),
    (["study", "--ranges", "bin.toml"], "not UTF-8"),
    (["study", "--ranges", "latin1.toml"], "not UTF-8"),
    (["reproduce", "--objects", "five.toml"], "bottles must be a table"),
    (["study", "--ranges", "five.toml"], "unknown constant"),
    (["reproduce", "--objects", "wall.toml", "--bottles", "B"], "wall_stiffness_n_m"),
    (["study", "--ranges", "latency.toml"], "hand_latency.fixed"),
    (["claims", "bin.toml"], "not UTF-8"),
    (["detect", "long.csv"], "longer than"),
    (["scan", "--layout", ""], "--layout"),
])
def test_bad_files_and_values_are_one_line(argv, says, no_work, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(_files(tmp_path, argv))
    assert main(argv) == 2
    _one_line(capsys, says)


def test_the_docs_carry_the_limits_table_of_the_code():
    from pathlib import Path

    doc = (Path(__file__).parents[2] / "docs" / "runtime.md").read_text()
    assert limits_markdown() in doc


def test_within_names_the_option_and_the_range():
    assert within("trials", 10) == 10
    with pytest.raises(ValueError, match=r"--rest .* \(plausible range > 0..600 s"):
        within("rest_s", float("inf"), "--rest")
    assert all(lim.lo <= lim.hi for lim in LIMITS.values())


def test_numba_cache_falls_back_to_a_private_folder_or_none(tmp_path, monkeypatch, capsys):
    from slipreflex.core import _numba_cache as nc

    unwritable = tmp_path / "ro"
    monkeypatch.setattr(nc, "_writable", lambda folder: tmp_path / "tmp" in folder.parents or
                        folder == tmp_path / "tmp")
    (tmp_path / "tmp").mkdir()
    folder, on, warning = nc.choose_cache(unwritable, unwritable / "cache", tmp_path / "tmp")
    assert on and folder == str(tmp_path / "tmp" / f"slipreflex-numba-{__import__('os').getuid()}")
    assert "neither" in warning
    monkeypatch.setattr(nc, "_writable", lambda folder: False)
    folder, on, warning = nc.choose_cache(unwritable, unwritable / "cache", tmp_path / "tmp")
    assert folder is None and not on and "compile in every process" in warning

    monkeypatch.setenv("NUMBA_CACHE_DIR", "set")   # restored (to unset) after the test
    monkeypatch.delenv("NUMBA_CACHE_DIR")
    monkeypatch.setattr(nc, "choose_cache", lambda *a: (str(tmp_path), True, "numba's cache: test"))
    import numba.core.config as config

    monkeypatch.setattr(config, "CACHE_DIR", config.CACHE_DIR)
    assert nc._decide() is True
    assert __import__("os").environ["NUMBA_CACHE_DIR"] == str(tmp_path) and config.CACHE_DIR == str(tmp_path)
    assert "warning: numba's cache: test" in capsys.readouterr().err
