"""The adaptive stepping against the fixed-step reference (docs/simulator.md, "Time step").

The fixed step is a parameter (``Rig(stepping="fixed")``, or ``SLIPREFLEX_STEPPING=fixed``); the
adaptive kernel takes coarse steps while nothing needs the fine one and keeps every sample on its
clock. These tests compare both on the same trials, never on time.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from scripts.research.stepping_rows import ROW_TOLERANCE  # the declared tolerance of a trial's row

from slipreflex.core import hardware as hw
from slipreflex.core.errors import ParameterError
from slipreflex.sim import PAPER_DROP, PAPER_POUR, Rig, simulate_open_loop
from slipreflex.sim import kernel as K
from slipreflex.sim.rig import STEPPING_ENV, default_stepping, stepping


def _held_pour(kind: str, seconds: float, fs: float | None = None):
    rig = Rig("TR", seed=3, stepping=kind)
    g = rig.grasp()
    rig.hand.set_positions({f: g.positions[f] + 40 for f in hw.TRIPOD})
    rig.perturb(PAPER_POUR, at=rig.t + 0.2)
    s0, k0 = rig.step_index, rig.steps_taken
    tr = simulate_open_loop(rig, seconds, tactile_fs=fs)
    return rig, tr, (rig.step_index - s0) / (rig.steps_taken - k0)


def test_the_fixed_step_reference_is_a_parameter_and_the_default_is_adaptive(monkeypatch):
    monkeypatch.delenv(STEPPING_ENV, raising=False)
    assert default_stepping() == "adaptive"
    assert Rig("TR").stepping == "adaptive"
    fixed = Rig("TR", stepping="fixed")
    assert fixed.stepping == "fixed" and fixed._P[K.P_COARSE] == 1
    # omega h <= 1 for the held bottle's stiffest mode: 16 fine steps of 0.1 ms on the paper's bottles
    assert Rig("TR")._P[K.P_COARSE] == Rig("TR").coarse_steps() == 16
    with stepping("fixed"):
        assert os.environ[STEPPING_ENV] == "fixed" and Rig("DK").stepping == "fixed"
    assert STEPPING_ENV not in os.environ


def test_an_unknown_stepping_is_refused_before_anything_runs(monkeypatch):
    with pytest.raises(ParameterError, match="stepping: unknown 'coarse'"):
        Rig("TR", stepping="coarse")
    with pytest.raises(ParameterError, match="unknown"):
        stepping("half")
    monkeypatch.setenv(STEPPING_ENV, "sometimes")
    with pytest.raises(ParameterError, match=f"{STEPPING_ENV}='sometimes'"):
        Rig("TR")


def test_with_fixed_steps_every_step_is_one_dt():
    rig = Rig("TX", seed=2, stepping="fixed")
    rig.grasp()
    rig.advance(0.5)
    assert rig.steps_taken == rig.step_index


@pytest.mark.slow
def test_a_held_pour_takes_coarse_steps_and_keeps_its_samples_on_their_clocks():
    ref_rig, ref, ref_ratio = _held_pour("fixed", 4.0, fs=hw.NMSD_FS)
    rig, tr, ratio = _held_pour("adaptive", 4.0, fs=hw.NMSD_FS)
    assert ref_ratio == 1.0 and ratio > 5.0           # ~10 fine steps per step (a count, not a time)
    assert np.array_equal(ref.daq.t, tr.daq.t)
    assert np.array_equal(ref.tactile_t, tr.tactile_t)
    # the same ADC codes (a coarse step moves the bottle by well under a code's worth of texture)
    same = ref.daq.volts == tr.daq.volts
    assert np.mean(same) >= 0.995 and np.max(np.abs(ref.daq.volts - tr.daq.volts)) <= hw.ADC_LSB + 1e-12
    assert np.max(np.abs(ref.daq.displacement - tr.daq.displacement)) < 10e-6
    assert np.array_equal(ref.daq.flow_pulses, tr.daq.flow_pulses)
    assert np.max(np.abs(ref.daq.load_mass - tr.daq.load_mass)) < 1e-12
    assert np.max(np.abs(ref.tactile - tr.tactile)) < 0.01     # N per taxel; the noise is 5 mN
    assert list(ref_rig.onsets) == list(rig.onsets)


def test_a_drop_keeps_its_onset_slide_and_tilt():
    out = {}
    for kind in ("fixed", "adaptive"):
        rig = Rig("TX", seed=4, stepping=kind)
        rig.grasp()
        rig.perturb(PAPER_DROP, at=rig.t + 0.05)
        tr = simulate_open_loop(rig, 0.6)
        out[kind] = (rig.onsets, rig.displacement, rig.tilt, tr.daq.volts)
    (on_f, x_f, th_f, v_f), (on_a, x_a, th_a, v_a) = out["fixed"], out["adaptive"]
    assert len(on_f) == len(on_a) and np.allclose(on_f, on_a, atol=1e-3)
    assert math.isclose(x_a, x_f, rel_tol=0.01) and math.isclose(th_a, th_f, rel_tol=0.02, abs_tol=1e-4)
    # the ringing's tail after the impact, under 2.5 um, is taken in coarse steps: a code apart here and there
    assert np.mean(v_f == v_a) >= 0.97 and np.max(np.abs(v_f - v_a)) <= hw.ADC_LSB + 1e-12


def test_samples_stay_on_their_clocks_however_the_run_is_cut():
    whole = Rig("DK", seed=5)
    cut = Rig("DK", seed=5)
    for rig in (whole, cut):
        rig.grasp()
        rig.perturb(PAPER_POUR, at=rig.t + 0.1)
    t_end = whole.t + 1.5
    a = whole.advance_block(t_end)
    parts = []
    while cut.t < t_end - 1e-9:
        parts.append(cut.advance_block(min(t_end, cut.t + 0.0137)))
    t = np.concatenate([p.t for p in parts])
    volts = np.concatenate([p.volts for p in parts])
    assert np.array_equal(a.t, t)
    assert np.mean(a.volts == volts) >= 0.995 and np.max(np.abs(a.volts - volts)) <= hw.ADC_LSB + 1e-12


def _rows_by_key(rows):
    return {(r["experiment"], r["bottle"], r["method"], r["trial"], r["event"]): r for r in rows}


@pytest.mark.slow
def test_adaptive_steps_keep_every_trial_row_and_every_claim_class():
    """The drop and the pour on every bottle with every method of the default grid, both kernels: the same
    slips and fall-outs, each row within :data:`ROW_TOLERANCE`, the same class of every claim; the scan
    does not step the physics (it reads the surface along a prescribed path) and is the same by
    construction."""
    from slipreflex.analysis.claims import judge
    from slipreflex.reproduce.experiments import ReproduceConfig, calibrate, run_trial

    config = ReproduceConfig(trials=2)
    rows = {}
    for kind in ("fixed", "adaptive"):
        with stepping(kind):
            thresholds = calibrate(config)
            rows[kind] = [dict(r) for cell in config.cells() for r in run_trial(cell, config, thresholds)[0]]
    ref, new = _rows_by_key(rows["fixed"]), _rows_by_key(rows["adaptive"])
    assert ref.keys() == new.keys()            # the same slips, event by event
    for key, r in ref.items():
        n = new[key]
        for field in ("n_events", "success", "fell_out", "n_true_slips"):
            assert r[field] == n[field], (key, field)
        for field, tol in ROW_TOLERANCE.items():
            a, b = r[field], n[field]
            assert (math.isnan(a) and math.isnan(b)) or abs(a - b) <= tol, (key, field, a, b)
    assert [(c.number, c.verdict) for c in judge(rows["fixed"])] == \
        [(c.number, c.verdict) for c in judge(rows["adaptive"])]


def test_the_speed_table_reads_both_kernels_and_their_ratio_from_the_benchmark():

    import scripts.docs.speed_table as speed_table
    lines = [f"{m:14s} {e:10s} {d:6.1f}   {500:8.0f} ({300:6.0f})   {1500:8.0f} ({900:6.0f})   {3.0:5.2f}x"
             for m in ("dath", "fixed", "nmsd", "swt") for e, d in (("drop", 2.5), ("pour", 32.5))]
    for what in ("", ", 260 Hz tactile", ", 380 Hz tactile"):
        lines.append(f"held pour{what}: open loop (physics + sensors alone) fixed   400 adaptive  2000 (5.00x, pairs "
                     f"4.10-5.20) sim-s per CPU-s; closed by a compiled reflex that never commands fixed   410 "
                     f"adaptive  1800 (4.39x, pairs 3.90-4.80)")
    row = speed_table.closed_loop("\n".join(lines))
    assert row.startswith("adaptive kernel (ratio to the fixed-step reference in the same run): pour 1500 (3.00x)")
    assert "never commands: 1800 (4.39x, 3.90-4.80x over the pairs; fixed 410)" in row
    with pytest.raises(speed_table.Missing, match="bench_closed_loop"):
        speed_table.closed_loop("\n".join(lines[1:]))


def test_the_closed_loop_benchmark_s_ratio_is_the_median_of_adjacent_pairs():
    """Each pair's two runs share one load: a load that halves both kernels' rates for three pairs leaves
    every pair's ratio, and so their median, range and the reported ratio, where a quiet machine puts it."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_closed_loop.py"
    spec = importlib.util.spec_from_file_location("bench_closed_loop", path)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    calls: list[str] = []
    slow = iter([1.0] * 4 + [2.0] * 6 + [1.0] * 4)   # pairs 1-2 and 6-7 on a quiet machine, 3-5 on a busy one

    def run(*, stepping):
        calls.append(stepping)
        cpu = (0.1 if stepping == "fixed" else 0.02) * (next(slow, 1.0) if len(calls) > 2 else 1.0)
        return 40.0, cpu, cpu
    out = bench.paired_rates(run, 7)
    assert calls[2:6] == ["fixed", "adaptive", "adaptive", "fixed"]   # the order alternates
    assert out["ratio"] == pytest.approx((5.0, 5.0, 5.0))
    assert (out["fixed"][0], out["adaptive"][0]) == pytest.approx((400.0, 2000.0))   # 4 quiet pairs of 7


def test_a_study_runs_every_plant_with_its_own_stepping_and_fingerprints_it(monkeypatch):
    from slipreflex.study import StudyConfig

    monkeypatch.setenv(STEPPING_ENV, "fixed")
    fixed = StudyConfig(plants=2)
    monkeypatch.delenv(STEPPING_ENV)
    adaptive = StudyConfig(plants=2)
    assert (fixed.stepping, adaptive.stepping) == ("fixed", "adaptive")
    assert fixed.fingerprint() != adaptive.fingerprint()
    with pytest.raises(ParameterError, match="stepping: unknown 'half'"):
        StudyConfig(plants=2, stepping="half")


def test_the_tabled_step_factors_are_the_ones_the_kernel_would_compute():
    from numba import njit

    @njit
    def computed(alpha, heal, dt, m):
        h = m * dt
        return -np.expm1(m * np.log1p(-alpha)), np.exp(-h / heal)

    rig = Rig("TR")
    for alpha, heal, dt in ((rig._P[K.P_ACC_ALPHA], rig._P[K.P_C0 + 2 * K.PC_SIZE + K.PC_HEAL], rig.physics.dt),
                            (0.05, 0.3, 1e-4), (0.3, 2.0, 5e-5), (1e-3, 0.07, 2e-4)):
        P = np.zeros(K.P_SIZE)
        P[K.P_DT], P[K.P_ACC_ALPHA] = dt, alpha
        for c in range(3):
            P[K.P_C0 + c * K.PC_SIZE + K.PC_HEAL] = heal * (c + 1)
        K.fill_step_tables(P)
        assert P[K.P_ACC_LQ] == np.log1p(-alpha)
        for m in range(2, K.ALPHA_STEPS + 1):   # bit for bit, not approximately
            assert P[K.P_ACC_ALPHA_H + m] == computed(alpha, heal, dt, m)[0]
            for c in range(3):
                tabled = P[K.P_HEAL_DECAY_H + c * (K.ALPHA_STEPS + 1) + m]
                assert tabled == computed(alpha, heal * (c + 1), dt, m)[1]
    assert rig._P[K.P_ACC_ALPHA_H + 1] == rig._P[K.P_ACC_ALPHA]   # one fine step: the filter's own factor


def test_a_filling_bottle_takes_longer_coarse_steps_with_rate_state_contacts_only():
    import dataclasses

    from slipreflex.sim import BOTTLES

    coulomb = dataclasses.replace(BOTTLES["TR"], friction_law="coulomb", cuff_friction_law="coulomb")
    caps = {}
    for bottle in (BOTTLES["TR"], coulomb):
        rig = Rig(bottle, seed=3, stepping="adaptive")
        g = rig.grasp()
        rig.hand.set_positions({f: g.positions[f] + 40 for f in hw.TRIPOD})
        rig.perturb(PAPER_POUR, at=rig.t + 0.2)
        rig.advance(2.0)
        early = rig.steps_taken
        rig.advance(1.0)
        early = rig.steps_taken - early
        rig.advance(8.0)
        late = rig.steps_taken
        rig.advance(1.0)
        caps[bottle.friction_law] = (early, rig.steps_taken - late, int(rig.kernel_arrays().C[K.C_CAP]))
    coarse = Rig("TR").coarse_steps()
    early, late, cap = caps["rate-state"]
    # with ~150 ml in it the bottle's stiffest mode is slow enough for one step per DAQ row
    assert cap == int(round(3e-3 / 1e-4)) > coarse and late < early
    assert late <= hw.DAQ_FS * 1.05
    assert caps["coulomb"][2] in (0, coarse)


def test_the_coarse_step_bound_grows_with_the_fill_from_the_empty_bottles():
    P = Rig("TR").kernel_arrays().P
    coarse = int(P[K.P_COARSE])
    caps = [int(K.mass_cap(mw, 0.3 * mw, P, coarse)) for mw in np.linspace(0.0, 0.5, 51)]
    assert caps[0] == coarse and caps == sorted(caps) and caps[-1] == int(P[K.P_COARSE_MAX]) == 30
