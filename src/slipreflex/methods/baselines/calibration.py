"""The one threshold rule of the comparison methods (docs/method.md section 2).

The paper gives no thresholds for NMSD or SWT-SD. We use one rule for both
methods and every bottle: record the rig **at rest** (object grasped, nothing
happening) with the tactile array at the method's own rate, compute the
method's own signed statistic on every taxel, and set

    threshold = REST_K * sd(statistic at rest)        (REST_K = 5)

pooled over all taxels and samples (the statistic is zero-mean at rest, so
``k`` standard deviations above zero is the usual noise-floor rule). Five
standard deviations keep the false-detection rate of a Gaussian noise floor
below about one per several minutes of 16 taxels at 260-380 Hz, while staying
as sensitive as the noise allows. The rule never sees a perturbation, so it
cannot be tuned per bottle.

Examples
--------
>>> import numpy as np
>>> rest = np.random.default_rng(0).normal(1.0, 0.01, size=(2000, 4, 4))
>>> t = rest_threshold(rest, "nmsd", fs=260.0)
>>> 30.0 < t < 35.0          # 5 x sqrt(6) x 0.01 N x 260 Hz = 31.8 N/s
True
"""

from __future__ import annotations

import numpy as np

from ... import methods  # the registry sits below the baselines: only its table is read here
from ...core.errors import DataError, ParameterError
from ...core.hardware import NMSD_FS
from ...core.validation import number
from ._validate import as_frames

__all__ = ["REST_K", "rest_statistic", "rest_threshold"]

#: Standard deviations of the at-rest statistic that make the threshold.
REST_K: float = 5.0


def rest_statistic(frames, method, fs: float = NMSD_FS) -> np.ndarray:
    """The method's signed statistic on a rest recording, warm-up samples dropped.

    Parameters
    ----------
    frames : array_like, shape (K, 4, 4)
        Tactile frames of the rig at rest, at the method's rate.
    method : str or callable
        A registered method with a rest statistic (``"nmsd"``, ``"swt"``, or one
        registered in :mod:`slipreflex.methods`), or the statistic itself,
        ``statistic(frames, fs) -> 1-D array``.
    fs : float
        Sampling rate (used by NMSD's derivative).

    Returns
    -------
    numpy.ndarray, 1-D
        All valid values, pooled over taxels.

    Examples
    --------
    >>> import numpy as np
    >>> rest_statistic(np.zeros((10, 4, 4)), "swt").shape
    (48,)
    """
    f = as_frames("frames", frames)
    return np.asarray(_statistic(method)(f, fs), dtype=np.float64).ravel()


def _statistic(method):
    """The rest statistic of ``method``: the callable itself, or the registry's entry."""
    if callable(method):
        return method
    stat = methods.get(method).rest_statistic
    if stat is None:
        raise ParameterError(f"method {method!r} has no rest statistic "
                             f"(methods with one: {', '.join(methods.calibrated())})")
    return stat


def rest_threshold(frames, method, fs: float = NMSD_FS, *, k: float = REST_K) -> float:
    """Threshold = ``k`` x standard deviation of the method's statistic at rest.

    Parameters
    ----------
    frames : array_like, shape (K, 4, 4)
        Tactile frames of the rig at rest, at the method's rate.
    method : str or callable
        A method with a rest statistic, or the statistic (see :func:`rest_statistic`).
    fs : float
        Sampling rate (Hz).
    k : float
        Standard deviations (> 0).

    Returns
    -------
    float

    Raises
    ------
    DataError
        When the recording is too short or noiseless (no threshold can be derived).

    Examples
    --------
    >>> import numpy as np
    >>> rest = np.random.default_rng(1).normal(0.5, 0.02, size=(4000, 4, 4))
    >>> round(rest_threshold(rest, "swt", fs=380.0), 2)    # 5 x 0.02 x sqrt(8)/sqrt(8)
    0.1
    """
    k = number("k", k, lo=0.0, lo_open=True)
    s = rest_statistic(frames, method, fs)
    if s.size < 32:
        raise DataError(f"rest recording too short for a {method} threshold: {s.size} values")
    sd = float(np.std(s))
    if not sd > 0.0:
        raise DataError(f"rest recording has no noise in the {method} statistic: "
                        "cannot derive a threshold from k standard deviations")
    return k * sd
