"""The kernel's files and the one module that gathers them: ``from slipreflex.sim import kernel as K; K.name``."""

from __future__ import annotations

import types

import numpy as np
import pytest

from slipreflex.core._slots import Layout
from slipreflex.sim import _kernel_layout, kernel_calm, kernel_contacts, kernel_noise, kernel_sensors, kernel_step
from slipreflex.sim import kernel as K

PIECES = (_kernel_layout, kernel_noise, kernel_contacts, kernel_sensors, kernel_calm, kernel_step)


def test_the_kernel_module_gathers_every_public_name_of_its_files():
    for module in PIECES:
        public = [n for n, v in vars(module).items()
                  if not n.startswith("_") and not isinstance(v, types.ModuleType)
                  and getattr(v, "__module__", module.__name__) == module.__name__
                  and (callable(v) or isinstance(v, Layout) or n.isupper())]
        missing = [n for n in public if getattr(K, n, None) is not vars(module)[n]]
        assert not missing, f"{module.__name__}: not re-exported by kernel: {missing}"
    assert K.step_until is kernel_step.step_until and K._rs_solve is kernel_contacts._rs_solve


def test_the_layout_module_doctests_pass():
    import doctest

    assert doctest.testmod(_kernel_layout).failed == 0


def test_every_slot_constant_is_bound_once_in_the_layout_module():
    for layout in (K.STATE, K.PARAMS, K.COUNTERS, K.DROP, K.POUR, K.DAQ_ROW, K.TACTILE_ROW):
        for name, index in layout.constants().items():
            assert getattr(_kernel_layout, name) == index == getattr(K, name), name


def test_the_noise_is_counter_based_and_the_calm_rules_round_to_steps():
    key = np.uint64(12345)
    assert kernel_noise.normal(key, 7) == K.normal_pair(key, 7)[0]   # the first of its Box-Muller pair
    assert 0.0 < kernel_noise.uniform(key, 3) < 1.0
    dt = 1e-4
    assert kernel_calm._fire_end(3 * dt, dt) == 3     # a sample due on a step boundary ends that step
    assert kernel_calm._fire_end(3.5 * dt, dt) == 4


@pytest.mark.slow
def test_the_scan_volts_are_the_sensors_along_a_track():
    from slipreflex.sim import Rig

    rig = Rig("TR", seed=1)
    A = rig.kernel_arrays()
    out = np.empty(4)
    kernel_sensors.volts_along(A.P, A.track, A.keys, np.linspace(0.0, 1e-3, 4), out)
    assert np.isfinite(out).all() and (out >= 0.0).all()



def test_a_borrowed_array_is_the_same_memory_without_reference_counts():
    """step_until hands its pieces borrowed arrays: the same memory (writes go through), and an inlined piece
    taking one costs no reference count (numba's atomic incref, which its pruning leaves in a branching loop)."""
    import re

    from numba import njit

    @njit(inline="always")
    def piece(a, x):
        if x > a[0]:
            a[1] += x
        return x * 0.5 + 1.0

    @njit
    def plain(a, n):
        x = 0.0
        for _ in range(n):
            x = piece(a, x)
        a[2] = x

    @njit
    def borrowed(a, n):
        b = kernel_step._borrow(a)
        x = 0.0
        for _ in range(n):
            x = piece(b, x)
        b[2] = x

    a, b = np.zeros(3), np.zeros(3)
    plain(a, 10)
    borrowed(b, 10)
    assert (a == b).all() and b[1] > 0.0
    increfs = [len(re.findall(r"call void @NRT_incref", f.inspect_llvm(f.signatures[0]))) for f in (plain, borrowed)]
    assert increfs[0] > 0 and increfs[1] == 0, increfs
