"""Work not repeated, the same bits: closing phases kept across frictions, rig copies, kept pours and textures."""

import copy
from dataclasses import replace

import numpy as np
import pytest

from slipreflex.analysis.onset import OnsetParams, accel_envelope
from slipreflex.sim import BOTTLES, PAPER_POUR, SURFACES, Rig
from slipreflex.sim import kernel as K
from slipreflex.sim.calibration import first_slip
from slipreflex.sim.closing_memo import CLOSINGS, ClosingMemo, closing_key, friction_slots
from slipreflex.sim.sensors import _kept_texture, texture


def _state(rig: Rig) -> list[np.ndarray]:
    """Every array a rig's future depends on or has recorded, and its hand's queue, as arrays to compare."""
    hand = rig.hand
    return [rig.kernel_arrays().S, rig.kernel_arrays().C, rig.kernel_arrays().D, rig.kernel_arrays().W,
            rig.events(), rig.daq_rows()[0], hand.targets, hand.speeds,
            np.array([repr(hand.queue()), repr(rig._grasp), rig._n_samplers_made, rig._oneoff])]


def _same(a: list[np.ndarray], b: list[np.ndarray]) -> bool:
    return len(a) == len(b) and all(x.shape == y.shape and x.tobytes() == y.tobytes() for x, y in zip(a, b))


def _slippery(mu: float):
    b = BOTTLES["TR"]
    return replace(b, mu_s=mu, mu_k=mu * b.mu_k / b.mu_s)


def _poured(bottle, seed: int, seconds: float) -> list[np.ndarray]:
    rig = Rig(bottle, seed=seed)
    rig.grasp()
    after_grasp = _state(rig)
    rig.perturb(PAPER_POUR, at=rig.t + 0.5)
    rig.run_to(rig.t + seconds)
    return after_grasp + _state(rig)


@pytest.mark.slow
def test_a_pour_from_a_kept_closing_is_the_pour_from_a_fresh_rig_bit_for_bit():
    CLOSINGS.clear()
    _poured(_slippery(1.0), 4, 0.1)                     # keeps seed 4's closing phase
    low = _slippery(0.4)
    with CLOSINGS.disabled():
        plain = _poured(low, 4, 6.0)
    hits = CLOSINGS.hits
    shared = _poured(low, 4, 6.0)
    assert CLOSINGS.hits == hits + 1                    # the closing phase was taken, not run
    assert _same(plain, shared)
    # the friction does act after the support is gone: the low-friction bottle slipped, the other did not
    assert K.E_ONSET in plain[len(plain) // 2 + 4][:, 1]
    with CLOSINGS.disabled():
        grippy = _poured(_slippery(1.0), 4, 6.0)
    assert not _same(plain, grippy)


def test_a_calibration_pour_from_a_shared_grasp_gives_the_same_first_slip():
    CLOSINGS.clear()
    first_slip(_slippery(0.9), seeds=(0,))
    with CLOSINGS.disabled():
        plain = first_slip(_slippery(0.7), seeds=(0,))
    assert first_slip(_slippery(0.7), seeds=(0,)) == plain and CLOSINGS.hits == 1


def test_only_friction_is_blanked_from_the_key():
    rig = Rig("TR")
    P, arrays = rig.kernel_arrays().P, (rig.kernel_arrays().S,)
    key = closing_key(P, arrays, rig.track.rho, "")
    other = P.copy()
    other[friction_slots()] *= 1.7
    assert closing_key(other, arrays, rig.track.rho, "") == key
    heavier = P.copy()
    heavier[K.P_MB] *= 1.01
    assert closing_key(heavier, arrays, rig.track.rho, "") != key
    assert closing_key(P, arrays, rig.track.rho, "force 0.9") != key
    assert closing_key(P, arrays, rig.track.rho[::-1].copy(), "") != key
    assert closing_key(P, (arrays[0] + 1.0,), rig.track.rho, "") != key


def test_a_rig_that_has_done_something_closes_in_full_and_other_inputs_miss():
    CLOSINGS.clear()
    Rig("TR", seed=2).grasp()
    started = Rig("TR", seed=2)
    started.run_to(0.01)
    started.grasp()
    Rig("TR", seed=2).grasp(0.9)                        # another force
    Rig("TX", seed=2).grasp()                           # another bottle
    assert CLOSINGS.hits == 0 and len(CLOSINGS) == 3


def test_the_memo_is_bounded_and_forgets_the_oldest():
    m = ClosingMemo(keep=2)
    for k in (b"a", b"b", b"c"):
        m.put(k, k)
    assert len(m) == 2 and m.get(b"a") is None and m.get(b"c") == b"c"
    m.get(b"b")
    m.put(b"d", b"d")                                  # b was used last: c goes
    assert m.get(b"c") is None and m.get(b"b") == b"b"
    with m.disabled():
        assert m.get(b"b") is None
        m.put(b"e", b"e")
    assert m.get(b"e") is None and m.get(b"b") == b"b"


def test_a_restored_rig_shares_nothing_writable_with_the_kept_closing():
    CLOSINGS.clear()
    a = Rig("DK", seed=9)
    a.grasp()
    b = Rig("DK", seed=9)
    b.grasp()
    assert CLOSINGS.hits == 1
    b.kernel_arrays().S[:] = 0.0
    b.daq_rows()[0][:] = 0.0
    c = Rig("DK", seed=9)
    c.grasp()
    assert _same(_state(a), _state(c))


def test_a_deep_copy_runs_as_the_rig_and_shares_only_the_track():
    rig = Rig("TX", seed=3)
    rig.grasp()
    twin = copy.deepcopy(rig)
    assert twin.track is rig.track and twin.kernel_arrays().S is not rig.kernel_arrays().S
    for r in (rig, twin):
        r.perturb(PAPER_POUR, at=r.t + 0.2)
        r.run_to(r.t + 3.0)
    assert _same(_state(rig), _state(twin))


def test_run_to_keeps_what_advance_block_returns():
    a, b = Rig("TR", seed=1), Rig("TR", seed=1)
    block = a.advance_block(0.2)
    assert b.run_to(0.2) == block.t.size
    rows, first = b.daq_rows()
    assert first == 0 and np.array_equal(rows[:, K.O_VOLTS], block.volts)
    assert np.array_equal(b.daq_history().accel, block.accel)


def test_a_search_with_more_seeds_reuses_the_first_seeds_pours():
    memo: dict = {}
    one = first_slip(_slippery(0.8), seeds=(0,), memo=memo)
    assert len(memo) == 1
    two = first_slip(_slippery(0.8), seeds=(0, 1), memo=memo)
    assert len(memo) == 2 and two.per_seed[0] == one.per_seed[0]
    assert two == first_slip(_slippery(0.8), seeds=(0, 1))
    renamed = replace(_slippery(0.8), name="OTHER", surface=SURFACES["white"])   # the surface feeds no pour
    assert first_slip(renamed, seeds=(0, 1), memo=memo) == two and len(memo) == 2


def test_a_kept_texture_is_the_drawn_one_and_leaves_the_generator_alike():
    surf = SURFACES["white"]
    spectrum = (surf.texture_exponent, surf.texture_min_wavelength_m, surf.texture_max_wavelength_m)
    fresh = np.random.default_rng(21)
    drawn = texture(3000, 5e-6, *spectrum, fresh)
    for _ in range(2):
        rng = np.random.default_rng(21)
        kept = _kept_texture(3000, 5e-6, surf, rng)
        assert kept.tobytes() == drawn.tobytes() and not kept.flags.writeable
        assert rng.bit_generator.state == fresh.bit_generator.state


@pytest.mark.parametrize("zero_phase", [False, True])
def test_the_kept_filter_design_filters_as_a_fresh_one(zero_phase):
    from scipy import signal as sps

    t = np.arange(600) / 333.0
    a = np.random.default_rng(0).normal(0.0, 0.01, 600)
    p = OnsetParams(zero_phase=zero_phase)
    x = np.abs(a - a[t < t[0] + p.baseline_s].mean())
    fs = float(1.0 / np.median(np.diff(t)))
    sos = sps.butter(2, p.cutoff, fs=fs, output="sos")
    want = sps.sosfiltfilt(sos, x) if zero_phase else sps.sosfilt(sos, x, zi=sps.sosfilt_zi(sos) * x[0])[0]
    for _ in range(2):
        assert accel_envelope(t, a, p).tobytes() == want.tobytes()
