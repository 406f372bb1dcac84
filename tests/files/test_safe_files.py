"""Files a command writes: created new, whole or absent, never someone else's; damage detected.

Covers docs/runtime.md "Files": recordings (`run --record`), exports, `virtual-rig --link-dir`
links, `reproduce`/`scan` output sets, metadata checksums, truncation against the planned
count and `recover` of nothing.
"""

from __future__ import annotations

import json
import os

import pytest

from slipreflex.cli import main
from slipreflex.core.errors import ParameterError
from slipreflex.files.paths import OutputSet, create_new, new_file, unique_name
from slipreflex.files.recording import METADATA_NAME, PLANNED_SAMPLES, Recorder, RecordingError, read_recording

RUN = ["run", "--daq", "/nonexistent/daq", "--hand", "/nonexistent/hand", "--p0", "148"]


def _recording(path, n=300, planned=None):
    from slipreflex.methods.chain import ReflexParams

    meta = {"reflex_params": json.dumps(ReflexParams(p0=100.0).to_dict()), "p0": '{"middle": 100.0}'}
    if planned:
        meta[PLANNED_SAMPLES] = str(planned)
    with Recorder(path, metadata={METADATA_NAME: meta}, chunk_size=2000) as rec:
        for k in range(n):
            rec.write("/daq/samples", {"seq": k, "t": k * 0.003, "slip_volts": 0.4, "flow_pulses": 0,
                                       "arrival": 0.0, "position": None}, k)
    return path


# --- created new: exclusive, no symlink followed, unique default names ---------------------------

def test_run_record_never_touches_an_existing_file_a_symlink_or_a_device(tmp_path, capsys):
    old = tmp_path / "old.mcap"
    old.write_bytes(b"x" * 1_000_000)
    target = tmp_path / "target"
    target.write_text("keep me")
    link = tmp_path / "link.mcap"
    link.symlink_to(target)
    for rec in (old, link, "/dev/null"):
        assert main(RUN + ["--record", str(rec)]) == 2
        err = capsys.readouterr().err
        assert "exists" in err and len(err.strip().splitlines()) == 1
    assert old.read_bytes() == b"x" * 1_000_000 and target.read_text() == "keep me"
    assert link.is_symlink() and os.path.exists("/dev/null")


def test_run_whose_port_fails_removes_only_the_recording_it_created(tmp_path, capsys):
    rec = tmp_path / "new.mcap"
    assert main(RUN + ["--record", str(rec)]) == 2
    assert "nonexistent" in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == []


def test_two_default_names_in_the_same_second_differ(tmp_path):
    a = Recorder(unique_name(tmp_path, "run-x", ".mcap", also=(".part",)))
    b = Recorder(unique_name(tmp_path, "run-x", ".mcap", also=(".part",)))
    a.close(), b.close()
    assert sorted(os.listdir(tmp_path)) == ["run-x-2.mcap", "run-x.mcap"]


def test_a_recording_is_named_only_when_closed(tmp_path):
    path = tmp_path / "r.mcap"
    rec = Recorder(path)
    assert not path.exists() and (tmp_path / "r.mcap.part").exists()
    rec.close()
    assert path.exists() and not (tmp_path / "r.mcap.part").exists()
    with pytest.raises(RecordingError, match="exists"):
        Recorder(path)


def test_create_new_and_new_file_refuse_what_exists(tmp_path):
    (tmp_path / "t").write_text("mine")
    (tmp_path / "l").symlink_to(tmp_path / "t")
    for name in ("t", "l"):
        with pytest.raises(FileExistsError):
            create_new(tmp_path / name)
        with pytest.raises(FileExistsError), new_file(tmp_path / name) as fh:
            fh.write("no")
    assert (tmp_path / "t").read_text() == "mine"
    with pytest.raises(KeyboardInterrupt), new_file(tmp_path / "half") as fh:
        fh.write("half")
        raise KeyboardInterrupt
    assert sorted(os.listdir(tmp_path)) == ["l", "t"]   # no temporary file left


def test_export_onto_its_recording_or_an_existing_csv_is_refused(tmp_path, capsys):
    path = _recording(tmp_path / "r.mcap")
    before = path.read_bytes()
    assert main(["export", str(path), "--out", str(path)]) == 2
    assert "exists" in capsys.readouterr().err and path.read_bytes() == before
    assert main(["export", str(path)]) == 0
    first = (tmp_path / "r.csv").read_text()
    assert main(["export", str(path)]) == 2 and "exists" in capsys.readouterr().err
    assert (tmp_path / "r.csv").read_text() == first


def test_link_dir_keeps_a_users_file_and_removes_only_its_own_links(tmp_path, capsys):
    from slipreflex.rig.devices.virtual import PtyPort

    (tmp_path / "daq").write_text("precious")
    assert main(["virtual-rig", "--link-dir", str(tmp_path), "--duration", "1"]) == 2
    assert "daq exists" in capsys.readouterr().err and (tmp_path / "daq").read_text() == "precious"
    with pytest.raises(ParameterError, match="not this rig's link"):
        PtyPort(str(tmp_path / "daq"))
    assert (tmp_path / "daq").read_text() == "precious"
    port = PtyPort(str(tmp_path / "hand"))
    assert (tmp_path / "hand").is_symlink()
    port.unplug(), port.replug()                   # its own link: removed and made again
    assert os.readlink(tmp_path / "hand") == port.slave_name
    os.unlink(tmp_path / "hand")
    (tmp_path / "hand").write_text("the user's since")
    port.close()
    assert (tmp_path / "hand").read_text() == "the user's since"


# --- output sets: whole, previous untouched on Ctrl-C, no stale files --------------------------

def test_output_set_refuses_a_users_file_and_replaces_its_own_set_whole(tmp_path):
    out = OutputSet(tmp_path, "demo")
    (tmp_path / "mine.txt").write_text("user")
    with pytest.raises(ParameterError, match="mine.txt exists and was not written by slipreflex demo"):
        out.check(["mine.txt"])
    s = out.stage()
    (s / "a.csv").write_text("1")
    (s / "old-only.png").write_text("1")
    out.commit(s)
    s = out.stage()
    (s / "a.csv").write_text("2")
    out.commit(s)
    assert sorted(os.listdir(tmp_path)) == [".slipreflex-outputs.json", "a.csv", "mine.txt"]  # no stale file
    assert (tmp_path / "a.csv").read_text() == "2"


def _fake_result():
    from slipreflex.analysis.outputs import ReproduceResult
    from slipreflex.reproduce.experiments import ReproduceConfig

    return ReproduceResult(ReproduceConfig(trials=1), [], [], {}, {}, 0.0, 1, 0.0, 1, 1)


def test_reproduce_interrupted_while_writing_leaves_the_previous_set(tmp_path, monkeypatch, capsys):
    import slipreflex.commands.reproduce as ex  # the command's names, patched where it calls them

    out = tmp_path / "out"
    argv = ["reproduce", "--trials", "1", "--bottles", "TX", "--methods", "dath", "--experiments", "drop",
            "--jobs", "1", "--no-progress", "--out", str(out)]
    monkeypatch.setattr(ex, "run_reproduce", lambda *a, **k: _fake_result())

    def writes(result, folder, **kw):
        for name in ("results.csv", "summary.csv", "report.md"):
            (folder / name).write_text("first")
        (folder / "figures").mkdir()
        (folder / "figures" / "old.png").write_text("first")

    monkeypatch.setattr(ex, "write_outputs", writes)
    assert main(argv) == 0
    capsys.readouterr()

    def half(result, folder, **kw):
        (folder / "results.csv").write_text("second")
        raise KeyboardInterrupt

    monkeypatch.setattr(ex, "write_outputs", half)
    assert main(argv) == 130
    err = capsys.readouterr().err
    assert "interrupted" in err and "untouched" in err
    assert sorted(os.listdir(out)) == [".slipreflex-outputs.json", "figures", "report.md", "results.csv",
                                       "summary.csv"]
    assert all((out / n).read_text() == "first" for n in ("results.csv", "summary.csv", "report.md"))

    def second(result, folder, **kw):
        for name in ("results.csv", "summary.csv", "report.md"):
            (folder / name).write_text("second")

    monkeypatch.setattr(ex, "write_outputs", second)
    assert main(argv) == 0
    assert not (out / "figures").exists()           # the earlier run's figures do not stay beside
    assert (out / "report.md").read_text() == "second"


def test_reproduce_refuses_an_out_holding_a_users_results_before_any_work(tmp_path, monkeypatch, capsys):
    import slipreflex.commands.reproduce as ex

    (tmp_path / "results.csv").write_text("mine")
    monkeypatch.setattr(ex, "run_reproduce", lambda *a, **k: pytest.fail("work started"))
    assert main(["reproduce", "--out", str(tmp_path)]) == 2
    assert "results.csv exists and was not written by slipreflex reproduce" in capsys.readouterr().err
    assert (tmp_path / "results.csv").read_text() == "mine"


# --- recordings that know they are damaged ------------------------------------------------------

def test_a_bit_flip_in_the_metadata_is_damaged_metadata_not_different(tmp_path, capsys):
    path = _recording(tmp_path / "r.mcap")
    data = bytearray(path.read_bytes())
    at = data.index(b'"kp": ') + len(b'"kp": ')
    data[at] ^= 0x01                                 # 5.0 -> 4.0: still valid JSON, a wrong gain
    path.write_bytes(bytes(data))
    rec = read_recording(path)
    assert rec.bad_metadata == [METADATA_NAME] and METADATA_NAME not in rec.metadata
    for cmd in (["replay", str(path)], ["replay", str(path), "--allow-partial"], ["export", str(path)]):
        assert main(cmd) == 2, cmd
        out = capsys.readouterr()
        assert "damaged metadata" in out.err and "DIFFERENT" not in out.out
    assert not (tmp_path / "r.csv").exists()


def test_a_truncation_is_reported_against_the_planned_count(tmp_path):
    whole = _recording(tmp_path / "w.mcap", n=2000, planned=2000).read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole[:len(whole) // 2])
    rec = read_recording(cut)
    got = len(rec.topic("/daq/samples"))
    assert 0 < got < 2000 and f"read {got} of the 2000 samples it should hold" in rec.gaps()
    unplanned = _recording(tmp_path / "u.mcap", n=2000).read_bytes()
    cut.unlink()
    cut.write_bytes(unplanned[:len(unplanned) // 2])
    assert "how many it should hold is not recorded" in read_recording(cut).gaps()


def test_recover_of_nothing_fails_and_its_summary_counts_what_it_read(tmp_path, capsys):
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"\x89MCAP0\r\n" + os.urandom(4000))
    assert main(["recover", str(junk)]) == 2
    assert "no readable message" in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == ["junk.mcap"]
    whole = _recording(tmp_path / "w.mcap", n=2000, planned=2000).read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole[:len(whole) // 2])
    got = len(read_recording(cut).topic("/daq/samples"))
    assert main(["recover", str(cut)]) == 0
    said = capsys.readouterr().out
    assert f"read {got} of the 2000 samples it should hold" in said and "read 0" not in said
    assert main(["recover", str(cut)]) == 2        # the recovered file exists: never replaced
    assert "exists" in capsys.readouterr().err
