"""Helpers shared by the test modules (fixtures; pytest finds them by name)."""

from __future__ import annotations

import numpy as np
import pytest


def _stream(reflex, samples, positions=None) -> np.ndarray:
    """Feed ``samples`` to ``reflex`` one by one; the commands, NaN where ``step`` gave None."""
    out = []
    for k, x in enumerate(samples):
        p = None if positions is None or np.isnan(positions[k]) else float(positions[k])
        v = reflex.step(x, position=p)
        out.append(np.nan if v is None else v)
    return np.array(out, dtype=float)


@pytest.fixture
def stream():
    """``stream(reflex, samples, positions=None)``: a streaming reflex's commands over a recording.

    Positions are fed where they are not NaN; the result has NaN where ``step``
    returned None, so it compares directly with the batch functions' output.
    """
    return _stream


@pytest.fixture
def assert_same_commands():
    """``assert_same_commands(a, b)``: equal where set, NaN in the same places, bit for bit."""
    def check(a, b):
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
        np.testing.assert_array_equal(a[~np.isnan(a)], b[~np.isnan(b)])
    return check
