"""The compiled closed loop (sim/closed.py) equals the Python loop: every command, every trace array,
the reflex's state and the rig's, bit for bit."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from numba import njit

from slipreflex import methods
from slipreflex.core import hardware as hw
from slipreflex.core.errors import ParameterError
from slipreflex.core.hardware import Finger, HandCommand
from slipreflex.core.interfaces import CompiledReflex
from slipreflex.reproduce.experiments import ReproduceConfig, calibrate
from slipreflex.sim import PAPER_DROP, PAPER_POUR, Drop, Pour, Rig, closed, run_closed_loop

SHORT_POUR = Pour(rate_l_min=1.0, volume_ml=150.0)
# (experiment, bottle, seed): drops and pours, every bottle, several seeds
CASES = [(PAPER_DROP, "TR", 1), (Drop(mass_kg=0.02, height_m=0.08), "TX", 2), (PAPER_POUR, "DK", 3),
         (PAPER_POUR, "TR", 4)]


@functools.cache
def _context() -> methods.MethodContext:
    """The calibrated thresholds, computed on first use (never at collection)."""
    return methods.MethodContext(thresholds=calibrate(ReproduceConfig(trials=1)), speed=500.0)


def _compiled_methods() -> list[str]:
    """The methods with a compiled step (whether one is does not depend on its threshold's value)."""
    placeholder = methods.MethodContext(thresholds={m: 1.0 for m in methods.names()}, speed=500.0)
    return [m for m in methods.names() if isinstance(methods.make(m, p0=100.0, context=placeholder), CompiledReflex)]


COMPILED = _compiled_methods()


def _run(method_or_factory, what, bottle, seed, compiled, **kw):
    rig = Rig(bottle, seed=seed)
    g = rig.grasp()
    p0 = float(round(g.positions[hw.SLIP_FINGER]))
    if callable(method_or_factory):
        reflex = method_or_factory(p0)
    else:
        reflex = methods.make(method_or_factory, p0=p0, context=_context())
    rig.perturb(what, at=rig.t + 0.2)
    duration = 0.2 + (what.duration_s if isinstance(what, Pour) else 0.0) + 0.8
    tr = run_closed_loop(rig, reflex, duration, compiled=compiled, **kw)
    return rig, reflex, tr


def _assert_same(a, b):
    """Two (rig, reflex, trace) runs are the same, bit for bit, and so is what each leaves behind."""
    (ra, fa, ta), (rb, fb, tb) = a, b
    np.testing.assert_array_equal(ta.cmd_t, tb.cmd_t)
    np.testing.assert_array_equal(ta.cmd_value, tb.cmd_value)
    for name in ta.daq.__dataclass_fields__:
        np.testing.assert_array_equal(getattr(ta.daq, name), getattr(tb.daq, name), err_msg=name)
    np.testing.assert_array_equal(ta.tactile_t, tb.tactile_t)
    np.testing.assert_array_equal(ta.tactile, tb.tactile)
    np.testing.assert_array_equal(ta.onsets, tb.onsets)
    assert ta.slip_events == tb.slip_events
    assert (ta.fallen, ta.fall_time, ta.t_end) == (tb.fallen, tb.fall_time, tb.t_end)
    np.testing.assert_array_equal(ra.events(), rb.events())
    # what the objects hold afterwards: the reflex's state, the physics, the hand's queue and servos
    if isinstance(fa, CompiledReflex):
        np.testing.assert_array_equal(fa.compiled()[1], fb.compiled()[1])
    ka, kb = ra.kernel_arrays(), rb.kernel_arrays()
    for name in ka.__dataclass_fields__:
        np.testing.assert_array_equal(getattr(ka, name), getattr(kb, name), err_msg=name)
    assert ra.hand.queue() == rb.hand.queue()
    assert ra.hand.closing_until == rb.hand.closing_until
    assert [s.next_index for s in ra.samplers] == [s.next_index for s in rb.samplers]


@pytest.mark.slow
@pytest.mark.parametrize("what,bottle,seed", CASES, ids=["drop-TR", "drop-TX", "pour-DK", "pour-TR"])
@pytest.mark.parametrize("method", COMPILED)
def test_the_compiled_loop_equals_the_python_loop(method, what, bottle, seed):
    a = _run(method, what, bottle, seed, compiled=True)
    assert closed.compilable(a[0], a[1], hw.TRIPOD)
    b = _run(method, what, bottle, seed, compiled=False)
    _assert_same(a, b)
    if method in (methods.DATH, methods.FIXED):
        assert a[2].cmd_t.size > 0, "the case must make the method command something"


def test_every_method_of_the_chain_has_a_compiled_step():
    assert {methods.DATH, methods.FIXED, methods.AUTHORS_GUI, methods.AUTHORS_CHAIN, methods.DATH_EVENT,
            methods.DATH_FLOOR, methods.DATH_LEAK} <= set(COMPILED)


@pytest.mark.slow
def test_finger_offsets_reach_the_offset_finger_only(monkeypatch):
    """authors-gui closes the middle finger 20 units further: at the first command, its group alone
    closes 20 / 625 s longer; later rises close every finger alike. Both loops split commands alike."""
    sent = []
    rig = Rig("TR", seed=4)
    g = rig.grasp()
    command = rig.hand.command
    monkeypatch.setattr(rig.hand, "command", lambda kind, fingers, value=0.0, at=None: (
        sent.append((kind, tuple(fingers), at)), command(kind, fingers, value, at=at))[1])
    reflex = methods.make(methods.AUTHORS_GUI, p0=float(round(g.positions[hw.SLIP_FINGER])), context=_context())
    assert reflex.finger_offsets == {Finger.MIDDLE: 20.0}
    rig.perturb(SHORT_POUR, at=rig.t + 0.2)
    tr = run_closed_loop(rig, reflex, 1.0 + SHORT_POUR.duration_s, compiled=False)
    assert tr.cmd_t.size

    def closing(fingers):  # seconds of closing the group was given: each CLOSE to its STOP
        mine = [(k, at) for k, f, at in sent if f == fingers]
        assert [k for k, _ in mine] == [HandCommand.CLOSE, HandCommand.STOP] * (len(mine) // 2)
        return sum(b - a for (_, a), (_, b) in zip(mine[::2], mine[1::2]))

    others, middle = closing((Finger.THUMB, Finger.INDEX)), closing((Finger.MIDDLE,))
    assert others > 0 and middle == pytest.approx(others + 20.0 / hw.FINGER_SPEED_UNITS_S)


def test_the_reflex_and_the_rig_continue_where_the_compiled_loop_left_them():
    """After the loop, reflex.step and the Python loop carry on exactly as after a Python loop."""
    runs = []
    for compiled in (True, False):
        rig, reflex, tr = _run(methods.DATH, SHORT_POUR, "TR", 4, compiled=compiled)
        tr2 = run_closed_loop(rig, reflex, 0.7, compiled=False)
        runs.append((rig, reflex, tr2))
    _assert_same(*runs)


def test_a_recorded_tactile_stream_and_a_queued_command_are_kept():
    """tactile_fs records frames; commands queued before the loop (CLOSE, STOP, OPEN) are applied in order."""
    runs = []
    for compiled in (True, False):
        rig = Rig("TX", seed=5)
        g = rig.grasp()
        reflex = methods.make(methods.DATH, p0=g.positions[hw.SLIP_FINGER])
        other = rig.tactile_sampler(100.0, Finger.THUMB, keep=True)   # a user's sampler stays fed
        rig.hand.command(HandCommand.CLOSE, [Finger.THUMB], 100.0, at=rig.t)
        rig.hand.command(HandCommand.STOP, [Finger.THUMB, Finger.INDEX], at=rig.t + 0.05)
        rig.hand.command(HandCommand.OPEN, [Finger.INDEX], 297.0, at=rig.t + 0.3)   # due after some commands
        rig.perturb(PAPER_DROP, at=rig.t + 0.1)
        tr = run_closed_loop(rig, reflex, 0.6, tactile_fs=hw.NMSD_FS, compiled=compiled)
        runs.append((rig, reflex, tr))
        assert tr.tactile.shape[0] == pytest.approx(0.6 * hw.NMSD_FS, abs=1)
        runs[-1] = runs[-1] + (other.read(),)
    (*a, fa), (*b, fb) = runs
    _assert_same(a, b)
    np.testing.assert_array_equal(fa[1], fb[1])
    assert fa[1].shape[0] == pytest.approx(0.6 * 100.0, abs=1)


# --- a tactile reflex with a compiled step (what NMSD and SWT-SD implement) ------------------------

@njit(cache=True)
def _squeeze_step(S, P, frame, position):
    """Close by P[0] units above the measured position whenever the frame's total falls below P[1]."""
    S[1] += 1.0
    if frame.sum() < P[1] and S[1] - S[0] > P[2]:
        S[0] = S[1]
        return position + P[0]
    return np.nan


class _Squeeze:
    name, input_kind = "squeeze", "tactile"

    def __init__(self, fs, gap=5.0):
        self.fs = fs
        self.S = np.zeros(2)
        self.P = np.array([3.0, 1.6, gap])

    def compiled(self):
        return _squeeze_step, self.S, self.P

    def step(self, frame, position=None):
        c = _squeeze_step(self.S, self.P, np.ascontiguousarray(frame, dtype=float).ravel(),
                          math.nan if position is None else float(position))
        return None if c != c else c

    def reset(self):
        self.S[:] = 0.0


@pytest.mark.slow
@pytest.mark.parametrize("fs", [hw.NMSD_FS, hw.SWT_FS])
@pytest.mark.parametrize("what,bottle,seed", CASES[:3], ids=["drop-TR", "drop-TX", "pour-DK"])
def test_a_compiled_tactile_reflex_equals_its_python_loop(fs, what, bottle, seed):
    a = _run(lambda p0: _Squeeze(fs), what, bottle, seed, compiled=True)
    assert closed.compilable(a[0], a[1], hw.TRIPOD)
    b = _run(lambda p0: _Squeeze(fs), what, bottle, seed, compiled=False)
    _assert_same(a, b)
    assert a[2].cmd_t.size > 0
    assert a[2].tactile.shape[0] == pytest.approx((a[2].t_end - a[2].t_start) * fs, abs=1)


# --- the fallback ----------------------------------------------------------------------------------

class _Plain:
    """A reflex without a compiled step: the Python loop runs it."""

    name, input_kind, fs = "plain", "slip", hw.DAQ_FS

    def __init__(self, p0):
        self.inner = methods.make(methods.DATH, p0=p0)

    def step(self, sample, position=None):
        return self.inner.step(sample, position)

    def reset(self):
        self.inner.reset()


def _no_compiled_loop(monkeypatch):
    def fail(*args, **kwargs):
        raise AssertionError("the compiled loop ran")
    monkeypatch.setattr(closed, "run_compiled", fail)


def test_a_reflex_without_a_compiled_step_runs_in_the_python_loop(monkeypatch):
    b = _run(methods.DATH, SHORT_POUR, "TR", 4, compiled=True)
    _no_compiled_loop(monkeypatch)
    a = _run(_Plain, SHORT_POUR, "TR", 4, compiled=True)
    assert not isinstance(a[1], CompiledReflex)
    np.testing.assert_array_equal(a[2].cmd_value, b[2].cmd_value)
    np.testing.assert_array_equal(a[2].daq.volts, b[2].daq.volts)


def test_commands_to_other_fingers_run_in_the_python_loop(monkeypatch):
    """The compiled loop drives the tripod only; a loop that also commands the ring finger falls back."""
    fingers = hw.TRIPOD + (Finger.RING,)
    _no_compiled_loop(monkeypatch)
    a = _run(methods.DATH, SHORT_POUR, "TR", 4, compiled=True, fingers=fingers)
    b = _run(methods.DATH, SHORT_POUR, "TR", 4, compiled=False, fingers=fingers)
    _assert_same(a, b)


def test_compiled_must_be_a_bool():
    rig = Rig("TR")
    with pytest.raises(ParameterError, match="compiled"):
        run_closed_loop(rig, methods.make(methods.DATH), 0.1, compiled="yes")


def test_the_loop_kernels_cache_goes_stale_when_the_physics_changes(tmp_path, monkeypatch):
    """The kernels compile step_until into themselves: their disk cache is stamped with the physics' files too."""
    from pathlib import Path

    from slipreflex.core import _numba_cache
    from slipreflex.sim import kernel_contacts, kernel_step

    locator = closed._closed_slip._cache._impl.locator
    assert isinstance(locator, _numba_cache._Stamped)
    files = _numba_cache.stamped_files(closed.__file__)
    assert {closed.__file__, kernel_step.__file__, kernel_contacts.__file__, hw.__file__} <= set(files)
    physics = tmp_path / "kernel_contacts.py"
    physics.write_text(Path(kernel_contacts.__file__).read_text())
    monkeypatch.setitem(_numba_cache._INLINES, kernel_step.__file__,
                        tuple(str(physics) if p == kernel_contacts.__file__ else p
                              for p in _numba_cache._INLINES[kernel_step.__file__]))
    before = locator.get_source_stamp()
    physics.write_text(physics.read_text() + "\n# a changed constant\n")
    assert locator.get_source_stamp() != before


def test_a_tactile_reflex_for_other_frames_fails_as_in_the_python_loop():
    """NMSD set up for a 7-channel sensor: both loops refuse the rig's 4 x 4 frames with the same error."""
    from slipreflex.core.errors import DataError

    for compiled in (True, False):
        rig = Rig("TR")
        rig.grasp()
        reflex = methods.make(methods.NMSD, p0=100.0, context=_context(), shape=(7,))
        with pytest.raises(DataError, match="shape"):
            run_closed_loop(rig, reflex, 0.1, compiled=compiled)


@njit(cache=True)
def _fail_step(S, P, raw, position):
    S[0] += 1.0
    if S[0] > P[0]:
        raise ValueError("the reflex failed")
    return position + S[0]   # a command on every sample: some are still queued when it fails


class _Failing:
    name, input_kind, fs = "failing", "slip", hw.DAQ_FS

    def __init__(self, after):
        self.S, self.P = np.zeros(1), np.array([float(after)])

    def compiled(self):
        return _fail_step, self.S, self.P

    def step(self, sample, position=None):
        c = _fail_step(self.S, self.P, float(sample), math.nan if position is None else float(position))
        return None if c != c else c

    def reset(self):
        self.S[:] = 0.0


def test_a_step_that_raises_leaves_the_rig_as_the_python_loop_leaves_it():
    runs = []
    for compiled in (True, False):
        rig = Rig("TR", seed=2)
        rig.grasp()
        reflex = _Failing(102)
        with pytest.raises(ValueError, match="the reflex failed"):
            run_closed_loop(rig, reflex, 1.0, compiled=compiled)
        runs.append((rig, reflex))
    (ra, fa), (rb, fb) = runs
    np.testing.assert_array_equal(fa.S, fb.S)
    assert ra.t == rb.t and ra.hand.queue() == rb.hand.queue() and ra.hand.queue()[0]
    for name in ra.daq_history().__dataclass_fields__:
        np.testing.assert_array_equal(getattr(ra.daq_history(), name), getattr(rb.daq_history(), name))


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("method", [methods.DATH, methods.NMSD])
def test_a_zero_length_run_from_the_start_returns(method, compiled):
    """From t = 0 no step is left before t_end: both loops return at once (the Python loop used to spin)."""
    rig = Rig("TR")
    tr = run_closed_loop(rig, methods.make(method, context=_context()), 0.0, compiled=compiled)
    assert rig.t == 0.0 and tr.t.size == 0 and tr.cmd_t.size == 0
    tr = run_closed_loop(rig, methods.make(method, context=_context()), 0.01, compiled=compiled)
    assert tr.t.size == 4 and tr.t[0] == 0.0


def test_a_compiled_tactile_reflex_beside_another_sampler():
    """With a user's thumb sampler open, the loop builds the reflex's frames among the other rows."""
    runs = []
    for compiled in (True, False):
        rig = Rig("TX", seed=2)
        rig.grasp()
        other = rig.tactile_sampler(100.0, Finger.THUMB, keep=True)
        rig.perturb(PAPER_DROP, at=rig.t + 0.1)
        reflex = _Squeeze(hw.SWT_FS)
        tr = run_closed_loop(rig, reflex, 0.8, compiled=compiled)
        runs.append(((rig, reflex, tr), other.read()))
    (a, fa), (b, fb) = runs
    _assert_same(a, b)
    assert a[2].cmd_t.size > 0 and fa[1].shape[0] > 0
    np.testing.assert_array_equal(fa[1], fb[1])


def test_a_compiled_method_that_is_not_numba_is_refused_before_the_run():
    class Fake(_Plain):
        def compiled(self):
            return (lambda S, P, raw, position: np.nan), np.zeros(1), np.zeros(1)

    rig = Rig("TR")
    with pytest.raises(ParameterError, match=r"Fake.compiled\(\) must return a numba @njit step"):
        run_closed_loop(rig, Fake(100.0), 0.1)
    assert rig.t == 0.0


@pytest.mark.parametrize("latency,dt", [(0.0123, 7e-5), (0.0005, 2.5e-4)])
@pytest.mark.parametrize("method", [methods.DATH, methods.AUTHORS_GUI, methods.NMSD])
def test_the_loops_agree_off_the_default_latency_and_time_step(method, latency, dt):
    """A latency off the step grid (or shorter than a DAQ period) and another dt: same due steps, same bits."""
    from slipreflex.sim import HandParams, PhysicsParams

    runs = []
    for compiled in (True, False):
        rig = Rig("DK", seed=5, hand=HandParams(latency_s=latency), physics=PhysicsParams(dt=dt))
        g = rig.grasp()
        reflex = methods.make(method, p0=float(round(g.positions[hw.SLIP_FINGER])), context=_context())
        rig.perturb(PAPER_DROP, at=rig.t + 0.3)
        runs.append((rig, reflex, run_closed_loop(rig, reflex, 1.5, compiled=compiled)))
    _assert_same(*runs)
    assert runs[0][2].cmd_t.size > 0


class _Checked(_Failing):
    """A compiled reflex with the Reflex diagnostics, for slipreflex.testing.check_reflex."""

    last_event, last_filtered, last_threshold, last_count = False, math.nan, None, None

    def __init__(self):
        super().__init__(1e9)


def test_check_reflex_holds_a_compiled_step_to_step():
    from slipreflex.testing import ContractError, check_reflex

    assert check_reflex(_Checked()).commands > 0

    class Copied(_Checked):
        def compiled(self):
            return _fail_step, self.S.copy(), self.P

    with pytest.raises(ContractError, match="live state"):
        check_reflex(Copied())

    class Other(_Checked):
        def compiled(self):
            return _never_step, self.S, self.P

    with pytest.raises(ContractError, match="compiled step on its state disagrees"):
        check_reflex(Other())


@njit(cache=True)
def _never_step(S, P, raw, position):
    S[0] += 1.0
    return np.nan


# --- the tripod is never opened by a reflex's command ----------------------------------------------

@pytest.mark.parametrize("method", [methods.DATH, methods.AUTHORS_GUI, methods.NMSD])
def test_a_reflex_only_ever_closes_the_tripod_in_a_closed_loop_pour(method, monkeypatch):
    """The grasp stops each finger at its own position (here the thumb 2 units further closed than
    the middle finger the reflex starts from): the reflex's command reaches the hand only as CLOSE
    and STOP (the grip-only rule, as runtime.run_loop sends it), in either loop, so no finger ever
    opens, whatever the command says."""
    from slipreflex.reproduce.experiments import trial_seed
    from slipreflex.sim.variations import grasped_rig

    def stops(trial):
        rig, _ = grasped_rig("DK", trial_seed(ReproduceConfig().seed, "pour", "DK", trial), hw.CONTACT_FORCE_N)
        return rig.hand.positions()

    # the first of the default trials whose grasp stopped the thumb further closed than the middle finger
    trial = next(k for k in range(20) if stops(k)[Finger.THUMB] > stops(k)[Finger.MIDDLE])
    seed = trial_seed(ReproduceConfig().seed, "pour", "DK", trial)
    runs, sent = [], []
    for compiled in (True, False):
        rig, g = grasped_rig("DK", seed, hw.CONTACT_FORCE_N)
        start = rig.hand.positions()
        assert start[Finger.THUMB] > start[Finger.MIDDLE], "the case needs a thumb that stopped further closed"
        reflex = methods.make(method, p0=start[hw.SLIP_FINGER], context=_context())
        if not compiled:   # the Python loop sends every command through the hand's command: keep them
            command = rig.hand.command
            monkeypatch.setattr(rig.hand, "command", lambda kind, fingers, value=0.0, at=None, command=command: (
                sent.extend((kind, f) for f in fingers), command(kind, fingers, value, at=at))[1])
        rig.perturb(PAPER_POUR, at=rig.t + 0.2)
        tr = run_closed_loop(rig, reflex, 0.2 + PAPER_POUR.duration_s + 1.0, compiled=compiled)
        assert tr.cmd_t.size > 0
        for i, f in enumerate(hw.TRIPOD):
            track = np.rint(tr.daq.fingers[:, i])
            assert track.min() >= start[f], f"{method}: {f.name} opened"
            assert np.all(np.diff(track) >= 0), f"{method}: {f.name} moved toward open"
        runs.append((rig, reflex, tr))
    _assert_same(*runs)
    assert {f for _, f in sent} == set(hw.TRIPOD)
    assert {k for k, _ in sent} == {HandCommand.CLOSE, HandCommand.STOP}


def test_a_command_out_of_the_finger_range_only_closes_for_its_rise():
    """A command of 600 from a middle finger at 0 is 600 units of grip: 0.96 s of closing, then STOP;
    never a position, for a tripod finger and for the thumb rotator alike."""
    class Once:
        name, input_kind, fs = "once", "slip", hw.DAQ_FS

        def step(self, sample, position=None):
            return 600.0

        def reset(self):
            pass

    rig = Rig("TR")
    run_closed_loop(rig, Once(), 0.1, fingers=(Finger.THUMB_ROTATOR, Finger.INDEX))
    pending, _ = rig.hand.queue()
    assert [(e[2], e[3]) for e in pending] == [(HandCommand.STOP, (Finger.THUMB_ROTATOR, Finger.INDEX))]
    assert rig.hand.closing_until[Finger.INDEX] == pytest.approx(600.0 / hw.FINGER_SPEED_UNITS_S)
    assert rig.hand.targets[1] == hw.FINGER_MAX  # closing (the CLOSE runs to the end of the range)


@pytest.mark.parametrize("rate", [0.0, hw.NMSD_FS, hw.SWT_FS])
@pytest.mark.parametrize("latency", [0.0, 0.001, 0.010, 0.0301])
def test_a_stretch_ends_on_a_sample_instant_no_later_than_the_latency_allows(rate, latency):
    daq_t = hw.DAQ_PERIOD_S
    for index in range(0, 400, 7):
        t = index * daq_t if rate == 0.0 else index / rate
        end = closed.stretch_end(index, rate, latency, daq_t)
        assert t - 1e-15 <= end <= t + latency + 1e-15
        on_daq = abs(end / daq_t - round(end / daq_t)) < 1e-9
        on_own = rate != 0.0 and abs(end * rate - round(end * rate)) < 1e-9
        assert on_daq or on_own, (index, end)
        # the furthest such instant: the next DAQ row or frame would be past the latency
        nxt = min((math.floor(end / daq_t + 1e-9) + 1) * daq_t,
                  (math.floor(end * rate + 1e-9) + 1) / rate if rate else math.inf)
        assert nxt > t + latency - 1e-12


def test_a_reflex_that_never_commands_costs_the_adaptive_kernel_no_extra_steps():
    """The loop's stretches end where the kernel ends a step anyway (a DAQ row): the closed held pour
    takes as many kernel steps as the same pour run open loop."""

    @njit(cache=True)
    def never(S, P, raw, position):
        return np.nan

    class Never:
        name, input_kind, fs = "never", "slip", hw.DAQ_FS

        def __init__(self):
            self.S, self.P = np.zeros(1), np.zeros(1)

        def compiled(self):
            return never, self.S, self.P

        def step(self, sample, position=None):
            return None

        def reset(self):
            pass

    steps = []
    for closed_loop in (False, True):
        rig = Rig("TR", seed=1, stepping="adaptive")
        g = rig.grasp()
        rig.hand.set_positions({f: g.positions[f] + 40 for f in hw.TRIPOD})
        rig.perturb(PAPER_POUR, at=rig.t + 0.5)
        before = rig.steps_taken
        if closed_loop:
            run_closed_loop(rig, Never(), 6.0)
        else:
            rig.advance_block(rig.t + 6.0)
        steps.append(rig.steps_taken - before)
    assert steps[1] == steps[0] < 6.0 / 1e-4 / 8


def test_a_compiled_loop_s_trace_reads_the_rig_s_history_without_copying_it():
    """The compiled loop writes its DAQ rows column by column: the trace's columns are read-only views of the
    rows the rig keeps, equal to the rows read back, and the Python loop's (copied) trace equals it."""
    traces, rows = [], []
    for compiled in (True, False):
        rig = Rig("TR", seed=2)
        g = rig.grasp()
        rig.perturb(SHORT_POUR, at=rig.t + 0.1)
        t0 = rig.t
        reflex = methods.make("dath", p0=float(round(g.positions[Finger.MIDDLE])), context=_context())
        traces.append(run_closed_loop(rig, reflex, 1.0, compiled=compiled))
        rows.append(rig.daq_rows(since=t0)[0])
    fast, plain = traces
    assert np.shares_memory(fast.daq.volts, rows[0]) and not np.shares_memory(plain.daq.volts, rows[1])
    for name in ("t", "volts", "accel", "fingers", "normal_force", "flow_pulses", "stuck"):
        a, b = getattr(fast.daq, name), getattr(plain.daq, name)
        assert not a.flags.writeable and not b.flags.writeable
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="read-only"):
        fast.daq.volts[0] = 0.0
