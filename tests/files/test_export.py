"""`slipreflex export`: the preamble that lets `detect` rerun the run's chain; safe output paths."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from slipreflex.cli import main
from slipreflex.files.csvfiles import read_preamble, read_slip_csv
from slipreflex.files.recording import EXPORT_FORMAT, METADATA_NAME, Recorder, read_recording
from slipreflex.methods.chain import ReflexParams, SlipReflex, run_chain
from slipreflex.rig.runtime import run_loop

P0 = {"thumb": 148.0, "index": 147.0, "middle": 147.0}


class _Slipping:
    """Samples that make the reflex act: still, then noisy (a slip), then still."""

    def __init__(self, n=1200, seed=3):
        rng = np.random.default_rng(seed)
        v = 0.4 + np.where((np.arange(n) > 300) & (np.arange(n) < 500), 0.2 * rng.standard_normal(n), 0.0)
        from slipreflex.core.interfaces import DaqSample
        self.left = [DaqSample(k, k * 0.003, float(v[k]), None, 0) for k in range(n)]

    def read(self, timeout):
        out, self.left = self.left[:8], self.left[8:]
        return out

    def close(self):
        pass


class _Hand:
    def __init__(self):
        self.pos = {}

    def set_positions(self, t):
        self.pos.update(t)

    def close_fingers(self, fingers, speed):
        pass

    def hold(self, fingers):
        pass

    def positions(self):
        return dict(self.pos)


def _recorded_run(tmp_path):
    params = ReflexParams(dath=True, p0=P0["middle"])
    path = tmp_path / "run.mcap"
    meta = {"reflex": "dath", "reflex_params": json.dumps(params.to_dict()), "p0": json.dumps(P0)}
    from slipreflex.core.hardware import Finger
    with Recorder(path, metadata={METADATA_NAME: meta}) as rec:
        res = run_loop(_Slipping(), _Hand(), SlipReflex(params), recorder=rec, duration=0.5,
                       p0={Finger[k.upper()]: v for k, v in P0.items()}, watchdog=0.5)
    assert res.samples == 1200 and res.commands_sent > 0
    return path


@pytest.mark.slow
def test_export_preamble_carries_p0_and_the_chain_so_the_commands_can_be_rerun(tmp_path, capsys):
    path = _recorded_run(tmp_path)
    assert main(["export", str(path)]) == 0
    csv = tmp_path / "run.csv"
    pre = read_preamble(csv)
    assert pre["format"] == EXPORT_FORMAT and pre["source"] == "run.mcap"
    assert json.loads(pre["p0"]) == P0
    params = ReflexParams.from_dict(json.loads(pre["reflex_params"]))
    t, x = read_slip_csv(csv)  # the preamble does not disturb the reader
    assert len(x) == 1200
    recorded = [m["target"] for m in read_recording(path).topic("/hand/commands")]
    assert run_chain(x, params).commands.tolist() == recorded  # the run's commands, rerun
    assert max(recorded) > P0["middle"]


@pytest.mark.slow
@pytest.mark.parametrize("out, says", [
    ("{tmp}", "not a regular file"), ("{tmp}/missing/x.csv", "does not exist"),
    ("/proc/version", "exists"), ("{tmp}/fifo", "not a regular file"),
])
def test_export_out_that_is_not_a_regular_file_is_one_line_and_replaces_nothing(tmp_path, capsys, out, says):
    path = _recorded_run(tmp_path)
    os.mkfifo(tmp_path / "fifo")
    target = out.format(tmp=tmp_path)
    code = main(["export", str(path), "--out", target])
    err = capsys.readouterr().err
    assert code == 2 and says in err and len(err.strip().splitlines()) == 1, err
    assert (tmp_path / "fifo").exists() and not (tmp_path / "fifo").is_file()


def test_export_all_checks_every_destination_before_writing_any(tmp_path, capsys):
    path = _recorded_run(tmp_path)
    (tmp_path / "run-faults.csv").mkdir()
    code = main(["export", str(path), "--all"])
    assert code == 2 and "run-faults.csv" in capsys.readouterr().err
    assert not (tmp_path / "run.csv").exists()  # nothing half-done
