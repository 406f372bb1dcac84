"""Outputs are new files: a symlink is never written through, a user's file never replaced, an
output set swapped whole and rolled back when its commit fails, one process at a time per folder,
and every refusal before any work."""

from __future__ import annotations

import json
import multiprocessing
import os
from pathlib import Path

import pytest

from slipreflex.cli import main
from slipreflex.core.errors import ParameterError
from slipreflex.files.paths import MANIFEST, OutputSet, unique_prefix


def _set(folder, names, text):
    out = OutputSet(folder, "demo")
    out.check(names)
    staged = out.stage()
    for n in names:
        (staged / n).write_text(text)
    return out, staged


def test_a_failed_manifest_write_rolls_back_to_the_previous_set(tmp_path, monkeypatch):
    out, staged = _set(tmp_path, ["a.csv", "b.csv"], "old")
    out.commit(staged)
    out, staged = _set(tmp_path, ["a.csv", "b.csv"], "new")
    from slipreflex.files import paths

    real = paths.new_file

    def no_inodes(path, *a, **kw):
        if Path(path).name == MANIFEST:
            raise OSError(28, "No space left on device")
        return real(path, *a, **kw)

    monkeypatch.setattr(paths, "new_file", no_inodes)
    with pytest.raises(OSError, match="No space"):
        out.commit(staged)
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text() == "old"
    assert json.loads((tmp_path / MANIFEST).read_text())["files"] == ["a.csv", "b.csv"]
    assert sorted(p.name for p in tmp_path.iterdir()) == [MANIFEST, "a.csv", "b.csv"]


def test_a_failed_rename_half_way_rolls_back_too(tmp_path, monkeypatch):
    out, staged = _set(tmp_path, ["a.csv", "b.csv"], "old")
    out.commit(staged)
    out, staged = _set(tmp_path, ["a.csv", "b.csv"], "new")
    real, calls = os.rename, []

    def fail_second_placement(src, dst):
        if ".demo-new-" in str(src) and Path(dst).parent == tmp_path:
            calls.append(dst)
            if len(calls) == 2:
                raise OSError(122, "Disk quota exceeded")
        return real(src, dst)

    monkeypatch.setattr(os, "rename", fail_second_placement)
    with pytest.raises(OSError):
        out.commit(staged)
    monkeypatch.undo()
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text() == "old"


def test_a_manifest_name_that_is_a_folder_is_refused_before_any_work(tmp_path):
    (tmp_path / MANIFEST).mkdir()
    with pytest.raises(ParameterError, match="is not a regular file"):
        OutputSet(tmp_path, "demo")


def _hold_lock(folder, ready, done):
    out = OutputSet(folder, "demo")
    out.claim()
    ready.set()
    done.wait(20)


def test_a_second_process_on_the_same_folder_is_refused_while_the_first_holds_it(tmp_path):
    ctx = multiprocessing.get_context("fork")
    ready, done = ctx.Event(), ctx.Event()
    proc = ctx.Process(target=_hold_lock, args=(tmp_path, ready, done))
    proc.start()
    try:
        assert ready.wait(20)
        with pytest.raises(ParameterError, match="another slipreflex command is writing"):
            OutputSet(tmp_path, "demo").claim()
    finally:
        done.set()
        proc.join(20)
    out = OutputSet(tmp_path, "demo")
    out.claim()                      # free again once the first has finished
    out.release()


def test_a_commit_waits_for_another_commit_and_both_sets_stay_whole(tmp_path):
    ctx = multiprocessing.get_context("fork")
    ready, done = ctx.Event(), ctx.Event()
    proc = ctx.Process(target=_hold_lock, args=(tmp_path, ready, done))
    proc.start()
    assert ready.wait(20)
    out, staged = _set(tmp_path, ["a.csv"], "second")
    ctx.Process(target=lambda: (ready.wait(0.3), done.set())).start()  # the first lets go in 0.3 s
    out.commit(staged)               # waits for it, then swaps
    proc.join(20)
    assert (tmp_path / "a.csv").read_text() == "second"


def test_unique_prefix_never_takes_a_symlink_name(tmp_path):
    (tmp_path / "run.samples.csv").symlink_to(tmp_path / "elsewhere")
    assert unique_prefix(tmp_path / "run", [".samples.csv", ".windows.csv"]).name == "run-2"


def test_detect_out_never_replaces_or_follows(tmp_path, capsys):
    src = tmp_path / "slip.csv"
    src.write_text("t,x\n" + "".join(f"{k * 0.003:.3f},0.4\n" for k in range(64)))
    victim = tmp_path / "victim.txt"
    victim.write_text("mine")
    (tmp_path / "res.samples.csv").write_text("user's own")
    (tmp_path / "res.windows.csv").symlink_to(victim)
    assert main(["detect", str(src), "--out", str(tmp_path / "res")]) == 0
    out = capsys.readouterr().out
    assert "res-2.samples.csv" in out and "exist and are kept" in out
    assert (tmp_path / "res.samples.csv").read_text() == "user's own" and victim.read_text() == "mine"
    assert (tmp_path / "res-2.samples.csv").exists() and (tmp_path / "res-2.windows.csv").exists()


@pytest.mark.slow
def test_calibrate_figure_never_writes_through_a_symlink(tmp_path, capsys):
    victim = tmp_path / "outside.txt"
    victim.write_text("mine")
    fig = tmp_path / "cal.png"
    fig.symlink_to(victim)
    assert main(["calibrate", "--bottles", "TX", "--figure", str(fig)]) == 0
    out = capsys.readouterr().out
    assert victim.read_text() == "mine" and fig.is_symlink()
    assert "cal-2.png" in out and (tmp_path / "cal-2.png").read_bytes()[:4] == b"\x89PNG"
