"""SWT-SD: slip detection with the stationary wavelet transform after Romeo et al.

The second comparison method of the paper's section II-E (docs/method.md
section 2), on the 4 x 4 tactile array sampled at 380 Hz. For every taxel, the
last ``window = 8`` samples (21 ms) are decomposed by :func:`pywt.swt` into
three levels with the Haar wavelet, and the statistic is the level-3 detail
coefficient at the first position of the window. Because the SWT is linear,
that coefficient is a fixed weighted sum of the window; the weights are taken
once from :func:`pywt.swt` applied to unit impulses (:func:`swt_kernel`), and
the batch and streaming paths apply them in the same order (same bits). With Haar and a window of
exactly ``2**3`` samples that coefficient is the only one whose filter does
not wrap around the window: ``(sum(older half) - sum(newer half)) / (2 * sqrt(2))``,
a matched step/ramp detector over the whole 21 ms (a force drop gives a
positive value). It is 0 until the window is full.

A taxel is over threshold when ``|c_k| > threshold``; slip is declared on a
taxel when it has been over threshold on the crossing sample and on the
``persist`` following samples; the ON/OFF signal is the OR over the taxels.
While ON, the hand is driven with the NMSD closing rule
(:mod:`slipreflex.methods.baselines.closing`, mode ``"hold"``).

The paper (II-E) says slip "was considered to have occurred if the value of the
third level detail coefficient crossed a threshold and movement would continue
for at least another 21 ms (see [16])". That sentence has two readings, both
kept, by name, in :data:`SWT_PERSISTENCE`:

* ``"within-window"`` (``persist = 0``, the default): ``c_k`` is the level-3
  detail at the *first* position of the 8-sample (21 ms) window, so it is known
  only once the 21 ms after that position are in, and it crosses only if the
  force kept changing through them (its older half against its newer half).
  The continuing movement is the window itself, and the crossing is the
  decision.
* ``"after-crossing"`` (``persist = 8``): the coefficient must stay over the
  threshold on the crossing sample and the 8 samples (21 ms) after it.

The default is the reading whose pour reaction times lie nearer the paper's own
(III-C: SWT-SD 86 ms on TR, 73 ms on DK; docs/method.md section 2 gives the
numbers, ``tests/methods/test_swt_persistence.py`` checks it). The wavelet, the use of
the first coefficient and these readings are ours; the threshold comes from
:func:`slipreflex.methods.baselines.rest_threshold`, the same rule as for NMSD.

Examples
--------
>>> import numpy as np
>>> f = np.zeros((30, 4, 4)); f[10:, 1, 2] = -np.arange(20) * 0.05   # force falling
>>> on = swt_on(f, threshold=0.05)                        # the default reading, "within-window"
>>> int(np.argmax(on)), bool(on[-1])
(12, True)
>>> int(np.argmax(swt_on(f, threshold=0.05, persist="after-crossing")))
20
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from ...core.errors import ParameterError
from ...core.hardware import SWT_FS
from ...core.validation import integer, number, set_field
from ._layout import KIND_SWT
from ._validate import as_frames
from .closing import closing_commands
from .shell import TactileParams, TactileReflex

__all__ = ["SWTParams", "SWTSD", "swt_statistic", "swt_on", "swt_commands", "swt_kernel",
           "swt_rest_statistic", "swt_persistence",
           "SWT_WINDOW", "SWT_LEVEL", "SWT_WAVELET", "SWT_PERSISTENCE", "SWT_PERSISTENCE_DEFAULT",
           "SWT_PERSIST"]

#: Moving-window length (samples): 21 ms at 380 Hz, as in the paper.
SWT_WINDOW: int = 8
#: Decomposition depth.
SWT_LEVEL: int = 3
#: Mother wavelet (our choice; see the module docstring).
SWT_WAVELET: str = "haar"
#: The readings of the paper's persistence rule: samples the crossing must persist after the
#: crossing sample (see the module docstring).
SWT_PERSISTENCE: Mapping[str, int] = MappingProxyType({"within-window": 0, "after-crossing": SWT_WINDOW})
#: The reading used unless another is asked for.
SWT_PERSISTENCE_DEFAULT: str = "within-window"
#: Its persistence in samples.
SWT_PERSIST: int = SWT_PERSISTENCE[SWT_PERSISTENCE_DEFAULT]


def swt_persistence(reading: str) -> int:
    """The persistence (samples after the crossing) of one named reading of the paper's rule.

    Parameters
    ----------
    reading : str
        A key of :data:`SWT_PERSISTENCE`.

    Returns
    -------
    int

    Raises
    ------
    ParameterError
        For a name that is not a reading, naming the known ones.

    Examples
    --------
    >>> swt_persistence("after-crossing"), swt_persistence("within-window")
    (8, 0)
    >>> swt_persistence("forever")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: SWT-SD persistence reading: unknown 'forever' (known: ...)
    """
    if not isinstance(reading, str) or reading not in SWT_PERSISTENCE:
        raise ParameterError(f"SWT-SD persistence reading: unknown {reading!r} "
                             f"(known: {', '.join(SWT_PERSISTENCE)})")
    return SWT_PERSISTENCE[reading]


@dataclass(frozen=True, slots=True)
class SWTParams(TactileParams):
    """Parameters of the SWT-SD reflex: :class:`~slipreflex.methods.baselines.shell.TactileParams` and ``persist``.

    ``threshold`` is on ``|cD3|`` in N; ``fs`` is 380 Hz in the paper;
    ``close_s`` is the closing quantum of the NMSD rule used while ON.

    Parameters
    ----------
    persist : int or str
        Samples the crossing must persist after the crossing sample (>= 0),
        or the name of a reading in :data:`SWT_PERSISTENCE` (stored as its
        count). Default :data:`SWT_PERSIST` (0, ``"within-window"``); 8
        samples = 21 ms at 380 Hz.

    Examples
    --------
    >>> SWTParams(threshold=0.1, speed=500.0).fs
    380.0
    >>> SWTParams(threshold=1.0, speed=500.0).closing.samples_per_close
    17
    >>> SWTParams(threshold=0.1, speed=500.0, persist="after-crossing").persist
    8
    """

    fs: float = SWT_FS
    persist: int = SWT_PERSIST

    def __post_init__(self) -> None:
        TactileParams.__post_init__(self)
        persist = swt_persistence(self.persist) if isinstance(self.persist, str) else self.persist
        set_field(self, "persist", integer("persist", persist, lo=0))


@functools.lru_cache(maxsize=8)
def _kernel(wavelet: str = SWT_WAVELET, level: int = SWT_LEVEL, window: int = SWT_WINDOW) -> np.ndarray:
    """The SWT as a linear map: cD_level[0] of a window = ``kernel @ window``.

    The SWT is linear, so applying :func:`pywt.swt` once to the ``window``
    unit impulses gives the exact weights it applies to a window; using them
    costs a dot product per step instead of a full decomposition.
    """
    import pywt  # deferred: heavy (pywt)

    eye = np.eye(window)
    k = pywt.swt(eye, wavelet, level=level, axis=-1)[0][1][:, 0]
    k.setflags(write=False)
    return k


def swt_kernel() -> np.ndarray:
    """Weights of the level-3 Haar SWT detail at the first position of an 8-sample window.

    Returns
    -------
    numpy.ndarray, shape (8,)
        Read-only; ``+1/(2 sqrt 2)`` on the older half, ``-1/(2 sqrt 2)`` on the newer.

    Examples
    --------
    >>> import numpy as np
    >>> np.round(swt_kernel() * 2 * np.sqrt(2), 12).tolist()
    [1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0, -1.0]
    """
    return _kernel()


def _apply(kernel: np.ndarray, windows: np.ndarray) -> np.ndarray:
    """``sum_j kernel[j] * windows[..., j, :]``, rows added one by one from the oldest.

    The order is written out (numpy's ``sum`` adds pairwise along a contiguous
    axis, e.g. for one taxel), so it is the compiled step's order: same bits.
    """
    out = kernel[0] * windows[..., 0, :]
    for j in range(1, kernel.size):
        out = out + kernel[j] * windows[..., j, :]
    return out


def swt_statistic(frames) -> np.ndarray:
    """Level-3 SWT detail of the last 8 samples of every taxel.

    Parameters
    ----------
    frames : array_like, shape (K, rows, cols) or (K, channels)
        Tactile forces (N).

    Returns
    -------
    numpy.ndarray, same shape as ``frames``
        ``c_k``; zero for the first 7 frames (window not yet full).

    Examples
    --------
    >>> import numpy as np
    >>> f = np.zeros((9, 4, 4)); f[:, 0, 0] = np.arange(9.0)
    >>> np.round(swt_statistic(f)[6:, 0, 0], 4).tolist()
    [0.0, -5.6569, -5.6569]
    """
    f = as_frames("frames", frames)
    k = len(f)
    out = np.zeros_like(f)
    if k >= SWT_WINDOW:
        flat = f.reshape(k, -1)
        win = np.lib.stride_tricks.sliding_window_view(flat, SWT_WINDOW, axis=0)  # (k-7, taxels, 8)
        win = np.swapaxes(win, 1, 2)                                               # (k-7, 8, taxels)
        out[SWT_WINDOW - 1:] = _apply(_kernel(), win).reshape(-1, *f.shape[1:])
    return out


def swt_rest_statistic(frames, fs: float = SWT_FS) -> np.ndarray:
    """SWT-SD's statistic on a rest recording, pooled over taxels, warm-up frames dropped.

    ``fs`` is accepted for a uniform signature (the statistic does not depend on it).

    Examples
    --------
    >>> import numpy as np
    >>> swt_rest_statistic(np.zeros((10, 4, 4))).shape
    (48,)
    """
    return swt_statistic(frames)[SWT_WINDOW - 1:].ravel()


def swt_on(frames, *, threshold: float, persist: int | str = SWT_PERSIST) -> np.ndarray:
    """The ON/OFF slip signal: any taxel over threshold for ``persist + 1`` samples running.

    Parameters
    ----------
    frames : array_like, shape (K, rows, cols) or (K, channels)
        Tactile forces (N).
    threshold : float
        Threshold on ``|c_k|`` (N).
    persist : int or str
        Samples the crossing must persist after the crossing sample, or a
        reading's name (:data:`SWT_PERSISTENCE`).

    Returns
    -------
    numpy.ndarray of bool, shape (K,)

    Examples
    --------
    >>> import numpy as np
    >>> f = np.zeros((20, 4, 4)); f[8:, 3, 3] = 1.0     # a step on one taxel
    >>> np.flatnonzero(swt_on(f, threshold=0.1, persist=2)).tolist()
    [10, 11, 12, 13, 14]
    """
    threshold = number("threshold", threshold, lo=0.0, lo_open=True)
    persist = integer("persist", swt_persistence(persist) if isinstance(persist, str) else persist, lo=0)
    over = np.asarray(np.abs(swt_statistic(frames)) > threshold).reshape(len(np.asarray(frames)), -1)
    k = np.arange(over.shape[0])[:, None]
    last_below = np.maximum.accumulate(np.where(over, -1, k), axis=0)
    run = k - last_below  # consecutive over-threshold samples ending at k
    return np.asarray((run > persist).any(axis=1))


def swt_commands(frames, params: SWTParams, positions=None) -> np.ndarray:
    """Batch SWT-SD reflex: frames in, finger targets out (NaN where unchanged).

    Gives exactly what :class:`SWTSD` returns sample by sample; the arguments
    and the result are those of :func:`slipreflex.methods.baselines.nmsd_commands`
    with an :class:`SWTParams`.

    Examples
    --------
    >>> import numpy as np
    >>> f = np.zeros((12, 4, 4)); f[8:, 0, 0] = 1.0
    >>> p = SWTParams(threshold=0.1, speed=380.0, persist=1)
    >>> swt_commands(f, p)[8:].tolist()
    [nan, 1.0, 2.0, 3.0]
    """
    on = swt_on(frames, threshold=params.threshold, persist=params.persist)
    return closing_commands(on, params.closing, mode="hold", positions=positions)


class SWTSD(TactileReflex):
    """Streaming SWT-SD reflex (implements :class:`slipreflex.core.interfaces.Reflex`).

    The shared :class:`~slipreflex.methods.baselines.shell.TactileReflex` shell (its
    parameters, attributes, diagnostics and compiled step) with SWT-SD's
    detector (:func:`swt_on`, the weights of :func:`swt_kernel` over a ring of
    the last 8 frames): the fingers close while the ON/OFF signal is ON. ``name`` is ``"swt"``, ``fs``
    380 Hz by default, ``last_statistic`` the largest ``|c_k|`` over the taxels,
    ``last_on`` the ON/OFF signal and ``last_event`` the start of an ON period.

    Examples
    --------
    >>> import numpy as np
    >>> from slipreflex.core.interfaces import Reflex
    >>> r = SWTSD(threshold=0.1, speed=380.0)
    >>> isinstance(r, Reflex), r.name, r.input_kind, r.fs
    (True, 'swt', 'tactile', 380.0)
    >>> r = SWTSD(threshold=0.1, speed=380.0, persist=1)
    >>> out = [r.step(np.full((4, 4), 1.0 if k >= 8 else 0.0)) for k in range(11)]
    >>> out[8:], r.last_on
    ([None, 1.0, 2.0], True)
    """

    name = "swt"
    params_class = SWTParams
    mode = "hold"
    kind = KIND_SWT

    def _weights(self) -> np.ndarray:
        return _kernel()

    @property
    def last_on(self) -> bool:
        """The ON/OFF slip signal at the last step.

        Examples
        --------
        >>> SWTSD(threshold=1.0, speed=100.0).last_on
        False
        """
        return self.last_level
