"""The fixed-point reflex: C core (firmware/reflex/) and Python twin (slipreflex.methods.board).

Bit-exactness by shared vectors (tests/data/board/vectors.txt) and random signals,
the negative control (a core built with truncation instead of rounding), and the
twin's semantics against the float chain of docs/method.md section 1.
"""

from __future__ import annotations

import importlib.util
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from slipreflex import encode_trace, lowpass, mpi, run_chain
from slipreflex.core import hardware
from slipreflex.core.errors import DataError, ParameterError
from slipreflex.core.interfaces import Reflex
from slipreflex.methods import board

ROOT = Path(__file__).resolve().parents[2]
FIRMWARE = ROOT / "firmware"
VECTORS = ROOT / "tests" / "data" / "board" / "vectors.txt"


def _load(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


gen = _load("slipreflex_fw_gen_board_vectors", FIRMWARE / "test" / "gen_board_vectors.py")


@pytest.fixture(scope="module")
def host_build(tmp_path_factory, tools):
    """The two host builds of the core's vector checker (right and wrong rounding)."""
    tools("make", "cc")
    out = tmp_path_factory.mktemp("board") / "build"
    targets = [f"{out}/test_board_vectors", f"{out}/test_board_vectors-wrong-rounding"]
    proc = subprocess.run(["make", "-C", str(FIRMWARE), f"BUILD={out}", *targets],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "-std=c99 -pedantic" in proc.stdout and "-Werror" in proc.stdout
    return out


def _run_c(exe: Path, vectors: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(exe), str(vectors)], capture_output=True, text=True)


def _read_vectors(path: Path) -> list[dict]:
    lines = [ln for ln in path.read_text().splitlines() if ln and not ln.startswith("#")]
    out = []
    for i in range(0, len(lines), 7):
        rec = {ln[0]: ln[2:] for ln in lines[i:i + 7]}
        assert "".join(ln[0] for ln in lines[i:i + 7]) == "VPIQXEW"
        out.append(rec)
    return out


def _ints(field: str) -> list[int]:
    return [] if field == "-" else [int(v) for v in field.split(",")]


def _params(field: str) -> board.BoardParams:
    kv = dict(item.split("=") for item in field.split(" "))
    args = {k: (None if v == "-" else int(v)) for k, v in kv.items()}
    args["filter"], args["dath"] = bool(args["filter"]), bool(args["dath"])
    return board.BoardParams(**args)


# -- the shared vectors ------------------------------------------------------------------

def test_vectors_file_is_what_the_generator_writes(tmp_path):
    """The committed file is current: regenerating it from the twin changes nothing."""
    fresh = tmp_path / "v.txt"
    with fresh.open("w") as f:
        gen.main(f)
    assert fresh.read_text() == VECTORS.read_text()


def test_twin_reproduces_every_vector():
    recs = _read_vectors(VECTORS)
    assert len(recs) >= 15
    names = set()
    for rec in recs:
        names.add(rec["V"])
        p = _params(rec["P"])
        q = rec["Q"]
        pos = None if q == "-" else [None if v == "-" else int(v) for v in q.split(",")]
        res = board.run_board_chain(_ints(rec["I"]), p, positions=pos)
        assert res.filtered.tolist() == _ints(rec["X"]), rec["V"]
        ev = "".join("f" if f else "1" if e else "0" for e, f in zip(res.events, res.faults))
        assert (ev or "-") == rec["E"], rec["V"]
        w = [] if rec["W"] == "-" else [tuple(map(int, x.split(":"))) for x in rec["W"].split(",")]
        assert list(zip(res.counts.tolist(), res.commands.tolist())) == w, rec["V"]
    # The vectors reach the corners the proofs talk about.
    assert {"rails_square_dath", "faults_range_and_stuck", "paper_x0_zero",
            "positions_at_reset", "noisy_dath_saturates"} <= names
    text = VECTORS.read_text()
    assert ":500" in text and "f" in "".join(r["E"] for r in recs)


@pytest.mark.slow
def test_c_core_reproduces_every_vector(host_build):
    proc = _run_c(host_build / "test_board_vectors", VECTORS)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "17 vectors, 11880 samples checked, 0 failures" in proc.stdout, proc.stdout


def test_negative_control_wrong_rounding_is_rejected(host_build):
    """The core built with truncation instead of round-half-up fails the same checker."""
    proc = _run_c(host_build / "test_board_vectors-wrong-rounding", VECTORS)
    assert proc.returncode == 1, proc.stdout
    fails = [ln for ln in proc.stdout.splitlines() if ln.startswith("FAIL")]
    assert len(fails) >= 10 and all(" x " in ln for ln in fails), proc.stdout


@pytest.mark.parametrize("line, mutate", [("X", "x"), ("E", "event"), ("W", "command")])
def test_c_checker_catches_a_wrong_vector(host_build, tmp_path, line, mutate):
    lines = VECTORS.read_text().splitlines()
    i = next(i for i, ln in enumerate(lines) if ln == "V walk_dath") + "VPIQXEW".index(line)
    if mutate == "x":
        vals = lines[i][2:].split(",")
        vals[700] = str(int(vals[700]) + 1)
        lines[i] = "X " + ",".join(vals)
    elif mutate == "event":
        k = lines[i].index("1", 500)
        lines[i] = lines[i][:k] + "0" + lines[i][k + 1:]
    else:
        items = lines[i][2:].split(",")
        v, c = items[-1].split(":")
        items[-1] = f"{v}:{int(c) + 1}"
        lines[i] = "W " + ",".join(items)
    bad = tmp_path / "v.txt"
    bad.write_text("\n".join(lines) + "\n")
    proc = _run_c(host_build / "test_board_vectors", bad)
    assert proc.returncode == 1 and "FAIL walk_dath" in proc.stdout, proc.stdout


def test_c_core_equals_twin_on_random_signals(host_build, tmp_path):
    """Property test: 60 random signals and parameter sets, one C run."""
    rng = np.random.default_rng(7)
    path = tmp_path / "random.txt"
    with path.open("w") as f:
        for i in range(60):
            k = int(rng.integers(0, 1500))
            kind = i % 3
            if kind == 0:      # random walk
                adc = np.round(rng.integers(0, 1024) + np.cumsum(rng.normal(0, rng.uniform(0.2, 6), k)))
            elif kind == 1:    # full-range noise
                adc = rng.integers(0, 1024, k)
            else:              # slow sine + noise, occasionally at the rails
                adc = 512 + 600 * np.sin(np.arange(k) / rng.uniform(3, 40)) + rng.normal(0, 2, k)
            adc = np.clip(adc, 0, 1023).astype(int)
            lo = int(rng.integers(-100, 200))
            p = board.BoardParams.from_chain(
                fs=float(rng.uniform(200, 1000)), cutoff=float(rng.uniform(2, 60)),
                filter=bool(rng.random() < 0.85), threshold=float(rng.uniform(0, 0.05)),
                dath=bool(rng.random() < 0.6), dath_samples=int(rng.integers(1, 40)),
                dath_floor=float(rng.choice([0.0, rng.uniform(0, 0.03)])),
                x0=None if rng.random() < 0.7 else float(rng.uniform(0, 4.99)),
                n=int(rng.integers(1, 40)), p0=int(rng.integers(-50, 600)),
                kp=int(rng.integers(0, 256)), ki=int(rng.integers(0, 256)),
                reset_after=int(rng.integers(1, 15)), lo=float(lo), hi=float(lo + rng.integers(0, 700)),
                adc_min=int(rng.integers(0, 50)), adc_max=int(rng.integers(970, 1024)),
                stuck_after=int(rng.choice([0, rng.integers(1, 30)])))
            nwin = k // p.n
            pos = [None if rng.random() < 0.5 else int(rng.integers(-100, 600)) for _ in range(nwin)]
            f.write(gen.vector(f"random_{i}", p, adc, pos))
    proc = _run_c(host_build / "test_board_vectors", path)
    assert proc.returncode == 0, proc.stdout[-2000:]
    assert "60 vectors" in proc.stdout and " 0 failures" in proc.stdout


# -- the twin against the float chain (docs/method.md section 1) --------------------------------------------

def test_documented_constants():
    p = board.BoardParams.from_chain()
    assert p.theta0 == 107374 == round(0.008 / hardware.ADC_LSB * 2**16)
    assert abs(p.theta0 / 2**16 * hardware.ADC_LSB - 0.008) < 1e-7
    g, a1, a2 = p.g, p.a1, p.a2
    assert 4 * g == 2**board.COEF_Q + a1 + a2          # DC gain exactly one
    from slipreflex.methods.chain.filters import _design
    sos, _ = _design(hardware.DAQ_FS, 10.0)
    assert abs(a1 / 2**24 - sos[0, 4]) <= 0.5 / 2**24
    assert abs(a2 / 2**24 - sos[0, 5]) <= 2.5 / 2**24
    assert abs(g / 2**24 - sos[0, 0]) <= 0.5 / 2**24


def _l1(b, a, n=4000):
    from scipy.signal import lfilter
    imp = np.zeros(n)
    imp[0] = 1.0
    return float(np.abs(lfilter(b, a, imp)).sum())


def test_overflow_bounds_hold_for_10_bit_input():
    """docs/firmware.md's proof, with the numbers: every intermediate fits its C type."""
    p = board.BoardParams.from_chain()
    one = 2.0**24
    b = np.array([p.g, 2 * p.g, p.g]) / one
    a = np.array([1.0, p.a1 / one, p.a2 / one])
    gain, noise = _l1(b, a), _l1([1.0], a)
    assert gain < 1.1 and noise < 36
    # |y - 511.5| <= gain * 511.5 + noise * 0.5 LSB(Q16) -> y in Q16:
    y_max = (511.5 + gain * 511.5) * 2**16 + noise * 0.5
    y_min = (511.5 - gain * 511.5) * 2**16 - noise * 0.5
    assert y_max < 1071 * 2**16 and y_min > -48 * 2**16
    span = y_max - y_min                          # bounds |d| and |acc| (telescoping)
    assert span < 2**27 < 2**31
    acc64 = p.g * 4092 * 2**16 + abs(p.a1) * y_max + abs(p.a2) * y_max
    assert acc64 < 2**53 < 2**63
    # The worst inputs reach neither bound: full-scale square waves and noise.
    rng = np.random.default_rng(3)
    for adc in (np.tile(np.r_[np.zeros(9), np.full(9, 1023)], 60), rng.integers(0, 1024, 5000)):
        x = board.run_board_chain(adc.astype(int)).filtered
        assert y_min <= x.min() and x.max() <= y_max


def test_filter_is_close_to_the_float_filter():
    rng = np.random.default_rng(11)
    adc = np.clip(np.round(300 + np.cumsum(rng.normal(0, 3, 20000))), 0, 1023).astype(int)
    x = board.run_board_chain(adc).filtered / 2**16
    xf = lowpass(adc.astype(float), fs=hardware.DAQ_FS, cutoff=10.0)
    assert np.max(np.abs(x - xf)) < 1e-3          # counts; about 1.3e-4 measured


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(0, 1023), min_size=1, max_size=300), st.booleans(),
       st.integers(0, 60_000), st.integers(1, 20))
def test_encoder_without_filter_is_the_spec_encoder(adc, dath, theta, d):
    """Filter off: x = adc << 16 are exact in float64, so the float encoder (docs/method.md section 1.2)
    on them must give the same events as the board's integer encoder."""
    res = board.run_board_chain(adc, filter=False, dath=dath, dath_samples=d,
                                threshold=theta / 2**16 * hardware.ADC_LSB)
    assert res.params.theta0 == theta
    x = np.array(adc, dtype=float) * 2**16
    ref = encode_trace(x, threshold=float(theta), dath=dath, dath_samples=d)
    assert res.events.tolist() == ref.events.tolist()


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(0, 1023), min_size=16, max_size=600), st.integers(0, 500),
       st.integers(0, 20), st.integers(0, 20), st.integers(1, 12))
def test_mpi_is_exact(adc, p0, kp, ki, reset_after):
    """The integer MPI equals the float MPI (docs/method.md section 1.4) on the same counts."""
    res = board.run_board_chain(adc, dath=True, p0=p0, kp=kp, ki=ki, reset_after=reset_after)
    ref = mpi(res.counts.astype(float), p0=p0, kp=kp, ki=ki, reset_after=reset_after)
    assert res.commands.tolist() == ref.tolist()
    assert np.all(np.diff(res.commands) >= 0)


def test_integral_saturation_is_output_neutral():
    c = board.BoardChain(board.BoardParams.from_chain(ki=1, p0=0))
    c.h = board.H_MAX - 3
    c._mpi(16, None)
    assert c.h == board.H_MAX and c.command == hardware.FINGER_MAX


@pytest.mark.slow
def test_agrees_with_float_chain_on_quantised_signals():
    rng = np.random.default_rng(5)
    for dath in (False, True):
        adc = np.clip(np.round(400 + np.cumsum(rng.normal(0, 2, 30000))), 0, 1023).astype(int)
        b = board.run_board_chain(adc, dath=dath)
        f = run_chain(adc * hardware.ADC_LSB, fs=hardware.DAQ_FS, dath=dath)
        assert np.mean(b.events == f.events) > 0.998
        assert b.events.sum() == pytest.approx(f.events.sum(), rel=0.01)


def test_constant_input_gives_nothing_and_start_is_steady():
    res = board.run_board_chain([777] * 100, dath=True, p0=42)
    assert not res.events.any() and set(res.filtered.tolist()) == {777 << 16}
    assert res.commands.tolist() == [42] * 6


def test_fault_skips_and_restarts_without_a_spike():
    adc = [300] * 20 + [0] * 5 + [900] * 40
    res = board.run_board_chain(adc, adc_min=10)
    assert res.faults.tolist() == [False] * 20 + [True] * 5 + [False] * 40
    # The jump from 300 to 900 across the fault is not a slip: the chain restarts there.
    assert not res.events.any() and res.filtered[-1] == 900 << 16
    stuck = board.run_board_chain([300, 301] * 5 + [305] * 12, stuck_after=4)
    assert stuck.faults.tolist() == [False] * 14 + [True] * 8


# -- the Reflex protocol ------------------------------------------------------------------

def test_board_reflex_is_a_reflex_and_quantises_like_the_adc():
    r = board.BoardReflex(dath=True, p0=100)
    assert isinstance(r, Reflex) and r.name == "dath-board" and r.input_kind == "slip"
    assert board.BoardReflex().name == "fixed-board"
    rng = np.random.default_rng(2)
    adc = np.clip(np.round(300 + np.cumsum(rng.normal(0, 2, 800))), 0, 1023).astype(int)
    volts = adc * hardware.ADC_LSB                 # what the simulated sensor outputs
    cmds = [u for u in (r.step(v) for v in volts) if u is not None]
    assert cmds == board.run_board_chain(adc, dath=True, p0=100).commands.astype(float).tolist()
    r.reset()
    assert r.step(float("nan")) is None and r.chain.fault
    assert [board.adc_counts(v) for v in (0.0, hardware.ADC_LSB * 0.999, 4.9999, 5.5)] == \
        [0, 0, 1023, 1023]


def test_bad_input_is_named():
    with pytest.raises(DataError, match=r"adc_counts\[2\] is 1024"):
        board.run_board_chain([1, 2, 1024])
    with pytest.raises(DataError, match=r"adc_counts\[1\] is 2.5"):
        board.run_board_chain(np.array([1.0, 2.5]))
    with pytest.raises(ParameterError, match="ki must be a whole number"):
        board.BoardParams.from_chain(ki=0.5)
    with pytest.raises(ParameterError, match="n must be an integer in 1..255"):
        board.BoardParams.from_chain(n=300)
    with pytest.raises(DataError, match="positions has 1 values"):
        board.run_board_chain([0] * 32, positions=[3])
    assert math.isfinite(board.volts_to_q16(0.0))


@pytest.mark.slow
def test_board_methods_run_in_reproduce_beside_the_float_chain():
    from slipreflex import methods
    from slipreflex.reproduce.experiments import ReproduceConfig, run_reproduce

    assert {"dath-board", "fixed-board"} <= set(methods.names())
    assert "dath-board" not in methods.names(paper=True)
    r = methods.make("dath-board", p0=123.6)
    assert isinstance(r, board.BoardReflex) and r.params.p0 == 124 and r.params.dath
    cfg = ReproduceConfig(trials=1, bottles=("TX",), methods=("dath", "dath-board"),
                          experiments=("drop",))
    res = run_reproduce(cfg, jobs=1, progress=False, plots=True)
    by = {row["method"]: row for row in res.rows}
    assert set(by) == {"dath", "dath-board"}
    assert by["dath-board"]["n_increases"] > 0 and math.isfinite(by["dath-board"]["response_ms"])


# -- the standalone board's hand rule: grip only added (BoardHand, twin of hand2560) --------

CLOSE, STOP = hardware.HandCommand.CLOSE, hardware.HandCommand.STOP


def _hand_run(steps, p0: int = 100):
    """Feed BoardHand (window, fault, command) per sample; return [(sample, packet)]."""
    h = board.BoardHand(board.BoardParams.firmware(p0=p0))
    return [(k, pk) for k, s in enumerate(steps) if (pk := h.step(*s)) is not None], h


def test_grip_time_is_the_documented_closing_speed_in_samples():
    per_unit, per_sample = board.grip_time_ratio()
    assert (per_unit, per_sample) == (board.GRIP_PER_UNIT, board.GRIP_PER_SAMPLE) == (8, 15)
    assert per_unit / per_sample == pytest.approx(1 / (hardware.FINGER_SPEED_UNITS_S * hardware.DAQ_PERIOD_S))
    assert board.grip_time_ratio(500.0, 0.004) == (1, 2)
    assert board.HAND_PWM == hardware.PWM_MAX == 297
    with pytest.raises(ParameterError, match="must be > 0"):
        board.grip_time_ratio(0.0)


@pytest.mark.parametrize("g", [1, 2, 7, 14, 15, 16, 30, 90, 187, 400])
def test_one_rise_closes_for_its_time_rounded_up_to_whole_samples(g):
    steps = [(True, False, 100 + g)] + [(False, False, 100 + g)] * 300
    packets, h = _hand_run(steps)
    n = math.ceil(8 * g / 15)
    assert packets == [(0, CLOSE), (n, STOP)]
    t, exact = n * hardware.DAQ_PERIOD_S, g / hardware.FINGER_SPEED_UNITS_S
    assert exact <= t < exact + hardware.DAQ_PERIOD_S                  # never short, < 1 sample long
    assert h.level == 100 + g and h.left == 0 and not h.closing


def test_a_rise_while_closing_makes_the_closing_longer():
    # 30 units at sample 0 (16 samples), 20 more at sample 15 while closing: one CLOSE,
    # STOP after ceil(8 x 50 / 15) = 27 samples, the partial samples carried exactly.
    steps = [(True, False, 130)] + [(False, False, 130)] * 14 + [(True, False, 150)] \
        + [(False, False, 150)] * 40
    packets, _ = _hand_run(steps)
    assert packets == [(0, CLOSE), (27, STOP)]
    # A command that does not rise (or falls: the MPI cannot, but the rule ignores it) adds nothing.
    steps = [(True, False, 130), (True, False, 120), (True, False, 130)] + [(False, False, 130)] * 40
    assert _hand_run(steps)[0] == [(0, CLOSE), (16, STOP)]


def test_a_fault_stops_the_closing_and_the_rest_is_owed():
    g = 90                                                  # 48 samples of closing
    steps = [(True, False, 100 + g)] + [(False, False, 100 + g)] * 9 \
        + [(False, True, 100 + g)] * 5 + [(False, False, 100 + g)] * 100
    packets, _ = _hand_run(steps)
    # STOP at the fault's first reading (10), nothing while it lasts, CLOSE at the next
    # good reading (15), STOP when the 48 samples are done: 10 before, 38 after.
    assert packets == [(0, CLOSE), (10, STOP), (15, CLOSE), (15 + 38, STOP)]


def test_a_fault_holds_even_when_not_closing_and_a_rise_in_it_waits():
    steps = [(False, False, 100)] * 3 + [(False, True, 100)] * 3 + [(True, True, 115)] \
        + [(False, True, 115)] * 2 + [(False, False, 115)] * 20
    packets, _ = _hand_run(steps)
    assert packets == [(3, STOP), (9, CLOSE), (9 + 8, STOP)]     # 15 units: ceil(120/15) = 8


def test_p0_is_bookkeeping_only_for_the_hand():
    adc = [300] * 32 + [300, 320] * 32 + [300] * 200
    runs = {p0: board.board_hand(board.run_board_chain(adc, board.BoardParams.firmware(p0=p0)))
            for p0 in (0, 100, 148, 400)}
    assert runs[0].packets == runs[100].packets == runs[148].packets        # same grip, same time
    assert [c for _, c in runs[0].packets] == [STOP, CLOSE, STOP, CLOSE, STOP]
    assert runs[0].grip == runs[148].grip == 140
    # From 400 the MPI reaches its ceiling (500) after 100 units: the same closings until then.
    assert runs[400].grip == 100 and runs[400].packets[:4] == runs[0].packets[:4]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.booleans(), st.booleans(), st.integers(0, 60)), min_size=1, max_size=400),
       st.integers(-50, 550))
def test_hand_rule_never_opens_never_short_at_most_a_sample_long(steps, p0):
    """Any sequence of windows, faults and rises: only CLOSE and STOP, CLOSE only from
    stopped, and the closing time sums to the grip's time rounded up per closing."""
    h = board.BoardHand(board.BoardParams.firmware(p0=p0))
    cmd, closing_samples, stops, last = h.level, 0, 0, None
    for window, fault, rise in steps:
        was_closing = h.closing
        if window:
            cmd = min(cmd + rise, 500)
        pk = h.step(window, fault, cmd)
        closing_samples += was_closing
        assert pk in (None, CLOSE, STOP)
        if pk is CLOSE:
            assert last in (None, STOP) and not fault and not was_closing
        if pk is STOP and was_closing:
            stops += 1
        last = pk if pk is not None else last
        assert h.closing == (h.left > 0 and not fault)
    grip = h.level - min(max(p0, 0), 500)
    # Closing time spent minus the grip's time plus what is still owed: the overshoots a
    # STOP dropped, each less than one sample (15), so never short.
    spent = 15 * closing_samples - 8 * grip + h.left
    assert 0 <= spent and (spent < 15 * stops or spent == 0)
