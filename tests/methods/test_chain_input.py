"""Parameter validation and bad samples (docs/method.md section 1)."""

import math

import numpy as np
import pytest

import slipreflex as sr
from slipreflex.core.errors import DataError, ParameterError


@pytest.mark.parametrize("kwargs,name", [
    (dict(threshold=-0.001), "threshold"),
    (dict(threshold=math.nan), "threshold"),
    (dict(n=0), "n"),
    (dict(n=2.5), "n"),
    (dict(lo=10.0, hi=5.0), "lo"),
    (dict(fs=0.0), "fs"),
    (dict(fs=-333.0), "fs"),
    (dict(fs=333.0, cutoff=166.5), "cutoff"),
    (dict(fs=333.0, cutoff=200.0), "cutoff"),
    (dict(cutoff=0.0), "cutoff"),
    (dict(p0=math.nan), "p0"),
    (dict(kp=math.inf), "kp"),
    (dict(ki=-1.0), "ki"),
    (dict(dath_samples=0), "dath_samples"),
    (dict(dath_floor=-1e-3), "dath_floor"),
    (dict(x0=math.nan), "x0"),
    (dict(reset_after=0), "reset_after"),
    (dict(dath="yes"), "dath"),
])
def test_bad_parameters_are_rejected_naming_the_parameter(kwargs, name):
    with pytest.raises(ParameterError, match=rf"^{name}\b"):
        sr.SlipReflex(**kwargs)
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        sr.run_chain([0.4, 0.5], **kwargs)


def test_batch_functions_validate_their_own_parameters():
    with pytest.raises(ParameterError, match="^threshold"):
        sr.encode([0.1], threshold=-1)
    with pytest.raises(ParameterError, match="^n "):
        sr.count_windows([True], n=0)
    with pytest.raises(ParameterError, match="^lo"):
        sr.mpi([1], lo=1.0, hi=0.0)
    with pytest.raises(ParameterError, match="^cutoff"):
        sr.lowpass([0.1], fs=10.0, cutoff=5.0)
    with pytest.raises(ParameterError, match="^fs"):
        sr.LowPass(fs=math.nan)


def test_unknown_keyword_is_an_error():
    with pytest.raises(ParameterError, match="thresh"):
        sr.SlipReflex(thresh=0.01)
    with pytest.raises(TypeError):
        sr.EventEncoder(thresh=0.01)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_batch_rejects_non_finite_naming_first_bad_index(bad):
    raw = np.full(50, 0.4)
    raw[17] = bad
    raw[30] = math.nan
    for fn in (sr.lowpass, sr.encode, sr.run_chain):
        with pytest.raises(ValueError, match=r"\[17\]"):
            fn(raw)
    with pytest.raises(DataError, match=r"v\[2\]"):
        sr.mpi([1, 2, bad])
    with pytest.raises(DataError, match=r"v\[1\]"):
        sr.mpi([1, -1])
    with pytest.raises(DataError, match=r"events\[1\]"):
        sr.count_windows([1, 2])


def test_stream_skips_nan_samples_and_keeps_running():
    rng = np.random.default_rng(5)
    raw = 0.4 + np.cumsum(rng.normal(0, 0.005, 160))
    bad_at = {3, 20, 21, 77}
    glitched = raw.copy()
    glitched[list(bad_at)] = math.nan
    reflex = sr.SlipReflex(dath=True)
    outs = [reflex.step(r) for r in glitched]
    # The window still advances by one sample per call, glitch or not.
    assert [i for i, u in enumerate(outs) if u is not None] == list(range(15, 160, 16))
    assert reflex.skipped_samples == len(bad_at)
    # Skipping = no event and no state change: same as the chain over the good samples
    # with a forced no-event at each glitch position.
    good = [r for i, r in enumerate(glitched) if i not in bad_at]
    x = sr.lowpass(good)
    ev = sr.encode(x, dath=True).tolist()
    for i in sorted(bad_at):
        ev.insert(i, False)
    expected = sr.mpi(sr.count_windows(np.array(ev)))
    assert [u for u in outs if u is not None] == expected.tolist()
    reflex.reset()
    assert reflex.skipped_samples == 0


def test_stream_survives_nan_first_sample():
    reflex = sr.SlipReflex()
    assert reflex.step(math.nan) is None
    assert math.isnan(reflex.last_filtered)
    outs = [reflex.step(0.4) for _ in range(15)]
    assert outs[-1] == 0.0


def test_multidimensional_input_is_rejected():
    with pytest.raises(DataError, match="one-dimensional"):
        sr.run_chain(np.zeros((4, 4)))
