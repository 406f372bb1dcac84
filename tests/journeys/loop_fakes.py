"""Fakes the journeys' loop tests share: a DAQ source that reads a still bottle, a hand that logs.

Examples
--------
>>> src = StillSource(); len(src.read(0.1)), src.now > 0
(4, True)
"""

from __future__ import annotations

from slipreflex.core.hardware import DAQ_PERIOD_S, Finger
from slipreflex.core.interfaces import DaqSample


class StillSource:
    """Four DAQ samples of 0.4 V per read, its clock advancing with them (``now``)."""

    def __init__(self):
        self.now, self.k = 0.0, 0

    def read(self, timeout):
        self.now += 4 * DAQ_PERIOD_S
        self.k += 4
        return [DaqSample(self.k + i, self.now, 0.4, None, 0) for i in range(4)]

    def close(self):
        pass


class LogHand:
    """Logs each CLOSE and STOP; a position command fails the test (the loop only ever adds grip)."""

    def __init__(self):
        self.log = []

    def set_positions(self, t):
        raise AssertionError("a position")

    def close_fingers(self, fingers, speed):
        self.log.append(("close", tuple(fingers)))

    def hold(self, fingers):
        self.log.append(("stop", tuple(fingers)))

    def positions(self):
        return {Finger.THUMB: 148.0, Finger.INDEX: 147.0, Finger.MIDDLE: 147.0}
