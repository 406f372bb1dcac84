"""The uncertain plant constants as data: one table, plants built from values, TOML ranges."""

import dataclasses

import pytest

from slipreflex.core.errors import ParameterError
from slipreflex.sim import BOTTLES, UNCERTAIN, Plant, load_ranges, plant_from_values
from slipreflex.sim.uncertain import UncertainConstant, nominal_values


def _reading_default(fld):
    """What the package uses when no study draws a reading: the method's and the judge's defaults."""
    from slipreflex.analysis.claims import Reading
    from slipreflex.analysis.trial import MAX_RESPONSE_S
    from slipreflex.methods.baselines import REST_K, SWTParams

    if fld == "cutoff_ms":
        assert Reading().cutoff_ms == 1e3 * MAX_RESPONSE_S
    persist = SWTParams.__dataclass_fields__["persist"].default
    return {"swt_persist": persist, "rest_k": REST_K}.get(fld, getattr(Reading(), fld, None))


def _field(plant, target, bottle="TR"):
    from slipreflex.sim.uncertain import _parse_target

    head, sel, fld, ratio_of = _parse_target(target)
    if head == "calibration":
        return getattr(plant, fld)
    if head in ("method", "judge"):
        return plant.readings.get(fld, _reading_default(fld))
    if head == "bottle":
        b = plant.bottles[(sel or (bottle,))[0]]
        if fld.startswith("surface."):
            return getattr(b.surface, fld.partition(".")[2])
        return getattr(b, fld) / getattr(b, ratio_of) if ratio_of else getattr(b, fld)
    return getattr(getattr(plant, head), fld)


def test_every_constant_is_documented_and_its_nominal_is_the_model_default():
    default = Plant()
    for name, c in UNCERTAIN.items():
        assert c.low <= c.nominal <= c.high, name
        assert c.source and c.unit and c.targets, name
        for target in c.targets:
            assert _field(default, target) == pytest.approx(c.nominal, rel=1e-6), (name, target)


def test_docs_simulator_md_quotes_the_table_as_it_is():
    from pathlib import Path

    from slipreflex.sim.uncertain import markdown_table

    text = (Path(__file__).resolve().parents[2] / "docs" / "simulator.md").read_text()
    assert markdown_table() in text, "regenerate the table in docs/simulator.md from markdown_table()"


@pytest.mark.parametrize("name", sorted(UNCERTAIN))
def test_each_constant_moves_its_targets(name):
    c = UNCERTAIN[name]
    value = c.value_at(0.9) if c.value_at(0.9) != c.nominal else c.value_at(0.1)
    plant = plant_from_values({name: value})
    for target in c.targets:
        assert _field(plant, target) == pytest.approx(value, rel=1e-9)
    assert plant.values[name] == value


def test_bottle_selectors_and_ratio_targets():
    from slipreflex.sim.uncertain import UncertainConstant

    table = {**UNCERTAIN, "tx_only": UncertainConstant("tx_only", "1", 1.0, 0.5, 1.5, "uniform", "test",
                                                       ("bottle[TX].mu_s",))}
    p = plant_from_values({"tx_only": 1.2, "pad_mu_k_ratio": 0.5, "pad_mu_k_ratio_TX": 0.5}, table=table)
    assert p.bottles["TX"].mu_s == 1.2 and p.bottles["TR"].mu_s == BOTTLES["TR"].mu_s
    assert p.bottles["TX"].mu_k == pytest.approx(0.6)
    assert p.bottles["TR"].mu_k == pytest.approx(0.5 * BOTTLES["TR"].mu_s)


def test_first_slip_target_recalibrates_the_pads():
    p = plant_from_values({"first_slip_ml": 230.0, "hand_latency": 0.02})
    assert p.first_slip_ml == 230.0
    c = p.calibrated(seeds=(0,))
    from slipreflex.sim.calibration import first_slip_ml

    # the observed first slip moves in flow-sensor pulses (2.2 ml): within the calibration's 2 %
    assert first_slip_ml(c.bottles["DK"], rig_kwargs=c.rig_kwargs(), seeds=(0,)) == pytest.approx(230.0, abs=4.6)


def test_plant_builds_rigs_with_its_parameters():
    p = plant_from_values({"hand_latency": 0.02, "wall_stiffness": 900.0})
    rig = p.rig("DK", seed=2)
    assert rig.hand.latency == 0.02 and rig.bottle.wall_stiffness_n_m == 900.0
    with pytest.raises(ParameterError, match="unknown bottle"):
        p.rig("XX")


def test_unknown_names_and_bad_values_are_errors():
    with pytest.raises(ParameterError, match="unknown uncertain constant 'nope'"):
        plant_from_values({"nope": 1.0})
    with pytest.raises(ParameterError, match="hand"):
        plant_from_values({"hand_latency": -1.0})


def test_value_at_maps_quantiles_onto_the_distribution():
    c = UNCERTAIN["wall_stiffness"]
    assert c.distribution == "loguniform"
    assert c.value_at(0.5) == pytest.approx((c.low * c.high) ** 0.5)
    u = UNCERTAIN["hand_latency"]
    assert u.value_at(0.25) == pytest.approx(u.low + 0.25 * (u.high - u.low))
    with pytest.raises(ParameterError):
        u.value_at(1.5)


def test_constant_validation():
    with pytest.raises(ParameterError, match="low <= nominal <= high"):
        UncertainConstant("x", "1", 5.0, 0.0, 1.0, "uniform", "s")
    with pytest.raises(ParameterError, match="distribution"):
        UncertainConstant("x", "1", 0.5, 0.0, 1.0, "normalish", "s")
    with pytest.raises(ParameterError, match="log-uniform"):
        UncertainConstant("x", "1", 0.5, 0.0, 1.0, "loguniform", "s")


def test_load_ranges_narrows_widens_and_fixes(tmp_path):
    f = tmp_path / "r.toml"
    f.write_text('[hand_latency]\nlow = 0.012\nhigh = 0.015\n\n[wall_stiffness]\nlow = 100.0\nhigh = 5000.0\n'
                 '\n[pad_mu_k_ratio]\nfixed = 0.8\n')
    t = load_ranges(f)
    assert (t["hand_latency"].low, t["hand_latency"].high) == (0.012, 0.015)
    assert t["hand_latency"].nominal == 0.012          # moved into the narrowed range
    assert t["wall_stiffness"].low == 100.0 and t["wall_stiffness"].nominal == UNCERTAIN["wall_stiffness"].nominal
    assert t["pad_mu_k_ratio"].fixed and t["pad_mu_k_ratio"].value_at(0.3) == 0.8
    assert plant_from_values(nominal_values(t), table=t).bottles["TR"].mu_k == pytest.approx(0.8 * BOTTLES["TR"].mu_s)
    assert UNCERTAIN["hand_latency"].low != 0.012      # the package table is untouched


@pytest.mark.parametrize("text, match", [
    ("[nope]\nlow = 1\n", "nope.*unknown constant"),
    ("[hand_latency]\nlo = 1\n", "hand_latency.lo: unknown key"),
    ("[hand_latency]\nlow = 0.02\nhigh = 0.01\n", "low 0.02 > high 0.01"),
    ("[hand_latency]\nfixed = 0.02\nlow = 0.01\n", "cannot be combined"),
    ("[hand_latency]\ndistribution = 'gauss'\n", "distribution"),
    ("[hand_latency\n", "invalid TOML"),
])
def test_load_ranges_errors_name_file_and_key(tmp_path, text, match):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    with pytest.raises(ParameterError, match=match) as err:
        load_ranges(f)
    assert str(f) in str(err.value)


def test_load_ranges_missing_file_and_directory(tmp_path):
    with pytest.raises(ParameterError, match="no such file"):
        load_ranges(tmp_path / "none.toml")
    with pytest.raises(ParameterError, match="is a directory, not a TOML file"):
        load_ranges(tmp_path)


def test_plant_is_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        Plant().hand = None


def test_a_reproduction_on_a_drawn_plant_runs_in_worker_processes_as_in_one():
    """A Plant pickles (its mappings are read-only proxies), so reproduce --jobs 2 runs on it, same rows."""
    from slipreflex.reproduce.experiments import ReproduceConfig, run_reproduce
    from slipreflex.sim.uncertain import plant_from_values

    plant = plant_from_values({"spot_travel_per_unit": 0.0})
    cfg = ReproduceConfig(trials=1, bottles=("TX",), methods=("dath",), experiments=("drop",), plant=plant)
    one = run_reproduce(cfg, jobs=1, progress=False, plots=False)
    two = run_reproduce(cfg, jobs=2, progress=False, plots=False)
    assert [repr(r) for r in one.rows] == [repr(r) for r in two.rows] and one.rows


@pytest.mark.slow
def test_the_nominal_plant_is_the_built_in_plant_bit_for_bit():
    from slipreflex.reproduce.experiments import ReproduceConfig, run_reproduce
    from slipreflex.sim import BOTTLES

    p = plant_from_values({})
    assert dict(p.bottles) == dict(BOTTLES)
    assert p.bottles["TX"].mu_k / p.bottles["TX"].mu_s != p.bottles["TR"].mu_k / p.bottles["TR"].mu_s
    kw = dict(trials=1, bottles=("TX",), methods=("dath",), experiments=("drop",))
    a = run_reproduce(ReproduceConfig(**kw), jobs=1, progress=False, plots=False).rows
    b = run_reproduce(ReproduceConfig(**kw, plant=p), jobs=1, progress=False, plots=False).rows
    assert [repr(dict(r)) for r in a] == [repr(dict(r)) for r in b]        # NaN-aware: same bits


def test_the_tape_s_pad_friction_is_drawn_apart_from_the_smooth_bottles():
    q = plant_from_values({"pad_mu_k_ratio": 0.9, "pad_mu_k_ratio_TX": 0.65})
    ratio = {b: q.bottles[b].mu_k / q.bottles[b].mu_s for b in q.bottles}
    assert ratio["TR"] == pytest.approx(0.9) and ratio["DK"] == pytest.approx(0.9)
    assert ratio["TX"] == pytest.approx(0.65)


def test_readings_of_the_paper_ride_beside_the_plant_and_reach_the_methods():
    p = plant_from_values({"swt_persist": 0.4, "rest_k": 3.5, "response_cutoff": 700.0})
    assert p.method_options() == {"swt_persist": 0, "rest_k": 3.5}
    assert p.readings["cutoff_ms"] == 700.0 and p.bottles == plant_from_values({}).bottles
    q = plant_from_values({"reflectance_DK": 0.2, "texture_TX": 0.04})
    assert q.bottles["DK"].surface.reflectance == 0.2 and q.bottles["TX"].surface.texture == 0.04
    assert q.bottles["TR"].surface == BOTTLES["TR"].surface
    import pickle

    assert pickle.loads(pickle.dumps(p)).readings == p.readings
