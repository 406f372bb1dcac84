"""One generic registry under the methods, the hands and the experiments (slipreflex.core.registry)."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from slipreflex import methods
from slipreflex.core import experiment_specs
from slipreflex.core.errors import ParameterError
from slipreflex.core.registry import EntryPoint, Registry
from slipreflex.rig import hands


@dataclass(frozen=True)
class Tool:
    name: str
    size: int = 1


def _no_giants(spec: Tool) -> None:
    if spec.size > 10:
        raise ParameterError(f"tool {spec.name}: size {spec.size} > 10")


def test_register_get_names_unregister_in_order():
    reg = Registry("tool", Tool, any_case=True, protected=("saw",))
    for name in ("saw", "drill", "file"):
        reg.register(Tool(name))
    assert reg.names() == ("saw", "drill", "file") and len(reg) == 3 and list(reg) == list(reg.names())
    assert reg.get(" DRILL ") is reg.get("drill") and reg.find("FILE").name == "file" and reg.find(3) is None
    reg.register(Tool("drill", 2), replace=True)                  # keeps its place
    assert reg.names() == ("saw", "drill", "file") and reg.get("drill").size == 2
    reg.unregister("Drill")
    assert reg.names() == ("saw", "file") and "drill" not in reg


def test_every_refusal_is_one_line_naming_what_is_wrong():
    reg = Registry("tool", Tool, label="--tool", check=_no_giants, protected=("saw",))
    reg.register(Tool("saw"))
    cases = [(lambda: reg.register("saw"), "the tool registry takes a Tool, got str"),
             (lambda: reg.register(Tool("saw")), "tool 'saw' is already registered (pass replace=True)"),
             (lambda: reg.register(Tool("ram", 99)), "tool ram: size 99 > 10"),
             (lambda: reg.get("hammer"), "--tool: unknown 'hammer' (known: saw)"),
             (lambda: reg.get("SAW"), "--tool: unknown 'SAW' (known: saw)"),   # case matters unless any_case
             (lambda: reg.unregister("saw"), "tool 'saw' is built in and cannot be unregistered"),
             (lambda: reg.unregister("nope"), "--tool: unknown 'nope'")]
    for call, says in cases:
        with pytest.raises(ParameterError) as err:
            call()
        assert str(err.value).startswith(says) and "\n" not in str(err.value)
    assert reg.names() == ("saw",)                 # nothing refused was stored


def test_the_three_registries_are_instances_of_it():
    assert isinstance(methods.METHODS, Registry) and methods.METHODS.spec_type is methods.MethodSpec
    assert isinstance(hands.HANDS, Registry) and hands.HANDS.names() == hands.hand_names()
    assert isinstance(experiment_specs.EXPERIMENTS, Registry)
    assert experiment_specs.EXPERIMENTS.names() == experiment_specs.names()
    assert methods.EntryPoint is EntryPoint and experiment_specs.EntryPoint is EntryPoint
    with pytest.raises(ParameterError, match="hand 'ilimb' is already registered"):
        hands.register_hand(hands.get_hand("ilimb"))
    with pytest.raises(ParameterError, match="method 'dath' is already registered"):
        methods.register(methods.get("dath"))
    with pytest.raises(ParameterError, match="experiment 'pour' is built in"):
        experiment_specs.unregister("pour")


def test_a_hand_that_says_tactile_must_give_its_frames_shape():
    spec = hands.get_hand("ability")
    odd = hands.HandSpec("odd", "Odd", spec.open, tactile=True)
    with pytest.raises(ParameterError, match="HandSpec odd: tactile=True but tactile_shape=()"):
        hands.register_hand(odd)
    assert "odd" not in hands.hand_names()


def test_the_registry_sits_at_the_bottom_of_the_import_graph():
    import ast
    from pathlib import Path

    import slipreflex.core.registry as mod
    tree = ast.parse(Path(mod.__file__).read_text())
    imported = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.level}
    assert imported <= {"errors", "validation"}, imported


def test_a_hand_registered_from_outside_the_package_opens_by_name():
    import serial

    def open_twin(port, **options):
        from slipreflex.rig.devices.ilimb import ILimb
        return ILimb(port, **options)

    hands.register_hand(hands.HandSpec("ilimb-twin", "i-Limb twin", open_twin))
    try:
        hand = hands.open_hand("ILIMB-twin", serial.serial_for_url("loop://"))
        assert hand.positions() == {} and "ilimb-twin" in hands.hand_names()
        hand.close()
    finally:
        hands.HANDS.unregister("ilimb-twin")
    assert "ilimb-twin" not in hands.hand_names()
