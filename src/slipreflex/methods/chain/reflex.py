"""The composed reflex: filter -> encoder -> windows -> MPI (docs/method.md section 1, Fig. 3).

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
from typing import TYPE_CHECKING, Any

import numpy as np

from ...core._slots import slot
from ...core.hardware import DAQ_FS, SLIP_FINGER, Finger
from . import _layout as _k
from ._checks import as_samples
from ._layout import init_state, pack_params
from .params import ReflexParams

if TYPE_CHECKING:
    from ...core.interfaces import InputKind

__all__ = ["SlipReflex", "run_chain", "ChainResult"]


class SlipReflex:
    """Streaming reflex chain: raw slip-sensor volts in, finger commands out.

    The chain's state is one float64 vector and every step is one call of the
    compiled :func:`slipreflex.methods.chain._kernels.chain_step`, the function
    :func:`run_chain` runs over a whole recording (and a compiled closed loop
    may call from its own numba code): streaming and batch agree by
    construction.

    Parameters
    ----------
    params : ReflexParams, optional
        A complete parameter set; alternatively give the fields as keywords
        (``fs``, ``cutoff``, ``filter``, ``threshold``, ``dath``, ``dath_samples``,
        ``x0``, ``dath_floor``, ``n``, ``p0``, ``kp``, ``ki``, ``reset_after``,
        ``lo``, ``hi`` and the variants' ``filter_kind``, ``mean_samples``,
        ``acc_reset``, ``acc_leak``, ``mpi_mode``, ``slip_finger_offset``).
        Unknown keywords are an error.

    Attributes
    ----------
    name : str
        The method name used by the trial runner: ``"dath"``, ``"fixed"``,
        ``"dath-event"``, or the preset's name (:meth:`from_preset`).
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

    input_kind: InputKind = "slip"
    __slots__ = ("params", "name", "_P", "_S", "_S0")

    def __init__(self, params: ReflexParams | None = None, **kwargs) -> None:
        if params is not None and kwargs:
            raise TypeError("give either params or keyword parameters, not both")
        self.params = params if params is not None else ReflexParams.from_dict(kwargs)

        _load_step()
        self.name = self.params.name
        self._P = pack_params(self.params)
        self._S0 = init_state(self._P)
        self._S = self._S0.copy()

    @classmethod
    def from_params(cls, params: ReflexParams) -> SlipReflex:
        """Build a chain from a :class:`ReflexParams` (e.g. read from a recording).

        Examples
        --------
        >>> SlipReflex.from_params(ReflexParams(dath=True)).name
        'dath'
        """
        return cls(params)

    @classmethod
    def from_preset(cls, name: str, fs: float = DAQ_FS, **overrides) -> SlipReflex:
        """A chain with a named parameter set (:meth:`ReflexParams.preset`), named after it.

        Parameters
        ----------
        name : {"paper", "fixed", "dath", "authors-gui", "dath-event"}
            ``"authors-gui"`` is the authors' rig code (docs/method.md).
        fs : float
            Sampling rate (Hz); the preset's lengths follow from it.
        **overrides
            Fields to change (``p0=...``).

        Examples
        --------
        >>> r = SlipReflex.from_preset("authors-gui", fs=333.0, p0=150.0)
        >>> r.name, r.params.n, r.finger_offsets
        ('authors-gui', 9, {<Finger.MIDDLE: 2>: 20.0})
        """
        params = ReflexParams.preset(name, fs, **overrides)
        reflex = cls(params)
        if name.casefold() not in ("paper", "fixed", "dath"):
            reflex.name = name.casefold()
        return reflex

    @property
    def fs(self) -> float:
        """Sampling rate (Hz)."""
        return self.params.fs

    @property
    def finger_offsets(self) -> dict[Finger, float]:
        """What a hand adds to the command per finger: {} for the paper, the middle's + 20
        for the authors' rig code (``slip_finger_offset``; the sim's closed loop applies it)."""
        off = self.params.slip_finger_offset
        return {SLIP_FINGER: off} if off else {}

    command = slot(_k.S_M, float, "The current finger command (the last MPI output, or clip(p0)).")
    last_filtered = slot(_k.S_LAST_X, float,
                         "The filtered sample of the last step (NaN if it was skipped or none yet).")
    last_event = slot(_k.S_LAST_EVENT, bool, "True if the last step spiked.")
    last_threshold = slot(_k.S_LAST_THETA, float, "The threshold the last sample was compared with.")
    last_accumulator = slot(_k.S_LAST_ACC, float, "The accumulator the last sample compared, before its reset.")

    @property
    def last_count(self) -> int | None:
        """The window count if the last step completed a window, else None."""
        c = self._S[_k.S_LAST_COUNT]
        return None if c < 0 else int(c)

    skipped_samples = slot(_k.S_SKIPPED, int, "Non-finite samples skipped since the last reset.")

    @property
    def state(self) -> np.ndarray:
        """A copy of the state vector (layout in :mod:`slipreflex.methods.chain._kernels`)."""
        return self._S.copy()

    def reset(self) -> None:
        """Restore every stage to its initial state."""
        self._S[:] = self._S0

    @property
    def probe_slots(self) -> dict[str, int]:
        """The slots of the state vector a closed loop records after every step (what it computed).

        ``x`` the filtered sample, ``event`` 1 for a spike, ``theta`` the threshold in
        force, ``acc`` the accumulator before its reset, ``count`` the window's spike
        count at a window's end (-1 elsewhere), ``command`` the MPI's command.

        Examples
        --------
        >>> sorted(SlipReflex().probe_slots)
        ['acc', 'command', 'count', 'event', 'theta', 'x']
        """
        return {"x": _k.S_LAST_X, "event": _k.S_LAST_EVENT, "theta": _k.S_LAST_THETA, "acc": _k.S_LAST_ACC,
                "count": _k.S_LAST_COUNT, "command": _k.S_M}

    def compiled(self):
        """The compiled step and this chain's live state: ``(chain_step, S, P)``.

        :class:`slipreflex.core.interfaces.CompiledReflex`: ``chain_step(S, P, raw, position)``
        is what :meth:`step` calls, on the very state vector ``S`` this object holds,
        so a compiled closed loop that steps it leaves the object where the loop ended.

        Examples
        --------
        >>> r = SlipReflex(threshold=0.008)
        >>> step, S, P = r.compiled()
        >>> import math
        >>> math.isnan(step(S, P, 0.4, math.nan)), float(r.state[0])   # a first sample arrived
        (True, 1.0)
        """
        return _chain_step, self._S, self._P

    def step(self, raw: float, position: float | None = None) -> float | None:
        """Feed one raw sample; return the new finger command when there is one.

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
            With the paper's MPI: the command u_z on the sample that completes
            window z, else None. With the event-driven MPI: the command on the
            samples where it changes, else None.
        """
        u = _chain_step(self._S, self._P, float(raw), _NAN if position is None else float(position))
        return None if u != u else u


_NAN = math.nan
_chain_step: Any = None  # the compiled step, imported with the first chain (numba stays out of `import`)


def _load_step() -> None:
    global _chain_step
    if _chain_step is None:
        from ._kernels import chain_step  # deferred: heavy (numba kernels)

        _chain_step = chain_step


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
        Per complete window: the command in force at the window's last sample
        (u_z for the paper's MPI).
    sample_commands : numpy.ndarray of float
        Per sample: the command in force after that sample (the event-driven
        MPI changes it between window ends).

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
    sample_commands: np.ndarray

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
    from ._kernels import chain_kernel, empty_like_chain  # deferred: heavy (numba kernels)

    out = empty_like_chain(r.size, p.n)
    if r.size:
        P = pack_params(p)
        chain_kernel(r, init_state(P), P, *out)
    x, events, acc, theta, counts, commands, sample_commands = out
    return ChainResult(p, x, events, acc, theta, counts, commands, sample_commands)
