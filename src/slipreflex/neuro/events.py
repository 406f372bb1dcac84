"""Spikes out in the neuromorphic field's formats: AEDAT4, tonic's ``events_struct``, NIR event data.

An event is ``(x, y, t, p)``: the pixel (the slip sensor is pixel (0, 0); a tactile array's
taxel in column ``x``, row ``y``, patches stacked downwards), the time in microseconds of the
DAQ clock (the sample's time stamp, rounded to the microsecond), and the polarity, True where
the change that fired was an increase (the sign of the accumulator that crossed the
threshold, Eq. 2). :data:`EVENT_DTYPE` is tonic's ``events_struct`` field for field.

Sources: :func:`chain_events` (raw volts and their times: a CSV that ``detect`` reads, a
recording's samples replayed, a simulated trial) and :func:`taxel_events` (tactile frames: the
fixed-threshold encoder on every taxel). Writers: :func:`write_npy`, :func:`write_aedat4`
(through ``faery``), :func:`write_nir_events` (through ``nir``); the last two need the ``neuro``
extra.

Examples
--------
>>> import numpy as np
>>> ev = chain_events(np.r_[np.full(40, 0.4), np.full(40, 0.5)], np.arange(80) * 0.003, filter=False)
>>> ev[["x", "y", "t", "p"]].tolist()
[(0, 0, 120000, True)]
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..core.errors import DataError, ParameterError
from .graph import _nir

__all__ = ["EVENT_DTYPE", "FORMATS", "chain_events", "taxel_events", "sensor_size", "write_events",
           "write_npy", "write_aedat4", "write_nir_events", "NIR_NODE", "NIR_OBSERVABLE"]

#: tonic's ``events_struct`` (tonic.io): the dtype of its event arrays.
EVENT_DTYPE = np.dtype([("x", np.int16), ("y", np.int16), ("t", np.int64), ("p", bool)])

#: The formats :func:`write_events` writes, by name, with their file suffix.
FORMATS: dict[str, str] = {"aedat4": ".aedat4", "tonic": ".npy", "nir": ".nir-events.h5"}

#: Where NIR event data puts the spikes: the node that fires them and its observable.
NIR_NODE, NIR_OBSERVABLE = "encoder", "spikes"


def _micros(t: np.ndarray) -> np.ndarray:
    t = np.asarray(t, dtype=np.float64)
    if t.size and (not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0)):
        raise DataError("event times must be finite and non-decreasing (s)")
    return np.round(t * 1e6).astype(np.int64)


def chain_events(raw, t, params=None, **chain: Any) -> np.ndarray:
    """The chain's spikes over raw slip-sensor volts, as events of pixel (0, 0).

    Parameters
    ----------
    raw, t : array_like
        Samples (V) and their DAQ times (s). A NaN sample is skipped as the streaming chain
        skips it.
    params : slipreflex.methods.chain.ReflexParams, optional
        The chain (a recording's own, for a replay); or give its parameters as keywords.

    Returns
    -------
    numpy.ndarray of :data:`EVENT_DTYPE`

    Examples
    --------
    >>> chain_events([0.4, 0.4, 0.3], [0.0, 0.003, 0.006], filter=False)["p"].tolist()
    [False]
    """
    from ..methods.chain import ReflexParams, SlipReflex  # deferred: heavy (numba kernels)

    p = params if params is not None else ReflexParams.from_dict(chain)
    raw = np.asarray(raw, dtype=np.float64)
    t_us = _micros(t)
    if raw.shape != t_us.shape:
        raise DataError(f"{raw.size} samples but {t_us.size} times")
    reflex = SlipReflex(p)
    fired, sign = np.zeros(raw.size, dtype=bool), np.zeros(raw.size, dtype=bool)
    for k, v in enumerate(raw):
        reflex.step(float(v))
        fired[k], sign[k] = reflex.last_event, reflex.last_accumulator > 0
    out = np.zeros(int(fired.sum()), dtype=EVENT_DTYPE)
    out["t"], out["p"] = t_us[fired], sign[fired]
    return out


def taxel_events(frames, t, threshold: float, *, fs: float | None = None, filter: bool = True,
                 patches: int = 1) -> np.ndarray:
    """The fixed-threshold encoder (Eq. 1-2) on every taxel of tactile frames.

    Parameters
    ----------
    frames : array_like, shape (K, rows, cols) or (K, patches * rows * cols)
        One frame per time stamp (any unit; ``threshold`` is in the same unit).
    t : array_like, shape (K,)
        Frame times (s).
    threshold : float
        The encoder's threshold.
    fs : float, optional
        Frame rate for the low-pass filter (default: from ``t``).
    filter : bool
        Low-pass every taxel first (the chain's 10 Hz filter; it needs fs > 20 Hz).
    patches : int
        Flat frames hold this many equal square patches, stacked downwards in y.

    Returns
    -------
    numpy.ndarray of :data:`EVENT_DTYPE`, sorted by time, then y, then x.

    Examples
    --------
    >>> f = np.zeros((3, 2, 2)); f[2, 1, 0] = -1.0
    >>> taxel_events(f, [0.0, 0.1, 0.2], 0.5, filter=False)[["x", "y", "p"]].tolist()
    [(0, 1, False)]
    """
    from ..methods.chain import encode_trace, lowpass  # deferred: heavy (numba kernels)

    grid = _as_grid(np.asarray(frames, dtype=np.float64), patches)
    t_us = _micros(t)
    if grid.shape[0] != t_us.size:
        raise DataError(f"{grid.shape[0]} frames but {t_us.size} times")
    if grid.shape[0] < 2:
        return np.zeros(0, dtype=EVENT_DTYPE)
    rate = fs if fs is not None else (grid.shape[0] - 1) / max((t_us[-1] - t_us[0]) * 1e-6, 1e-9)
    rows = []
    for y in range(grid.shape[1]):
        for x in range(grid.shape[2]):
            sig = grid[:, y, x]
            sig = lowpass(sig, fs=rate) if filter else sig
            tr = encode_trace(sig, threshold=threshold)
            k = np.flatnonzero(tr.events)
            rows.append(np.rec.fromarrays([np.full(k.size, x), np.full(k.size, y), t_us[k],
                                           tr.accumulator[k] > 0], dtype=EVENT_DTYPE))
    out = np.concatenate(rows).view(np.ndarray).astype(EVENT_DTYPE)
    return out[np.lexsort((out["x"], out["y"], out["t"]))]


def _as_grid(frames: np.ndarray, patches: int) -> np.ndarray:
    if frames.ndim == 3:
        return frames
    if frames.ndim != 2:
        raise DataError(f"tactile frames must be (K, rows, cols) or (K, taxels), got shape {frames.shape}")
    side = int(round(np.sqrt(frames.shape[1] / patches)))
    if side * side * patches != frames.shape[1]:
        raise DataError(f"{frames.shape[1]} taxels are not {patches} square patch(es)")
    return frames.reshape(frames.shape[0], patches * side, side)


def sensor_size(events: np.ndarray) -> tuple[int, int]:
    """(width, height) that holds every event's pixel (at least 1 x 1).

    Examples
    --------
    >>> sensor_size(np.zeros(0, dtype=EVENT_DTYPE))
    (1, 1)
    """
    if events.size == 0:
        return 1, 1
    return int(events["x"].max()) + 1, int(events["y"].max()) + 1


def write_npy(events: np.ndarray, path: str | Path) -> Path:
    """Events as a ``.npy`` of tonic's ``events_struct`` (``np.load`` gives tonic's array).

    Examples
    --------
    >>> write_npy(np.zeros(0, dtype=EVENT_DTYPE), "spikes.npy")       # doctest: +SKIP
    PosixPath('spikes.npy')
    """
    path = Path(path)
    np.save(path, np.asarray(events, dtype=EVENT_DTYPE), allow_pickle=False)
    return path


def write_aedat4(events: np.ndarray, path: str | Path, size: tuple[int, int] | None = None) -> Path:
    """Events as an AEDAT4 file (through ``faery``, the ``neuro`` extra).

    Examples
    --------
    >>> write_aedat4(np.zeros(0, dtype=EVENT_DTYPE), "spikes.aedat4")  # doctest: +SKIP
    PosixPath('spikes.aedat4')
    """
    try:
        import faery  # deferred: optional extra (faery, pip install slipreflex[neuro])
    except ImportError:
        raise ParameterError("AEDAT4 needs the 'faery' package: pip install 'slipreflex[neuro]'") from None
    path = Path(path)
    width, height = size or sensor_size(events)
    arr = np.zeros(events.size, dtype=faery.EVENTS_DTYPE)
    for name in ("t", "x", "y"):
        arr[name] = events[name]
    arr["on"] = events["p"]
    faery.events_stream_from_array(arr, dimensions=(width, height)).to_file(path)
    return path


def write_nir_events(events: np.ndarray, path: str | Path, size: tuple[int, int] | None = None) -> Path:
    """Events as NIR event data (``nir.write_data``): the node ``encoder``'s observable ``spikes``.

    Neuron index ``2 * (y * width + x) + (0 for ON, 1 for OFF)``; times in microseconds of the
    DAQ clock (float), ``t_max`` the last event's time.

    Examples
    --------
    >>> write_nir_events(np.zeros(0, dtype=EVENT_DTYPE), "spikes.h5")  # doctest: +SKIP
    PosixPath('spikes.h5')
    """
    nir = _nir()
    path = Path(path)
    width, height = size or sensor_size(events)
    idx = 2 * (events["y"].astype(np.int64) * width + events["x"]) + (~events["p"]).astype(np.int64)
    data = nir.EventData(idx=idx[None, :], time=events["t"].astype(np.float64)[None, :],
                         n_neurons=2 * width * height, t_max=float(events["t"].max()) if events.size else 0.0)
    graph_data = nir.NIRGraphData({NIR_NODE: nir.NIRNodeData({NIR_OBSERVABLE: data})})
    nir.write_data(str(path), graph_data)
    return path


def write_events(events: np.ndarray, path: str | Path, fmt: str) -> Path:
    """Write ``events`` in the format ``fmt`` (a key of :data:`FORMATS`).

    Examples
    --------
    >>> write_events(np.zeros(0, dtype=EVENT_DTYPE), "x.avi", "avi")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: event format 'avi' is not one of aedat4, tonic, nir
    """
    if fmt not in FORMATS:
        raise ParameterError(f"event format {fmt!r} is not one of {', '.join(FORMATS)}")
    writer = {"aedat4": write_aedat4, "tonic": write_npy, "nir": write_nir_events}[fmt]
    return writer(events, path)
