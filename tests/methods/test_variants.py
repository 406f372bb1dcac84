"""The method family (docs/method.md, "Variants"): the authors-gui preset, an accumulator
that forgets, a DATH floor, the event-driven MPI; each against a literal transcription
(tests/spec_oracle.py), on hand-worked examples, and streaming against batch."""

import math

import numpy as np
import pytest

import slipreflex as sr
import spec_oracle as oracle
from slipreflex.core import hardware as hw
from slipreflex.core.errors import ParameterError
from slipreflex.methods.chain import ReflexParams, SlipReflex

U = 1.0 / 1024.0  # an exact binary unit: hand-worked sums carry no rounding


def _signals(fs):
    rng = np.random.default_rng(1406)
    k = int(4 * fs)
    t = np.arange(k) / fs
    slip = np.where((t > 1.0) & (t < 1.6), 0.02 * np.sin(2 * np.pi * 14 * t), 0.0)
    quant = lambda v: np.round(v / hw.ADC_LSB) * hw.ADC_LSB  # noqa: E731
    return {
        "rest-then-slip": quant(0.41 + slip + rng.normal(0, 0.001, k)),
        "walk": 0.4 + np.cumsum(rng.normal(0, 0.003, k)),
        "dark": quant(3.33 + 0.5 * slip + rng.normal(0, 0.002, k)),
        "short": np.array([0.4, 0.41, 0.39]),
    }


def _stream(reflex, raw):
    out = [reflex.step(r) for r in raw]
    return [(k, u) for k, u in enumerate(out) if u is not None]


# --- the authors-gui preset (docs/method.md section 1.6) -------------------------------------------------------

@pytest.mark.parametrize("fs", [333.0, hw.DAQ_FS, 1000.0])
def test_authors_gui_equals_its_literal_transcription_bit_for_bit(fs):
    for name, raw in _signals(fs).items():
        x, ys, v, cmds = oracle.authors_gui(raw.tolist(), fs)
        res = sr.run_chain(raw, ReflexParams.preset("authors-gui", fs=fs))
        assert res.filtered.tolist() == x, name
        assert res.events.astype(int).tolist() == ys, name
        assert res.counts.tolist() == v, name
        assert res.commands.tolist() == cmds, name
        reflex = SlipReflex.from_preset("authors-gui", fs=fs)
        w = ReflexParams.preset("authors-gui", fs=fs).n
        assert _stream(reflex, raw) == [((z + 1) * w - 1, c) for z, c in enumerate(cmds)], name


def test_authors_gui_lengths_at_the_rigs_rates():
    for fs in (333.0, hw.DAQ_FS):
        p = ReflexParams.preset("authors-gui", fs=fs)
        assert (p.mean_samples, p.acc_reset, p.n) == (67, 33, 9)
        assert (p.threshold, p.dath, p.x0, p.reset_after, p.p0) == (0.005, False, 0.0, None, 125.0)
        assert p.slip_finger_offset == 20.0
    assert SlipReflex.from_preset("AUTHORS-GUI").name == "authors-gui"
    assert SlipReflex.from_preset("authors-gui", p0=210.0).command == 210.0


def test_authors_gui_first_sample_spikes_and_mean_starts_with_what_has_arrived():
    raw = np.array([0.4, 0.5, 0.6])
    res = sr.run_chain(raw, ReflexParams.preset("authors-gui"))
    assert res.events[0]  # prev = 0.0: the start-up spike of the paper's text
    assert res.filtered.tolist() == [0.4, (0.4 + 0.5) / 2, (0.4 + 0.5 + 0.6) / 3]


def test_authors_gui_never_resets_its_mpi():
    # one spike window, then a long quiet: the paper's MPI resets after 10 zero windows
    # (P0 := command), the authors' does not (P0 stays 125), so a later spike window
    # rises less there.
    y = [0] * 8 + [1] + [0] * 9 * 15 + [0] * 8 + [1]
    v = oracle.windows(y, 9)
    assert oracle.mpi(v, p0=125.0, R=None)[-1] == sr.mpi(v, p0=125.0, reset_after=None)[-1] == 140.0
    assert sr.mpi(v, p0=125.0, reset_after=10)[-1] == 145.0  # P0 became 135 after 10 zero windows


def test_preset_names_and_errors():
    assert ReflexParams.preset("paper") == ReflexParams()
    assert ReflexParams.preset("dath-event").name == "dath-event"
    with pytest.raises(ParameterError, match="preset: unknown 'authors'"):
        ReflexParams.preset("authors")
    with pytest.raises(ParameterError, match="unknown parameter"):
        ReflexParams.preset("authors-gui", thresh=1.0)


# --- an accumulator that forgets --------------------------------------------------------------

def test_periodic_reset_hand_worked():
    # Steps of 2 U, theta 8 U. Paper: acc 2, 4, 6, 8, 10 > 8 at k = 5, again at k = 10.
    # acc_reset = 4: cleared after k = 3 (acc 6) and k = 7 (acc 8, not > 8): never fires.
    x = np.arange(12) * 2 * U
    assert np.flatnonzero(sr.encode(x, threshold=8 * U)).tolist() == [5, 10]
    tr = sr.encode_trace(x, threshold=8 * U, acc_reset=4)
    assert not tr.events.any()
    assert (tr.accumulator / U).tolist() == [0, 2, 4, 6, 2, 4, 6, 8, 2, 4, 6, 8]


def test_periodic_reset_counts_samples_not_spikes():
    # A spike does not restart the clock: steps of 9 U spike every sample; with acc_reset = 3
    # the clock still clears at k = 2, 5, 8 (no effect on events, acc is 0 after a spike).
    x = np.arange(10) * 9 * U
    enc = sr.EventEncoder(threshold=8 * U, acc_reset=3)
    clocks = []
    for v in x:
        enc.step(v)
        clocks.append(enc.clock)
    assert clocks == [1, 2, 0, 1, 2, 0, 1, 2, 0, 1]


def test_leak_hand_worked():
    # tau = 1 / ln 2: the accumulator halves every sample. Steps of 5 U, theta 8 U:
    # acc 5, 7.5, 8.75 > 8 -> spike at k = 3, 6, 9 (paper: 5, 10 > 8 -> every 2nd sample).
    tau = 1 / math.log(2)
    x = np.arange(10) * 5 * U
    tr = sr.encode_trace(x, threshold=8 * U, acc_leak=tau)
    assert np.flatnonzero(tr.events).tolist() == [3, 6, 9]
    np.testing.assert_allclose(tr.accumulator[1:4] / U, [5, 7.5, 8.75], rtol=1e-12)
    assert np.flatnonzero(sr.encode(x, threshold=8 * U)).tolist() == [2, 4, 6, 8]


def _residue_then_blip():
    """The issue's case: a slip leaves 7 U in the accumulator, a 2 U blip 1 s later."""
    quiet = np.full(333, 7 * U)
    return np.r_[0.0, 7 * U, quiet, 9 * U, np.full(16, 9 * U), 9 * U + 0.25 * U, np.full(8, 9.25 * U)]


def test_leak_forgets_a_residue_that_the_paper_encoder_keeps():
    x = _residue_then_blip()
    paper = sr.encode_trace(x, threshold=8 * U, x0=0.0)
    assert np.flatnonzero(paper.events).tolist() == [335]  # 7 U kept for a second, + 2 U blip
    leaky = sr.encode(x, threshold=8 * U, x0=0.0, acc_leak=33.0)  # 0.1 s at 333 Hz
    reset = sr.encode(x, threshold=8 * U, x0=0.0, acc_reset=33)
    assert not leaky.any() and not reset.any()


def test_dath_floor_stops_the_zoom_below_one_adc_step():
    # The same residue with DATH: the blip's spike at k = 335 has |d| = 2 U, so DATH drops theta
    # to 2 U for 16 samples, and a drift of a quarter U per sample (far below one ADC step) fires
    # again when it adds up to 2.25 U at k = 344. With the documented floor of one ADC step
    # (hw.ADC_LSB = 5 V / 1024 = 5 U) theta stays at 5 U: 16 quarters (4 U) never fire.
    x = np.r_[_residue_then_blip()[:336], 9 * U + np.cumsum(np.full(16, 0.25 * U))]
    dath = sr.encode_trace(x, threshold=8 * U, x0=0.0, dath=True)
    floored = sr.encode_trace(x, threshold=8 * U, x0=0.0, dath=True, dath_floor=hw.ADC_LSB)
    assert dath.threshold[336] == 2 * U and floored.threshold[336] == hw.ADC_LSB == 5 * U
    assert np.flatnonzero(dath.events).tolist() == [335, 344]
    assert np.flatnonzero(floored.events).tolist() == [335]


def test_chain_parameters_take_numpy_numbers_like_every_other_class():
    # one validator (slipreflex.core.validation): numpy integers and floats are numbers, bool is not
    p = ReflexParams(n=np.int64(8), acc_reset=np.int32(33), acc_leak=np.float32(12.5), kp=np.int16(3))
    assert (p.n, p.acc_reset, p.acc_leak, p.kp) == (8, 33, 12.5, 3.0)
    assert type(p.n) is int and type(p.acc_leak) is float and type(p.kp) is float
    with pytest.raises(ParameterError, match="n must be an integer >= 1, got True"):
        ReflexParams(n=True)


def test_forgetting_options_refused_when_meaningless():
    with pytest.raises(ParameterError, match="acc_leak must be a finite number > 0"):
        ReflexParams(acc_leak=0.0)
    with pytest.raises(ParameterError, match="acc_reset must be an integer >= 1"):
        sr.EventEncoder(acc_reset=0)
    with pytest.raises(ParameterError, match="mpi_mode: unknown 'instant'"):
        SlipReflex(mpi_mode="instant")


# --- the event-driven MPI ----------------------------------------------------------------------

def _train_to_raw(y, theta):
    """Filtered-off raw volts whose encoder spikes exactly where y is 1 (steps of 2 theta)."""
    return np.cumsum(np.asarray(y, dtype=float)) * 2 * theta


def _event_chain(**kw):
    return ReflexParams(filter=False, x0=0.0, threshold=8 * U, mpi_mode="event", **kw)


def _random_trains(seed, count=30, k=700):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        rate = rng.choice([0.005, 0.03, 0.2])
        yield (rng.random(k) < rate).astype(int).tolist()


@pytest.mark.parametrize("kw", [dict(), dict(n=5, reset_after=2, p0=100.0, kp=2.0, ki=0.5),
                                dict(reset_after=None, p0=490.0), dict(n=1, reset_after=1)])
def test_event_mpi_equals_its_literal_transcription(kw):
    ok = dict(n=kw.get("n", 16), p0=kw.get("p0", 0.0), kp=kw.get("kp", 5.0), ki=kw.get("ki", 5.0),
              R=kw.get("reset_after", 10))
    for y in _random_trains(7):
        res = sr.run_chain(_train_to_raw(y, 8 * U), _event_chain(**kw))
        assert res.events.astype(int).tolist() == y
        assert res.sample_commands.tolist() == oracle.event_mpi(y, **ok)


def test_event_mpi_never_decreases_and_responds_on_the_spike_sample():
    for y in _random_trains(8):
        raw = _train_to_raw(y, 8 * U)
        # measured positions, often below the command: a reset may lower P0, never the command
        reflex = SlipReflex(_event_chain(p0=50.0))
        last = reflex.command
        for k, r in enumerate(raw):
            u = reflex.step(r, position=float(k % 97))
            assert reflex.command >= last and (u is None or u == reflex.command != last)
            last = reflex.command
        # without positions: the command changes only on spike samples, and the first spike
        # from the start or after a quiet reset (10 windows, 160 samples) raises it at once
        reflex = SlipReflex(_event_chain(p0=50.0))
        quiet = 10 * 16
        for k, r in enumerate(raw):
            before = reflex.command
            u = reflex.step(r)
            if u is not None:
                assert y[k] == 1
            first = y[k] and (k < quiet and not any(y[:k]) or k >= quiet and not any(y[k - quiet:k]))
            if first and before < 500.0:
                assert u is not None and u > before, k


def test_event_mpi_worked_example():
    # N = 4, Kp = Ki = 5, p0 = 0. Spikes at k = 1 and k = 2:
    # k=1: s=1, h=1 -> 10;  k=2: s=2, h=2 -> 20;  k=3..4: s=2 -> 20;  k=5: s=1 (k=1 left) -> 15 -> held 20.
    y = [0, 1, 1, 0, 0, 0, 0]
    res = sr.run_chain(_train_to_raw(y, 8 * U), _event_chain(n=4))
    assert res.sample_commands.tolist() == [0.0, 10.0, 20.0, 20.0, 20.0, 20.0, 20.0]
    # the paper's MPI answers once, at the window end (k = 3): PI = 0 + 5*2 + 5*2
    assert sr.run_chain(_train_to_raw(y, 8 * U), filter=False, x0=0.0, threshold=8 * U,
                        n=4).commands.tolist() == [20.0]


def _window_end_trains(seed, n, count=30, windows=60):
    """Spike trains whose spikes all fall on windows' last samples (at most one per window)."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        y = np.zeros(windows * n, dtype=int)
        hit = rng.random(windows) < rng.choice([0.1, 0.4, 0.9])
        y[np.flatnonzero(hit) * n + n - 1] = 1
        yield y.tolist()


@pytest.mark.parametrize("kw", [dict(), dict(n=5, reset_after=2, p0=100.0, kp=2.0, ki=0.5),
                                dict(reset_after=None), dict(n=3, reset_after=1, p0=480.0)])
def test_event_mpi_reduces_to_the_window_mpi_when_spikes_fall_on_window_ends(kw):
    # docs/method.md proves it: with every spike on a window's last sample, the sliding count
    # equals the window's count at window ends and the previous window's between them, the
    # integral is the same sum, the quiet stretches end on the same samples; so at every
    # window end both MPIs give the same command, measured positions included.
    n = kw.get("n", 16)
    for y in _window_end_trains(9, n):
        raw = _train_to_raw(y, 8 * U)
        rng = np.random.default_rng(len(y) + sum(y))
        pos = rng.uniform(0, 500, len(y)).round()
        event = SlipReflex(_event_chain(**kw))
        window = SlipReflex(filter=False, x0=0.0, threshold=8 * U, **kw)
        for k, r in enumerate(raw):
            event.step(r, position=pos[k])
            u = window.step(r, position=pos[k])
            if u is not None:
                assert event.command == u, (k, y)


def test_event_mpi_is_faster_by_the_window_wait():
    # one spike at the window's first sample: the event MPI answers at once, the paper's
    # MPI N - 1 samples later (the wait the event-driven MPI removes: (N - 1) / 2 on average)
    y = [0] * 16 + [1] + [0] * 15
    raw = _train_to_raw(y, 8 * U)
    event = _stream(SlipReflex(_event_chain()), raw)
    paper = [(k, u) for k, u in _stream(SlipReflex(filter=False, x0=0.0, threshold=8 * U), raw) if u > 0]
    assert event[0] == (16, 10.0) and paper[0] == (31, 10.0)


# --- streaming equals batch for every option -----------------------------------------------------

OPTIONS = [dict(acc_reset=33), dict(acc_leak=33.0), dict(dath=True, acc_leak=5.0, acc_reset=16),
           dict(dath=True, dath_floor=hw.ADC_LSB), dict(filter_kind="mean"), dict(filter_kind="mean", mean_samples=5),
           dict(reset_after=None), dict(mpi_mode="event"), dict(dath=True, mpi_mode="event", reset_after=None),
           dict(filter=False, mpi_mode="event", n=3), ReflexParams.preset("authors-gui").to_dict(),
           ReflexParams.preset("dath-event", p0=200.0).to_dict()]


@pytest.mark.parametrize("kw", OPTIONS, ids=lambda kw: ",".join(f"{k}={v}" for k, v in sorted(kw.items())
                                                                 if v != getattr(ReflexParams(), k)))
def test_streaming_equals_batch_for_every_option(kw):
    p = ReflexParams.from_dict(kw)
    for name, raw in _signals(p.fs).items():
        res = sr.run_chain(raw, p)
        reflex = SlipReflex(p)
        got = []
        for k, r in enumerate(raw):
            u = reflex.step(r)
            got.append(reflex.command)
            assert reflex.last_filtered == res.filtered[k] and reflex.last_event == res.events[k]
            assert reflex.last_accumulator == res.accumulator[k] and reflex.last_threshold == res.threshold[k]
            if p.mpi_mode == "window":
                assert (u is not None) == ((k + 1) % p.n == 0)
        assert got == res.sample_commands.tolist(), name
        reflex.reset()
        assert reflex.state.tobytes() == SlipReflex(p).state.tobytes()


@pytest.mark.parametrize("kw", [dict(acc_reset=7), dict(acc_leak=12.5), dict(dath=True, acc_leak=3.0, acc_reset=5),
                                dict(x0=0.0, dath=True, dath_floor=0.003, acc_reset=2)])
def test_encoder_options_match_the_oracle_and_the_stream(kw):
    ok = dict(theta0=kw.get("threshold", 0.008), dath=kw.get("dath", False), x0=kw.get("x0"),
              floor=kw.get("dath_floor", 0.0), acc_reset=kw.get("acc_reset"), leak=kw.get("acc_leak"))
    for name, raw in _signals(hw.DAQ_FS).items():
        x = sr.lowpass(raw)
        ys, thetas = oracle.encode(x, **ok)
        tr = sr.encode_trace(x, **kw)
        assert tr.events.astype(int).tolist() == ys and tr.threshold.tolist() == thetas, name
        enc = sr.EventEncoder(**kw)
        assert [enc.step(v) for v in x] == tr.events.tolist(), name


def test_window_mpi_without_reset_matches_oracle_and_stream():
    rng = np.random.default_rng(5)
    v = rng.poisson(0.3, 300)
    expected = oracle.mpi(v.tolist(), p0=30.0, R=None)
    assert sr.mpi(v, p0=30.0, reset_after=None).tolist() == expected
    c = sr.MPIController(p0=30.0, reset_after=None)
    assert [c.step(x) for x in v] == expected


# --- the authors' hand rule in the simulated closed loop -----------------------------------------

def test_closed_loop_sends_the_middle_finger_its_offset():
    """The middle finger's + 20 is extra closing time at the first command; rises close all alike."""
    from slipreflex.core.hardware import FINGER_SPEED_UNITS_S, TRIPOD, Finger, HandCommand
    from slipreflex.sim.loop import _grip_sender, grip_groups

    class Hand:
        closing_until: dict = {}

        def __init__(self):
            self.sent = []

        def command(self, kind, fingers, value, at=None):
            self.sent.append((kind, tuple(fingers), round(at, 9)))

    hand = Hand()
    reflex = SlipReflex.from_preset("authors-gui", p0=150.0)
    send = _grip_sender(hand, grip_groups(TRIPOD, reflex.finger_offsets), 150.0)
    send(150.0, 0.0)    # no rise: only the middle finger's offset
    send(162.5, 0.1)    # 12.5 units for every finger: 20 ms
    ti, m = (Finger.THUMB, Finger.INDEX), (Finger.MIDDLE,)
    c, s = HandCommand.CLOSE, HandCommand.STOP
    assert hand.sent == [(c, m, 0.0), (s, m, round(20 / FINGER_SPEED_UNITS_S, 9)),
                         (c, ti, 0.1), (s, ti, 0.12), (c, m, 0.1), (s, m, 0.12)]
    assert grip_groups(TRIPOD, SlipReflex(dath=True).finger_offsets) == [(TRIPOD, 0.0)]


def test_registered_variants_build_their_chains():
    from slipreflex import methods

    assert {"authors-gui", "authors-chain", "dath-event", "dath-floor"} <= set(methods.names())
    assert methods.names(paper=True) == ("dath", "fixed", "nmsd", "swt")
    gui = methods.make("authors-gui", p0=150.0)
    assert gui.name == "authors-gui" and gui.params == ReflexParams.preset("authors-gui", p0=150.0,
                                                                           fs=hw.DAQ_FS)
    assert methods.make("dath-event", p0=10.0).params.mpi_mode == "event"
    chain = methods.make("authors-chain", p0=150.0)
    assert chain.name == "authors-chain" and chain.finger_offsets == {}
    assert chain.params == ReflexParams.preset("authors-gui", p0=150.0, slip_finger_offset=0.0)
    leak = methods.make("dath-leak")
    assert leak.name == "dath-leak" and leak.params.acc_leak == pytest.approx(0.1 * hw.DAQ_FS)
    floor = methods.make("dath-floor")
    assert floor.name == "dath-floor" and floor.params.dath_floor == hw.ADC_LSB


def test_detect_preset_authors_gui_runs_the_preset(tmp_path, capsys):
    from pathlib import Path

    from slipreflex.cli import main
    from slipreflex.files.csvfiles import read_slip_csv

    example = Path(__file__).resolve().parents[2] / "examples" / "slip_example.csv"
    assert main(["detect", str(example), "--preset", "authors-gui", "--out", str(tmp_path / "g")]) == 0
    out = capsys.readouterr().out
    t, raw = read_slip_csv(example)
    fs = 1 / np.median(np.diff(t))
    x, ys, v, cmds = oracle.authors_gui(raw.tolist(), fs)
    windows = np.genfromtxt(tmp_path / "g.windows.csv", delimiter=",", names=True)
    assert windows["command"].tolist() == cmds and windows["v"].tolist() == v
    assert "preset authors-gui: acc_reset, filter_kind, reset_after, slip_finger_offset" in out
    assert f"p0 {125:g}" in out
    assert main(["detect", str(example), "--preset", "authors-gui", "--p0", "200", "--out",
                 str(tmp_path / "h")]) == 0
    assert np.genfromtxt(tmp_path / "h.windows.csv", delimiter=",", names=True)["command"][0] >= 200
    assert main(["detect", str(example), "--preset", "authors-gui", "--board"]) == 2
    assert "--preset and --board" in capsys.readouterr().err


def test_a_compiled_caller_runs_the_same_step_as_slipreflex():
    # what a compiled closed loop does: hold (S, P) and call chain_step from its own numba code
    from numba import njit

    from slipreflex.methods.chain._kernels import chain_step
    from slipreflex.methods.chain._layout import init_state, pack_params

    @njit
    def loop(S, P, raw, positions, out):
        for k in range(raw.size):
            out[k] = chain_step(S, P, raw[k], positions[k])

    raw = _signals(hw.DAQ_FS)["rest-then-slip"].copy()
    raw[[5, 400]] = np.nan
    positions = np.where(np.arange(raw.size) % 7 == 0, np.nan, 150.0)
    for p in (ReflexParams(dath=True, p0=100.0), ReflexParams.preset("authors-gui"),
              ReflexParams.preset("dath-event", p0=90.0)):
        P = pack_params(p)
        S = init_state(P)
        out = np.empty(raw.size)
        loop(S, P, raw, positions, out)
        reflex = SlipReflex(p)
        ref = [reflex.step(r, None if np.isnan(q) else q) for r, q in zip(raw, positions)]
        assert [None if np.isnan(u) else u for u in out] == ref
        assert S.tobytes() == reflex.state.tobytes()


@pytest.mark.parametrize("option, value", [
    ("acc_reset", 33), ("acc_leak", 32.0), ("mpi_mode", "event"), ("filter_kind", "mean"),
    ("reset_after", None), ("slip_finger_offset", 20.0)])
def test_the_board_refuses_a_chain_option_it_cannot_reproduce(option, value):
    from slipreflex.methods.board import BoardParams

    with pytest.raises(ParameterError, match=f"^{option}=") as err:
        BoardParams.from_chain(**{option: value})
    assert "\n" not in str(err.value)
    with pytest.raises(ParameterError, match="paper's method only"):
        BoardParams.from_chain(ReflexParams.preset("authors-gui"))


def test_the_board_refuses_a_level_that_would_round_to_zero_and_keeps_a_real_dath_floor():
    from slipreflex.methods.board import BoardParams, volts_to_q16

    for option in ("threshold", "dath_floor"):
        with pytest.raises(ParameterError, match=f"^{option}=1e-09 V is below the board's resolution"):
            BoardParams.from_chain(**{option: 1e-9})
    assert BoardParams.from_chain(dath=True, dath_floor=0.001).dath_floor == volts_to_q16(0.001) > 0
    assert BoardParams.from_chain(dath=True).dath_floor == 0
