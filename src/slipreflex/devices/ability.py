"""The PSYONIC Ability Hand on its UART: the extended API, a driver, and its touch sensors.

Written from the hand's published interface control document (the Ability Hand ICD,
sections 3.3-3.5: extended API frames, position data, touch sensor data, checksums,
PPP byte stuffing); nothing here depends on PSYONIC's own Python wrapper.

Frames
    Every frame is byte-stuffed (ICD 3.5.5): it starts and ends with 0x7E, and a 0x7E or
    0x7D inside it is sent as 0x7D followed by the byte XOR 0x20. Inside: the hand's
    slave address (0x50 by default), a format header, the data, and a checksum that makes
    the 8-bit sum of the frame zero (ICD 3.4.8).
Commands (host -> hand)
    Position mode, header ``0x10 + variant``: six int16 little-endian positions,
    ``degrees * 32767 / 150``, in the hand's order index, middle, ring, pinky, thumb
    flexor, thumb rotator (the rotator's angles are negative). Velocity mode, header
    ``0x20 + variant``: six int16 velocities, ``degrees/s * 32767 / 3000`` (ICD 3.4.2;
    positive closes). Read-only mode, header ``0xA0 + variant``: no data; the hand replies
    without changing what it does.
Replies (hand -> host), variant 0 (the ICD's "variant 1")
    header, then per finger position and motor current (int16 each, 24 bytes), then the
    30 touch sites as 12-bit values packed two per three bytes (45 bytes; 6 sites per
    finger, index first, thumb last), a hot/cold status byte and the checksum.
Touch sensors
    FSRs: ``V = D * 3.3 / 4096``, ``R = 33000 / V + 10000`` ohm, and the ICD's placeholder
    calibration ``F = C1 / R + C2`` newtons (C1 = 121591, C2 = 0.878894; "a rough
    approximation", ICD 3.4.6). A raw value of 0 reads as 0 N.

Positions in this package are finger units, 0 (open) .. 500 (closed), the same for every
hand (:data:`slipreflex.hardware.FINGER_MAX`); this driver maps them linearly onto
0 .. :data:`FULL_CLOSE_DEG` degrees of flexion (the thumb rotator onto 0 .. minus that).

Examples
--------
>>> frame = encode_positions([30.0, 30.0, 30.0, 30.0, 30.0, -30.0])
>>> frame[0], frame[-1], len(unstuff(frame)[0])          # delimiters; address + header + 12 + sum
(126, 126, 15)
>>> round(decode_command(unstuff(frame)[0])[2][0], 2)
30.0
>>> reply = decode_reply(unstuff(encode_reply([10.0] * 5 + [-10.0], touch=[0, 2048] * 15))[0])
>>> round(reply.positions[0], 2), reply.touch[:2]
(10.0, (0, 2048))
"""

from __future__ import annotations

import collections
import math
import struct
import threading
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import DataError, DeviceError, ParameterError
from ..hardware import FINGER_MAX, FINGER_MIN, PWM_MAX, Finger, HandCommand
from ..interfaces import TactileSample
from .port import ReconnectingPort

__all__ = ["ABILITY_BAUD", "ADDRESS", "ORDER", "TOUCH_FINGERS", "SITES", "FULL_CLOSE_DEG",
           "checksum", "stuff", "unstuff", "Unstuffer", "encode_positions", "encode_velocities", "encode_read",
           "decode_command", "AbilityReply", "decode_reply", "encode_reply", "touch_newtons",
           "touch_counts", "degrees_of", "units_of", "AbilityHand", "API_TIMEOUT_S", "KEEPALIVE_S",
           "stalled_fingers"]

#: UART baud rate of the hand (ICD 3.1: the default of the flash setting).
ABILITY_BAUD: int = 460800
#: Default slave address (ICD 3.1).
ADDRESS: int = 0x50
#: The hand's finger order in every frame.
ORDER: tuple[Finger, ...] = (Finger.INDEX, Finger.MIDDLE, Finger.RING, Finger.LITTLE, Finger.THUMB,
                             Finger.THUMB_ROTATOR)
#: Fingers with touch sites, in frame order; 6 sites each.
TOUCH_FINGERS: tuple[Finger, ...] = ORDER[:5]
SITES: int = 6
#: Degrees of flexion that finger unit 500 means. Estimate: the ICD says out-of-range commands
#: are truncated to each finger's limit without listing the limits; its examples command up
#: to 90 degrees, and 100 keeps 0..500 inside the fingers' travel with the hand doing the clipping.
FULL_CLOSE_DEG: float = 100.0
_SCALE = 32767 / 150  # int16 counts per degree (ICD 3.4.1)
_FRAME, _ESC, _MASK = 0x7E, 0x7D, 0x20
_POSITION, _VELOCITY, _READ = 0x10, 0x20, 0xA0
_VSCALE = 32767 / 3000  # int16 counts per degree per second (ICD 3.4.2)
#: Seconds of silence after which the hand leaves API mode (PSYONIC's manual: about 300 ms,
#: "may be accompanied by undesired finger movements").
API_TIMEOUT_S: float = 0.3
#: The driver's longest silence (s): a read-only request at least this often, a sixth of the timeout.
KEEPALIVE_S: float = 0.05
#: Frames the driver keeps for :meth:`AbilityHand.read_frames` (about 15 s at 260 Hz).
_FRAME_BACKLOG = 4096
_REPLY_LEN = 1 + 24 + 45 + 1  # header, position/current pairs, touch, status (checksum apart)
_FSR_C1, _FSR_C2 = 121591.0, 0.878894
_ADC_V, _ADC_COUNTS, _R_TOP, _R_BOTTOM = 3.3, 4096, 33000.0, 10000.0


def checksum(data: bytes | Iterable[int]) -> int:
    """The byte that makes the 8-bit sum of ``data`` plus it zero (ICD 3.4.8).

    Examples
    --------
    >>> (sum(b"\\x50\\x10") + checksum(b"\\x50\\x10")) % 256
    0
    """
    return -sum(data) & 0xFF


def stuff(payload: bytes) -> bytes:
    """PPP byte stuffing: delimiters and escapes (ICD 3.5.5).

    Examples
    --------
    >>> stuff(bytes([1, 0x7E, 0x7D])).hex(" ")
    '7e 01 7d 5e 7d 5d 7e'
    """
    out = bytearray([_FRAME])
    for b in payload:
        if b in (_FRAME, _ESC):
            out += bytes([_ESC, b ^ _MASK])
        else:
            out.append(b)
    out.append(_FRAME)
    return bytes(out)


class Unstuffer:
    """Stateful inverse of :func:`stuff`: bytes in, whole frames out.

    Attributes
    ----------
    frames, discarded : int
        Frames returned; bytes thrown away (between frames, or a frame over 512 bytes).

    Examples
    --------
    >>> u = Unstuffer(); f = stuff(b"\\x50\\x10\\x7e")
    >>> u.feed(f[:3]), u.feed(f[3:])
    ([], [b'P\\x10~'])
    """

    _MAX = 512

    def __init__(self) -> None:
        self._buf = bytearray()
        self._esc = False
        self._inside = False
        self.frames = 0
        self.discarded = 0

    def feed(self, data: bytes) -> list[bytes]:
        out = []
        for b in data:
            if b == _FRAME:
                if self._inside and len(self._buf) > 1:
                    out.append(bytes(self._buf))
                    self.frames += 1
                self._buf.clear()
                self._inside, self._esc = True, False
                continue
            if not self._inside:
                self.discarded += 1
                continue
            if b == _ESC:
                self._esc = True
                continue
            if self._esc:
                b ^= _MASK
                self._esc = False
            self._buf.append(b)
            if len(self._buf) > self._MAX:
                self.discarded += len(self._buf)
                self._buf.clear()
                self._inside = False
        return out


def unstuff(data: bytes) -> list[bytes]:
    """The frames in ``data`` (see :class:`Unstuffer`).

    Examples
    --------
    >>> unstuff(stuff(b"ab") + stuff(b"cd"))
    [b'ab', b'cd']
    """
    return Unstuffer().feed(data)


def _framed(body: bytes) -> bytes:
    return stuff(body + bytes([checksum(body)]))


def _variant(variant: int) -> int:
    if variant not in (0, 1, 2):
        raise ParameterError(f"Ability Hand reply variant must be 0, 1 or 2, got {variant!r}")
    return variant


def encode_positions(degrees: Sequence[float], variant: int = 0, address: int = ADDRESS) -> bytes:
    """A position command: six angles in degrees, in :data:`ORDER`.

    Raises
    ------
    ParameterError
        Not six finite angles, or an angle outside +-150 degrees (the int16 range).

    Examples
    --------
    >>> encode_positions([0] * 6).hex(" ")
    '7e 50 10 00 00 00 00 00 00 00 00 00 00 00 00 a0 7e'
    """
    vals = [float(d) for d in degrees]
    if len(vals) != len(ORDER) or not all(math.isfinite(v) and abs(v) <= 150.0 for v in vals):
        raise ParameterError(f"Ability Hand position command needs 6 angles within +-150 degrees, got {vals}")
    body = struct.pack("<BB6h", address, _POSITION + _variant(variant), *(round(v * _SCALE) for v in vals))
    return _framed(body)


def encode_velocities(deg_s: Sequence[float], variant: int = 0, address: int = ADDRESS) -> bytes:
    """A velocity command: six speeds in degrees per second, in :data:`ORDER` (positive closes).

    Raises
    ------
    ParameterError
        Not six finite speeds within +-3000 degrees/s.

    Examples
    --------
    >>> body = unstuff(encode_velocities([100.0, 0, 0, 0, 0, 0]))[0]
    >>> hex(body[1]), round(decode_command(body)[2][0], 1)
    ('0x20', 100.0)
    """
    vals = [float(v) for v in deg_s]
    if len(vals) != len(ORDER) or not all(math.isfinite(v) and abs(v) <= 3000.0 for v in vals):
        raise ParameterError(f"Ability Hand velocity command needs 6 speeds within +-3000 degrees/s, got {vals}")
    body = struct.pack("<BB6h", address, _VELOCITY + _variant(variant), *(round(v * _VSCALE) for v in vals))
    return _framed(body)


def encode_read(variant: int = 0, address: int = ADDRESS) -> bytes:
    """A read-only request: the hand replies and keeps doing what it does.

    Examples
    --------
    >>> encode_read().hex(" ")
    '7e 50 a0 10 7e'
    """
    return _framed(struct.pack("<BB", address, _READ + _variant(variant)))


def decode_command(frame: bytes) -> tuple[int, int, list[float] | None]:
    """``(address, header, values or None)`` of a command frame (the hand's side): degrees for
    a position frame, degrees per second for a velocity frame, None for any other.

    Raises
    ------
    DataError
        A bad checksum or a position frame of the wrong size.

    Examples
    --------
    >>> decode_command(unstuff(encode_read())[0])
    (80, 160, None)
    """
    if len(frame) < 3 or sum(frame) & 0xFF:
        raise DataError(f"Ability Hand command frame fails its checksum: {frame.hex(' ')}")
    address, header = frame[0], frame[1]
    if header & 0xF0 in (_POSITION, _VELOCITY):
        if len(frame) != 15:
            raise DataError(f"Ability Hand position or velocity frame has {len(frame)} bytes, not 15")
        scale = _SCALE if header & 0xF0 == _POSITION else _VSCALE
        return address, header, [v / scale for v in struct.unpack("<6h", frame[2:14])]
    return address, header, None


@dataclass(frozen=True, slots=True)
class AbilityReply:
    """One decoded reply (variant 0).

    Attributes
    ----------
    header : int
    positions : tuple of float
        Degrees, in :data:`ORDER`.
    currents : tuple of float
        Raw int16 motor currents, in :data:`ORDER`.
    touch : tuple of int
        The 30 raw 12-bit touch values (6 per finger of :data:`TOUCH_FINGERS`).
    status : int
        Hot/cold status byte.

    Examples
    --------
    >>> AbilityReply(0x10, (0.0,) * 6, (0,) * 6, (0,) * 30, 0).status
    0
    """

    header: int
    positions: tuple[float, ...]
    currents: tuple[int, ...]
    touch: tuple[int, ...]
    status: int


def _pack_touch(counts: Sequence[int]) -> bytes:
    out = bytearray()
    for a, b in zip(counts[0::2], counts[1::2]):
        out += bytes([a & 0xFF, ((a >> 8) & 0x0F) | ((b & 0x0F) << 4), (b >> 4) & 0xFF])
    return bytes(out)


def _unpack_touch(data: bytes) -> tuple[int, ...]:
    out = []
    for k in range(0, len(data), 3):
        b0, b1, b2 = data[k], data[k + 1], data[k + 2]
        out += [b0 | ((b1 & 0x0F) << 8), (b1 >> 4) | (b2 << 4)]
    return tuple(out)


def decode_reply(frame: bytes) -> AbilityReply:
    """Decode a variant-0 reply (after :func:`unstuff`).

    Raises
    ------
    DataError
        Wrong length or checksum (the message says which).

    Examples
    --------
    >>> decode_reply(b"\\x10\\x00")
    Traceback (most recent call last):
    ...
    slipreflex.errors.DataError: Ability Hand reply has 2 bytes, not 72 (variant 0)
    """
    if len(frame) != _REPLY_LEN + 1:
        raise DataError(f"Ability Hand reply has {len(frame)} bytes, not {_REPLY_LEN + 1} (variant 0)")
    if sum(frame) & 0xFF:
        raise DataError("Ability Hand reply fails its checksum")
    vals = struct.unpack("<12h", frame[1:25])
    return AbilityReply(frame[0], tuple(v / _SCALE for v in vals[0::2]), tuple(vals[1::2]),
                        _unpack_touch(frame[25:70]), frame[70])


def encode_reply(degrees: Sequence[float], currents: Sequence[int] = (0,) * 6,
                 touch: Sequence[int] = (0,) * 30, status: int = 0, header: int = _POSITION) -> bytes:
    """A variant-0 reply as the hand sends it (the virtual hand's side).

    Examples
    --------
    >>> len(unstuff(encode_reply([0.0] * 6))[0])
    72
    """
    counts = [int(min(max(c, 0), 4095)) for c in touch]
    if len(counts) != 30 or len(degrees) != 6 or len(currents) != 6:
        raise ParameterError("Ability Hand reply needs 6 angles, 6 currents and 30 touch values")
    pairs = [v for d, c in zip(degrees, currents) for v in (round(d * _SCALE), int(c))]
    body = struct.pack("<B12h", header, *pairs) + _pack_touch(counts) + bytes([status & 0xFF])
    return stuff(body + bytes([checksum(body)]))


def touch_newtons(counts: Sequence[int] | np.ndarray) -> np.ndarray:
    """Raw touch values -> newtons by the ICD's FSR law (0 stays 0).

    Examples
    --------
    >>> touch_newtons([0, 4095]).round(3).tolist()
    [0.0, 6.958]
    """
    d = np.asarray(counts, dtype=np.float64)
    with np.errstate(divide="ignore"):
        r = _R_TOP / (d * _ADC_V / _ADC_COUNTS) + _R_BOTTOM
        f = _FSR_C1 / r + _FSR_C2
    return np.where(d > 0, f, 0.0)


def touch_counts(newtons: Sequence[float] | np.ndarray) -> np.ndarray:
    """Newtons -> the raw value whose :func:`touch_newtons` is nearest (the virtual hand's side).

    Forces below the law's offset (C2) read 0; forces above full scale read 4095.

    Examples
    --------
    >>> touch_counts(touch_newtons([0, 1, 2048, 4095])).tolist()
    [0, 1, 2048, 4095]
    """
    f = np.asarray(newtons, dtype=np.float64)
    grid = touch_newtons(np.arange(_ADC_COUNTS))
    k = np.clip(np.searchsorted(grid[1:], f), 0, _ADC_COUNTS - 2) + 1
    lower = np.clip(k - 1, 1, _ADC_COUNTS - 1)
    k = np.where(np.abs(grid[lower] - f) <= np.abs(grid[k] - f), lower, k)
    return np.where(f < _FSR_C2, 0, k).astype(int)


def degrees_of(finger: Finger, units: float) -> float:
    """Finger units (0..500) -> the hand's degrees.

    Examples
    --------
    >>> degrees_of(Finger.INDEX, 250), degrees_of(Finger.THUMB_ROTATOR, 250)
    (50.0, -50.0)
    """
    deg = units * FULL_CLOSE_DEG / FINGER_MAX
    return -deg if finger == Finger.THUMB_ROTATOR else deg


def units_of(finger: Finger, degrees: float) -> float:
    """The hand's degrees -> finger units.

    Examples
    --------
    >>> units_of(Finger.THUMB_ROTATOR, -50.0)
    250.0
    """
    d = -degrees if finger == Finger.THUMB_ROTATOR else degrees
    return d * FINGER_MAX / FULL_CLOSE_DEG


class AbilityHand:
    """The Ability Hand on a serial port: a :class:`~slipreflex.interfaces.Hand` and a
    :class:`~slipreflex.interfaces.TactileSource` (one finger's 6 touch sites per frame).

    As PSYONIC's own wrapper runs it: a thread of the driver (the pump) reads the replies
    continuously and, whenever nothing was written for one period (``1 / fs``, at most
    ``keepalive``), writes a read-only request, so the hand hears from the host well inside its
    API timeout (:data:`API_TIMEOUT_S`) whether or not the loop sends anything, and
    :meth:`positions` is the newest reply's in every run, not only when tactile frames are
    read. Every reply is a frame (it carries the touch sites), so a command's reply stands
    for that period's request and the frames stay near ``fs``.

    At construction it asks the hand for one reply (read-only mode) and fails unless one
    comes: every later command then starts from the fingers' measured positions, so a
    command never moves a finger it does not name. The reply's status byte is read: a
    finger whose bit is set has stalled (collision): the hand ignores further closing of it
    until it is opened (:meth:`stalled`).

    Parameters
    ----------
    port : str or serial.Serial
    fs : float
        Rate (Hz) of the read-only requests.
    tactile_finger : Finger
        The finger whose touch sites are the tactile frame (index by default, as the
        paper's tactile array).
    reply_timeout : float
        Seconds to wait for the first reply.
    write_timeout, reconnect_interval : float
        As :class:`~slipreflex.devices.ilimb.ILimb`.
    keepalive : float
        Longest silence (s) the driver leaves the hand in (0 < keepalive <= API_TIMEOUT_S / 3).

    Attributes
    ----------
    shape : tuple of int
        Shape of a tactile frame: ``(6,)``.
    replies, bad_replies, requests : int

    Raises
    ------
    DeviceError
        The port cannot be opened, or the hand does not reply (the message names the port).

    Examples
    --------
    >>> AbilityHand("/nonexistent/tty")           # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipreflex.errors.DeviceError: /nonexistent/tty: cannot open Ability Hand port: ...
    """

    def __init__(self, port: Any, *, fs: float = 260.0, tactile_finger: Finger = Finger.INDEX,
                 reply_timeout: float = 1.0, write_timeout: float = 0.01,
                 reconnect_interval: float = 0.2, keepalive: float = KEEPALIVE_S) -> None:
        if not (math.isfinite(fs) and fs > 0):
            raise ParameterError(f"Ability Hand: fs must be > 0 Hz, got {fs!r}")
        if not (math.isfinite(keepalive) and 0 < keepalive <= API_TIMEOUT_S / 3):
            raise ParameterError(f"Ability Hand: keepalive must be in (0, {API_TIMEOUT_S / 3:g}] s "
                                 f"(well inside the hand's API timeout), got {keepalive!r}")
        if Finger(tactile_finger) not in TOUCH_FINGERS:
            raise ParameterError(f"Ability Hand: {Finger(tactile_finger).name.lower()} has no touch sites")
        self._port = ReconnectingPort(port, what="Ability Hand", baudrate=ABILITY_BAUD,
                                      write_timeout=write_timeout, reconnect_interval=reconnect_interval)
        self.port_name = self._port.port_name
        self.fs = float(fs)
        self.shape = (SITES,)
        self._period = min(1.0 / self.fs, float(keepalive))
        self._site0 = TOUCH_FINGERS.index(Finger(tactile_finger)) * SITES
        self._unstuffer = Unstuffer()
        self._measured: dict[Finger, float] = {}
        self._stalled: frozenset[Finger] = frozenset()
        self._targets: dict[Finger, float] = {}
        self._closing: dict[Finger, float] = {}  # finger -> closing speed, degrees/s
        self._reflex = False  # the grip-only guard (reflex_running)
        self._wlock = threading.Lock()  # writes: the loop's commands and the pump's requests
        self._arrived = threading.Condition()
        self._frames: collections.deque[TactileSample] = collections.deque(maxlen=_FRAME_BACKLOG)
        self._error: DeviceError | None = None
        self._stop = threading.Event()
        self._last_write = -math.inf
        self._t0 = time.perf_counter()
        self._seq = 0
        self.replies = self.bad_replies = self.requests = 0
        self.last_reply: AbilityReply | None = None
        self.last_arrival = math.nan
        deadline = time.monotonic() + reply_timeout
        try:
            self._write(encode_read())
            while self.last_reply is None and time.monotonic() < deadline:
                self._receive(0.02)
        except DeviceError:
            self._port.close()
            raise
        if self.last_reply is None:
            self._port.close()
            raise DeviceError(f"{self.port_name}: no reply from an Ability Hand within {reply_timeout:g} s "
                              f"(UART API with byte stuffing on, {ABILITY_BAUD} baud?)")
        self._pump = threading.Thread(target=self._pump_run, name="ability-hand-pump", daemon=True)
        self._pump.start()

    # -- bytes ------------------------------------------------------------------------
    def _write(self, frame: bytes) -> None:
        import serial  # deferred: heavy (serial)

        with self._wlock:
            if self._port.serial is None and not self._port.ensure_open():
                raise DeviceError(f"{self.port_name}: Ability Hand port is not connected")
            try:
                self._port.write(frame)
            except (serial.SerialException, OSError) as err:
                raise self._port.fail(err, "write failed") from None
            self._last_write = time.perf_counter()

    def _receive(self, timeout: float) -> list[TactileSample]:
        import serial  # deferred: heavy (serial)

        ser = self._port.serial
        if ser is None:
            return []
        try:
            if ser.timeout != timeout:
                ser.timeout = timeout
            data = ser.read(ser.in_waiting or 1)
            if data and ser.in_waiting:
                data += ser.read(ser.in_waiting)
        except (serial.SerialException, OSError, TypeError) as err:
            raise self._port.fail(err) from None
        if not data:
            return []
        arrival = time.perf_counter()
        out = []
        for frame in self._unstuffer.feed(data):
            try:
                reply = decode_reply(frame)
            except DataError:
                self.bad_replies += 1
                continue
            self.replies += 1
            self.last_reply, self.last_arrival = reply, arrival
            self._measured = {f: units_of(f, d) for f, d in zip(ORDER, reply.positions)}
            self._stalled = stalled_fingers(reply.status)
            site = touch_newtons(reply.touch[self._site0:self._site0 + SITES])
            out.append(TactileSample(self._seq, arrival - self._t0, site))
            self._seq += 1
        return out

    def _pump_run(self) -> None:
        """The driver's own thread: a read-only request whenever nothing was written for a period,
        and every reply read as it comes (frames queued for :meth:`read_frames`)."""
        while not self._stop.is_set():
            try:
                if time.perf_counter() - self._last_write >= self._period:
                    self._write(encode_read())
                    self.requests += 1
                frames = self._receive(self._period / 2)
            except DeviceError as err:
                with self._arrived:
                    self._error = err
                    self._arrived.notify_all()
                self._stop.wait(self._period)
                continue
            if frames:
                with self._arrived:
                    self._frames.extend(frames)
                    self._arrived.notify_all()
            elif self._port.serial is None or not hasattr(self._port.serial, "fileno"):
                self._stop.wait(self._period / 4)  # a port without a blocking read: do not spin

    # -- Hand -------------------------------------------------------------------------
    def _command(self, targets: Mapping[Finger, float]) -> tuple[bytes, dict[Finger, float]]:
        if self._reflex:  # every position frame, an empty one included, carries every finger's angle
            raise ParameterError("Ability Hand: position command refused while a reflex runs (a position "
                                 "frame moves every finger to an angle; the reflex adds grip only by "
                                 "closing and holding)")
        full = {**self._measured, **self._targets}
        for f, v in targets.items():
            f = Finger(f)
            if f not in ORDER:
                raise ParameterError(f"Ability Hand has no {f.name.lower()} finger")
            v = float(v)
            if not (math.isfinite(v) and FINGER_MIN <= v <= FINGER_MAX):
                raise ParameterError(f"Ability Hand: {f.name} position must be in {FINGER_MIN}..{FINGER_MAX}, "
                                     f"got {v!r}")
            full[f] = v
        return encode_positions([degrees_of(f, full.get(f, 0.0)) for f in ORDER]), full

    def set_positions(self, targets: Mapping[Finger, float]) -> None:
        """Send position targets (finger units); the fingers not named keep their last
        target, or their measured position if they never had one.

        Raises
        ------
        ParameterError
            A finger the hand lacks, a position outside 0..500, or any position frame while
            a reflex runs (nothing is written).
        DeviceError
            The port is gone.
        """
        frame, full = self._command(targets)
        self._write(frame)
        self._targets = {f: v for f, v in full.items()}

    def close_fingers(self, fingers: Iterable[Finger], speed: float) -> None:
        """Start closing ``fingers`` at ``speed`` finger units per second, until :meth:`hold`.

        Sent in velocity mode (ICD 3.4.2): the named fingers at ``speed`` (in degrees per
        second, :func:`degrees_of`), every other finger at 0, which holds it.

        Raises
        ------
        ParameterError
            A finger the hand lacks, or a speed that is not > 0 (nothing is written).
        """
        fs = [Finger(f) for f in fingers]
        bad = [f for f in fs if f not in ORDER]
        if bad or not (math.isfinite(speed) and speed > 0):
            raise ParameterError(f"Ability Hand: cannot close {[f.name.lower() for f in bad] or fs} at {speed!r} "
                                 f"units/s (fingers of the hand, speed > 0)")
        closing = {**self._closing, **{f: abs(degrees_of(f, speed)) for f in fs}}
        self._write(encode_velocities([closing.get(f, 0.0) * (-1 if f == Finger.THUMB_ROTATOR else 1)
                                       for f in ORDER]))
        self._closing = closing

    def hold(self, fingers: Iterable[Finger] = ()) -> None:
        """Stop ``fingers`` where they are: velocity 0 (never opens the hand); fingers still
        closing keep closing.

        Not a position at the last measurement: a finger that closed since that reply would
        be sent back, i.e. opened.
        """
        fs = [Finger(f) for f in fingers]
        closing = {f: v for f, v in self._closing.items() if f not in fs}
        self._write(encode_velocities([closing.get(f, 0.0) * (-1 if f == Finger.THUMB_ROTATOR else 1)
                                       for f in ORDER]))
        self._closing = closing

    def reflex_running(self, running: bool = True) -> None:
        """Switch the grip-only guard on (a reflex runs) or off: while on, every position frame
        is refused before a byte is written (a reflex adds grip only by closing and holding).
        """
        self._reflex = bool(running)

    def positions(self) -> dict[Finger, float]:
        """The positions of the newest reply (the pump reads them continuously), in finger units."""
        return dict(self._measured)

    def stalled(self) -> frozenset[Finger]:
        """Fingers the newest reply's status byte reports stalled: the hand ignores closing them
        until they are opened, so grip sent to them is not grip added."""
        return self._stalled

    # -- TactileSource ---------------------------------------------------------------
    def read_frames(self, timeout: float) -> list[TactileSample]:
        """The frames of the replies that came since the last call (waiting at most ``timeout``).

        Raises
        ------
        DeviceError
            The port failed and no frame came (the pump keeps trying to reopen it).
        """
        with self._arrived:
            if not self._frames and self._error is None:
                self._arrived.wait(max(0.0, timeout))
            out = list(self._frames)
            self._frames.clear()
            err, self._error = self._error, None
        if err is not None and not out:
            raise err
        return out

    def drop_buffered(self) -> int:
        """Drop the frames the pump queued and no one has read yet.

        ``run_loop`` calls this once just before its clock starts: frames that came while the
        run set up (the chain warmed up, the safe start's STOP) are from before the run and
        would otherwise be processed as a stale backlog, as :meth:`SerialDaq.drop_buffered
        <slipreflex.devices.daq.SerialDaq.drop_buffered>` drops the DAQ's.

        Returns
        -------
        int
            Frames dropped.
        """
        with self._arrived:
            dropped = len(self._frames)
            self._frames.clear()
        return dropped

    def close(self) -> None:
        """Stop the pump and close the port if this driver opened it."""
        self._stop.set()
        if self._pump.is_alive() and self._pump is not threading.current_thread():
            self._pump.join(timeout=1.0)
        self._port.close()

    def __enter__(self) -> AbilityHand:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def stalled_fingers(status: int) -> frozenset[Finger]:
    """The fingers a reply's status byte reports stalled: bit ``k`` is finger ``ORDER[k]``.

    PSYONIC's wrapper logs any non-zero value as a collision; this driver reads it per
    finger, in the frame's finger order.

    Examples
    --------
    >>> sorted(f.name for f in stalled_fingers(0b000011))
    ['INDEX', 'MIDDLE']
    """
    return frozenset(f for k, f in enumerate(ORDER) if status >> k & 1)


#: How the virtual hand spreads a 4 x 4 tactile frame over a fingertip's 6 sites:
#: 3 bands of rows (0, 1-2, 3) by 2 halves of columns, each site the sum of its taxels
#: (a stand-in layout for tests: the total force is kept, the site geometry is not the hand's).
_SITE_ROWS = ((0,), (1, 2), (3,))
#: A site with less force than this (N) is untouched (reads 0) in the virtual hand.
_TOUCHED_N = 1e-3


def sites_from_array(frame: np.ndarray) -> np.ndarray:
    """Six site forces from a ``(4, 4)`` frame (see :data:`_SITE_ROWS`).

    Examples
    --------
    >>> sites_from_array(np.ones((4, 4))).tolist()
    [2.0, 2.0, 4.0, 4.0, 2.0, 2.0]
    """
    f = np.asarray(frame, dtype=np.float64)
    return np.array([f[list(rows)][:, half * 2:half * 2 + 2].sum() for rows in _SITE_ROWS for half in (0, 1)])


class VirtualAbilityHand:
    """The hand's side of the UART, on a rig: what the virtual devices run behind a pty.

    :meth:`feed` takes the bytes the host wrote; each position command is applied to
    ``rig.hand`` (finger units, :func:`units_of`) and each command, position or read-only,
    is answered with a variant-0 reply: the measured positions and, for each finger the rig
    has a tactile array on (``rig.tactile(finger)``, a ``(4, 4)`` frame in newtons), its
    six sites (:func:`sites_from_array`) as raw FSR values (:func:`touch_counts`). The ICD's
    placeholder law reads no touch below its offset C2 (0.88 N) and at least C2 on any
    touched site, so a site the rig presses with f newtons is sent as f + C2: the driver
    reads the rig's force plus a constant on touched sites, which a method that looks at
    changes (NMSD, SWT-SD) does not see.

    It models the two behaviours of the hand a host can get wrong: its API timeout (after
    ``api_timeout`` seconds without a frame, checked by :meth:`tick`, it leaves API mode:
    ``api_timeouts`` counts it and the fingers go open, the "undesired finger movements" of
    PSYONIC's manual at their worst for a grasp) and the stall (:meth:`stall` a finger: its
    status bit is set in every reply and closing it does nothing until it is opened).

    Attributes
    ----------
    commands, rejected, api_timeouts : int

    Examples
    --------
    >>> class Rig:
    ...     class hand:
    ...         pos = {}
    ...         def set_positions(t): Rig.hand.pos.update(t)
    ...         def positions(): return dict(Rig.hand.pos)
    ...     def tactile(self, finger): return np.full((4, 4), 0.1)
    >>> v = VirtualAbilityHand(Rig())
    >>> reply = v.feed(encode_positions([degrees_of(f, 100.0) for f in ORDER]))
    >>> sites = touch_newtons(decode_reply(unstuff(reply)[0]).touch)[:6] - 0.878894
    >>> round(Rig.hand.pos[Finger.INDEX], 1), sites.round(2).tolist()
    (100.0, [0.2, 0.2, 0.4, 0.4, 0.2, 0.2])
    """

    def __init__(self, rig: Any, tactile: Iterable[Finger] = (Finger.THUMB, Finger.INDEX, Finger.MIDDLE), *,
                 api_timeout: float = API_TIMEOUT_S, clock: Any = time.perf_counter) -> None:
        self.rig = rig
        self.tactile = tuple(f for f in tactile if f in TOUCH_FINGERS) if hasattr(rig, "tactile") else ()
        self._unstuffer = Unstuffer()
        self.commands = self.rejected = self.api_timeouts = 0
        self.api_timeout, self.clock = float(api_timeout), clock
        self.in_api = False
        self._heard = -math.inf
        self._stalled: set[Finger] = set()

    def stall(self, finger: Finger) -> None:
        """Stall ``finger`` (a collision): reported in the status byte, closing ignored until opened."""
        self._stalled.add(Finger(finger))

    def tick(self) -> None:
        """Leave API mode if the host has been silent for longer than the API timeout."""
        if self.in_api and self.clock() - self._heard > self.api_timeout:
            self.in_api = False
            self.api_timeouts += 1
            self.rig.hand.set_positions({f: 0.0 for f in ORDER if f != Finger.THUMB_ROTATOR})

    def _touch(self) -> list[int]:
        counts = [0] * (len(TOUCH_FINGERS) * SITES)
        for f in self.tactile:
            k = TOUCH_FINGERS.index(f) * SITES
            force = sites_from_array(self.rig.tactile(f))
            # the placeholder law reads at least C2 on any touched site: a touch of f reads f + C2
            counts[k:k + SITES] = touch_counts(np.where(force > _TOUCHED_N, force + _FSR_C2, 0.0)).tolist()
        return counts

    def _velocities(self, deg_s: dict[Finger, float]) -> None:
        """Velocity mode on the rig's hand: a closing finger closes at that speed, a finger at
        0 holds, an opening one goes to 0 (the simulated hand speaks i-Limb commands)."""

        hand = self.rig.hand
        full = getattr(getattr(hand, "params", None), "speed_units_s", None)
        for f, v in deg_s.items():
            if f == Finger.THUMB_ROTATOR:
                continue
            units = units_of(f, v)
            if f in self._stalled:
                if units >= 0:
                    units = 0.0  # a stalled finger ignores closing
                else:
                    self._stalled.discard(f)
            if units > 0 and hasattr(hand, "command") and full:
                hand.command(HandCommand.CLOSE, [f], min(float(PWM_MAX), units / full * PWM_MAX))
            elif units == 0 and hasattr(hand, "command"):
                hand.command(HandCommand.STOP, [f], 0.0)
            elif units < 0:
                hand.set_positions({f: 0.0})
            elif units > 0:
                hand.set_positions({f: float(FINGER_MAX)})

    def reply(self) -> bytes:
        """The reply to a command now: measured positions and touch values."""
        pos = self.rig.hand.positions()
        status = sum(1 << k for k, f in enumerate(ORDER) if f in self._stalled)
        return encode_reply([degrees_of(f, float(pos.get(f, 0.0))) for f in ORDER], touch=self._touch(),
                            status=status)

    def feed(self, data: bytes) -> bytes:
        """Apply the commands in ``data``; return the replies to write back."""
        out = bytearray()
        for frame in self._unstuffer.feed(data):
            try:
                _, header, degrees = decode_command(frame)
            except DataError:
                self.rejected += 1
                continue
            self.commands += 1
            self._heard, self.in_api = self.clock(), True
            if degrees is not None and header & 0xF0 == _POSITION:
                targets = {f: min(max(units_of(f, d), FINGER_MIN), FINGER_MAX)
                           for f, d in zip(ORDER, degrees) if f != Finger.THUMB_ROTATOR}
                now = self.rig.hand.positions()
                self._stalled -= {f for f, v in targets.items() if v < float(now.get(f, 0.0))}  # opened
                self.rig.hand.set_positions({f: v for f, v in targets.items()
                                             if f not in self._stalled or v <= float(now.get(f, 0.0))})
            elif degrees is not None:
                self._velocities(dict(zip(ORDER, degrees)))
            out += self.reply()
        return bytes(out)


__all__ += ["sites_from_array", "VirtualAbilityHand"]
