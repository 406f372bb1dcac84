"""Recordings cut by a crash or damaged: every gap reported, standard MCAP readers after `recover`.

The `mcap` command-line tool could not be installed here (the Go module proxy refuses
github.com/foxglove/mcap/go/cli/mcap), so the standard readers checked are the mcap
package's `make_reader` (seeking) and `NonSeekingReader`.
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading

import pytest
from mcap.reader import NonSeekingReader, make_reader
from test_recording import _CHILD

from conftest import reap_child
from slipreflex.cli import main
from slipreflex.core.errors import DataError
from slipreflex.files.recording import METADATA_NAME, PLANNED_SAMPLES, Recorder, read_recording, recover_recording
from slipreflex.methods.chain import ReflexParams, SlipReflex
from slipreflex.rig.replay import replay

N = 2000


def _run_recording(path, n=N, chunk_size=2000, planned=True):
    """A recording like `run --duration` writes: parameters with the planned sample count, samples,
    the reflex's commands, a final /stats."""
    params = ReflexParams(p0=100.0, dath=True)
    reflex = SlipReflex(params)
    meta = {METADATA_NAME: {"reflex_params": json.dumps(params.to_dict()),
                            **({PLANNED_SAMPLES: str(n)} if planned else {})}}
    with Recorder(path, metadata=meta, chunk_size=chunk_size) as rec:
        for k in range(n):
            v = 0.4 + (0.05 * ((k * 7919) % 13 - 6) if 600 < k < 900 else 0.0)
            cmd = reflex.step(v)
            rec.write("/daq/samples", {"seq": k, "t": k * 0.003, "slip_volts": v, "flow_pulses": 0,
                                       "arrival": k * 0.003, "position": None}, k)
            if reflex.last_event:
                rec.write("/chain/events", {"seq": k, "t": k * 0.003}, k)
            if cmd is not None:
                rec.write("/hand/commands", {"seq": k, "t": k * 0.003, "target": cmd, "fingers": ["middle"],
                                             "sent": True, "latency": 1e-4}, k)
        rec.write("/stats", {"time": n * 0.003, "counters": {"samples": n}}, n)
    return path


def _count_standard(path):
    """Messages mcap's own readers find (seeking and streaming)."""
    with open(path, "rb") as fh:
        seeking = sum(1 for _ in make_reader(fh).iter_messages())
    with open(path, "rb") as fh:
        streaming = sum(1 for _ in NonSeekingReader(fh).iter_messages())
    return seeking, streaming


def _chunk_offsets(data):
    pos, out = 8, []
    while pos + 9 <= len(data):
        if data[pos] == 0x06:
            out.append(pos)
        if data[pos] == 0x02:
            break
        pos += 9 + int.from_bytes(data[pos + 1:pos + 9], "little")
    return out


@pytest.mark.slow
def test_a_sigkilled_recording_opens_with_make_reader_after_recover(tmp_path, capsys):
    path = tmp_path / "killed.mcap"
    proc = subprocess.Popen([sys.executable, "-c", _CHILD, str(path)], stdout=subprocess.PIPE, text=True)
    killer = threading.Timer(90, proc.kill)
    killer.start()
    try:
        for line in proc.stdout:
            if int(line) >= 700:
                break
        proc.kill()
        proc.wait(timeout=10)
    finally:
        reap_child(proc, killer)
    path = tmp_path / "killed.mcap.part"   # a killed run leaves NAME.part
    with open(path, "rb") as fh, pytest.raises(Exception):  # noqa: B017 - any failure: no footer
        sum(1 for _ in make_reader(fh).iter_messages())  # why `recover` exists
    ours = read_recording(path)
    assert not ours.complete and ours.gaps()
    out = tmp_path / "killed-recovered.mcap"
    assert main(["recover", str(path)]) == 0
    said = capsys.readouterr().out
    assert f"to {out}" in said and "killed.mcap" in said.splitlines()[-1]
    n = len(ours.topic("/chain/events"))
    assert n >= 400 and _count_standard(out) == (n, n)
    again = read_recording(out)
    assert again.complete and not again.gaps() and again.topic("/chain/events") == ours.topic("/chain/events")


@pytest.mark.slow
@pytest.mark.parametrize("keep", [0.37, 0.61, 0.93, 0.999])
def test_a_recording_cut_anywhere_is_recovered_up_to_its_last_complete_chunk(tmp_path, keep):
    whole = _run_recording(tmp_path / "whole.mcap").read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole[:int(len(whole) * keep)])
    rec = read_recording(cut)
    got = len(rec.topic("/daq/samples"))
    assert 0 < got <= N and rec.cut_at is not None
    assert f"read {got} of the {N} samples it should hold; cut short at byte {rec.cut_at}" in rec.gaps()
    res = recover_recording(cut, tmp_path / "fixed.mcap")
    total = sum(len(m) for m in rec.messages.values())
    assert res.messages == total and _count_standard(tmp_path / "fixed.mcap") == (total, total)


def test_a_bit_flip_in_a_chunk_is_skipped_reported_and_needs_allow_partial(tmp_path, capsys):
    path = _run_recording(tmp_path / "flip.mcap")
    data = bytearray(path.read_bytes())
    chunks = _chunk_offsets(data)
    bad = chunks[len(chunks) // 2]
    data[bad + 300] ^= 0x10
    path.write_bytes(bytes(data))
    rec = read_recording(path)
    assert [pos for pos, _ in rec.damaged] == [bad]
    samples = [m["seq"] for m in rec.topic("/daq/samples")]
    missing = sorted(set(range(N)) - set(samples))
    assert missing and missing == list(range(missing[0], missing[-1] + 1))  # one chunk's worth
    assert samples[-1] == N - 1  # the reader went on after the damaged chunk
    line = f"read {len(samples)} of the {N} samples it should hold; chunk at byte {bad} damaged"
    assert line in rec.gaps()
    for cmd in (["replay", str(path)], ["export", str(path)]):
        assert main(cmd) == 2
        err = capsys.readouterr().err
        assert line in err and "--allow-partial" in err and len(err.strip().splitlines()) == 1
    assert main(["replay", str(path), "--allow-partial"]) == 0  # exact up to the damage
    out = capsys.readouterr()
    assert line in out.err and "checked up to the first gap" in out.out
    assert replay(rec).samples == missing[0]
    assert main(["export", str(path), "--allow-partial"]) == 0
    assert line in capsys.readouterr().err


def test_empty_header_only_and_early_cut_recordings_are_errors_not_identical(tmp_path, capsys):
    empty = tmp_path / "empty.mcap"
    meta = {METADATA_NAME: {"reflex_params": json.dumps(ReflexParams().to_dict())}}
    with Recorder(empty, metadata=meta):
        pass
    assert main(["replay", str(empty)]) == 2
    assert "no samples" in capsys.readouterr().err
    whole = _run_recording(tmp_path / "whole.mcap").read_bytes()
    for n in (3, 200, 480):
        early = tmp_path / f"early{n}.mcap"
        early.write_bytes(whole[:n])
        assert main(["replay", str(early), "--allow-partial"]) == 2
        err = capsys.readouterr().err
        assert "cut short" in err and "not a slipreflex run recording" not in err, err
    with pytest.raises(DataError, match="no samples"):
        replay(read_recording(empty))

