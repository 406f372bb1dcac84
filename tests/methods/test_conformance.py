"""Every registered method keeps the Reflex contract and its spec (slipreflex.testing.check_method)."""

from __future__ import annotations

import numpy as np
import pytest

from slipreflex import methods
from slipreflex.core.interfaces import Reflex
from slipreflex.methods.baselines import NMSD, SWTSD
from slipreflex.methods.chain import SlipReflex
from slipreflex.testing import ContractError, check_method, check_reflex, reflex_for_check


@pytest.mark.parametrize("name", methods.names())
def test_every_registered_method_keeps_the_reflex_contract(name):
    assert isinstance(reflex_for_check(name), Reflex)
    report = check_method(name)
    # the synthetic slip must make every method act, or the check proved little
    assert report.commands > 0 and report.events > 0, report


def test_a_specification_that_disagrees_with_its_reflex_is_caught():
    wrong = methods.MethodSpec(name="dath-wrong", label="x", input_kind="slip", fs=100.0,
                               build=methods.get("dath").build)
    methods.register(wrong)
    try:
        with pytest.raises(ContractError, match="at 100 Hz, the reflex reads 'slip' at 333.333"):
            check_method("dath-wrong")
    finally:
        methods.unregister("dath-wrong")


@pytest.mark.parametrize("shape", [(4, 4), (3, 5), (7,)])
def test_tactile_methods_keep_the_contract_on_any_array_shape(shape):
    for name in methods.names():
        if methods.get(name).input_kind == "tactile":
            reflex = reflex_for_check(name, shape=shape)
            assert reflex.params.shape == shape
            assert check_reflex(reflex).commands > 0


class _Base:
    name, input_kind, fs = "probe", "slip", 100.0

    def __init__(self):
        self.reset()

    def reset(self):
        self.n = 0
        self.last_event, self.last_filtered, self.last_threshold, self.last_count = False, np.nan, None, None

    def step(self, sample, position=None):
        self.n += 1
        return 150.0 if self.n % 50 == 0 else None


def test_the_checker_passes_a_plain_conforming_reflex():
    assert check_reflex(_Base()).commands > 0


class _NoReset(_Base):
    def reset(self):
        if not hasattr(self, "n"):
            super().reset()


class _Random(_Base):
    def step(self, sample, position=None):
        return float(np.random.default_rng().integers(1, 500)) if sample > 0.42 else None


class _WrongType(_Base):
    def step(self, sample, position=None):
        return "close"


class _NoDiagnostics:
    name, input_kind, fs = "bare", "slip", 100.0

    def step(self, sample, position=None):
        return None

    def reset(self):
        pass


class _BadKind(_Base):
    input_kind = "audio"


class _CrashesOnNaN(_Base):
    def step(self, sample, position=None):
        if sample != sample:
            raise ZeroDivisionError("nan")
        return super().step(sample, position)


class _Mutable(_Base):
    """Keeps state reset() forgets: an array it fills in place."""

    def __init__(self):
        self.buf = np.zeros(3)
        super().__init__()

    def step(self, sample, position=None):
        self.buf[self.n % 3] = sample
        return super().step(sample, position)


@pytest.mark.parametrize("reflex, message", [
    (_NoReset(), "reset"), (_Mutable(), "reset"), (_Random(), "bits"), (_WrongType(), "None or a finite float"),
    (_NoDiagnostics(), "missing: last_"), (_BadKind(), "input_kind"),
])
def test_the_checker_names_the_broken_rule(reflex, message):
    with pytest.raises(ContractError, match=message):
        check_reflex(reflex)


def test_a_crash_on_a_non_finite_sample_is_not_hidden():
    with pytest.raises(ZeroDivisionError):
        check_reflex(_CrashesOnNaN())


def test_the_declared_diagnostics_are_what_the_chain_sets():
    r = SlipReflex(dath=True)
    events, counts = [], []
    for v in [0.4] * 20 + [0.5] * 44:
        r.step(v)
        events.append(r.last_event)
        counts.append(r.last_count)
    assert isinstance(r, Reflex) and any(events) and r.last_threshold > 0 and np.isfinite(r.last_filtered)
    assert [k for k, c in enumerate(counts) if c is not None] == [15, 31, 47, 63]   # one per 16-sample window
    for cls, kw in ((NMSD, {}), (SWTSD, {})):
        t = cls(threshold=1.0, speed=100.0, **kw)
        assert np.isnan(t.last_filtered) and t.last_threshold == 1.0 and t.last_count is None
