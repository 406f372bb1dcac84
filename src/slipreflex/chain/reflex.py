"""The composed reflex: filter -> encoder -> windows -> MPI (SPEC 1, Fig. 3).

:class:`SlipReflex` is the one object that runs in simulation, on hardware and
in replay: one raw sample in, a new finger command out on the samples that
complete a window. :func:`run_chain` is its batch twin over a whole recording
(one fused numba pass), and gives identical numbers.

Examples
--------
>>> import numpy as np
>>> reflex = SlipReflex(dath=True)
>>> raw = np.r_[np.full(32, 0.40), 0.40 + 0.05 * np.sin(np.arange(64) / 3.0)]
>>> commands = [u for u in map(reflex.step, raw) if u is not None]
>>> commands == run_chain(raw, dath=True).commands.tolist()
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._checks import as_samples
from .encoder import EventEncoder
from .filters import LowPass, _design
from .mpi import MPIController, _clip
from .params import ReflexParams
from .windows import WindowCounter

__all__ = ["SlipReflex", "run_chain", "ChainResult"]


class SlipReflex:
    """Streaming reflex chain: raw slip-sensor volts in, finger commands out.

    Parameters
    ----------
    params : ReflexParams, optional
        A complete parameter set; alternatively give the fields as keywords
        (``fs``, ``cutoff``, ``filter``, ``threshold``, ``dath``, ``dath_samples``,
        ``x0``, ``dath_floor``, ``n``, ``p0``, ``kp``, ``ki``, ``reset_after``,
        ``lo``, ``hi``). Unknown keywords are an error.

    Attributes
    ----------
    name : str
        ``"dath"`` or ``"fixed"``, the method name used by the trial runner.
    input_kind : str
        ``"slip"``: :meth:`step` takes slip-sensor volts.
    fs : float
        Sampling rate (Hz) at which :meth:`step` must be called.
    last_filtered, last_event, last_threshold, last_accumulator, last_count
        What the last :meth:`step` saw: filtered sample (NaN if skipped), spike,
        threshold in force, accumulator before reset, and the window count if
        the sample completed a window (else None).
    skipped_samples : int
        NaN or inf samples skipped since the last reset.

    Examples
    --------
    >>> reflex = SlipReflex(threshold=0.008, dath=False)
    >>> [reflex.step(0.4) for _ in range(16)][-1]   # no slip: the command stays at p0
    0.0
    >>> reflex.step(float("nan")) is None, reflex.skipped_samples
    (True, 1)
    """

    input_kind = "slip"

    def __init__(self, params: ReflexParams | None = None, **kwargs) -> None:
        if params is not None and kwargs:
            raise TypeError("give either params or keyword parameters, not both")
        self.params = params if params is not None else ReflexParams.from_dict(kwargs)
        p = self.params
        self._filter = LowPass(fs=p.fs, cutoff=p.cutoff, enabled=p.filter)
        self._encoder = EventEncoder(**vars_of(p.encoder))
        self._windows = WindowCounter(n=p.n)
        self._mpi = MPIController(**vars_of(p.mpi))
        self.reset()

    @classmethod
    def from_params(cls, params: ReflexParams) -> "SlipReflex":
        """Build a chain from a :class:`ReflexParams` (e.g. read from a recording).

        Examples
        --------
        >>> SlipReflex.from_params(ReflexParams(dath=True)).name
        'dath'
        """
        return cls(params)

    @property
    def name(self) -> str:
        """Method name, ``"dath"`` or ``"fixed"``."""
        return self.params.name

    @property
    def fs(self) -> float:
        """Sampling rate (Hz)."""
        return self.params.fs

    @property
    def command(self) -> float:
        """The current finger command (the last MPI output, or clip(p0))."""
        return self._mpi.command

    def reset(self) -> None:
        """Restore every stage to its initial state."""
        self._filter.reset()
        self._encoder.reset()
        self._windows.reset()
        self._mpi.reset()
        self.skipped_samples = 0
        self.last_filtered = math.nan
        self.last_event = False
        self.last_threshold = self.params.threshold
        self.last_accumulator = 0.0
        self.last_count: int | None = None

    def step(self, raw: float, position: float | None = None) -> float | None:
        """Feed one raw sample; return the new finger command when a window completes.

        Parameters
        ----------
        raw : float
            Raw slip-sensor voltage. A NaN or inf sample is skipped: no event,
            no filter or encoder state change, the window still advances by one
            sample, and ``skipped_samples`` counts it.
        position : float, optional
            The hand's measured middle-finger position, used as P0 when the MPI
            resets (paper: "P0 is set to the current position of the middle
            finger"); without it the last command is used.

        Returns
        -------
        float or None
            The command u_z on the sample that completes window z, else None.
        """
        r = float(raw)
        if math.isfinite(r):
            x = self._filter.step(r)
            event = self._encoder.step(x)
            self.last_filtered = x
            self.last_threshold = self._encoder.last_threshold
            self.last_accumulator = self._encoder.last_accumulator
        else:
            self.skipped_samples += 1
            event = False
            self.last_filtered = math.nan
        self.last_event = event
        v = self._windows.step(event)
        self.last_count = v
        if v is None:
            return None
        return self._mpi.step(v, position)


def vars_of(params) -> dict:
    """Field dict of a slotted dataclass."""
    return {name: getattr(params, name) for name in params.__dataclass_fields__}


@dataclass(frozen=True)
class ChainResult:
    """Everything the batch chain computed over a recording.

    Attributes
    ----------
    params : ReflexParams
    filtered, accumulator, threshold : numpy.ndarray of float
        Per sample: x_k, the accumulator before reset, the threshold in force.
    events : numpy.ndarray of bool
        Per sample: y_k.
    counts : numpy.ndarray of int64
        Per complete window: v_z.
    commands : numpy.ndarray of float
        Per complete window: u_z.

    Examples
    --------
    >>> import numpy as np
    >>> res = run_chain(np.full(40, 0.4))
    >>> res.counts.tolist(), res.window_end_index().tolist()
    ([0, 0], [15, 31])
    """

    params: ReflexParams
    filtered: np.ndarray
    events: np.ndarray
    accumulator: np.ndarray
    threshold: np.ndarray
    counts: np.ndarray
    commands: np.ndarray

    def window_end_index(self) -> np.ndarray:
        """Index of the sample that completes each window."""
        n = self.params.n
        return np.arange(1, self.counts.size + 1) * n - 1

    def sample_columns(self, t: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Per-sample columns: t, x (filtered), threshold, event.

        Parameters
        ----------
        t : numpy.ndarray, optional
            Sample times (s); default k / fs.
        """
        t = np.arange(self.filtered.size) / self.params.fs if t is None else np.asarray(t)
        return {"t": t, "x": self.filtered, "threshold": self.threshold,
                "event": self.events.astype(np.int64)}

    def window_columns(self, t: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Per-window columns: t_end (time of the completing sample), v, command."""
        t = np.arange(self.filtered.size) / self.params.fs if t is None else np.asarray(t)
        return {"t_end": t[self.window_end_index()], "v": self.counts, "command": self.commands}


def run_chain(raw, params: ReflexParams | None = None, **kwargs) -> ChainResult:
    """Run the whole chain over a recording of raw slip-sensor volts.

    Parameters
    ----------
    raw : array_like of float
        Raw samples; NaN or inf raises ValueError naming the first bad index
        (the streaming :class:`SlipReflex` skips them instead).
    params : ReflexParams, optional
        Parameters; or give them as keywords like :class:`SlipReflex`.

    Returns
    -------
    ChainResult
        Identical, bit for bit, to feeding :class:`SlipReflex` sample by sample.

    Examples
    --------
    >>> import numpy as np
    >>> raw = np.r_[np.full(32, 0.40), 0.40 + 0.05 * np.sin(np.arange(64) / 3.0)]
    >>> run_chain(raw, dath=True).commands.tolist()
    [0.0, 0.0, 50.0, 115.0, 140.0, 165.0]
    """
    if params is not None and kwargs:
        raise TypeError("give either params or keyword parameters, not both")
    p = params if params is not None else ReflexParams.from_dict(kwargs)
    r = as_samples("raw", raw)
    from ._kernels import chain_kernel, empty_like_chain

    out = empty_like_chain(r.size, p.n)
    if r.size:
        sos, zi0 = _design(p.fs, p.cutoff)
        zi = zi0 * r[0]
        x0 = 0.0 if p.x0 is None else p.x0
        chain_kernel(r, p.filter, sos, zi, x0, p.x0 is not None, p.threshold, p.dath, p.dath_samples,
                     p.dath_floor, p.n, p.p0, _clip(p.p0, p.lo, p.hi), p.kp, p.ki, p.reset_after,
                     p.lo, p.hi, *out)
    x, events, acc, theta, counts, commands = out
    return ChainResult(p, x, events, acc, theta, counts, commands)
