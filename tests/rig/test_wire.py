"""Tests of slipreflex.rig.devices.wire against the shared vectors file and by fuzzing."""

from __future__ import annotations

import doctest
from pathlib import Path

import numpy as np
import pytest

from slipreflex.core import hardware
from slipreflex.core.errors import DataError, ParameterError, SlipreflexError
from slipreflex.core.interfaces import DaqSample
from slipreflex.rig.devices import wire

VECTORS = Path(__file__).parents[1] / "data" / "wire" / "vectors.txt"


def _records(kind: str) -> list[list[str]]:
    rows = []
    for line in VECTORS.read_text().splitlines():
        if line and not line.startswith("#"):
            parts = line.split(" ")
            assert parts[0] in "FRBS", line
            if parts[0] == kind:
                rows.append(parts[1:])
    return rows


def _hex(text: str) -> bytes:
    return b"" if text == "-" else bytes.fromhex(text)


F_ROWS = _records("F")
R_ROWS = _records("R")
B_ROWS = _records("B")
S_ROWS = _records("S")


def test_vector_file_has_every_kind():
    assert len(F_ROWS) >= 8 and len(R_ROWS) >= 4 and len(B_ROWS) >= 10 and len(S_ROWS) >= 20
    reasons = {row[2] for row in B_ROWS}
    assert reasons == {"truncated", "sync", "crc", "version", "adc"}


def test_crc_check_value_and_residue():
    # The catalogue check value of CRC-16/CCITT-FALSE, and a zero residue over body + CRC.
    assert wire.crc16(b"123456789") == 0x29B1
    raw = wire.encode_frame(seq=3, adc=4)
    assert wire.crc16(raw[2:]) == 0
    assert wire.crc16(b"56789", wire.crc16(b"1234")) == 0x29B1


def test_layout_constants():
    assert wire.FRAME_LEN == len(wire.SYNC) + wire.PAYLOAD_LEN + 2 == 20
    assert wire.ADC_MAX == 1023
    # The UART divider is exact at 16 MHz: F_CPU / (16 * BAUD) is an integer.
    assert hardware.F_CPU % (16 * wire.BAUD) == 0
    # A frame (10 bits per byte at 8N1) fits in one sample period with room to spare.
    assert wire.FRAME_LEN * 10 / wire.BAUD < 0.5 * hardware.DAQ_PERIOD_S


@pytest.mark.parametrize("row", F_ROWS, ids=[r[0] for r in F_ROWS])
def test_good_vectors(row):
    name, hx, seq, flags, adc, ax, ay, az, flow = row
    raw = _hex(hx)
    seq, flags, adc, ax, ay, az, flow = map(int, (seq, flags, adc, ax, ay, az, flow))
    f = wire.decode_frame(raw)
    assert (f.seq, f.flags, f.adc, f.accel, f.flow_pulses, f.index) == (
        seq, flags, adc, (ax, ay, az), flow, seq)
    accel = (ax, ay, az) if flags & wire.FLAG_ACCEL_FRESH else None
    assert wire.encode_frame(seq, adc, accel, flow, flags & ~wire.FLAG_ACCEL_FRESH) == raw
    parser = wire.FrameParser()
    assert parser.feed(raw) == [f]
    assert parser.stats.frames == 1 and parser.stats.garbage_bytes == 0


@pytest.mark.parametrize("row", R_ROWS, ids=[r[0] for r in R_ROWS])
def test_good_version_2_vectors(row):
    """Frames of a board running the reflex: decoded, re-encoded, parsed among v1 frames."""
    name, hx, *fields = row
    raw = _hex(hx)
    seq, flags, adc, ax, ay, az, flow, bits, v, command, x = map(int, fields)
    f = wire.decode_frame(raw)
    assert len(raw) == wire.FRAME_LEN_REFLEX and raw[2] == wire.VERSION_REFLEX
    assert (f.seq, f.flags, f.adc, f.accel, f.flow_pulses) == (seq, flags, adc, (ax, ay, az), flow)
    assert f.reflex == wire.ReflexFields(bits, v, command, x)
    accel = (ax, ay, az) if flags & wire.FLAG_ACCEL_FRESH else None
    assert wire.encode_frame(seq, adc, accel, flow, flags & ~wire.FLAG_ACCEL_FRESH,
                             reflex=f.reflex) == raw
    v1 = wire.encode_frame(seq=(seq + 1) % 65536, adc=1)
    parser = wire.FrameParser()
    got = parser.feed(raw + v1)
    assert [g.reflex for g in got] == [f.reflex, None] and parser.stats.garbage_bytes == 0
    assert f.to_sample().slip_volts == adc * hardware.ADC_LSB
    with pytest.raises(ParameterError, match="reflex.bits"):
        wire.encode_frame(seq, adc, reflex=wire.ReflexFields(0x80, 0, 0, 0))


@pytest.mark.parametrize("row", B_ROWS, ids=[r[0] for r in B_ROWS])
def test_bad_vectors(row):
    name, hx, reason = row
    raw = _hex(hx)
    words = {"truncated": "bytes, expected (20|28)", "sync": "sync", "crc": "bad CRC",
             "version": "unknown version", "adc": "out of range"}[reason]
    with pytest.raises(DataError, match=words):
        wire.decode_frame(raw)
    parser = wire.FrameParser()
    assert parser.feed(raw) + parser.flush() == [] or reason == "truncated"


def _run(data: bytes, chunks: list[int] | None = None):
    parser = wire.FrameParser()
    frames = []
    if chunks is None:
        frames += parser.feed(data)
    else:
        pos = 0
        for size in chunks:
            frames += parser.feed(data[pos:pos + size])
            pos += size
        frames += parser.feed(data[pos:])
    frames += parser.flush()
    return frames, parser.stats


@pytest.mark.parametrize("row", S_ROWS, ids=[r[0] for r in S_ROWS])
def test_stream_vectors(row):
    name, hx, *counts, seqs = row
    data = _hex(hx)
    expected = [int(c) for c in counts]
    want_seqs = [] if seqs == "-" else [int(s) for s in seqs.split(",")]
    keys = ["frames", "crc_errors", "truncated", "invalid", "garbage_bytes", "resyncs",
            "seq_gaps", "frames_lost"]
    rng = np.random.default_rng(len(data))
    # The same answer whether the stream comes in one piece, byte by byte or in random cuts.
    for chunks in (None, [1] * len(data), list(rng.integers(0, 23, size=len(data)))):
        frames, stats = _run(data, chunks)
        assert [getattr(stats, k) for k in keys] == expected, (name, chunks)
        assert [f.seq for f in frames] == want_seqs
        assert stats.bytes_fed == len(data)
        assert stats.pending == 0
        assert stats.bytes_fed == sum(wire.FRAME_LEN_REFLEX if f.reflex else wire.FRAME_LEN
                                      for f in frames) + stats.garbage_bytes + stats.dropped_bytes


def test_unwrapping_and_time_across_wrap():
    seqs = [65533, 65534, 65535, 0, 1, 5]
    parser = wire.FrameParser()
    frames = parser.feed(b"".join(wire.encode_frame(seq=s, adc=1) for s in seqs))
    assert [f.index for f in frames] == [65533, 65534, 65535, 65536, 65537, 65541]
    t = [f.to_sample().t for f in frames]
    assert t == pytest.approx([i * hardware.DAQ_PERIOD_S for i in
                               (65533, 65534, 65535, 65536, 65537, 65541)])
    assert parser.stats.seq_gaps == 1 and parser.stats.frames_lost == 3


def test_to_sample_units():
    f = wire.decode_frame(wire.encode_frame(seq=10, adc=68, accel=(16384, -8192, 0),
                                            flow_pulses=450))
    s = f.to_sample()
    assert isinstance(s, DaqSample)
    assert s.seq == 10 and s.t == pytest.approx(0.03)
    assert s.slip_volts == pytest.approx(68 * 5.0 / 1024)
    assert s.accel_g == (1.0, -0.5, 0.0)
    assert s.flow_pulses == 450
    stale = wire.decode_frame(wire.encode_frame(seq=11, adc=68, flags=wire.FLAG_IMU_ERROR))
    assert stale.to_sample().accel_g is None and stale.imu_error and not stale.accel_fresh


def test_encode_sample_round_trip():
    s = DaqSample(seq=65537, t=0.0, slip_volts=3.33, accel_g=(0.25, -1.0, 1.999),
                  flow_pulses=2**32 + 5)
    f = wire.decode_frame(wire.encode_sample(s))
    assert f.seq == 1 and f.flow_pulses == 5
    back = f.to_sample()
    assert abs(back.slip_volts - 3.33) <= hardware.ADC_LSB / 2
    assert back.accel_g == pytest.approx((0.25, -1.0, 1.999), abs=1 / wire.ACCEL_LSB_PER_G)


@pytest.mark.parametrize("kwargs, words", [
    (dict(seq=-1, adc=0), "seq"),
    (dict(seq=0, adc=1024), "adc"),
    (dict(seq=0, adc=-1), "adc"),
    (dict(seq=0, adc=1.5), "adc must be an integer"),
    (dict(seq=True, adc=0), "seq must be an integer"),
    (dict(seq=0, adc=0, accel=(1, 2)), "3 values"),
    (dict(seq=0, adc=0, accel=(40000, 0, 0)), r"accel\[0\]"),
    (dict(seq=0, adc=0, flow_pulses=-3), "flow_pulses"),
    (dict(seq=0, adc=0, flags=wire.FLAG_ACCEL_FRESH), "FLAG_ACCEL_FRESH"),
    (dict(seq=0, adc=0, flags=256), "flags"),
])
def test_encode_rejects_bad_input(kwargs, words):
    with pytest.raises(ParameterError, match=words):
        wire.encode_frame(**kwargs)


def test_numpy_integers_accepted_and_nan_rejected():
    assert wire.encode_frame(np.int64(3), np.uint16(9)) == wire.encode_frame(3, 9)
    with pytest.raises(ParameterError, match="NaN"):
        wire.adc_from_volts(float("nan"))
    with pytest.raises(ParameterError, match="NaN"):
        wire.accel_raw_from_g(float("nan"))


def test_feed_rejects_text():
    with pytest.raises(ParameterError, match="bytes-like"):
        wire.FrameParser().feed("a55a")  # type: ignore[arg-type]
    assert issubclass(ParameterError, SlipreflexError)


@pytest.mark.parametrize("version", [wire.VERSION, wire.VERSION_REFLEX])
def test_fuzz_recovers_every_untouched_frame(version):
    """Corrupt some frames (bit flips, dropped and inserted bytes) in a long stream:
    every untouched frame comes back, nothing that was not sent comes back, and the
    counters add up (for version-1 and version-2 streams)."""
    rng = np.random.default_rng(1234)
    size = wire.FRAME_LEN if version == wire.VERSION else wire.FRAME_LEN_REFLEX

    def reflex():
        if version == wire.VERSION:
            return None
        return wire.ReflexFields(int(rng.integers(0, 16)), int(rng.integers(0, 256)),
                                 int(rng.integers(-32768, 32768)), int(rng.integers(-2**31, 2**31)))

    n = 3000
    sent, damaged, chunks = [], set(), []
    for k in range(n):
        seq = (60000 + k) % wire.SEQ_MODULO
        accel = tuple(int(a) for a in rng.integers(-32768, 32768, 3)) if k % 3 else None
        raw = bytearray(wire.encode_frame(seq, int(rng.integers(0, 1024)), accel,
                                          int(rng.integers(0, 2**32)), reflex=reflex()))
        sent.append(bytes(raw))
        if k % 4 == 2 and rng.random() < 0.5:  # never two damaged frames in a row
            how = rng.integers(0, 3)
            pos = int(rng.integers(0, size))
            if how == 0:
                raw[pos] ^= 1 << int(rng.integers(0, 8))
            elif how == 1:
                del raw[pos]
            else:  # inside the frame: a byte inserted before the sync leaves it intact
                raw.insert(max(pos, 1), int(rng.integers(0, 256)))
            if sent[-1] not in raw:  # (an inserted 0xA5 right after the first may not hurt)
                damaged.add(seq)
        chunks.append(bytes(raw))
    data = b"".join(chunks)
    cuts = np.cumsum(rng.integers(1, 64, size=len(data) // 16))
    parser = wire.FrameParser()
    got, last = [], 0
    for c in cuts[cuts < len(data)]:
        got += parser.feed(data[last:c])
        last = int(c)
    got += parser.feed(data[last:]) + parser.flush()
    got_seqs = [f.seq for f in got]
    expected = [(60000 + k) % wire.SEQ_MODULO for k in range(n)
                if (60000 + k) % wire.SEQ_MODULO not in damaged]
    assert got_seqs == expected
    assert {bytes(wire.encode_frame(f.seq, f.adc, f.accel if f.accel_fresh else None,
                                    f.flow_pulses, reflex=f.reflex)) for f in got} <= set(sent)
    s = parser.stats
    assert s.frames == len(expected)
    assert s.seq_gaps == len(damaged) and s.frames_lost == len(damaged)
    assert s.crc_errors + s.truncated >= 1
    assert s.bytes_fed == len(data) == size * s.frames + s.garbage_bytes
    assert got[-1].index == 60000 + n - 1  # unwrapped past 65535


def test_parser_holds_at_most_two_frames():
    parser = wire.FrameParser()
    raw = wire.encode_frame(seq=1, adc=2)
    bad = bytearray(raw)
    bad[19] ^= 1
    parser.feed(bytes(bad) + raw[:15])
    assert parser.stats.pending <= 2 * wire.FRAME_LEN
    assert [f.seq for f in parser.feed(raw[15:])] == [1]


def test_docstrings_run_and_cover_all_public_names():
    for name in wire.__all__:
        obj = getattr(wire, name)
        if callable(obj):
            assert obj.__doc__ and "Examples" in obj.__doc__, name
    result = doctest.testmod(wire, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 15 and result.failed == 0
