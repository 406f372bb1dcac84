"""The i-Limb control unit's serial protocol and a driver for it (docs/method.md section 3).

A command packet is the start byte :data:`~slipreflex.core.hardware.ILIMB_START`, one
byte with the number of data bytes (4 per finger), then per finger
``{finger id, command, value MSB, value LSB}``, then the end byte
:data:`~slipreflex.core.hardware.ILIMB_END`; the port runs at
:data:`~slipreflex.core.hardware.ILIMB_BAUD` baud.

This module holds the one definition of that format: :func:`encode_packet`
(validates every finger id, command and value *before* producing a byte),
:class:`PacketParser` (the inverse, incremental and resynchronising, used by
the virtual hand and the tests), the :class:`ILimb` driver (a
:class:`~slipreflex.core.interfaces.Hand` on a pyserial port that survives the port
disappearing and coming back) and :func:`tripod_grasp`.

Examples
--------
>>> from slipreflex.core.hardware import Finger, HandCommand
>>> pkt = encode_packet([FingerCommand(Finger.MIDDLE, HandCommand.POSITION, 300)])
>>> pkt.hex(" ")
'24 04 02 03 01 2c 21'
>>> PacketParser().feed(pkt)
[(FingerCommand(finger=<Finger.MIDDLE: 2>, command=<HandCommand.POSITION: 3>, value=300),)]
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from ...core.errors import DeviceError, ParameterError
from ...core.hardware import (
    CONTACT_FORCE_N,
    FINGER_MAX,
    FINGER_MIN,
    FINGER_SPEED_UNITS_S,
    ILIMB_BAUD,
    ILIMB_END,
    ILIMB_START,
    PWM_MAX,
    THUMB_ROTATOR_MAX,
    TRIPOD,
    Finger,
    HandCommand,
)
from ...core.interfaces import GraspResult
from .port import ReconnectingPort

__all__ = [
    "FingerCommand", "value_range", "encode_packet", "PacketParser", "ILimb",
    "tripod_grasp", "GraspResult", "BYTES_PER_FINGER",
]

#: Data bytes per finger in a packet: id, command, value MSB, value LSB.
BYTES_PER_FINGER: int = 4
_MAX_FINGERS = len(Finger)


def value_range(finger: Finger, command: HandCommand) -> tuple[int, int]:
    """The inclusive range of the value field for ``finger`` and ``command``.

    Positions are 0..500 for the fingers and 0..750 for the thumb rotator;
    open/close take a PWM duty 0..297; stop takes 0. The wrist is driven only
    by open/close/stop (the protocol gives it no position range).

    Parameters
    ----------
    finger : Finger
    command : HandCommand

    Returns
    -------
    tuple of int
        ``(lo, hi)``, both inclusive.

    Raises
    ------
    ParameterError
        For a position command to the wrist.

    Examples
    --------
    >>> value_range(Finger.THUMB_ROTATOR, HandCommand.POSITION)
    (0, 750)
    >>> value_range(Finger.INDEX, HandCommand.CLOSE)
    (0, 297)
    """
    if command == HandCommand.STOP:
        return (0, 0)
    if command in (HandCommand.OPEN, HandCommand.CLOSE):
        return (0, PWM_MAX)
    if finger == Finger.THUMB_ROTATOR:
        return (FINGER_MIN, THUMB_ROTATOR_MAX)
    if finger == Finger.WRIST:
        raise ParameterError("i-Limb: the wrist takes no position command (use open/close/stop)")
    return (FINGER_MIN, FINGER_MAX)


@dataclass(frozen=True, slots=True)
class FingerCommand:
    """One finger's share of a packet, validated at construction.

    Parameters
    ----------
    finger : Finger or int
        Finger id 0..6.
    command : HandCommand or int
        0 stop, 1 close, 2 open, 3 position.
    value : int
        Position (0..500, thumb rotator 0..750) or PWM (0..297); 0 for stop.
        A float is accepted only if it is integral; round before.

    Raises
    ------
    ParameterError
        For an unknown finger or command, or a value out of its range; the
        message names the finger, command and range.

    Examples
    --------
    >>> FingerCommand(1, 3, 250)
    FingerCommand(finger=<Finger.INDEX: 1>, command=<HandCommand.POSITION: 3>, value=250)
    >>> FingerCommand(Finger.INDEX, HandCommand.POSITION, 501)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: i-Limb: INDEX POSITION value must be an integer in 0..500, got 501
    """

    finger: Finger
    command: HandCommand
    value: int

    def __post_init__(self) -> None:
        try:
            finger = Finger(self.finger)
        except ValueError:
            raise ParameterError(f"i-Limb: unknown finger id {self.finger!r} "
                                 f"(valid: {', '.join(f'{f.name}={f.value}' for f in Finger)})") from None
        try:
            command = HandCommand(self.command)
        except ValueError:
            raise ParameterError(f"i-Limb: unknown command {self.command!r} "
                                 f"(valid: {', '.join(f'{c.name}={c.value}' for c in HandCommand)})") from None
        lo, hi = value_range(finger, command)
        v = self.value
        ok = (not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v)
              and float(v).is_integer() and lo <= v <= hi)
        if not ok:
            raise ParameterError(f"i-Limb: {finger.name} {command.name} value must be an integer "
                                 f"in {lo}..{hi}, got {v!r}")
        object.__setattr__(self, "finger", finger)
        object.__setattr__(self, "command", command)
        object.__setattr__(self, "value", int(v))


def encode_packet(commands: Iterable[FingerCommand]) -> bytes:
    """Encode one packet for the control unit.

    Parameters
    ----------
    commands : iterable of FingerCommand
        One to seven commands, each finger at most once.

    Returns
    -------
    bytes

    Raises
    ------
    ParameterError
        For an empty packet, a repeated finger, or anything that is not a
        :class:`FingerCommand`.

    Examples
    --------
    >>> encode_packet([FingerCommand(0, 0, 0), FingerCommand(1, 1, 297)]).hex(" ")
    '24 08 00 00 00 00 01 01 01 29 21'
    """
    cmds = list(commands)
    if not cmds:
        raise ParameterError("i-Limb: a packet needs at least one finger command")
    seen: set[Finger] = set()
    body = bytearray()
    for c in cmds:
        if not isinstance(c, FingerCommand):
            raise ParameterError(f"i-Limb: expected FingerCommand, got {c!r}")
        if c.finger in seen:
            raise ParameterError(f"i-Limb: finger {c.finger.name} appears twice in one packet")
        seen.add(c.finger)
        body += bytes((c.finger, c.command, c.value >> 8, c.value & 0xFF))
    return bytes((ILIMB_START, len(body))) + bytes(body) + bytes((ILIMB_END,))


class PacketParser:
    """Incremental parser of i-Limb packets (the control unit's side).

    Feed it any byte chunks; it returns the complete, valid packets and skips
    garbage, counting what it skipped. A candidate packet is valid when its
    length byte is a non-zero multiple of 4 up to 28, its end byte is right,
    and every finger command is valid; otherwise the parser drops the start
    byte and searches again from the next byte.

    Attributes
    ----------
    packets : int
        Valid packets returned so far.
    rejected : int
        Candidate packets rejected (bad length, end byte or content).
    skipped_bytes : int
        Bytes discarded while resynchronising.

    Examples
    --------
    >>> p = PacketParser()
    >>> good = encode_packet([FingerCommand(2, 3, 10)])
    >>> [len(x) for x in p.feed(b"junk" + good[:3])], [len(x) for x in p.feed(good[3:])]
    ([], [1])
    >>> p.skipped_bytes
    4
    """

    def __init__(self) -> None:
        self._buf = bytearray()
        self.packets = 0
        self.rejected = 0
        self.skipped_bytes = 0

    def feed(self, data: bytes) -> list[tuple[FingerCommand, ...]]:
        """Add bytes; return the packets completed by them.

        Parameters
        ----------
        data : bytes

        Returns
        -------
        list of tuple of FingerCommand

        Examples
        --------
        >>> PacketParser().feed(bytes([0x24, 4, 2, 3, 0, 5, 0x21]))[0][0].value
        5
        """
        buf = self._buf
        buf += data
        out: list[tuple[FingerCommand, ...]] = []
        while buf:
            start = buf.find(ILIMB_START)
            if start < 0:
                self.skipped_bytes += len(buf)
                buf.clear()
                break
            if start:
                self.skipped_bytes += start
                del buf[:start]
            if len(buf) < 2:
                break
            n = buf[1]
            if n == 0 or n % BYTES_PER_FINGER or n > BYTES_PER_FINGER * _MAX_FINGERS:
                self._reject(buf)
                continue
            if len(buf) < n + 3:
                break
            if buf[n + 2] != ILIMB_END:
                self._reject(buf)
                continue
            try:
                cmds = tuple(FingerCommand(buf[i], buf[i + 1], (buf[i + 2] << 8) | buf[i + 3])  # pyright: ignore[reportArgumentType] (ints, converted and checked)
                             for i in range(2, n + 2, BYTES_PER_FINGER))
                if len({c.finger for c in cmds}) != len(cmds):
                    raise ParameterError("repeated finger")
            except ParameterError:
                self._reject(buf)
                continue
            del buf[:n + 3]
            self.packets += 1
            out.append(cmds)
        return out

    def _reject(self, buf: bytearray) -> None:
        self.rejected += 1
        self.skipped_bytes += 1
        del buf[:1]


class ILimb:
    """The i-Limb behind its control unit, on a serial port: a :class:`~slipreflex.core.interfaces.Hand`.

    Every command is validated before a byte is written. The port may
    disappear (unplugged, control unit reset): a failed write closes it,
    raises :class:`~slipreflex.core.errors.DeviceError` naming the port, and later
    calls try to reopen it (at most every ``reconnect_interval`` seconds),
    then re-send the latest targets so the hand never falls back to an older
    grip. The control unit reports no positions, so :meth:`positions`
    returns nothing (:meth:`targets` gives the last position targets written).

    While a reflex runs (:meth:`reflex_running`, the grip-only rule of
    :mod:`slipreflex.core.grip`) the driver refuses every command that could open
    a finger: OPEN, and a POSITION below the finger's last position target or
    for a finger that a CLOSE has since moved by an amount nobody measured.
    After a lost port it then re-sends STOP, never the old position targets.

    Parameters
    ----------
    port : str or serial.Serial
        A device path / pyserial URL (opened here, at ``ILIMB_BAUD``), or an
        already open port (its owner keeps the right to close it; not
        reopened on failure).
    write_timeout : float
        Seconds a write may block before it counts as a failure (a packet
        takes 1.7 ms at 115200 baud; a write blocks only when the port has
        stopped draining its buffer).
    reconnect_interval : float
        Minimum seconds between reopen attempts.

    Raises
    ------
    DeviceError
        If the port cannot be opened at construction.

    Examples
    --------
    >>> import serial
    >>> loop = serial.serial_for_url("loop://", timeout=0)
    >>> hand = ILimb(loop)
    >>> hand.set_positions({Finger.THUMB: 120, Finger.INDEX: 120.4})
    >>> PacketParser().feed(loop.read(100))[0][1]
    FingerCommand(finger=<Finger.INDEX: 1>, command=<HandCommand.POSITION: 3>, value=120)
    >>> hand.targets()[Finger.INDEX], hand.positions()
    (120.0, {})
    >>> hand.close(); loop.close()
    """

    def __init__(self, port: Any, *, write_timeout: float = 0.01,
                 reconnect_interval: float = 0.2) -> None:
        self._port = ReconnectingPort(port, what="i-Limb", baudrate=ILIMB_BAUD,
                                      write_timeout=write_timeout,
                                      reconnect_interval=reconnect_interval)
        self.port_name = self._port.port_name
        self.write_timeout = write_timeout
        self.reconnect_interval = reconnect_interval
        self._targets: dict[Finger, float] = {}
        self._reflex = False
        self._closed: set[Finger] = set()  # fingers a CLOSE moved while a reflex runs
        #: Packets written and write failures.
        self.packets_sent = 0
        self.write_failures = 0

    @property
    def reconnects(self) -> int:
        """Successful reopens of the port after a failure.

        Examples
        --------
        >>> import serial
        >>> ILimb(serial.serial_for_url("loop://")).reconnects
        0
        """
        return self._port.reconnects

    @property
    def connected(self) -> bool:
        """True while the port is open.

        Examples
        --------
        >>> import serial
        >>> h = ILimb(serial.serial_for_url("loop://")); h.connected
        True
        """
        return self._port.connected

    def _write(self, packet: bytes) -> None:
        import serial  # deferred: heavy (serial)

        if self._port.serial is None:
            if not self._port.ensure_open():
                raise DeviceError(f"{self.port_name}: i-Limb port is not connected")
            if self._reflex:  # back after a loss while a reflex runs: hold, never an old position
                self._write(encode_packet([FingerCommand(f, HandCommand.STOP, 0)
                                           for f in sorted(set(self._targets) | self._closed)]
                                          or [FingerCommand(f, HandCommand.STOP, 0) for f in TRIPOD]))
            elif self._targets:  # back after a loss: restore the whole grip first
                self._write(self._targets_packet(self._targets))
        try:
            self._port.write(packet)
        except (serial.SerialException, OSError) as err:
            self.write_failures += 1
            raise self._port.fail(err, "write failed") from None
        self.packets_sent += 1

    # -- commands ------------------------------------------------------------
    def send(self, commands: Sequence[FingerCommand]) -> None:
        """Validate, encode and write one packet.

        Parameters
        ----------
        commands : sequence of FingerCommand

        Raises
        ------
        ParameterError
            Invalid packet content (nothing is written).
        DeviceError
            The port is gone; it will be reopened on a later call.

        Examples
        --------
        >>> import serial
        >>> loop = serial.serial_for_url("loop://", timeout=0)
        >>> ILimb(loop).send([FingerCommand(Finger.WRIST, HandCommand.STOP, 0)])
        >>> loop.read(100).hex(" ")
        '24 04 06 00 00 00 21'
        """
        commands = list(commands)
        packet = encode_packet(commands)  # validates everything first
        if self._reflex:
            for c in commands:
                self._check_grip_only(c)
        self._write(packet)
        if self._reflex:
            self._closed.update(c.finger for c in commands if c.command == HandCommand.CLOSE)

    def _check_grip_only(self, c: FingerCommand) -> None:
        if c.command == HandCommand.OPEN:
            raise ParameterError(f"i-Limb: {c.finger.name} OPEN refused while a reflex runs "
                                 f"(grip is only ever added)")
        if c.command == HandCommand.POSITION:
            if c.finger in self._closed:
                raise ParameterError(f"i-Limb: {c.finger.name} POSITION {c.value} refused while a reflex "
                                     f"runs: a CLOSE moved the finger to a position the hand does not "
                                     f"report, so the target could open it")
            last = self._targets.get(c.finger)
            if last is None or c.value < last:
                why = "no target known" if last is None else f"below its target {last:g}"
                raise ParameterError(f"i-Limb: {c.finger.name} POSITION {c.value} refused while a reflex "
                                     f"runs ({why})")

    @staticmethod
    def _targets_packet(targets: Mapping[Finger, float]) -> bytes:
        return encode_packet([FingerCommand(f, HandCommand.POSITION, _round_position(f, v))
                              for f, v in targets.items()])

    def set_positions(self, targets: Mapping[Finger, float]) -> None:
        """Send position targets (rounded to the nearest integer).

        Parameters
        ----------
        targets : mapping of Finger to float
            Position per finger, within its range (0..500; rotator 0..750).

        Raises
        ------
        ParameterError
            A finger id or position out of range (nothing is written).
        DeviceError
            The port is gone (the targets are kept and re-sent on reconnect).

        Examples
        --------
        >>> import serial
        >>> loop = serial.serial_for_url("loop://", timeout=0)
        >>> ILimb(loop).set_positions({Finger.MIDDLE: 499.6})
        >>> PacketParser().feed(loop.read(100))[0][0].value
        500
        """
        fingers = {Finger(_finger_id(f)): v for f, v in targets.items()}
        packet = self._targets_packet(fingers)  # validates everything first
        if self._reflex:
            for f, v in fingers.items():
                self._check_grip_only(FingerCommand(f, HandCommand.POSITION, _round_position(f, v)))
        self._targets.update({f: float(_round_position(f, v)) for f, v in fingers.items()})
        self._write(packet)

    def hold(self, fingers: Iterable[Finger] = TRIPOD) -> None:
        """Stop the motors of ``fingers`` where they are (never opens the hand).

        Examples
        --------
        >>> import serial
        >>> loop = serial.serial_for_url("loop://", timeout=0)
        >>> ILimb(loop).hold([Finger.MIDDLE])
        >>> loop.read(100).hex(" ")
        '24 04 02 00 00 00 21'
        """
        self.send([FingerCommand(f, HandCommand.STOP, 0) for f in fingers])

    def close_fingers(self, fingers: Iterable[Finger], speed: float) -> None:
        """Close ``fingers`` at ``speed`` units/s until they are told to hold (CLOSE at a PWM duty).

        The duty is ``speed`` over the documented full-PWM speed
        (:data:`~slipreflex.core.hardware.FINGER_SPEED_UNITS_S`) times 297, rounded, at least 1.

        Raises
        ------
        ParameterError
            For a speed that is not a number > 0 (nothing is written).
        DeviceError
            The port is gone.

        Examples
        --------
        >>> import serial
        >>> loop = serial.serial_for_url("loop://", timeout=0)
        >>> ILimb(loop).close_fingers([Finger.MIDDLE], 625.0)
        >>> loop.read(100).hex(" ")
        '24 04 02 01 01 29 21'
        """
        if isinstance(speed, bool) or not isinstance(speed, (int, float)) or not (math.isfinite(speed)
                                                                                and speed > 0):
            raise ParameterError(f"i-Limb: closing speed must be a number > 0 units/s, got {speed!r}")
        pwm = min(PWM_MAX, max(1, int(round(speed / FINGER_SPEED_UNITS_S * PWM_MAX))))
        self.send([FingerCommand(f, HandCommand.CLOSE, pwm) for f in fingers])

    def reflex_running(self, running: bool = True) -> None:
        """Switch the grip-only guard on (a reflex runs) or off.

        While on, OPEN and any POSITION that could open a finger are refused with
        :class:`~slipreflex.core.errors.ParameterError` before a byte is written.

        Examples
        --------
        >>> import serial
        >>> hand = ILimb(serial.serial_for_url("loop://", timeout=0))
        >>> hand.set_positions({Finger.INDEX: 148}); hand.reflex_running()
        >>> hand.set_positions({Finger.INDEX: 140})
        Traceback (most recent call last):
        ...
        slipreflex.core.errors.ParameterError: i-Limb: INDEX POSITION 140 refused while a reflex runs (below its ...
        """
        self._reflex = bool(running)
        self._closed.clear()

    def targets(self) -> dict[Finger, float]:
        """The last position targets written, per finger (not a measurement).

        Examples
        --------
        >>> import serial
        >>> ILimb(serial.serial_for_url("loop://")).targets()
        {}
        """
        return dict(self._targets)

    def positions(self) -> dict[Finger, float]:
        """Measured positions: none, the control unit reports no positions.

        Examples
        --------
        >>> import serial
        >>> ILimb(serial.serial_for_url("loop://")).positions()
        {}
        """
        return {}

    def close(self) -> None:
        """Close the port if this driver opened it.

        Examples
        --------
        >>> import serial
        >>> h = ILimb(serial.serial_for_url("loop://")); h.close(); h.connected
        False
        """
        self._port.close()

    def __enter__(self) -> ILimb:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _finger_id(f: Any) -> int:
    try:
        return int(Finger(f))
    except (ValueError, TypeError):
        raise ParameterError(f"i-Limb: unknown finger id {f!r}") from None


def _round_position(finger: Finger, value: float) -> int:
    lo, hi = value_range(finger, HandCommand.POSITION)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(f"i-Limb: {finger.name} position must be a finite number, got {value!r}")
    v = int(math.floor(value + 0.5))
    if not lo <= v <= hi:
        raise ParameterError(f"i-Limb: {finger.name} POSITION value must be an integer in "
                             f"{lo}..{hi}, got {value!r}")
    return v


def tripod_grasp(hand: Any, contact_force: Callable[[], float], *,
                 force: float = CONTACT_FORCE_N, start: float = float(FINGER_MIN),
                 step: float = 5.0, settle: Callable[[], None] | None = None,
                 fingers: Sequence[Finger] = TRIPOD) -> GraspResult:
    """Close thumb, index and middle together until the contact force reaches ``force``.

    The paper closes the tripod until the tactile sensors on the index and
    thumb read 0.8 N (:data:`~slipreflex.core.hardware.CONTACT_FORCE_N`). Each
    iteration moves the fingers ``step`` position units further, calls
    ``settle()`` (let the hand move: sleep on hardware, advance the
    simulation in a simulator) and reads ``contact_force()``.

    Parameters
    ----------
    hand : Hand
        Anything with ``set_positions``.
    contact_force : callable
        Returns the current contact force in newtons (e.g. the smaller of
        the index and thumb readings).
    force : float
        Target contact force (N).
    start, step : float
        First position and increment (position units); ``step > 0``.
    settle : callable, optional
        Called after each increment, before the force is read.
    fingers : sequence of Finger
        Fingers closed together (default: the tripod).

    Returns
    -------
    GraspResult
        The commanded positions where closing stopped and the tactile reading then
        (``stable`` is None: the hardware cannot tell).

    Raises
    ------
    ParameterError
        For ``step <= 0`` or ``force <= 0``.

    Examples
    --------
    >>> class Toy:                    # contact begins at position 200, 0.02 N per unit
    ...     pos = 0.0
    ...     def set_positions(self, t): self.pos = max(t.values())
    >>> toy = Toy()
    >>> r = tripod_grasp(toy, lambda: max(0.0, (toy.pos - 200) * 0.02))
    >>> r.position, r.contact
    (240.0, True)
    """
    if not (math.isfinite(step) and step > 0):
        raise ParameterError(f"tripod_grasp: step must be > 0, got {step!r}")
    if not (math.isfinite(force) and force > 0):
        raise ParameterError(f"tripod_grasp: force must be > 0, got {force!r}")
    pos = float(start)
    steps = 0
    f = float(contact_force())
    while f < force and pos < FINGER_MAX:
        pos = min(float(FINGER_MAX), pos + step)
        hand.set_positions({finger: pos for finger in fingers})
        steps += 1
        if settle is not None:
            settle()
        f = float(contact_force())
    return GraspResult(position=pos, force_n=f, positions={finger: pos for finger in fingers}, contact=f >= force,
                       steps=steps)
