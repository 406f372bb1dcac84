"""The one validator module: what it accepts and refuses, and that its users agree."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from slipreflex.core import validation as V
from slipreflex.core.errors import ParameterError


@pytest.mark.parametrize("value", [3, 3.0, np.int8(3), np.int64(3), np.uint16(3), np.float32(3.0)])
def test_number_accepts_every_real_type_and_returns_float(value):
    out = V.number("x", value, lo=0.0)
    assert out == 3.0 and type(out) is float


@pytest.mark.parametrize("value", [True, np.bool_(True), "3", None, float("nan"), float("inf"),
                                   np.float64("-inf"), [3.0], 1 + 2j])
def test_number_refuses_non_reals_and_non_finite_naming_the_parameter(value):
    with pytest.raises(ParameterError, match=r"^gain must be a finite number"):
        V.number("gain", value)


@pytest.mark.parametrize("lo,hi,lo_open,hi_open,value,ok", [
    (0.0, None, False, False, 0.0, True), (0.0, None, True, False, 0.0, False),
    (None, 1.0, False, False, 1.0, True), (None, 1.0, False, True, 1.0, False),
    (0.0, 1.0, False, False, -1e-12, False), (0.0, 1.0, False, False, 0.5, True)])
def test_number_bounds(lo, hi, lo_open, hi_open, value, ok):
    if ok:
        assert V.number("x", value, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open) == value
    else:
        with pytest.raises(ParameterError, match=r"^x must be a finite number [<>]"):
            V.number("x", value, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open)


@pytest.mark.parametrize("value", [4, np.int8(4), np.int64(4), np.uint64(4)])
def test_integer_accepts_python_and_numpy_integers(value):
    out = V.integer("n", value, lo=1, hi=10)
    assert out == 4 and type(out) is int


@pytest.mark.parametrize("value", [4.0, np.float64(4.0), True, np.bool_(False), "4", None, 0, 11])
def test_integer_refuses_floats_bools_and_out_of_range(value):
    with pytest.raises(ParameterError, match=r"^n must be an integer >= 1 and <= 10, got"):
        V.integer("n", value, lo=1, hi=10)


def test_flag_choice_choices_text():
    assert V.flag("f", np.bool_(True)) is True
    with pytest.raises(ParameterError, match="^f must be True or False"):
        V.flag("f", 0)
    assert V.choice("m", "a", ("a", "b")) == "a"
    with pytest.raises(ParameterError, match=r"^m: unknown 'c' \(known: a, b\)"):
        V.choice("m", "c", ("a", "b"))
    with pytest.raises(ParameterError, match="^m: unknown"):
        V.choice("m", ["a"], ("a", "b"))          # unhashable is just unknown
    assert V.choices("m", ["b", "a"], ("a", "b")) == ("b", "a")
    for bad, msg in (("ab", "must be a sequence"), ((), "choose at least one"), (("a", "a"), "repeated")):
        with pytest.raises(ParameterError, match=f"^m.*{msg}"):
            V.choices("m", bad, ("a", "b"))
    assert V.choices("m", (), ("a",), allow_empty=True) == ()
    with pytest.raises(ParameterError, match="^name must be a non-empty string"):
        V.text("name", 3)


@dataclasses.dataclass(frozen=True)
class _P:
    a: float
    b: int = 2

    def __post_init__(self):
        V.set_field(self, "a", V.positive("a", self.a))
        V.set_field(self, "b", V.integer("b", self.b, lo=0))


def test_resolve_params_contract():
    assert V.resolve_params(_P, None, {"a": 1}) == _P(1.0, 2)
    p = _P(1.0)
    assert V.resolve_params(_P, p, {}) is p
    assert V.resolve_params(_P, p, {"b": np.int32(5)}) == _P(1.0, 5)
    assert p.b == 2                                          # the original is untouched
    with pytest.raises(ParameterError, match=r"unknown parameter\(s\) for _P: c \(known: a, b\)"):
        V.resolve_params(_P, p, {"c": 1})
    with pytest.raises(ParameterError, match="^params must be a _P, got dict"):
        V.resolve_params(_P, {"a": 1}, {})
    with pytest.raises(ParameterError, match="^a must be a finite number > 0"):
        V.resolve_params(_P, p, {"a": 0})                    # overrides are checked again
    with pytest.raises(TypeError):
        V.resolve_params(_P, None, {})                      # a required field stays required


def test_numpy_integers_are_accepted_alike_by_the_migrated_users():
    from slipreflex.methods.baselines import SWTParams
    from slipreflex.reproduce.experiments import ReproduceConfig

    assert SWTParams(threshold=0.1, speed=500.0, persist=np.int64(3)).persist == 3
    cfg = ReproduceConfig(trials=np.int64(2), seed=np.uint32(7), swt_persist=np.int16(4))
    assert (cfg.trials, cfg.seed, cfg.swt_persist) == (2, 7, 4)
    assert type(cfg.trials) is int
    for bad in (dict(trials=2.0), dict(trials=True), dict(seed=-1), dict(rest_k=float("nan"))):
        with pytest.raises(ParameterError, match=f"^{next(iter(bad))} must be"):
            ReproduceConfig(**bad)
