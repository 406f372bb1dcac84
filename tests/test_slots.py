"""The state-slot properties of SlipReflex and Rig (slipreflex._slots.slot)."""

import doctest
import math

import pytest

from slipreflex import _slots
from slipreflex.chain import SlipReflex
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
