"""Named slots: the state-slot properties of SlipReflex and Rig, and the layouts of every compiled vector."""

import doctest
import math

import numpy as np
import pytest

from slipreflex.core import _slots
from slipreflex.methods.chain import SlipReflex
from slipreflex.sim import Rig


def test_the_slot_module_doctest_passes():
    assert doctest.testmod(_slots).failed == 0


def test_reflex_diagnostics_follow_the_state_and_are_read_only():
    r = SlipReflex(dath=True, p0=100.0)
    for x in (0.0, 0.5, -0.5, float("nan")):
        r.step(x)
    assert r.skipped_samples == 1 and isinstance(r.skipped_samples, int)
    assert isinstance(r.last_event, bool) and math.isnan(r.last_filtered)
    assert r.command == 100.0 and SlipReflex.command.__doc__.startswith("The current finger command")
    with pytest.raises(AttributeError):
        r.command = 1.0
    r.reset()
    assert r.skipped_samples == 0


def test_rig_truth_slots_are_documented_floats():
    rig = Rig("TR")
    rig.grasp()
    for name in ("displacement", "slip", "velocity", "normal_force", "load_mass"):
        assert isinstance(getattr(rig, name), float), name
        assert getattr(Rig, name).__doc__, name
    assert rig.normal_force > 0.0
    with pytest.raises(AttributeError):
        rig.slip = 0.0


# ---- layouts: every compiled vector's slots named once, NaN until filled, checked complete ----

LAYOUT_MODULES = ["slipreflex.methods.chain._layout", "slipreflex.methods.baselines._layout", "slipreflex.sim.kernel"]


def _layouts():
    import importlib

    out = []
    for name in LAYOUT_MODULES:
        mod = importlib.import_module(name)
        out += [(name, attr, obj) for attr, obj in vars(mod).items() if isinstance(obj, _slots.Layout)]
    return out


def test_every_compiled_vector_has_a_layout():
    found = {(m, a) for m, a, _ in _layouts()}
    assert {("slipreflex.methods.chain._layout", "PARAMS"), ("slipreflex.methods.chain._layout", "STATE"),
            ("slipreflex.methods.baselines._layout", "PARAMS"), ("slipreflex.methods.baselines._layout", "STATE"),
            ("slipreflex.sim.kernel", "PARAMS"), ("slipreflex.sim.kernel", "STATE"),
            ("slipreflex.sim.kernel", "DROP"), ("slipreflex.sim.kernel", "POUR")} <= found


@pytest.mark.parametrize("module, attr, layout", _layouts(), ids=lambda x: x if isinstance(x, str) else "")
def test_every_slot_constant_is_its_layouts_name(module, attr, layout):
    """The kernels' constants (``P_KN``...) are bound by unpacking: each must be the slot it names."""
    import importlib

    mod = importlib.import_module(module)
    for name, index in layout.constants().items():
        assert getattr(mod, name) == index, f"{module}.{name} is {getattr(mod, name)}, its slot is {index}"


def test_a_vector_starts_nan_and_an_unfilled_slot_is_an_error_naming_it():
    from slipreflex.methods.chain import ReflexParams
    from slipreflex.methods.chain import _layout as L

    head = L.PARAMS.new()
    assert np.isnan(head).all()
    with pytest.raises(_slots.LayoutError, match="THETA0"):
        P = L.pack_params(ReflexParams())
        head = P[:L.P_SOS].copy()
        head[L.P_THETA0] = np.nan
        L.PARAMS.check(head)
    S = L.init_state(L.pack_params(ReflexParams()))
    assert math.isnan(S[L.S_LAST_X]) and S[L.S_LAST_COUNT] == -1.0   # NaN where the layout says so


def test_a_rig_with_a_parameter_nobody_filled_refuses_to_run(monkeypatch):
    """A forgotten fill is an error before any kernel runs, not a silent 0.0 in the physics."""
    from slipreflex.sim import rig_params

    monkeypatch.setattr(rig_params, "fill_slip_sensor_params", lambda P, *a, **k: P)
    with pytest.raises(_slots.LayoutError, match="the rig's parameters P: slot.*VCC"):
        Rig("TR")
