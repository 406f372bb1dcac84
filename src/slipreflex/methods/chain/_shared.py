"""What the chain's layout and its stream classes share: the low-pass design and the command clip.

At the bottom of :mod:`slipreflex.methods.chain`: it imports no other module of the chain, so the
layout (:mod:`._layout`), the filters and the MPI can all use it without a circle.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__: list[str] = []

FILTER_ORDER = 2


@lru_cache(maxsize=32)
def _design(fs: float, cutoff: float) -> tuple[np.ndarray, np.ndarray]:
    """Second-order sections and their steady-state factors, read only (cached)."""
    # function-level: keeps scipy.signal (about 0.5 s) out of `import slipreflex`
    from scipy.signal import butter, sosfilt_zi  # deferred: heavy (scipy.signal)

    sos = np.asarray(butter(FILTER_ORDER, cutoff, fs=fs, output="sos"))
    zi = np.asarray(sosfilt_zi(sos))
    sos.setflags(write=False)
    zi.setflags(write=False)
    return sos, zi


def _clip(value: float, lo: float, hi: float) -> float:
    """``value`` saturated to ``[lo, hi]``."""
    return lo if value < lo else hi if value > hi else value
