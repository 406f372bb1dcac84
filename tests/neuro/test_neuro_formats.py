"""Spikes out: AEDAT4, tonic's events_struct and NIR event data, each read back with its own library."""

from __future__ import annotations

import numpy as np
import pytest

from slipreflex.cli import main
from slipreflex.methods.chain import run_chain
from slipreflex.neuro import events as ev

aedat = pytest.importorskip("aedat", reason="the neuro extra (pip install 'slipreflex[neuro]')")
nir = pytest.importorskip("nir", reason="the neuro extra")
tonic = pytest.importorskip("tonic", reason="the neuro extra")
pytest.importorskip("faery", reason="the neuro extra")


def _events() -> np.ndarray:
    rng = np.random.default_rng(1)
    n = 40
    out = np.zeros(n, dtype=ev.EVENT_DTYPE)
    out["t"] = np.cumsum(rng.integers(1, 5000, n))
    out["x"], out["y"] = rng.integers(0, 4, n), rng.integers(0, 8, n)
    out["p"] = rng.random(n) < 0.5
    return out


def test_the_npy_is_tonics_events_struct_and_tonic_reads_it(tmp_path):
    e = _events()
    back = np.load(ev.write_npy(e, tmp_path / "s.npy"))
    assert back.dtype == np.dtype(tonic.io.events_struct)
    assert back.tolist() == e.tolist()
    frames = tonic.transforms.ToFrame(sensor_size=(4, 8, 2), event_count=1)(back)
    assert frames.shape == (e.size, 2, 8, 4)
    on = frames[:, 1].sum(axis=0)         # tonic's channel 1 is polarity True
    assert int(on.sum()) == int(e["p"].sum()) and int(frames.sum()) == e.size


def test_aedat4_round_trips_through_the_aedat_decoder(tmp_path):
    e = _events()
    path = ev.write_aedat4(e, tmp_path / "s.aedat4")
    dec = aedat.Decoder(str(path))
    assert dec.id_to_stream()[0]["width"] == 4 and dec.id_to_stream()[0]["height"] == 8
    got = np.concatenate([packet["events"] for packet in dec if "events" in packet])
    assert got["t"].tolist() == e["t"].tolist() and got["x"].tolist() == e["x"].tolist()
    assert got["y"].tolist() == e["y"].tolist() and got["on"].tolist() == e["p"].tolist()


def test_nir_event_data_round_trips_through_nir_read_data(tmp_path):
    e = _events()
    data = nir.read_data(str(ev.write_nir_events(e, tmp_path / "s.h5")))
    spikes = data.nodes[ev.NIR_NODE].observables[ev.NIR_OBSERVABLE]
    assert spikes.n_neurons == 2 * 4 * 8
    idx = spikes.idx[0]
    assert (idx // 2 % 4).tolist() == e["x"].tolist() and (idx // 8).tolist() == e["y"].tolist()
    assert (idx % 2 == 0).tolist() == e["p"].tolist() and spikes.time[0].tolist() == e["t"].astype(float).tolist()


def test_the_chains_spikes_keep_their_polarity_and_the_daq_clock_in_microseconds():
    raw = np.r_[np.full(30, 0.4), np.full(30, 0.45), np.full(30, 0.38)]
    t = 2.5 + np.arange(raw.size) * 0.003
    e = ev.chain_events(raw, t, filter=False)
    res = run_chain(raw, filter=False)
    k = np.flatnonzero(res.events)
    assert e["t"].tolist() == np.round(t[k] * 1e6).astype(int).tolist()
    assert e["p"].tolist() == [True, False] and set(e["x"]) == {0} and set(e["y"]) == {0}


def test_taxels_become_pixels():
    frames = np.zeros((6, 4, 3))
    frames[3:, 2, 1] = 10.0           # one taxel, row 2 column 1, steps up
    frames[4:, 0, 2] = -10.0          # another steps down
    e = ev.taxel_events(frames, np.arange(6) * 0.01, threshold=5.0, filter=False)
    assert e[["x", "y", "t", "p"]].tolist() == [(1, 2, 30000, True), (2, 0, 40000, False)]


@pytest.mark.slow
def test_spikes_writes_all_three_files_of_a_csv_and_refuses_to_overwrite(tmp_path, capsys):
    src = tmp_path / "in.csv"
    t = np.arange(300) * 0.003
    x = 0.4 + 0.05 * np.sin(2 * np.pi * 3 * t) * (t > 0.3)
    src.write_text("t,x\n" + "\n".join(f"{a:.6f},{b:.6f}" for a, b in zip(t, x)) + "\n")
    out = tmp_path / "spk"
    assert main(["spikes", str(src), "-o", str(out)]) == 0
    expected = ev.chain_events(x, t)
    assert np.load(tmp_path / "spk.npy").tolist() == expected.tolist() and expected.size > 3
    assert (tmp_path / "spk.aedat4").is_file() and (tmp_path / "spk.nir-events.h5").is_file()
    assert main(["spikes", str(src), "-o", str(out), "--format", "tonic"]) == 2
    assert "exists" in capsys.readouterr().err


def test_spikes_refuses_a_bad_format_before_any_work(tmp_path, capsys):
    assert main(["spikes", str(tmp_path / "none.csv"), "-o", str(tmp_path / "x"), "--format", "avi"]) == 2
    assert "--format: avi" in capsys.readouterr().err
