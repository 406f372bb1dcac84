"""The characterization scan matches the paper's numbers (levels, DATH > fixed, ~0.09 mm spacing)
and the CLI writes its files."""

import numpy as np
import pytest

from slipreflex.cli import main
from slipreflex.core import hardware as hw
from slipreflex.sim import scan


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_scan_numbers_match_the_paper(seed):
    r = scan(seed=seed)
    assert r.position[-1] == pytest.approx(0.05, abs=1e-5) and np.allclose(np.diff(r.t), hw.DAQ_PERIOD_S)
    s = r.analyse()
    wlo, whi = s.ranges["white"]
    blo, bhi = s.ranges["black"]
    # one texture draw: near the paper's levels (the ensemble test below holds the calibration)
    assert 0.2 < wlo < whi < 0.7              # paper: 300-500 mV on white
    assert 3.30 < blo < bhi < 3.37            # paper: 3.32-3.35 V on black
    assert s.spikes["dath"] > s.spikes["fixed"]
    for region in ("white", "black"):
        assert s.spikes_in[("dath", region)] > s.spikes_in[("fixed", region)] > 0


@pytest.mark.slow
def test_the_test_surface_is_calibrated_on_the_ensemble_medians():
    from slipreflex.sim.scan import scan_ensemble

    e = scan_ensemble(200)
    for stat, want in (("white_lo", 0.3), ("white_hi", 0.5), ("black_lo", 3.32), ("black_hi", 3.35)):
        assert np.median(getattr(e, stat)) == pytest.approx(want, abs=0.01), stat
    lo, hi = e.band("fixed_gap")
    assert lo < 0.09 < hi                                       # the paper's 0.09 mm inside the central 90 %
    assert np.allclose(e.dath_gap, e.step_mm, rtol=0.01)       # DATH: one sample, on every seed


def test_scan_only_moves_with_the_surface():
    still = scan(seed=0, speed=1e-9, distance=1e-9 * 3.0, layout=(("white", 0.01),))
    assert still.volts.std() < 2 * hw.ADC_LSB


@pytest.mark.slow
def test_scan_command_writes_csv_and_figure(tmp_path, capsys):
    assert main(["scan", "--out", str(tmp_path), "--seed", "1"]) == 0
    out = capsys.readouterr().out
    assert "white filtered volts" in out and "black filtered volts" in out
    assert "smallest spacing" in out and "DATH" in out
    header = (tmp_path / "scan.csv").read_text().splitlines()[0].split(",")
    assert header[:4] == ["t", "position_mm", "volts", "filtered"] and "dath_threshold" in header
    assert (tmp_path / "scan.png").stat().st_size > 10_000


def test_scan_command_rejects_bad_arguments(capsys):
    assert main(["scan", "--speed", "0", "--no-figure"]) == 2
    assert "error" in capsys.readouterr().err


def test_scan_takes_own_surfaces_and_bottles_from_objects(tmp_path, capsys):
    """--objects FILE.toml and --layout with its surfaces (or a bottle's surface)."""
    from slipreflex.cli import main
    objs = tmp_path / "o.toml"
    objs.write_text('[surfaces.foil]\nreflectance = 0.8\ntexture = 0.02\n\n'
                    '[bottles.JAR]\nmass_kg = 0.1\ndiameter_m = 0.07\nmu_s = 1.0\nmu_k = 0.8\nsurface = "foil"\n')
    assert main(["scan", "--out", str(tmp_path / "s"), "--objects", str(objs), "--no-figure",
                 "--layout", "stand:5,foil:10,JAR:10,black:10", "--distance", "35"]) == 0
    out = capsys.readouterr().out
    assert "foil  filtered volts" in out and "JAR   filtered volts" in out and "black filtered volts" in out
    assert "white" not in out
    assert main(["scan", "--out", str(tmp_path / "s"), "--layout", "stand:2,foil:4"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--layout part 2: unknown surface 'foil'" in err
