"""The simulated i-Limb of a rig (:attr:`slipreflex.sim.Rig.hand`): position servos, a speed limit and a latency."""

from __future__ import annotations

import bisect
import math
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING

import numpy as np

from ..core import hardware as hw
from ..core.errors import ParameterError
from ..core.hardware import Finger, HandCommand
from .params import (
    HandParams,
)
from .stepping import STEP_ROUND as _ROUND

if TYPE_CHECKING:
    from .rig import Rig

__all__ = ["SimHand"]


class SimHand:
    """The simulated i-Limb: position servos with a speed limit and a command latency.

    Implements :class:`slipreflex.core.interfaces.Hand`. Commands take effect
    ``latency`` seconds after they are given (rig time). Thumb, index and
    middle are simulated with their dynamics; the other digits, the thumb
    rotator and the wrist just take their targets after the latency.
    Besides position targets it accepts the i-Limb's close / open / stop
    commands with a PWM speed (0..297).

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> from slipreflex.core.interfaces import Hand
    >>> rig = Rig("TR")
    >>> isinstance(rig.hand, Hand)
    True
    >>> rig.hand.set_positions({Finger.THUMB: 100})
    >>> _ = rig.advance(0.5)
    >>> rig.hand.positions()[Finger.THUMB]
    100.0
    """

    def __init__(self, rig: Rig, params: HandParams) -> None:
        self._rig = rig
        self.params = params
        self._pending: list[tuple[int, int, HandCommand, tuple[Finger, ...], float]] = []
        self._count = 0
        self._others: dict[Finger, float] = {f: 0.0 for f in Finger if f not in hw.TRIPOD}
        #: When the closing a closed loop started for each finger ends (rig time, s; the grip
        #: rule of :mod:`slipreflex.core.grip`: a later rise extends it rather than cutting it short).
        self.closing_until: dict[Finger, float] = {}
        #: Servo targets and speed limits of thumb, index and middle (the rig hands them to the physics).
        self.targets = np.zeros(len(hw.TRIPOD))
        self.speeds = np.full(len(hw.TRIPOD), params.speed_units_s)

    @property
    def latency(self) -> float:
        """Command latency (s).

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> Rig("TR").hand.latency
        0.01
        """
        return self.params.latency_s

    def command(self, kind: HandCommand, fingers: Iterable[Finger], value: float = 0.0,
                at: float | None = None) -> None:
        """Queue one i-Limb command for some fingers.

        Parameters
        ----------
        kind : HandCommand
            POSITION (value = target 0..500, rounded to whole units as the
            packet carries them), CLOSE / OPEN (value = PWM 0..297, the
            speed), or STOP (hold the whole-unit position the finger has when
            the command arrives).
        fingers : iterable of Finger
        value : float
        at : float, optional
            Time the command is sent (default: now). Must not be before the
            rig's time minus the latency.

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> rig = Rig("TR")
        >>> rig.hand.command(HandCommand.CLOSE, [Finger.INDEX], 297)
        >>> _ = rig.advance(0.2)
        >>> 110 < rig.hand.positions()[Finger.INDEX] < 125
        True
        """
        kind = HandCommand(kind)
        fingers = tuple(Finger(f) for f in fingers)
        if not math.isfinite(value):
            raise ParameterError(f"hand command value must be finite, got {value!r}")
        sent = self._rig.t if at is None else float(at)
        dt = self._rig.physics.dt
        step = max(int(math.ceil((sent + self.params.latency_s) / dt - _ROUND)), self._rig.step_index)
        bisect.insort(self._pending, (step, self._count, kind, fingers, float(value)))
        self._count += 1

    def set_positions(self, targets: Mapping[Finger, float], at: float | None = None) -> None:
        """Position targets (0..500, clipped) for the named fingers.

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> Rig("TR").hand.set_positions({Finger.MIDDLE: 250})
        """
        by_value: dict[float, list[Finger]] = {}
        for f, v in targets.items():
            by_value.setdefault(float(v), []).append(f)
        for v, fingers in by_value.items():
            self.command(HandCommand.POSITION, fingers, v, at=at)

    def close_fingers(self, fingers: Iterable[Finger], speed: float, at: float | None = None) -> None:
        """CLOSE ``fingers`` at ``speed`` units/s (the PWM duty ``speed / speed_units_s * 297``).

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> rig = Rig("TR"); rig.hand.close_fingers([Finger.INDEX], 625.0)
        >>> rig.hand.queue()[0][0][2:]
        (<HandCommand.CLOSE: 1>, (<Finger.INDEX: 1>,), 297.0)
        """
        if not (math.isfinite(speed) and speed > 0):
            raise ParameterError(f"closing speed must be a number > 0 units/s, got {speed!r}")
        pwm = min(float(hw.PWM_MAX), speed / self.params.speed_units_s * hw.PWM_MAX)
        self.command(HandCommand.CLOSE, fingers, pwm, at=at)

    def hold(self, fingers: Iterable[Finger], at: float | None = None) -> None:
        """STOP ``fingers`` where they are.

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> rig = Rig("TR"); rig.hand.hold([Finger.INDEX]); rig.hand.queue()[0][0][2]
        <HandCommand.STOP: 0>
        """
        self.command(HandCommand.STOP, fingers, 0.0, at=at)

    def positions(self) -> dict[Finger, float]:
        """Measured positions (rounded to whole units, as the control unit reports them).

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> Rig("TR").hand.positions()[Finger.INDEX]
        0.0
        """
        q = self._rig.finger_q
        out = {f: float(round(q[i])) for i, f in enumerate(hw.TRIPOD)}
        out.update({f: float(round(v)) for f, v in self._others.items()})
        return dict(sorted(out.items()))

    def queue(self) -> tuple[list[tuple[int, int, HandCommand, tuple[Finger, ...], float]], int]:
        """The pending commands (due step, sequence number, kind, fingers, value), in order, and the next number.

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> rig = Rig("TR"); rig.hand.set_positions({Finger.INDEX: 10})
        >>> rig.hand.queue()
        ([(100, 0, <HandCommand.POSITION: 3>, (<Finger.INDEX: 1>,), 10.0)], 1)
        """
        return list(self._pending), self._count

    def restore_queue(self, pending: list[tuple[int, int, HandCommand, tuple[Finger, ...], float]],
                      count: int) -> None:
        """Replace the pending commands and the next sequence number (what a compiled loop hands back).

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> rig = Rig("TR"); rig.hand.set_positions({Finger.INDEX: 10})
        >>> rig.hand.restore_queue([], 1); rig.hand.next_due_step() is None
        True
        """
        self._pending = sorted(pending)
        self._count = int(count)

    def next_due_step(self) -> int | None:
        """Physics step at which the next queued command takes effect (None: nothing queued).

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> rig = Rig("TR"); rig.hand.set_positions({Finger.INDEX: 10}); rig.hand.next_due_step()
        100
        """
        return self._pending[0][0] if self._pending else None

    def apply_due(self, n: int) -> bool:
        """Carry out the commands due by physics step ``n`` (called by the rig); True if any was.

        Updates :attr:`targets` and :attr:`speeds` of the tripod fingers.

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> rig = Rig("TR"); rig.hand.set_positions({Finger.INDEX: 10})
        >>> rig.hand.apply_due(99), rig.hand.apply_due(100), float(rig.hand.targets[1])
        (False, True, 10.0)
        """
        if not (self._pending and self._pending[0][0] <= n):
            return False
        p = self.params
        q = self._rig.finger_q
        tgt, spd = self.targets, self.speeds
        while self._pending and self._pending[0][0] <= n:
            _, _, kind, fingers, value = self._pending.pop(0)
            for f in fingers:
                if f in hw.TRIPOD:
                    i = hw.TRIPOD.index(f)
                    if kind == HandCommand.POSITION:
                        # the packet carries whole units (value MSB, LSB)
                        tgt[i] = min(max(round(value), hw.FINGER_MIN), hw.FINGER_MAX)
                        spd[i] = p.speed_units_s
                    elif kind in (HandCommand.CLOSE, HandCommand.OPEN):
                        tgt[i] = hw.FINGER_MAX if kind == HandCommand.CLOSE else hw.FINGER_MIN
                        spd[i] = p.speed_units_s * min(max(value, 0.0), hw.PWM_MAX) / hw.PWM_MAX
                    else:
                        # STOP: the digit controller holds its encoder count (whole units)
                        tgt[i] = round(q[i])
                        spd[i] = p.speed_units_s
                else:
                    top = hw.THUMB_ROTATOR_MAX if f == Finger.THUMB_ROTATOR else hw.FINGER_MAX
                    if kind == HandCommand.POSITION:
                        self._others[f] = min(max(value, 0.0), top)
                    elif kind == HandCommand.CLOSE:
                        self._others[f] = float(top)
                    elif kind == HandCommand.OPEN:
                        self._others[f] = 0.0
        return True
