"""The standalone board's hand rule (``hand2560``): grip only added, CLOSE then STOP, never OPEN on a fault.

Re-exported by :mod:`slipreflex.methods.board`.

Examples
--------
>>> HAND_PWM > 0, GRIP_PER_UNIT > 0
(True, True)
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np

from ...core import hardware as hw
from ...core.errors import ParameterError
from ...core.validation import instance

if TYPE_CHECKING:
    pass

from .fixed import BoardParams, BoardResult

__all__ = [
    "grip_time_ratio", "GRIP_PER_UNIT", "GRIP_PER_SAMPLE", "HAND_PWM", "BoardHand", "HandTrace", "board_hand"
]


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


class BoardHand:
    """The standalone board's hand rule (``hand2560``): grip only added, as CLOSE and STOP.

    The twin of the hand code in ``firmware/src/main.c``. The MPI's command never
    reaches the hand as a position: a window whose command rises ``g`` units above the
    level already turned into grip owes ``g`` units of closing, i.e. ``g / 625`` s at
    full PWM (:data:`~slipreflex.core.hardware.FINGER_SPEED_UNITS_S`). The closing time still
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
    >>> from slipreflex.methods.board import run_board_chain
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
        >>> from slipreflex.methods.board import run_board_chain
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
    >>> from slipreflex.methods.board import run_board_chain
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


