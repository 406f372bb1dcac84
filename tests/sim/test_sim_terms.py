"""The physics terms' table: one row per term, read by the simulator's docs and the physics scripts."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from slipreflex.core.errors import ParameterError
from slipreflex.sim.terms import (
    GROUPS,
    PHYSICS_TERMS,
    SWITCHES,
    VERDICT_SWITCHES,
    PhysicsTerm,
    absent_values,
    markdown_table,
)
from slipreflex.sim.uncertain import UNCERTAIN, plant_from_values

ROOT = Path(__file__).resolve().parents[2]


def _script(name: str):
    spec = importlib.util.spec_from_file_location(f"slipreflex_script_{name}",
        ROOT / "scripts" / ("research" if name == "ablation" else "docs") / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _value(plant, target: str):
    head, _, fld = target.partition(".")
    obj = plant.bottles["TR"] if head == "bottle" else getattr(plant, head)
    return getattr(obj, fld)


@pytest.mark.parametrize("name", sorted(PHYSICS_TERMS))
def test_switching_a_term_off_sets_its_parameters_to_the_absent_value(name):
    term = PHYSICS_TERMS[name]
    nominal, absent = plant_from_values({}), plant_from_values(absent_values(name))
    for target in term.parameters:
        assert _value(absent, target) == term.absent, target
    moved = [t for t in term.parameters if _value(nominal, t) != term.absent]
    others = [n for n in PHYSICS_TERMS if n != name]
    for other in others:    # switching one term off leaves the others' parameters nominal
        for target in PHYSICS_TERMS[other].parameters:
            assert _value(absent, target) == _value(nominal, target), (other, target)
    assert moved or term.uncertain.nominal == term.absent


def test_the_range_and_source_are_the_uncertain_tables_not_a_copy():
    for term in PHYSICS_TERMS.values():
        c = UNCERTAIN[term.constant]
        assert (term.low, term.high, term.source, term.parameters) == (c.low, c.high, c.source, c.targets)
    with pytest.raises(ParameterError, match="outside"):
        PhysicsTerm("x", "a term", "motor_vibration", -1.0)
    with pytest.raises(ParameterError, match="unknown uncertain constant"):
        PhysicsTerm("x", "a term", "no_such_constant", 0.0)


def test_switches_and_groups():
    assert absent_values("grip") == {"wall_softening": 0.0, "motor_droop": 0.0}
    assert set(absent_values()) == {t.constant for t in PHYSICS_TERMS.values()}
    grouped = {n for g in GROUPS.values() for n in g}
    assert set(VERDICT_SWITCHES) == set(GROUPS) | (set(PHYSICS_TERMS) - grouped)
    assert set(SWITCHES) == set(GROUPS) | set(PHYSICS_TERMS)
    with pytest.raises(ParameterError, match="unknown physics term 'nope'"):
        absent_values("nope")


def test_docs_simulator_md_quotes_the_table_as_it_is():
    text = (ROOT / "docs" / "simulator.md").read_text()
    assert markdown_table() in text, "regenerate the terms table in docs/simulator.md from markdown_table()"


def test_the_physics_scripts_build_their_plants_from_the_table():
    runs = _script("physics_terms").plants()
    assert list(runs) == ["base", *VERDICT_SWITCHES, "all"]
    assert runs["base"] == absent_values() and runs["all"] == {}
    for name in VERDICT_SWITCHES:     # each run: every term absent but its own
        assert set(runs["base"]) - set(runs[name]) == set(absent_values(name))
    claims = _script("term_claims")
    assert not hasattr(claims, "TERMS")     # no private copy of the absent values


def test_the_ablation_switches_a_term_off_by_its_name(capsys):
    import argparse

    ablation = _script("ablation")
    ap = argparse.ArgumentParser(prog="ablation")
    assert ablation._changed(ap, "tilt", None) == {"drop_eccentricity": 0.0}
    assert ablation._changed(ap, "hand_latency", 0.02) == {"hand_latency": 0.02}
    for name, value in (("nope", None), ("nope", 1.0)):
        with pytest.raises(SystemExit) as stop:
            ablation._changed(ap, name, value)
        assert stop.value.code == 2 and "'nope'" in capsys.readouterr().err
