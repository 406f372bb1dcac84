"""Streaming objects, batch functions and the specification oracle agree bit for bit."""

import itertools

import numpy as np
import pytest

import slipreflex as sr
import spec_oracle as oracle

LSB = 5.0 / 1024


def _signals():
    rng = np.random.default_rng(20261121)
    sigs = {
        "empty": np.array([]),
        "one": np.array([0.42]),
        "two": np.array([0.42, 0.44]),
        "constant": np.full(100, 3.33),
        "step": np.r_[np.full(50, 0.4), np.full(80, 3.3)],
        "down-step": np.r_[np.full(40, 3.3), np.full(60, 0.35)],
        "ramp": np.linspace(0.3, 0.6, 333),
        "lsb-noise": 0.40 + LSB * rng.integers(-2, 3, 700),
        "quantized-walk": np.round((0.4 + np.cumsum(rng.normal(0, 0.004, 900))) / LSB) * LSB,
        "sine-burst": np.r_[np.full(100, 0.4), 0.4 + 0.03 * np.sin(np.arange(200) / 2.5), np.full(100, 0.4)],
        "spikes": np.where(rng.random(400) < 0.05, 0.9, 0.4),
        "alternating": np.tile([0.4, 0.4 + 2 * LSB], 200),
        "exact-threshold-steps": np.cumsum(np.full(64, 0.008)),
        "big": rng.normal(1.0, 1.0, 1000),
    }
    for i in range(25):
        k = int(rng.integers(0, 600))
        sigs[f"random-{i}"] = rng.normal(rng.uniform(0, 3.5), rng.uniform(1e-4, 0.05), k).cumsum() * 0.1
    return sigs


SIGNALS = _signals()
ENCODERS = [
    dict(),
    dict(dath=True),
    dict(dath=True, x0=0.0),
    dict(x0=0.0),
    dict(dath=True, dath_samples=1),
    dict(dath=True, dath_samples=5, dath_floor=0.002),
    dict(threshold=0.0),
    dict(threshold=0.0, dath=True),
    dict(threshold=0.02, dath=True, x0=1.0),
]
CONTROLLERS = [dict(), dict(n=1, reset_after=1), dict(n=3, reset_after=2, p0=100.0, kp=2.5, ki=0.5),
               dict(n=16, p0=480.0), dict(n=7, lo=50.0, hi=60.0)]


def _stream_chain(raw, **kw):
    reflex = sr.SlipReflex(**kw)
    xs, ys, th, acc, counts, cmds = [], [], [], [], [], []
    for r in raw:
        u = reflex.step(r)
        xs.append(reflex.last_filtered)
        ys.append(reflex.last_event)
        th.append(reflex.last_threshold)
        acc.append(reflex.last_accumulator)
        if u is not None:
            counts.append(reflex.last_count)
            cmds.append(u)
    return xs, ys, th, acc, counts, cmds


@pytest.mark.parametrize("name", sorted(SIGNALS))
def test_stages_agree_with_oracle_and_each_other(name):
    raw = SIGNALS[name]
    x = sr.lowpass(raw)
    lp = sr.LowPass()
    assert [lp.step(r) for r in raw] == x.tolist()
    # the default rate is the DAQ's (1 / 3 ms), as everywhere in the package
    np.testing.assert_allclose(x, oracle.lowpass(raw, 1.0 / 0.003, 10.0), rtol=0, atol=1e-12)
    for enc in ENCODERS:
        kw = dict(threshold=enc.get("threshold", 0.008), dath=enc.get("dath", False),
                  dath_samples=enc.get("dath_samples", 16), x0=enc.get("x0"),
                  dath_floor=enc.get("dath_floor", 0.0))
        tr = sr.encode_trace(x, **kw)
        e = sr.EventEncoder(**kw)
        stream = [e.step(v) for v in x]
        assert stream == tr.events.tolist(), enc
        ys, thetas = oracle.encode(x, kw["threshold"], kw["dath"], kw["dath_samples"], kw["x0"],
                                   kw["dath_floor"])
        assert ys == tr.events.astype(int).tolist(), enc
        assert thetas == tr.threshold.tolist(), enc
        for n in (1, 3, 16):
            v = sr.count_windows(tr.events, n=n)
            wc = sr.WindowCounter(n=n)
            assert [c for c in map(wc.step, stream) if c is not None] == v.tolist()
            assert oracle.windows(ys, n) == v.tolist()


@pytest.mark.parametrize("enc,ctl", list(itertools.product(ENCODERS, CONTROLLERS)))
def test_composed_stream_equals_batch_chain(enc, ctl):
    for name in ("empty", "one", "lsb-noise", "sine-burst", "spikes", "random-3", "big", "step"):
        raw = SIGNALS[name]
        res = sr.run_chain(raw, **enc, **ctl)
        xs, ys, th, acc, counts, cmds = _stream_chain(raw, **enc, **ctl)
        assert xs == res.filtered.tolist()
        assert ys == res.events.tolist()
        assert th == res.threshold.tolist()
        assert acc == res.accumulator.tolist()
        assert counts == res.counts.tolist()
        assert cmds == res.commands.tolist()
        mk = {k: ctl[k] for k in ("p0", "kp", "ki", "reset_after", "lo", "hi") if k in ctl}
        assert res.commands.tolist() == sr.mpi(res.counts, **mk).tolist()
        ok = {"p0": 0.0, "kp": 5.0, "ki": 5.0, "reset_after": 10, "lo": 0.0, "hi": 500.0}
        ok.update({k: v for k, v in mk.items()})
        assert oracle.mpi(res.counts.tolist(), ok["p0"], ok["kp"], ok["ki"], ok["reset_after"],
                          ok["lo"], ok["hi"]) == res.commands.tolist()


def test_chain_without_filter_equals_stages_on_raw():
    raw = SIGNALS["quantized-walk"]
    res = sr.run_chain(raw, filter=False, dath=True)
    assert res.events.tolist() == sr.encode(raw, dath=True).tolist()
    _, ys, *_ , cmds = _stream_chain(raw, filter=False, dath=True)
    assert cmds == res.commands.tolist()


def test_mpi_stream_equals_batch_on_random_counts():
    rng = np.random.default_rng(7)
    for _ in range(50):
        v = rng.integers(0, 8, int(rng.integers(0, 200))) * (rng.random(1) < 0.5 or rng.random(200)[0] < 0.6)
        v = np.where(rng.random(v.size) < 0.6, 0, v)
        c = sr.MPIController(p0=float(rng.uniform(-10, 520)))
        batch = sr.mpi(v, p0=c.params.p0)
        assert [c.step(z) for z in v] == batch.tolist()


def test_reset_restores_initial_state():
    raw = SIGNALS["sine-burst"]
    reflex = sr.SlipReflex(dath=True)
    first = [reflex.step(r) for r in raw]
    reflex.reset()
    assert [reflex.step(r) for r in raw] == first
    for obj, inputs in ((sr.LowPass(), raw), (sr.EventEncoder(dath=True), raw),
                        (sr.WindowCounter(n=5), [True, False] * 20), (sr.MPIController(), [3, 0, 1] * 9)):
        a = [obj.step(i) for i in inputs]
        obj.reset()
        assert [obj.step(i) for i in inputs] == a


@pytest.mark.parametrize("enc,ctl", list(itertools.product(ENCODERS, CONTROLLERS)))
def test_staged_batch_equals_composed_step_sample_for_sample(enc, ctl):
    """run_chain's stage-by-stage fast path gives every output of stepping the composed chain."""
    from slipreflex.methods.chain import _kernels as K
    from slipreflex.methods.chain._layout import (
        S_LAST_ACC,
        S_LAST_EVENT,
        S_LAST_THETA,
        S_LAST_X,
        S_M,
        init_state,
        pack_params,
    )
    from slipreflex.methods.chain.params import ReflexParams

    for name in ("one", "sine-burst", "spikes", "random-3", "step"):
        raw = np.asarray(SIGNALS[name], dtype=float)
        res = sr.run_chain(raw, **enc, **ctl)
        P = pack_params(ReflexParams.from_dict({**enc, **ctl}))
        S = init_state(P)
        cols = {"filtered": [], "events": [], "accumulator": [], "threshold": [], "sample_commands": []}
        for v in raw:
            K.chain_step(S, P, float(v), np.nan)
            for key, i in (("filtered", S_LAST_X), ("accumulator", S_LAST_ACC), ("threshold", S_LAST_THETA),
                           ("sample_commands", S_M)):
                cols[key].append(float(S[i]))
            cols["events"].append(bool(S[S_LAST_EVENT]))
        for key, want in cols.items():
            assert getattr(res, key).tolist() == want, (name, key, enc, ctl)
