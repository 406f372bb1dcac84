"""The board's fixed-point chain: the Q formats, the parameters, the filter, encoder, windows and MPI on ADC counts.

The integer operations of ``firmware/reflex/reflex.c``, in the same order, so the two agree
bit for bit (:func:`run_board_chain` over a run, :class:`BoardChain` one sample at a time).
Re-exported by :mod:`slipreflex.methods.board`.

Examples
--------
>>> adc_counts(1.0), volts_to_q16(0.008)
(204, 107374)
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ...core import hardware as hw
from ...core.errors import DataError, ParameterError
from ...core.validation import instance
from ..chain.encoder import dath_update
from ..chain.filters import _design
from ..chain.params import ReflexParams

if TYPE_CHECKING:
    pass


__all__ = [
    "COEF_Q", "SIG_Q", "H_MAX", "BoardParams", "BoardChain", "BoardResult", "run_board_chain", "adc_counts",
    "quantize_lowpass", "volts_to_q16", "FIRMWARE_ADC_MIN", "FIRMWARE_ADC_MAX", "FIRMWARE_STUCK_AFTER",
    "board_params_from_json"
]


#: Fractional bits of the filter coefficients.
COEF_Q: int = 24
#: Fractional bits of the signals (filtered samples, thresholds, accumulator), in counts.
SIG_Q: int = 16
#: The MPI integral saturates here; output-neutral (docs/firmware.md).
H_MAX: int = 65535
#: Largest ADC reading.
ADC_MAX: int = (1 << hw.ADC_BITS) - 1
_ROUND = 1 << (COEF_Q - 1)

#: The firmware's fault rules (written into firmware/reflex/reflex_config.h): a reading
#: within 8 counts (39 mV) of either rail means a disconnected or shorted sensor (the
#: OPR5005 gives 0.3..3.35 V, 61..686 counts), and 1000 identical readings in a row
#: (3 s) a stuck converter or a dead sensor; the chain skips such readings.
FIRMWARE_ADC_MIN: int = 8
FIRMWARE_ADC_MAX: int = ADC_MAX - 8
FIRMWARE_STUCK_AFTER: int = 1000


def adc_counts(volts: float) -> int:
    """Volts -> the count the board's 10-bit ADC reads (floor at 5 V / 1024, clipped).

    The AVR's ADC returns ``floor(V * 1024 / Vref)``, saturated to 0..1023; the
    simulated sensor (``slipreflex.sim``) quantises the same way, so its volts come
    back as exact counts.

    Parameters
    ----------
    volts : float
        Finite input voltage.

    Returns
    -------
    int

    Examples
    --------
    >>> adc_counts(2.5), adc_counts(300 * 5 / 1024), adc_counts(-0.1), adc_counts(7.0)
    (512, 300, 0, 1023)
    """
    if not math.isfinite(volts):
        raise DataError(f"slip-sensor volts must be finite, got {volts!r}")
    return int(min(max(math.floor(volts / hw.ADC_LSB), 0), ADC_MAX))


def volts_to_q16(volts: float) -> int:
    """A voltage difference as Q16 counts, rounded half up (thresholds, floor, x0).

    Examples
    --------
    >>> volts_to_q16(0.008)      # 1.6384 counts
    107374
    """
    return math.floor(volts / hw.ADC_LSB * (1 << SIG_Q) + 0.5)


def quantize_lowpass(fs: float = hw.DAQ_FS, cutoff: float = 10.0) -> tuple[int, int, int]:
    """Integer coefficients ``(g, a1, a2)`` in Q24 of the chain's Butterworth low-pass.

    ``a1`` is rounded to nearest; ``g`` is ``(2**24 + a1 + a2) / 4`` rounded, and
    ``a2`` is then set to ``4 g - 2**24 - a1`` (a change of at most 2 in Q24), so
    that the DC gain is exactly one and a constant input passes unchanged.

    Examples
    --------
    >>> quantize_lowpass()
    (131201, -29103869, 12851457)
    """

    sos, _ = _design(float(fs), float(cutoff))
    one = 1 << COEF_Q
    a1 = math.floor(float(sos[0, 4]) * one + 0.5)
    a2 = math.floor(float(sos[0, 5]) * one + 0.5)
    g = math.floor((one + a1 + a2) / 4 + 0.5)
    return g, a1, 4 * g - one - a1


def board_params_from_json(text: str, where: Any = "board_params") -> BoardParams:
    """:class:`BoardParams` from the JSON a ``run --board-reflex`` recording stores.

    Raises
    ------
    DataError
        Malformed JSON or fields, naming ``where`` (the recording).

    Examples
    --------
    >>> import json
    >>> p = BoardParams.firmware(p0=7)
    >>> board_params_from_json(json.dumps(p.to_dict())) == p
    True
    """

    try:
        return BoardParams(**json.loads(text))
    except (ValueError, TypeError) as err:
        raise DataError(f"{where}: bad board parameters in the metadata: {err}") from None


def _int(name: str, value: Any, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= value <= hi:
        raise ParameterError(f"{name} must be an integer in {lo}..{hi}, got {value!r}")
    return int(value)


# field -> (lo, hi) of the C type in struct reflex_params
_RANGES: dict[str, tuple[int, int]] = {
    "g": (-2**31, 2**31 - 1), "a1": (-2**31, 2**31 - 1), "a2": (-2**31, 2**31 - 1),
    "theta0": (0, 2**31 - 1), "dath_floor": (0, 2**31 - 1), "x0": (0, ADC_MAX << SIG_Q),
    "p0": (-32768, 32767), "lo": (-32768, 32767), "hi": (-32768, 32767),
    "adc_min": (0, ADC_MAX), "adc_max": (0, ADC_MAX), "stuck_after": (0, 65535),
    "dath_samples": (1, 255), "n": (1, 255), "kp": (0, 255), "ki": (0, 255),
    "reset_after": (1, 255),
}


@dataclass(frozen=True, slots=True)
class BoardParams:
    """The C core's ``struct reflex_params``: every parameter in integer units.

    Build it from the float chain's parameters with :meth:`from_chain`. Fields
    are those of the C struct (Q24 coefficients, Q16 thresholds, whole positions);
    ``x0`` is None when the reference starts at the first filtered sample.

    Examples
    --------
    >>> p = BoardParams.from_chain(dath=True, p0=125)
    >>> p.dath, p.theta0, p.p0, p.n
    (True, 107374, 125, 16)
    >>> BoardParams.from_chain(kp=2.5)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: kp must be a whole number for the board, got 2.5
    """

    g: int
    a1: int
    a2: int
    theta0: int
    filter: bool = True
    dath: bool = False
    dath_samples: int = hw.WINDOW_N
    dath_floor: int = 0
    x0: int | None = None
    n: int = hw.WINDOW_N
    p0: int = 0
    kp: int = 5
    ki: int = 5
    reset_after: int = 10
    lo: int = hw.FINGER_MIN
    hi: int = hw.FINGER_MAX
    adc_min: int = 0
    adc_max: int = ADC_MAX
    stuck_after: int = 0

    def __post_init__(self) -> None:
        for name, (lo, hi) in _RANGES.items():
            value = getattr(self, name)
            if name == "x0" and value is None:
                continue
            object.__setattr__(self, name, _int(name, value, lo, hi))
        for name in ("filter", "dath"):
            if not isinstance(getattr(self, name), bool):
                raise ParameterError(f"{name} must be True or False, got {getattr(self, name)!r}")
        if self.lo > self.hi:
            raise ParameterError(f"lo must be <= hi, got lo={self.lo}, hi={self.hi}")
        if self.adc_min > self.adc_max:
            raise ParameterError(f"adc_min must be <= adc_max, got {self.adc_min} > {self.adc_max}")

    @classmethod
    def from_chain(cls, params=None, *, adc_min: int = 0, adc_max: int = ADC_MAX,
                   stuck_after: int = 0, **kwargs) -> BoardParams:
        """Quantise the float chain's parameters (:class:`~slipreflex.ReflexParams`).

        Parameters
        ----------
        params : ReflexParams, optional
            Or the same fields as keywords (``fs`` defaults to the board's 333.33 Hz).
            Volts become Q16 counts (:func:`volts_to_q16`); positions and gains must
            be whole numbers. Only the paper's method: any ``params.variants``
            (moving-mean filter, ``acc_reset``, ``acc_leak``, the event-driven MPI,
            no reset, a finger offset) is refused, as is a positive threshold or
            DATH floor too small for Q16.
        adc_min, adc_max, stuck_after : int
            Fault rules (the defaults never fault on a 10-bit reading).

        Returns
        -------
        BoardParams

        Examples
        --------
        >>> BoardParams.from_chain(x0=0.0).x0
        0
        >>> BoardParams.from_chain(acc_leak=32.0)
        Traceback (most recent call last):
        ...
        slipreflex.core.errors.ParameterError: acc_leak=32.0: the board's fixed-point chain runs the paper's ...
        """

        if params is not None and kwargs:
            raise TypeError("give either params or keyword parameters, not both")
        if params is None:
            params = ReflexParams.from_dict({"fs": hw.DAQ_FS, **kwargs})
        p = params
        for name in p.variants:  # other methods: refused, never silently run as the paper's chain
            raise ParameterError(f"{name}={getattr(p, name)!r}: the board's fixed-point chain runs the "
                                 f"paper's method only (no {name}); use the float chain (slipreflex.methods.chain)")
        for name in ("threshold", "dath_floor"):  # a positive level must stay positive in Q16
            if getattr(p, name) > 0 and volts_to_q16(getattr(p, name)) == 0:
                raise ParameterError(f"{name}={getattr(p, name)!r} V is below the board's resolution "
                                     f"({hw.ADC_LSB / (1 << SIG_Q):.3g} V): it would become 0")
        whole = {}
        for name in ("p0", "kp", "ki", "lo", "hi"):
            value = getattr(p, name)
            if value != math.floor(value):
                raise ParameterError(f"{name} must be a whole number for the board, got {value!r}")
            whole[name] = int(value)
        g, a1, a2 = quantize_lowpass(p.fs, p.cutoff)
        assert p.reset_after is not None, "an MPI that never resets is a variant, refused above"
        return cls(g=g, a1=a1, a2=a2, theta0=volts_to_q16(p.threshold), filter=p.filter,
                   dath=p.dath, dath_samples=p.dath_samples, dath_floor=volts_to_q16(p.dath_floor),
                   x0=None if p.x0 is None else volts_to_q16(p.x0), n=p.n,
                   reset_after=p.reset_after, adc_min=adc_min, adc_max=adc_max,
                   stuck_after=stuck_after, **whole)

    @classmethod
    def firmware(cls, *, dath: bool = True, p0: int = 0) -> BoardParams:
        """What the firmware built with ``REFLEX_DATH=dath REFLEX_P0=p0`` runs.

        The paper's chain at the board's 333.33 Hz with the firmware's fault rules
        (:data:`FIRMWARE_ADC_MIN`, :data:`FIRMWARE_ADC_MAX`, :data:`FIRMWARE_STUCK_AFTER`).

        Examples
        --------
        >>> BoardParams.firmware(p0=100).adc_min, BoardParams.firmware().stuck_after
        (8, 1000)
        """
        return cls.from_chain(dath=dath, p0=p0, adc_min=FIRMWARE_ADC_MIN, adc_max=FIRMWARE_ADC_MAX,
                              stuck_after=FIRMWARE_STUCK_AFTER)

    def to_dict(self) -> dict[str, Any]:
        """Plain dict of every field.

        Examples
        --------
        >>> BoardParams.from_chain().to_dict()["g"]
        131201
        """
        return dataclasses.asdict(self)


class BoardChain:
    """Streaming integer chain on ADC counts: ``reflex_step`` of the C core.

    Attributes after each :meth:`step`: ``x`` (the filtered sample, Q16 counts,
    kept over faults), ``event``, ``fault``, ``window`` (the sample completed a
    window), ``v`` (its count) and ``command`` (the command in force).

    Examples
    --------
    >>> c = BoardChain(BoardParams.from_chain())
    >>> [c.step(300) for _ in range(16)][-1], c.v, c.command
    (True, 0, 0)
    """

    def __init__(self, params: BoardParams) -> None:
        self.params = instance("params", params, BoardParams)
        self.reset()

    def reset(self) -> None:
        """Back to ``reflex_init``: P0 = p0, command = clip(p0), nothing seen."""
        p = self.params
        self.y1 = self.y2 = self.x = 0
        self.prev = self.acc = 0
        self.theta = p.theta0
        self.r1 = self.r2 = 0
        self.P0 = p.p0
        self.m = min(max(p.p0, p.lo), p.hi)
        self.h = 0
        self.last_adc, self.same = 0xFFFF, 0
        self.remaining = 0
        self.primed = self.started = False
        self.in_window = self.count = self.zeros = 0
        self.event = self.fault = self.window = False
        self.v = 0

    @property
    def command(self) -> int:
        """The command in force (the last MPI output, or clip(p0))."""
        return self.m

    def _prime(self, r: int) -> None:
        xq = r << SIG_Q
        self.r1 = self.r2 = r
        self.y1 = self.y2 = xq
        p = self.params
        self.prev = p.x0 if (not self.started and p.x0 is not None) else xq
        self.acc = 0
        self.theta = p.theta0
        self.remaining = 0
        self.primed = self.started = True

    def _lowpass(self, r: int) -> int:
        p = self.params
        acc = p.g * ((r + 2 * self.r1 + self.r2) << SIG_Q) - p.a1 * self.y1 - p.a2 * self.y2
        y = (acc + _ROUND) >> COEF_Q      # Python's >> floors, like the AVR's arithmetic shift
        self.r2, self.r1 = self.r1, r
        self.y2, self.y1 = self.y1, y
        return y

    def _encode(self, x: int) -> bool:
        p = self.params
        d = x - self.prev
        self.acc += d
        y = abs(self.acc) > self.theta
        if y:
            self.acc = 0
        if p.dath:
            self.remaining, self.theta = dath_update(self.remaining, self.theta, y, d, p.theta0, p.dath_floor,
                                                     p.dath_samples)
        self.prev = x
        return y

    def _mpi(self, v: int, position: int | None) -> None:
        p = self.params
        self.h = min(self.h + v, H_MAX)
        pi = self.P0 + p.kp * v + p.ki * self.h
        self.m = min(max(max(pi, self.m), p.lo), p.hi)
        if v == 0:
            self.zeros += 1
            if self.zeros == p.reset_after:
                self.P0 = self.m if position is None else position
                self.h = 0
                self.zeros = 0
        else:
            self.zeros = 0

    def step(self, adc: int, position: int | None = None) -> bool:
        """One ADC reading in; True when it completed a window (then see ``v``, ``command``).

        Parameters
        ----------
        adc : int
            The reading, 0..65535 as the C ``uint16_t`` (above 1023 is a fault).
        position : int, optional
            Measured slip-finger position (-32768..32767), P0 at an MPI reset.
        """
        p = self.params
        fault = adc > ADC_MAX or adc < p.adc_min or adc > p.adc_max
        self.same = min(self.same + 1, 0xFFFF) if adc == self.last_adc else 0
        self.last_adc = adc
        if p.stuck_after and self.same >= p.stuck_after:
            fault = True
        self.fault, self.event = fault, False
        if fault:
            self.primed = False
        else:
            if not self.primed:
                self._prime(adc)
            self.x = self._lowpass(adc) if p.filter else adc << SIG_Q
            self.event = self._encode(self.x)
        self.window, self.v = False, 0
        self.count += self.event
        self.in_window += 1
        if self.in_window == p.n:
            self.window, self.v = True, self.count
            self.in_window = self.count = 0
            self._mpi(self.v, position)
        return self.window


@dataclass(frozen=True)
class BoardResult:
    """Everything the board chain produced over a run of ADC counts.

    Attributes
    ----------
    params : BoardParams
    adc : numpy.ndarray of int64
    filtered : numpy.ndarray of int64
        Per sample: x_k in Q16 counts (the last good one on a fault sample).
    events, faults : numpy.ndarray of bool
        Per sample.
    counts, commands : numpy.ndarray of int64
        Per complete window.

    Examples
    --------
    >>> res = run_board_chain([300] * 40)
    >>> res.counts.tolist(), res.window_end_index().tolist(), res.filtered[0] == 300 << SIG_Q
    ([0, 0], [15, 31], np.True_)
    """

    params: BoardParams
    adc: np.ndarray
    filtered: np.ndarray
    events: np.ndarray
    faults: np.ndarray
    counts: np.ndarray
    commands: np.ndarray

    def window_end_index(self) -> np.ndarray:
        """Index of the sample that completes each window."""
        return np.arange(1, self.counts.size + 1) * self.params.n - 1

    def sample_columns(self) -> dict[str, np.ndarray]:
        """Per-sample columns as the board runner writes them: sample, event."""
        return {"sample": np.arange(self.events.size), "event": self.events.astype(np.int64)}

    def window_columns(self) -> dict[str, np.ndarray]:
        """Per-window columns as the board runner writes them: window, v, command."""
        return {"window": np.arange(self.counts.size), "v": self.counts, "command": self.commands}


def _as_counts(adc_counts) -> np.ndarray:
    arr = np.asarray(adc_counts)
    if arr.ndim != 1:
        raise DataError(f"adc_counts must be one-dimensional, got shape {arr.shape}")
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        vals = arr.astype(float)
        bad = np.flatnonzero(~np.isfinite(vals) | (vals != np.floor(vals)))
        if bad.size:
            i = int(bad[0])
            raise DataError(f"adc_counts[{i}] is {arr[i].item()!r}: ADC counts must be whole numbers")
    arr = arr.astype(np.int64)
    bad = np.flatnonzero((arr < 0) | (arr > ADC_MAX))
    if bad.size:
        i = int(bad[0])
        raise DataError(f"adc_counts[{i}] is {arr[i]}: ADC counts must be in 0..{ADC_MAX}")
    return arr


def run_board_chain(adc_counts, params: BoardParams | None = None, *, positions=None,
                    **kwargs) -> BoardResult:
    """Run the board's chain over ADC counts, as the firmware does, sample by sample.

    Parameters
    ----------
    adc_counts : array_like of int
        10-bit readings, 0..1023 (anything else raises DataError naming the index).
    params : BoardParams, optional
        Or keywords for :meth:`BoardParams.from_chain` (``dath=True``, ``p0=125``, ...).
    positions : sequence of int or None, optional
        Per window, the measured slip-finger position passed to the MPI (None: none).

    Returns
    -------
    BoardResult
        Identical to feeding :class:`BoardChain` one reading at a time (it is that loop).

    Examples
    --------
    >>> run_board_chain([300] * 16 + [310] * 16, dath=True).counts.tolist()
    [0, 8]
    """
    if params is not None and kwargs:
        raise TypeError("give either params or keyword parameters, not both")
    p = params if params is not None else BoardParams.from_chain(**kwargs)
    arr = _as_counts(adc_counts)
    chain = BoardChain(p)
    k = arr.size
    filtered = np.zeros(k, dtype=np.int64)
    events = np.zeros(k, dtype=bool)
    faults = np.zeros(k, dtype=bool)
    nwin = k // p.n
    pos = [None] * nwin if positions is None else list(positions)
    if len(pos) < nwin:
        raise DataError(f"positions has {len(pos)} values, the run has {nwin} windows")
    counts = np.zeros(nwin, dtype=np.int64)
    commands = np.zeros(nwin, dtype=np.int64)
    z = 0
    for i, a in enumerate(arr.tolist()):
        if chain.step(a, pos[z] if z < nwin else None):
            counts[z], commands[z] = chain.v, chain.command
            z += 1
        filtered[i], events[i], faults[i] = chain.x, chain.event, chain.fault
    return BoardResult(p, arr, filtered, events, faults, counts, commands)


