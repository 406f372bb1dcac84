"""NMSD and SWT-SD on any tactile array: (K, rows, cols) or (K, channels)."""

from __future__ import annotations

import numpy as np
import pytest

from slipreflex.core.errors import DataError, ParameterError
from slipreflex.core.hardware import NMSD_FS, SWT_FS
from slipreflex.methods.baselines import (
    NMSD,
    SWTSD,
    NMSDParams,
    SWTParams,
    nmsd_commands,
    rest_statistic,
    rest_threshold,
    swt_commands,
)


def _frames(fs, shape, seed=0):
    rng = np.random.default_rng(seed)
    k = int(1.5 * fs)
    f = 0.5 + rng.normal(0.0, 0.004, (k, *shape))
    flat = f.reshape(k, -1)
    t = np.arange(k) / fs
    flat[:, 0] += np.where(t > 0.8, -0.3, 0.0)                  # a sudden unloading (NMSD)
    flat[:, -1] += -2.0 * np.clip(t - 0.8, 0.0, 0.2)            # a slide (SWT-SD)
    return f


@pytest.mark.parametrize("shape", [(4, 4), (3, 5), (7,), (1,)])
def test_streaming_equals_batch_on_any_shape(shape, stream, assert_same_commands):
    for cls, pcls, batch, fs in ((NMSD, NMSDParams, nmsd_commands, NMSD_FS),
                                 (SWTSD, SWTParams, swt_commands, SWT_FS)):
        frames = _frames(fs, shape)
        name = "nmsd" if cls is NMSD else "swt"
        p = pcls(threshold=rest_threshold(frames[: int(0.7 * fs)], name, fs), speed=500.0, p0=100.0,
                 shape=shape)
        out = stream(cls(p), frames)
        assert_same_commands(batch(frames, p), out)
        assert np.isfinite(out).any()


def test_the_threshold_pools_every_taxel_and_sample_whatever_the_layout():
    grid = np.random.default_rng(3).normal(1.0, 0.01, (500, 4, 4))
    flat = grid.reshape(500, 16)
    for m in ("nmsd", "swt"):
        a, b = rest_statistic(grid, m, NMSD_FS), rest_statistic(flat, m, NMSD_FS)
        np.testing.assert_array_equal(a, b)            # same values, pooled the same way
        assert rest_threshold(grid, m, NMSD_FS) == rest_threshold(flat, m, NMSD_FS)
        assert a.size == (500 - (2 if m == "nmsd" else 7)) * 16


def test_a_frame_of_the_wrong_shape_or_a_bad_shape_is_refused():
    r = NMSD(threshold=1.0, speed=100.0, shape=(7,))
    with pytest.raises(DataError, match=r"\(7,\)"):
        r.step(np.zeros((4, 4)))
    for bad in ((), (2, 2, 2), (0, 3), (2.0, 3), "44"):
        with pytest.raises(ParameterError, match="shape"):
            SWTParams(threshold=1.0, speed=1.0, shape=bad)
    assert NMSDParams(threshold=1.0, speed=1.0, shape=(np.int64(2), 8)).shape == (2, 8)
