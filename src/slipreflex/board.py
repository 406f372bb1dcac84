"""The reflex as the microcontroller runs it: the Python twin of ``firmware/reflex/``.

The C99 core in ``firmware/reflex/reflex.c`` runs the chain of docs/method.md section 1
in integer fixed point on 10-bit ADC counts. This module does the same integer
operations, in the same order, so the two agree bit for bit on every sample; the
shared vectors in ``tests/data/board/vectors.txt`` and random signals check that
(tests/test_board.py). docs/firmware.md states the formats:

* filter: 2nd-order Butterworth low-pass in direct form I, coefficients with
  :data:`COEF_Q` = 24 fractional bits (``b = g (1, 2, 1)``, ``a = (1, a1, a2)``,
  ``4 g = 2**24 + a1 + a2`` so the DC gain is exactly 1), output in counts with
  :data:`SIG_Q` = 16 fractional bits, rounded half up (add ``2**23``, arithmetic
  shift right by 24) -- the chain's only rounding;
* encoder: the float chain's rules on Q16 counts; theta0 = 0.008 V =
  1.6384 counts = 107374 in Q16; DATH's ``|x_k - x_(k-1)|`` is the exact difference
  of two Q16 samples;
* windows and MPI: integers (the MPI is exact, commands are whole positions).
* the standalone board's hand (``hand2560``): :class:`BoardHand`, grip only added --
  each rise of the command is CLOSE at full PWM and a STOP ``ceil(8 g / 15)`` samples
  later, a fault sends STOP, never OPEN or POSITION (:func:`board_hand` over a run).

Examples
--------
>>> import numpy as np
>>> adc = np.r_[np.full(32, 300), 300 + np.round(10 * np.sin(np.arange(64) / 3.0))].astype(int)
>>> res = run_board_chain(adc, dath=True)
>>> res.counts.tolist(), res.commands.tolist()
([0, 0, 5, 9, 7, 6], [0, 0, 50, 115, 140, 165])
>>> BoardParams.from_chain().theta0          # 0.008 V in Q16 counts
107374
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
from collections import deque
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from . import hardware as hw
from .chain.encoder import dath_update
from .chain.filters import _design
from .chain.params import ReflexParams
from .csvfiles import write_columns
from .errors import DataError, ParameterError
from .methods import Detections, MethodContext
from .validation import instance

if TYPE_CHECKING:
    from .interfaces import InputKind

__all__ = [
    "COEF_Q", "SIG_Q", "H_MAX", "BoardParams", "BoardChain", "BoardReflex", "BoardResult",
    "run_board_chain", "adc_counts", "quantize_lowpass", "volts_to_q16", "board_detections",
    "FIRMWARE_ADC_MIN", "FIRMWARE_ADC_MAX", "FIRMWARE_STUCK_AFTER", "read_adc_csv",
    "write_board_outputs", "CheckedBoardReflex", "BoardSource", "board_params_from_json",
    "grip_time_ratio", "GRIP_PER_UNIT", "GRIP_PER_SAMPLE", "HAND_PWM", "BoardHand", "HandTrace",
    "board_hand", "build_board_method", "board_method_detections",
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


def grip_time_ratio(speed: float = hw.FINGER_SPEED_UNITS_S, period: float = hw.DAQ_PERIOD_S
                    ) -> tuple[int, int]:
    """Closing time as whole numbers: ``(per_unit, per_sample)`` with one unit of grip
    closing for ``per_unit / per_sample`` samples.

    One unit closes in ``1 / speed`` s, i.e. ``1 / (speed x period)`` samples; with the
    i-Limb's 625 units/s and the board's 3 ms sample that is 8/15 of a sample (1.6 ms).
    The board counts the closing time still owed in ``1 / per_sample`` of a sample
    (0.2 ms), so every rise adds an exact integer.

    Examples
    --------
    >>> grip_time_ratio()
    (8, 15)
    """

    units_per_sample = Fraction(repr(float(speed))) * Fraction(repr(float(period)))
    if units_per_sample <= 0:
        raise ParameterError(f"closing speed x sample period must be > 0, got {speed!r} x {period!r}")
    return units_per_sample.denominator, units_per_sample.numerator


#: One unit of grip is GRIP_PER_UNIT / GRIP_PER_SAMPLE samples of closing (8/15 of 3 ms).
GRIP_PER_UNIT, GRIP_PER_SAMPLE = grip_time_ratio()
#: The PWM duty of the board's CLOSE packets: full (the documented closing speed).
HAND_PWM: int = hw.PWM_MAX


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
    slipreflex.errors.ParameterError: kp must be a whole number for the board, got 2.5
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
        slipreflex.errors.ParameterError: acc_leak=32.0: the board's fixed-point chain runs the paper's method only ...
        """

        if params is not None and kwargs:
            raise TypeError("give either params or keyword parameters, not both")
        if params is None:
            params = ReflexParams.from_dict({"fs": hw.DAQ_FS, **kwargs})
        p = params
        for name in p.variants:  # other methods: refused, never silently run as the paper's chain
            raise ParameterError(f"{name}={getattr(p, name)!r}: the board's fixed-point chain runs the "
                                 f"paper's method only (no {name}); use the float chain (slipreflex.chain)")
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


class BoardHand:
    """The standalone board's hand rule (``hand2560``): grip only added, as CLOSE and STOP.

    The twin of the hand code in ``firmware/src/main.c``. The MPI's command never
    reaches the hand as a position: a window whose command rises ``g`` units above the
    level already turned into grip owes ``g`` units of closing, i.e. ``g / 625`` s at
    full PWM (:data:`~slipreflex.hardware.FINGER_SPEED_UNITS_S`). The closing time still
    owed, ``left``, is counted in fifteenths of a sample (:data:`GRIP_PER_SAMPLE`; a unit
    is :data:`GRIP_PER_UNIT` = 8 of them, 1.6 ms). After every sample, in this order:

    1. if the fingers are closing, one sample has passed: ``left -= 15``;
    2. at a window whose command is above ``level``: ``left += 8 (command - level)``,
       ``level = command`` (a rise while closing makes the closing longer);
    3. the fingers are to close while ``left > 0`` and the reading is good;
    4. CLOSE (PWM :data:`HAND_PWM`, thumb, index, middle) when they start to close;
       STOP when their time is up, or at the first faulty reading of a fault (whether
       or not they were closing: a fault holds the hand); nothing otherwise;
    5. once stopped, a negative ``left`` (the last sample's overshoot) is dropped.

    So a closing lasts its grip's time rounded **up** to whole samples (``ceil(8 G /
    15)`` samples for ``G`` units, at most 3 ms = 1.875 units more, never less); a fault
    cuts it short and the rest is owed: CLOSE again at the next good reading. No packet
    is ever OPEN or POSITION; ``p0`` only sets ``level``'s start (clip(p0), as the MPI).

    Parameters
    ----------
    params : BoardParams
        The chain the board runs (``p0``, ``lo``, ``hi`` give the start).

    Examples
    --------
    >>> h = BoardHand(BoardParams.firmware(p0=100))
    >>> h.step(True, False, 110), h.left          # a rise of 10: 80/15 samples of closing
    (<HandCommand.CLOSE: 1>, 80)
    >>> [h.step(False, False, 110) for _ in range(6)][-2:]   # STOP after ceil(80/15) = 6
    [None, <HandCommand.STOP: 0>]
    """

    def __init__(self, params: BoardParams) -> None:
        self.params = instance("params", params, BoardParams)
        self.reset()

    def reset(self) -> None:
        """Power-on: nothing owed, not closing, level = clip(p0)."""
        p = self.params
        self.level = min(max(p.p0, p.lo), p.hi)
        self.left = 0
        self.closing = self.fault = False
        self.rise = 0

    def step(self, window: bool, fault: bool, command: int) -> hw.HandCommand | None:
        """One sample's chain output in; the packet the board sends after it, if any.

        Parameters
        ----------
        window : bool
            The sample completed a window (then ``command`` is the MPI's new command).
        fault : bool
            The sample's reading was faulty.
        command : int
            The command in force after the sample.

        Returns
        -------
        HandCommand or None
            ``CLOSE`` or ``STOP`` for the tripod, or None (no packet).
        """
        if self.closing:
            self.left -= GRIP_PER_SAMPLE
        self.rise = 0
        if window and command > self.level:
            self.rise = int(command) - self.level
            self.left += GRIP_PER_UNIT * self.rise
            self.level = int(command)
        want = self.left > 0 and not fault
        onset = fault and not self.fault
        packet = None
        if want and not self.closing:
            packet = hw.HandCommand.CLOSE
        elif (self.closing and not want) or onset:
            packet = hw.HandCommand.STOP
        self.closing, self.fault = want, bool(fault)
        if not want and self.left < 0:
            self.left = 0
        return packet


@dataclass(frozen=True)
class HandTrace:
    """What :func:`board_hand` found: the standalone board's hand packets over a run.

    Attributes
    ----------
    packets : list of (int, HandCommand)
        ``(sample, CLOSE or STOP)`` in order; the first is ``(-1, STOP)``, the hold
        the board sends at every reset before its first sample.
    rises : numpy.ndarray of int64
        Per sample: the grip (units) that sample's window added (0 mostly).
    left : numpy.ndarray of int64
        Per sample: the closing time still owed after it, in 1/15 of a sample.
    closing : numpy.ndarray of bool
        Per sample: the fingers are closing after it.

    Examples
    --------
    >>> t = board_hand(run_board_chain([300] * 32 + [300, 320] * 32, BoardParams.firmware()))
    >>> t.grip, int(t.left[47]), int(t.closing.sum())      # 90 units: 720/15 = 48 samples
    (90, 720, 48)
    """

    packets: list
    rises: np.ndarray
    left: np.ndarray
    closing: np.ndarray

    @property
    def grip(self) -> int:
        """Units of grip the run's rises added.

        Examples
        --------
        >>> board_hand(run_board_chain([300] * 64, BoardParams.firmware())).grip
        0
        """
        return int(self.rises.sum())


def board_hand(result: BoardResult) -> HandTrace:
    """The hand packets the standalone board sends for a run of its chain (:class:`BoardHand`).

    Parameters
    ----------
    result : BoardResult
        From :func:`run_board_chain` with the board's parameters.

    Returns
    -------
    HandTrace

    Examples
    --------
    >>> res = run_board_chain([300] * 32 + [300, 320] * 32, BoardParams.firmware())
    >>> [(k, c.name) for k, c in board_hand(res).packets]
    [(-1, 'STOP'), (47, 'CLOSE'), (95, 'STOP')]
    """
    p = result.params
    k = result.adc.size
    hand = BoardHand(p)
    rises = np.zeros(k, dtype=np.int64)
    left = np.zeros(k, dtype=np.int64)
    closing = np.zeros(k, dtype=bool)
    packets: list[tuple[int, hw.HandCommand]] = [(-1, hw.HandCommand.STOP)]
    cmds = result.commands.tolist()
    for i, fault in enumerate(result.faults.tolist()):
        window = (i + 1) % p.n == 0
        packet = hand.step(window, fault, cmds[(i + 1) // p.n - 1] if window else hand.level)
        if packet is not None:
            packets.append((i, packet))
        rises[i], left[i], closing[i] = hand.rise, hand.left, hand.closing
    return HandTrace(packets, rises, left, closing)


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


class BoardReflex:
    """The board's chain behind the :class:`~slipreflex.interfaces.Reflex` protocol.

    Takes slip-sensor volts like the float :class:`~slipreflex.SlipReflex`,
    quantises them as the board's ADC does (:func:`adc_counts`) and runs
    :class:`BoardChain`; a measured position is rounded half up to a whole position.
    Named ``"dath-board"`` or ``"fixed-board"``.

    Parameters
    ----------
    params : BoardParams, optional
        Or keywords for :meth:`BoardParams.from_chain`.

    Examples
    --------
    >>> r = BoardReflex(dath=True, p0=100)
    >>> r.name, r.input_kind, round(r.fs, 2)
    ('dath-board', 'slip', 333.33)
    >>> [r.step(1.5) for _ in range(16)][-1]
    100.0
    """

    input_kind: InputKind = "slip"

    def __init__(self, params: BoardParams | None = None, *, fs: float = hw.DAQ_FS,
                 **kwargs) -> None:
        if params is not None and kwargs:
            raise TypeError("give either params or keyword parameters, not both")
        self.fs = float(fs)
        self.params = params if params is not None else BoardParams.from_chain(fs=fs, **kwargs)
        self.chain = BoardChain(self.params)

    @property
    def name(self) -> str:
        """``"dath-board"`` or ``"fixed-board"``."""
        return "dath-board" if self.params.dath else "fixed-board"

    def reset(self) -> None:
        """Restore the initial state."""
        self.chain.reset()

    @property
    def last_event(self) -> bool:
        """The last sample was a spike (the :class:`~slipreflex.interfaces.Reflex` diagnostics)."""
        return bool(self.chain.event)

    @property
    def last_filtered(self) -> float:
        """The filtered sample in volts (NaN on a fault sample)."""
        return math.nan if self.chain.fault else self.chain.x * hw.ADC_LSB / (1 << SIG_Q)

    @property
    def last_threshold(self) -> float:
        """The encoder threshold in force, in volts."""
        return self.chain.theta * hw.ADC_LSB / (1 << SIG_Q)

    @property
    def last_count(self) -> int | None:
        """The window's spike count if the last sample completed a window, else None."""
        return int(self.chain.v) if self.chain.window else None

    def step(self, sample: float, position: float | None = None) -> float | None:
        """One sample in volts; the new command when a window completes, else None."""
        pos = None if position is None else min(max(math.floor(float(position) + 0.5), -32768), 32767)
        volts = float(sample)
        # A NaN or inf reading is a fault, like a reading outside 0..1023 on the board.
        adc = adc_counts(volts) if math.isfinite(volts) else 0xFFFF
        if self.chain.step(adc, pos):
            return float(self.chain.command)
        return None


def board_detections(reflex: BoardReflex, volts) -> tuple[np.ndarray, np.ndarray]:
    """The filtered trace (volts) and spikes of a board reflex over a whole trial's volts.

    NaN or inf volts are faults, as in :meth:`BoardReflex.step`.

    Returns
    -------
    x : numpy.ndarray of float
        Filtered samples converted back to volts (Q16 counts x ADC_LSB / 2**16).
    events : numpy.ndarray of bool

    Examples
    --------
    >>> x, ev = board_detections(BoardReflex(), [1.0] * 4 + [1.2] * 8)
    >>> ev.nonzero()[0].tolist(), round(float(x[0]), 4)
    ([6, 7, 8, 9, 10, 11], 0.9961)
    """
    chain = BoardChain(reflex.params)
    v = np.asarray(volts, dtype=float)
    x = np.empty(v.size)
    events = np.zeros(v.size, dtype=bool)
    for i, volt in enumerate(v.tolist()):
        chain.step(adc_counts(volt) if math.isfinite(volt) else 0xFFFF)
        x[i], events[i] = chain.x * hw.ADC_LSB / (1 << SIG_Q), chain.event
    return x, events


def read_adc_csv(path) -> np.ndarray:
    """Read a CSV of ADC counts: a header with a column ``adc``, integers 0..1023.

    Other columns are ignored; ``#`` lines before the header are skipped.

    Raises
    ------
    DataError
        Unreadable file, no ``adc`` column, or a cell that is not a count; the
        message names the file and the line.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "adc.csv"
    >>> _ = p.write_text("adc\\n300\\n301\\n")
    >>> read_adc_csv(p).tolist()
    [300, 301]
    """

    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:  # a byte order mark is not a column name
            rows = [(i + 1, [c.strip() for c in row]) for i, row in enumerate(csv.reader(fh))
                    if any(c.strip() for c in row) and not row[0].lstrip().startswith("#")]
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise DataError(f"{path}: cannot read: {getattr(err, 'strerror', None) or err}") from None
    if not rows or "adc" not in rows[0][1]:
        raise DataError(f"{path}, line {rows[0][0] if rows else 1}: no column 'adc' "
                        "(need a header naming adc, one ADC count 0..1023 per row)")
    col = rows[0][1].index("adc")
    out = np.empty(len(rows) - 1, dtype=np.int64)
    for k, (line, row) in enumerate(rows[1:]):
        cell = row[col] if col < len(row) else ""
        if not cell.isdigit() or int(cell) > ADC_MAX:
            raise DataError(f"{path}, line {line}: column 'adc' is not a count 0..{ADC_MAX}: {cell!r}")
        out[k] = int(cell)
    return out


def write_board_outputs(prefix, events, counts, commands) -> tuple[Any, Any]:
    """Write PREFIX.samples.csv (``sample, event``) and PREFIX.windows.csv
    (``window, v, command``): the board's outputs, as the simavr runner and
    ``slipreflex detect --board`` write them.

    Returns
    -------
    (Path, Path)
        The two files written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> prefix = pathlib.Path(tempfile.mkdtemp()) / "run"
    >>> res = run_board_chain([300] * 16)
    >>> s, w = write_board_outputs(prefix, res.events, res.counts, res.commands)
    >>> w.read_text().splitlines()
    ['window,v,command', '0,0,0']
    """


    events = np.asarray(events, dtype=np.int64)
    counts = np.asarray(counts, dtype=np.int64)
    samples_path, windows_path = Path(f"{prefix}.samples.csv"), Path(f"{prefix}.windows.csv")
    write_columns(samples_path, {"sample": np.arange(events.size), "event": events}, replace=False)
    write_columns(windows_path, {"window": np.arange(counts.size), "v": counts,
                                 "command": np.asarray(commands, dtype=np.int64)}, replace=False)
    return samples_path, windows_path


class CheckedBoardReflex(BoardReflex):
    """The twin of a board that runs the reflex itself, checking it on every sample.

    ``slipreflex run --board-reflex`` reads a board built with the reflex on board
    (version-2 frames: docs/wire-protocol.md) through a :class:`BoardSource`, which
    hands this reflex each sample's frame. :meth:`step` runs the twin on the sample and
    compares its filtered value, spike, fault flag, window, count and command with the
    board's. The command it returns is the twin's, equal to the board's while they agree.

    Attributes
    ----------
    last_board : dict or None
        The board's output for the last sample (``spike, window, fault, hand, v,
        command, x``) and ``match`` (whether the twin agreed).
    last_mismatch : str or None
        Set on the sample where board and twin start to disagree (one message per
        episode, naming the seq and the fields), else None.
    checked, mismatches : int
        Samples compared, and those that disagreed.

    Examples
    --------
    >>> from slipreflex.devices import wire
    >>> twin = CheckedBoardReflex(BoardParams.firmware(p0=0))
    >>> good = wire.ReflexFields(0, 0, 0, 300 << 16)
    >>> twin.take_frames([wire.decode_frame(wire.encode_frame(seq=0, adc=300, reflex=good))])
    >>> twin.step(300 * hw.ADC_LSB), twin.last_mismatch, twin.last_board["match"]
    (None, None, True)
    >>> bad = wire.ReflexFields(wire.REFLEX_SPIKE, 0, 0, 300 << 16)
    >>> twin.take_frames([wire.decode_frame(wire.encode_frame(seq=1, adc=300, reflex=bad))])
    >>> _ = twin.step(300 * hw.ADC_LSB); twin.last_mismatch
    'seq 1: the board says spike=True, the twin spike=False'
    """

    def __init__(self, params: BoardParams | None = None, **kwargs) -> None:
        super().__init__(params, **kwargs)

        self._frames: Any = deque()
        self._reset_check()

    def _reset_check(self) -> None:
        self._frames.clear()
        self.last_board: dict[str, Any] | None = None
        self.last_mismatch: str | None = None
        self.checked = self.mismatches = 0
        self._bad = False

    def reset(self) -> None:
        """Restore the initial state and forget pending frames and counters."""
        super().reset()
        self._reset_check()

    def take_frames(self, frames) -> None:
        """Queue the board's frames of the samples :meth:`step` will get next, in order."""
        self._frames.extend(frames)

    def _disagreement(self, frame) -> str | None:
        if frame is None:
            return "a sample came without its board frame (read the board through BoardSource)"
        r = frame.reflex
        if r is None:
            return (f"seq {frame.seq}: a version-1 frame: this board does not run the reflex "
                    "(flash daq-reflex or hand2560, docs/firmware.md)")
        if self.checked == 0 and frame.seq != 0:
            return (f"the board was running before the host connected (first seq {frame.seq}, not 0): "
                    "its chain state is unknown; reset the board")
        c = self.chain
        pairs = (("x", r.x, c.x), ("spike", r.spike, c.event), ("fault", r.fault, c.fault),
                 ("window", r.window, c.window), ("v", r.v, c.v), ("command", r.command, c.command))
        diff = [f"{k}={b}" for k, b, t in pairs if b != t]
        if not diff:
            return None
        twin = [f"{k}={t}" for k, b, t in pairs if b != t]
        return f"seq {frame.seq}: the board says {', '.join(diff)}, the twin {', '.join(twin)}"

    def step(self, sample: float, position: float | None = None) -> float | None:
        """Run the twin on one sample and compare it with the board's frame for it."""
        frame = self._frames.popleft() if self._frames else None
        cmd = super().step(sample, position)
        problem = self._disagreement(frame)
        self.checked += 1
        self.mismatches += problem is not None
        self.last_mismatch = problem if problem is not None and not self._bad else None
        self._bad = problem is not None
        r = frame.reflex if frame is not None else None
        self.last_board = None if r is None else {
            "spike": r.spike, "window": r.window, "fault": r.fault, "hand": r.hand, "v": r.v,
            "command": r.command, "x": r.x, "match": problem is None}
        return cmd


class BoardSource:
    """A :class:`~slipreflex.devices.daq.SerialDaq` that hands each sample's frame to a
    :class:`CheckedBoardReflex` (everything else is the reader's: stats, arrival times).

    Examples
    --------
    >>> import serial
    >>> from slipreflex.devices import wire
    >>> from slipreflex.devices.daq import SerialDaq
    >>> loop = serial.serial_for_url("loop://")
    >>> twin = CheckedBoardReflex(BoardParams.firmware())
    >>> src = BoardSource(SerialDaq(loop), twin)
    >>> _ = loop.write(wire.encode_frame(seq=0, adc=300, reflex=wire.ReflexFields(0, 0, 0, 300 << 16)))
    >>> [twin.step(s.slip_volts) for s in src.read(0.1)], twin.mismatches
    ([None], 0)
    >>> src.close(); loop.close()
    """

    def __init__(self, daq: Any, reflex: CheckedBoardReflex) -> None:
        self.daq, self.reflex = daq, reflex

    def read(self, timeout: float) -> list:
        """The reader's samples; their frames go to the reflex first."""
        samples = self.daq.read(timeout)
        if samples:
            self.reflex.take_frames(self.daq.last_frames)
        return samples

    def drop_buffered(self) -> int:
        """Drop nothing: the twin must see every frame from the board's seq 0 (``run_loop``
        calls this before its clock starts; the reader's own would bypass the twin)."""
        return 0

    def close(self) -> None:
        """Close the reader."""
        self.daq.close()

    def __getattr__(self, name: str) -> Any:
        return getattr(self.daq, name)


# --- the registry's board methods (slipreflex.methods names these by entry point) ------------

def build_board_method(dath: bool, p0: float, context: MethodContext, **params: Any) -> BoardReflex:
    """The registry's ``dath-board`` / ``fixed-board``: a :class:`BoardReflex` at the rounded ``p0``.

    Examples
    --------
    >>> build_board_method(True, 99.6, MethodContext()).params.p0
    100
    """
    return BoardReflex(**{"dath": dath, **params, "p0": int(np.floor(p0 + 0.5))})


def board_method_detections(reflex: BoardReflex, volts: np.ndarray) -> Detections:
    """What a trial figure draws for a board method: its Q16 low-pass and its spikes.

    Examples
    --------
    >>> board_method_detections(build_board_method(True, 100.0, MethodContext()), np.full(64, 0.4)).event_label
    'events (spikes)'
    """
    x, events = board_detections(reflex, volts)
    return Detections(x, "slip sensor on the board, Q16 low-pass (V)", events, "events (spikes)")
