"""The DAQ board's wire protocol: the one definition of its packet format.

The ATmega328P DAQ firmware (``firmware/``) sends one fixed-length frame per
3 ms sample period over its UART at :data:`BAUD` (8N1). Every reader and writer
of that byte stream (the serial DAQ reader, the virtual DAQ on a pty, the simavr
tests) uses this module; ``docs/wire-protocol.md`` describes the same layout in
prose and ``tests/data/wire/vectors.txt`` holds test vectors that the C tests
and the Python tests both check.

Frame layout (:data:`FRAME_LEN` = 20 bytes; multi-byte fields little-endian,
except the CRC, which is big-endian so that the CRC over bytes 2..19 of a good
frame is zero)::

    off len field
      0  2  sync        0xA5 0x5A                      (SYNC)
      2  1  version     0x01                           (VERSION)
      3  2  seq         uint16, +1 per period, wraps at 65536
      5  1  flags       bit0 ACCEL_FRESH, bit1 IMU_ERROR, bit2 OVERRUN
      6  2  adc         uint16, slip-sensor ADC counts 0..1023
      8  6  ax, ay, az  int16, raw MPU6050 counts (+-2 g), 0 unless ACCEL_FRESH
     14  4  flow        uint32, cumulative YF-S201 pulses, wraps at 2**32
     18  2  crc         CRC-16/CCITT-FALSE of bytes 2..17, big-endian

Version 2 (:data:`VERSION_REFLEX`, :data:`FRAME_LEN_REFLEX` = 28 bytes) is sent by a
board running the reflex itself (``firmware/`` built with ``REFLEX_ON_BOARD``): bytes
0..17 as above with version 0x02, then the chain's output for the sample
(:class:`ReflexFields`), then the CRC::

     18  1  reflex      bit0 SPIKE, bit1 WINDOW, bit2 FAULT, bit3 HAND
     19  1  v           spikes in the window this sample completed (else 0)
     20  2  command     int16, finger command in force after this sample
     22  4  x           int32, filtered sample in Q16 ADC counts
     26  2  crc         CRC-16/CCITT-FALSE of bytes 2..25, big-endian

The parser reads both versions from one stream (the version byte gives the length).

Examples
--------
>>> from slipreflex.rig.devices import wire
>>> raw = wire.encode_frame(seq=7, adc=512, accel=(0, 0, 16384), flow_pulses=3)
>>> len(raw) == wire.FRAME_LEN
True
>>> parser = wire.FrameParser()
>>> [f.to_sample().accel_g for f in parser.feed(b"junk" + raw)]
[(0.0, 0.0, 1.0)]
>>> parser.stats.garbage_bytes, parser.stats.resyncs
(4, 1)
"""

from __future__ import annotations

import binascii
import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass, field, fields

from ...core import hardware
from ...core.errors import DataError, ParameterError
from ...core.interfaces import DaqSample
from ...core.validation import integer

__all__ = [
    "SYNC", "VERSION", "FRAME_LEN", "PAYLOAD_LEN", "BAUD", "SEQ_MODULO", "FLOW_MODULO",
    "ADC_MAX", "ACCEL_LSB_PER_G", "FLAG_ACCEL_FRESH", "FLAG_IMU_ERROR", "FLAG_OVERRUN",
    "VERSION_REFLEX", "FRAME_LEN_REFLEX", "REFLEX_SPIKE", "REFLEX_WINDOW", "REFLEX_FAULT",
    "REFLEX_HAND", "ReflexFields", "crc16", "Frame", "encode_frame", "encode_sample", "decode_frame",
    "adc_from_volts", "accel_raw_from_g", "ParserStats", "FrameParser",
]

#: The two bytes that start every frame.
SYNC: bytes = b"\xa5\x5a"
#: Protocol version byte (offset 2); a frame with another version is rejected.
VERSION: int = 1
#: Bytes per frame, sync and CRC included.
FRAME_LEN: int = 20
#: Bytes covered by the CRC: version .. flow (offsets 2..17).
PAYLOAD_LEN: int = FRAME_LEN - len(SYNC) - 2
#: UART rate (baud, 8N1). At 16 MHz the divider UBRR0 = F_CPU/(16*BAUD) - 1 = 3
#: is exact (0 % error); a frame takes 20 x 10 bits = 0.8 ms of the 3 ms period.
BAUD: int = 250_000
#: The sequence number counts modulo this.
SEQ_MODULO: int = 1 << 16
#: A frame at most this many behind the last one is late (reordered) and dropped; further
#: behind (or more than half the modulo ahead), the board restarted its sequence.
LATE_WINDOW: int = 2
#: The cumulative flow-pulse counter counts modulo this.
FLOW_MODULO: int = 1 << 32
#: Largest ADC reading (10-bit ADC).
ADC_MAX: int = (1 << hardware.ADC_BITS) - 1
#: MPU6050 accelerometer scale at its +-2 g range (AFS_SEL = 0): counts per g.
ACCEL_LSB_PER_G: int = hardware.IMU_LSB_PER_G
#: flags bit 0: the accel fields hold a reading completed during this period.
FLAG_ACCEL_FRESH: int = 0x01
#: flags bit 1: the last I2C transaction with the MPU6050 failed (NACK, bus error, timeout).
FLAG_IMU_ERROR: int = 0x02
#: flags bit 2: the firmware missed a deadline (a sample was not framed in time); sticky
#: for one frame. Never set at the design rates; the seq gap shows what was lost.
FLAG_OVERRUN: int = 0x04
_KNOWN_FLAGS = FLAG_ACCEL_FRESH | FLAG_IMU_ERROR | FLAG_OVERRUN

# version, seq, flags, adc, ax, ay, az, flow: offsets 2..17, little-endian.
_BODY = struct.Struct("<BHBHhhhI")
assert _BODY.size == PAYLOAD_LEN
_CRC = struct.Struct(">H")

#: Protocol version of a board running the reflex on board (adds the chain's output).
VERSION_REFLEX: int = 2
#: Bytes per version-2 frame.
FRAME_LEN_REFLEX: int = 28
#: Version-2 ``reflex`` byte: the encoder fired on this sample.
REFLEX_SPIKE: int = 0x01
#: This sample completed a window; ``v`` is its spike count.
REFLEX_WINDOW: int = 0x02
#: The reading was out of range or stuck: the chain skipped it (and the hand holds).
REFLEX_FAULT: int = 0x04
#: A hand packet (CLOSE or STOP) was queued on the board's hand UART at this sample.
REFLEX_HAND: int = 0x08
_KNOWN_REFLEX = REFLEX_SPIKE | REFLEX_WINDOW | REFLEX_FAULT | REFLEX_HAND
# reflex bits, v, command, x: offsets 18..25 of a version-2 frame.
_REFLEX = struct.Struct("<BBhi")
assert PAYLOAD_LEN + _REFLEX.size + 4 == FRAME_LEN_REFLEX
_LENGTHS = {VERSION: FRAME_LEN, VERSION_REFLEX: FRAME_LEN_REFLEX}


def _bit(field_name: str, bit: int, doc: str) -> property:
    """A read-only property: whether ``bit`` is set in the integer field ``field_name``."""
    return property(lambda self: bool(getattr(self, field_name) & bit), doc=doc)


@dataclass(frozen=True, slots=True)
class ReflexFields:
    """What a board running the reflex reports with each sample (version-2 frames).

    Parameters
    ----------
    bits : int
        ``REFLEX_*`` bits.
    v : int
        Spikes in the window this sample completed (0 unless ``window``).
    command : int
        Finger command in force after this sample.
    x : int
        Filtered sample, Q16 ADC counts (``slipreflex.methods.board``).

    Examples
    --------
    >>> r = ReflexFields(bits=REFLEX_SPIKE | REFLEX_WINDOW, v=3, command=40, x=300 << 16)
    >>> r.spike, r.window, r.fault, r.hand
    (True, True, False, False)
    """

    bits: int
    v: int
    command: int
    x: int

    # One property per bit of ``bits`` (REFLEX_*).
    spike = _bit("bits", REFLEX_SPIKE, "The encoder fired on this sample.")
    window = _bit("bits", REFLEX_WINDOW, "This sample completed a window.")
    fault = _bit("bits", REFLEX_FAULT, "The reading was skipped as out of range or stuck.")
    hand = _bit("bits", REFLEX_HAND, "A hand packet (CLOSE or STOP, hand2560) was queued at this sample.")


def crc16(data: bytes | bytearray | memoryview, crc: int = 0xFFFF) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor).

    Parameters
    ----------
    data : bytes-like
        Bytes to checksum.
    crc : int, optional
        Running value to continue from (default: the initial value 0xFFFF).

    Returns
    -------
    int
        The CRC, 0..65535.

    Examples
    --------
    >>> hex(crc16(b"123456789"))
    '0x29b1'
    """
    return binascii.crc_hqx(data, crc)


@dataclass(frozen=True, slots=True)
class Frame:
    """One decoded frame, in the board's raw units.

    Parameters
    ----------
    seq : int
        Sequence number as sent, 0..65535.
    flags : int
        Flag byte (see ``FLAG_*``).
    adc : int
        Slip-sensor ADC counts, 0..1023.
    accel : tuple of int
        Raw MPU6050 x, y, z counts; (0, 0, 0) unless ``accel_fresh``.
    flow_pulses : int
        Cumulative YF-S201 pulses as sent (wraps at 2**32).
    index : int, optional
        Unwrapped sequence number: the parser counts on past 65535 (and across
        gaps). Defaults to ``seq`` (what :func:`decode_frame` gives).
    reflex : ReflexFields or None, optional
        The board's chain output (version-2 frames); None for version 1.

    Examples
    --------
    >>> f = decode_frame(encode_frame(seq=1, adc=100))
    >>> f.seq, f.adc, f.accel_fresh
    (1, 100, False)
    """

    seq: int
    flags: int
    adc: int
    accel: tuple[int, int, int]
    flow_pulses: int
    index: int = field(default=-1)
    reflex: ReflexFields | None = None

    def __post_init__(self) -> None:
        if self.index == -1:
            object.__setattr__(self, "index", self.seq)

    # One property per bit of the flag byte (FLAG_*).
    accel_fresh = _bit("flags", FLAG_ACCEL_FRESH, """True when the accel fields hold a fresh reading.

        Examples
        --------
        >>> decode_frame(encode_frame(seq=0, adc=0, accel=(1, 2, 3))).accel_fresh
        True
        """)
    imu_error = _bit("flags", FLAG_IMU_ERROR, """True when the firmware reports a failed MPU6050 transaction.

        Examples
        --------
        >>> decode_frame(encode_frame(seq=0, adc=0, flags=FLAG_IMU_ERROR)).imu_error
        True
        """)
    overrun = _bit("flags", FLAG_OVERRUN, """True when the firmware reports a missed deadline before this frame.

        Examples
        --------
        >>> decode_frame(encode_frame(seq=0, adc=0)).overrun
        False
        """)

    def to_sample(self) -> DaqSample:
        """Convert to a :class:`slipreflex.core.interfaces.DaqSample` in physical units.

        Volts = counts x ``hardware.ADC_LSB``; g = counts / :data:`ACCEL_LSB_PER_G`
        (None when not fresh); t = ``index`` x ``hardware.DAQ_PERIOD_S``.

        Returns
        -------
        DaqSample

        Examples
        --------
        >>> s = decode_frame(encode_frame(seq=2, adc=1023, accel=(-8192, 0, 16384))).to_sample()
        >>> round(s.t, 3), round(s.slip_volts, 3), s.accel_g
        (0.006, 4.995, (-0.5, 0.0, 1.0))
        """
        accel = (tuple(a / ACCEL_LSB_PER_G for a in self.accel) if self.accel_fresh else None)
        return DaqSample(seq=self.seq, t=self.index * hardware.DAQ_PERIOD_S,
                         slip_volts=self.adc * hardware.ADC_LSB,
                         accel_g=accel,  # type: ignore[arg-type]
                         flow_pulses=self.flow_pulses)


def encode_frame(seq: int, adc: int, accel: Sequence[int] | None = None,
                 flow_pulses: int = 0, flags: int = 0, reflex: ReflexFields | None = None) -> bytes:
    """Build one frame from raw board values.

    Parameters
    ----------
    seq : int
        Sequence number, >= 0; taken modulo 65536, so a running counter may be passed.
    adc : int
        ADC counts, 0..1023.
    accel : sequence of 3 int or None, optional
        Raw MPU6050 counts (-32768..32767); given -> ``FLAG_ACCEL_FRESH`` is set,
        None -> zeros are sent and the flag is clear.
    flow_pulses : int, optional
        Cumulative pulses, >= 0; taken modulo 2**32.
    flags : int, optional
        Extra flags (``FLAG_IMU_ERROR``, ``FLAG_OVERRUN``); ``FLAG_ACCEL_FRESH``
        follows from ``accel`` and must not be passed.
    reflex : ReflexFields, optional
        Given: a version-2 frame carrying the board's chain output.

    Returns
    -------
    bytes
        :data:`FRAME_LEN` bytes (:data:`FRAME_LEN_REFLEX` with ``reflex``).

    Raises
    ------
    ParameterError
        A value is out of range or not an integer.

    Examples
    --------
    >>> encode_frame(seq=1, adc=512).hex()
    'a55a01010000000200000000000000000000cc61'
    """
    seq = integer("seq", seq, lo=0, hi=2**63) % SEQ_MODULO
    adc = integer("adc", adc, lo=0, hi=ADC_MAX)
    flow = integer("flow_pulses", flow_pulses, lo=0, hi=2**63) % FLOW_MODULO
    flags = integer("flags", flags, lo=0, hi=255)
    if flags & FLAG_ACCEL_FRESH:
        raise ParameterError("flags must not contain FLAG_ACCEL_FRESH: pass accel instead")
    if accel is None:
        ax = ay = az = 0
    else:
        if len(accel) != 3:
            raise ParameterError(f"accel must have 3 values (x, y, z), got {len(accel)}")
        ax, ay, az = (integer(f"accel[{i}]", a, lo=-32768, hi=32767) for i, a in enumerate(accel))
        flags |= FLAG_ACCEL_FRESH
    if reflex is None:
        body = _BODY.pack(VERSION, seq, flags, adc, ax, ay, az, flow)
    else:
        r = reflex
        body = _BODY.pack(VERSION_REFLEX, seq, flags, adc, ax, ay, az, flow) + _REFLEX.pack(
            integer("reflex.bits", r.bits, lo=0, hi=_KNOWN_REFLEX), integer("reflex.v", r.v, lo=0, hi=255),
            integer("reflex.command", r.command, lo=-32768, hi=32767),
            integer("reflex.x", r.x, lo=-2**31, hi=2**31 - 1))
    return SYNC + body + _CRC.pack(crc16(body))


def adc_from_volts(volts: float) -> int:
    """Volts -> ADC counts as the board's 10-bit ADC would read them (round, clip).

    Parameters
    ----------
    volts : float
        Input voltage; clipped to the 0..1023 count range.

    Returns
    -------
    int
        Counts, 0..1023.

    Raises
    ------
    ParameterError
        ``volts`` is NaN.

    Examples
    --------
    >>> adc_from_volts(2.5), adc_from_volts(-1.0), adc_from_volts(9.0)
    (512, 0, 1023)
    """
    return _quantize("volts", volts, hardware.ADC_LSB, 0, ADC_MAX)


def accel_raw_from_g(g: float) -> int:
    """Acceleration in g -> raw MPU6050 counts at +-2 g (round, clip to int16).

    Parameters
    ----------
    g : float

    Returns
    -------
    int
        Counts, -32768..32767 (:data:`ACCEL_LSB_PER_G` per g).

    Raises
    ------
    ParameterError
        ``g`` is NaN.

    Examples
    --------
    >>> accel_raw_from_g(1.0), accel_raw_from_g(-3.0)
    (16384, -32768)
    """
    return _quantize("g", g, 1.0 / ACCEL_LSB_PER_G, -32768, 32767)   # a power of two: exact


def _quantize(name: str, value: float, lsb: float, lo: int, hi: int) -> int:
    """``value / lsb`` rounded and clipped to ``lo..hi``, as the board's converter would give it."""
    if math.isnan(value):
        raise ParameterError(f"{name} must not be NaN")
    return int(min(max(round(value / lsb), lo), hi))


def encode_sample(sample: DaqSample, flags: int = 0) -> bytes:
    """Build the frame the board would send for a sample in physical units.

    Volts and g are quantized with :func:`adc_from_volts` and
    :func:`accel_raw_from_g`; ``sample.seq`` is sent modulo 65536 and
    ``sample.t`` is not sent (the receiver derives it from the sequence number).

    Parameters
    ----------
    sample : DaqSample
    flags : int, optional
        Extra flags, as in :func:`encode_frame`.

    Returns
    -------
    bytes

    Examples
    --------
    >>> s = DaqSample(seq=70000, t=210.0, slip_volts=0.42, accel_g=None, flow_pulses=9)
    >>> f = decode_frame(encode_sample(s))
    >>> f.seq, f.adc, f.flow_pulses
    (4464, 86, 9)
    """
    accel = None if sample.accel_g is None else [accel_raw_from_g(a) for a in sample.accel_g]
    return encode_frame(seq=sample.seq, adc=adc_from_volts(sample.slip_volts), accel=accel,
                        flow_pulses=sample.flow_pulses, flags=flags)


def _frame_len(buf: bytes | bytearray | memoryview, i: int) -> int:
    """Length of the frame starting at ``i`` by its version byte (v1 length if unknown)."""
    return _LENGTHS.get(buf[i + 2], FRAME_LEN) if len(buf) > i + 2 else FRAME_LEN


def _unpack(raw: bytes | bytearray | memoryview) -> tuple[Frame | None, str]:
    """Decode a candidate that starts with SYNC, of its version's length; (frame, "") or
    (None, reason)."""
    n = len(raw)
    if crc16(raw[2:n]) != 0:
        return None, "bad CRC"
    version, seq, flags, adc, ax, ay, az, flow = _BODY.unpack_from(raw, 2)
    if _LENGTHS.get(version) != n:
        return None, f"unknown version {version} (expected {VERSION} or {VERSION_REFLEX})"
    if adc > ADC_MAX:
        return None, f"adc {adc} out of range 0..{ADC_MAX}"
    reflex = None
    if version == VERSION_REFLEX:
        reflex = ReflexFields(*_REFLEX.unpack_from(raw, 2 + PAYLOAD_LEN))
    return Frame(seq=seq, flags=flags, adc=adc, accel=(ax, ay, az), flow_pulses=flow,
                 reflex=reflex), ""


def decode_frame(data: bytes | bytearray | memoryview) -> Frame:
    """Decode exactly one frame.

    Parameters
    ----------
    data : bytes-like
        :data:`FRAME_LEN` bytes (version 1) or :data:`FRAME_LEN_REFLEX` (version 2).

    Returns
    -------
    Frame
        With ``index == seq``.

    Raises
    ------
    DataError
        Wrong length, missing sync, bad CRC, unknown version or ADC out of range.

    Examples
    --------
    >>> decode_frame(bytes.fromhex("a55a01010000000200000000000000000000cc61")).adc
    512
    >>> decode_frame(bytes.fromhex("a55a01010000000200000000000000000000cc60"))
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.DataError: frame a55a0101...cc60: bad CRC
    """
    data = bytes(data)
    short = f"{data[:4].hex()}...{data[-2:].hex()}" if len(data) > 8 else data.hex()
    want = _frame_len(data, 0) if data[:2] == SYNC else FRAME_LEN
    if len(data) != want:
        raise DataError(f"frame {short}: {len(data)} bytes, expected {want}")
    if data[:2] != SYNC:
        raise DataError(f"frame {short}: does not start with sync {SYNC.hex()}")
    frame, reason = _unpack(data)
    if frame is None:
        raise DataError(f"frame {short}: {reason}")
    return frame


@dataclass(frozen=True, slots=True)
class ParserStats:
    """Counters of a :class:`FrameParser` (a snapshot).

    Every byte fed is eventually either part of a good frame, counted in
    ``garbage_bytes`` or ``dropped_bytes``, or still pending: ``bytes_fed ==
    FRAME_LEN * frames + garbage_bytes + dropped_bytes + pending`` (for version-1 frames).

    Attributes
    ----------
    bytes_fed : int
        Bytes passed to ``feed``.
    frames : int
        Good frames returned.
    crc_errors : int
        Complete candidate frames (sync + 18 bytes) whose CRC failed.
    truncated : int
        Frames cut short: a failed candidate that contains the start of a good
        frame, or an incomplete frame left at :meth:`FrameParser.flush`.
    invalid : int
        Frames with a good CRC but an unknown version or an ADC value > 1023.
    garbage_bytes : int
        Bytes discarded outside good frames (noise, failed and truncated frames).
    resyncs : int
        Times the parser locked onto a good frame after discarding bytes
        (the first frame of a stream joined mid-frame counts).
    seq_gaps : int
        Good frames whose seq is not the previous seq + 1 (mod 65536).
    frames_lost : int
        Sum over gaps of the frames skipped, ``(seq - expected) mod 65536``.
    duplicates : int
        Good frames with the same seq as the one before: dropped.
    reordered : int
        Good frames up to :data:`LATE_WINDOW` behind the last one: dropped.
    resets : int
        Sequence restarts (a board reset): the frame starts a new segment and
        its time continues one period after the last frame's.
    dropped_bytes : int
        Bytes of the duplicated and late frames.
    pending : int
        Bytes held back waiting for the rest of a frame.

    Examples
    --------
    >>> p = FrameParser(); _ = p.feed(b"\\x00" * 3); p.stats.garbage_bytes
    3
    """

    bytes_fed: int = 0
    frames: int = 0
    crc_errors: int = 0
    truncated: int = 0
    invalid: int = 0
    garbage_bytes: int = 0
    resyncs: int = 0
    seq_gaps: int = 0
    frames_lost: int = 0
    duplicates: int = 0
    reordered: int = 0
    resets: int = 0
    dropped_bytes: int = 0
    pending: int = 0


class FrameParser:
    """Incremental parser of the DAQ byte stream: feed bytes, get frames.

    Never blocks and never raises on bad input: it resynchronizes on the next
    sync pattern and counts what it skipped (see :class:`ParserStats`). Good
    frames get an unwrapped sequence number ``index`` (the first good frame
    keeps its seq; later ones add ``(seq - previous) mod 65536``), so a
    sample's time stays monotonic across wraparound and gaps. A repeated or
    late frame is dropped and a sequence restart (board reset) continues the
    time at the next period, so time never jumps back or by minutes.

    A candidate whose CRC fails is reported as truncated (not as a CRC error)
    when a good frame starts inside it; to decide that, the parser may hold up
    to one frame of bytes until the next ``feed``.

    Examples
    --------
    >>> good = [encode_frame(seq=s, adc=7) for s in (65534, 65535, 0, 2)]
    >>> p = FrameParser()
    >>> frames = p.feed(b"".join(good[:2]) + good[2][:7] + good[2] + good[3])
    >>> [(f.seq, f.index) for f in frames]
    [(65534, 65534), (65535, 65535), (0, 65536), (2, 65538)]
    >>> s = p.stats; s.truncated, s.seq_gaps, s.frames_lost, s.garbage_bytes
    (1, 1, 1, 7)
    """

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """Forget pending bytes, counters and the sequence history.

        Examples
        --------
        >>> p = FrameParser(); _ = p.feed(b"xy"); p.reset(); p.stats.bytes_fed
        0
        """
        self._buf = bytearray()
        self._c = {f.name: 0 for f in fields(ParserStats) if f.name != "pending"}
        self._last_seq: int | None = None
        self._index = 0
        self._lost_lock = False

    @property
    def stats(self) -> ParserStats:
        """Snapshot of the counters.

        Examples
        --------
        >>> FrameParser().stats.frames
        0
        """
        return ParserStats(pending=len(self._buf), **self._c)

    def feed(self, data: bytes | bytearray | memoryview) -> list[Frame]:
        """Add received bytes; return the good frames they complete, in order.

        Parameters
        ----------
        data : bytes-like
            Any number of bytes (possibly empty), cut anywhere.

        Returns
        -------
        list of Frame

        Raises
        ------
        ParameterError
            ``data`` is not bytes-like (e.g. a str).

        Examples
        --------
        >>> raw = encode_frame(seq=5, adc=9)
        >>> p = FrameParser()
        >>> p.feed(raw[:10]), [f.adc for f in p.feed(raw[10:])]
        ([], [9])
        """
        if isinstance(data, str) or not isinstance(data, (bytes, bytearray, memoryview)):
            raise ParameterError(f"data must be bytes-like, got {type(data).__name__}")
        self._c["bytes_fed"] += len(data)
        self._buf += data
        return self._scan(final=False)

    def flush(self) -> list[Frame]:
        """End of stream: decide on held-back bytes and discard the rest.

        An incomplete frame left over counts as truncated; a held-back failed
        candidate counts as a CRC error. The sequence history is kept, so
        feeding may continue afterwards.

        Returns
        -------
        list of Frame
            Good frames found among the held-back bytes.

        Examples
        --------
        >>> p = FrameParser(); _ = p.feed(encode_frame(seq=0, adc=1)[:12])
        >>> p.flush(), p.stats.truncated, p.stats.garbage_bytes
        ([], 1, 12)
        """
        return self._scan(final=True)

    # -- internals ---------------------------------------------------------------------

    def _discard(self, n: int) -> None:
        if n > 0:
            self._c["garbage_bytes"] += n
            self._lost_lock = True

    def _accept(self, frame: Frame, size: int) -> Frame | None:
        c = self._c
        if self._last_seq is None:
            self._index = frame.seq
        else:
            step = (frame.seq - self._last_seq) % SEQ_MODULO
            if step == 0 or step >= SEQ_MODULO - LATE_WINDOW:  # a repeat or a late frame: drop
                c["duplicates" if step == 0 else "reordered"] += 1
                c["dropped_bytes"] += size
                return None
            if step >= SEQ_MODULO // 2:  # far behind: the board restarted; time goes on
                c["resets"] += 1
                step = 1
            elif step != 1:
                c["seq_gaps"] += 1
                c["frames_lost"] += step - 1
            self._index += step
        self._last_seq = frame.seq
        c["frames"] += 1
        if self._lost_lock:
            c["resyncs"] += 1
            self._lost_lock = False
        return Frame(frame.seq, frame.flags, frame.adc, frame.accel, frame.flow_pulses,
                     self._index, frame.reflex)

    def _scan(self, final: bool) -> list[Frame]:
        buf, c, out = self._buf, self._c, []
        i, n = 0, len(buf)
        while True:
            j = buf.find(SYNC, i)
            if j < 0:
                keep = 1 if (not final and n > i and buf[-1] == SYNC[0]) else 0
                self._discard(n - keep - i)
                i = n - keep
                break
            self._discard(j - i)
            i = j
            size = _frame_len(buf, i)
            if n - i < max(size, 3):
                if final:
                    c["truncated"] += 1
                    self._discard(n - i)
                    i = n
                break
            frame, _ = _unpack(buf[i:i + size])
            if frame is not None:
                accepted = self._accept(frame, size)
                if accepted is not None:
                    out.append(accepted)
                i += size
                continue
            if crc16(buf[i + 2:i + size]) == 0:  # good CRC, bad content
                c["invalid"] += 1
                self._discard(size)
                i += size
                continue
            # Failed CRC: a truncated frame if a good frame starts inside the candidate.
            # Otherwise no good frame starts inside it: drop all of it (at flush, only up
            # to the first sync that cannot be checked, which then counts as truncated).
            verdict, k, skip = "crc", i + 1, size
            while True:
                k = buf.find(SYNC, k, i + size + 1)
                if k < 0:
                    if not final and n == i + size and buf[-1] == SYNC[0]:
                        verdict = "wait"  # a sync may start at the candidate's last byte
                    break
                ksize = _frame_len(buf, k)
                if k + max(ksize, 3) > n:
                    if not final:
                        verdict = "wait"
                        break
                    skip = min(skip, k - i)
                elif _unpack(buf[k:k + ksize])[0] is not None:
                    verdict = "truncated"
                    break
                k += 1
            if verdict == "wait":
                break
            if verdict == "truncated":
                c["truncated"] += 1
                self._discard(k - i)
                i = k
            else:
                c["crc_errors"] += 1
                self._discard(skip)
                i += skip
        del buf[:i]
        return out
