"""The PSYONIC Ability Hand's UART frames: encoding, decoding, byte stuffing and the touch sensors.

Written from the hand's published interface control document (the Ability Hand ICD,
sections 3.3-3.5); the driver that speaks them is :mod:`slipreflex.rig.devices.ability`, which
re-exports every name here.

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


Examples
--------
>>> frame = encode_positions([30.0, 30.0, 30.0, 30.0, 30.0, -30.0])
>>> frame[0], frame[-1], len(unstuff(frame)[0])          # delimiters; address + header + 12 + sum
(126, 126, 15)
"""

from __future__ import annotations

import math
import struct
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from ...core.errors import DataError, ParameterError
from ...core.hardware import FINGER_MAX, Finger

__all__ = ["ABILITY_BAUD", "ADDRESS", "ORDER", "TOUCH_FINGERS", "SITES", "FULL_CLOSE_DEG",
           "checksum", "stuff", "unstuff", "Unstuffer", "encode_positions", "encode_velocities", "encode_read",
           "decode_command", "AbilityReply", "decode_reply", "encode_reply", "touch_newtons",
           "touch_counts", "degrees_of", "units_of"]

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
    slipreflex.core.errors.DataError: Ability Hand reply has 2 bytes, not 72 (variant 0)
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
