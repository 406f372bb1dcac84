"""Bounded reading of recordings: a compression bomb (zstd or lz4, an honest or a lying chunk
header), a crafted file that made the resync quadratic, and files that are not regular."""

from __future__ import annotations

import dataclasses
import os
import struct
import zlib

import lz4.frame
import pytest
import zstandard

from slipreflex.cli import main
from slipreflex.core.errors import DataError
from slipreflex.core.validation import LIMITS
from slipreflex.files.recording import read_recording, reader


def _string(s: bytes) -> bytes:
    return struct.pack("<I", len(s)) + s


def _record(op: int, body: bytes) -> bytes:
    return bytes([op]) + struct.pack("<Q", len(body)) + body


def _header() -> bytes:
    return _record(0x01, _string(b"") + _string(b"bomb"))


def _chunk(inner_size: int, crc: int, compression: bytes, payload: bytes) -> bytes:
    body = (struct.pack("<QQQI", 0, 0, inner_size, crc) + _string(compression)
            + struct.pack("<Q", len(payload)) + payload)
    return _record(0x06, body)


def _zeros_zstd(n: int) -> bytes:
    """n zero bytes, zstd-compressed without the content size in the frame (as a streaming writer)."""
    c = zstandard.ZstdCompressor(level=1, write_content_size=False).compressobj()
    block = bytes(1 << 20)
    out = b"".join(c.compress(block) for _ in range(n >> 20))
    return out + c.flush()


def _write(tmp_path, name, *records) -> str:
    p = tmp_path / name
    p.write_bytes(reader._MAGIC + _header() + b"".join(records))
    return str(p)


def test_a_chunk_declaring_more_than_the_chunk_limit_is_not_decompressed(tmp_path):
    payload = _zeros_zstd(1 << 20)
    path = _write(tmp_path, "declared.mcap", _chunk(8 << 30, 0, b"zstd", payload))
    rec = read_recording(path)
    assert rec.damaged and "more than the" in rec.damaged[0][1] and not rec.messages


@pytest.mark.parametrize("compression", [b"zstd", b"lz4"])
def test_a_chunk_that_lies_about_its_size_is_read_no_further_than_it_says(tmp_path, compression):
    big = 64 << 20  # 64 MiB of zeros in a few kB
    payload = _zeros_zstd(big) if compression == b"zstd" else lz4.frame.compress(bytes(big))
    assert len(payload) < 2 << 20
    path = _write(tmp_path, f"lying-{compression.decode()}.mcap", _chunk(1 << 20, 0, compression, payload))
    rec = read_recording(path)
    assert rec.damaged and "more than its declared" in rec.damaged[0][1]


@pytest.fixture
def small_chunks(monkeypatch):
    """A 1 MiB chunk limit, so the honest bomb below costs the test 2 MiB, not 128 MiB."""
    monkeypatch.setitem(LIMITS, "recording_chunk_bytes", dataclasses.replace(LIMITS["recording_chunk_bytes"],
                                                                             hi=float(1 << 20)))
    return 1 << 20


@pytest.mark.slow
def test_many_honest_chunks_stop_at_the_total_budget_in_one_line(tmp_path, capsys, small_chunks):
    size = small_chunks  # each chunk declares (and holds) the most a chunk may
    zeros = bytes(size)
    chunk = _chunk(size, zlib.crc32(zeros), b"lz4", lz4.frame.compress(zeros))
    path = _write(tmp_path, "bomb.mcap", *[chunk] * 4)
    assert os.path.getsize(path) * LIMITS["recording_expansion"].hi < 2 * size
    with pytest.raises(DataError, match="decompresses to more than"):
        read_recording(path)
    for command in (["replay", path], ["export", path, "--out", str(tmp_path / "x.csv")],
                    ["recover", path, "--out", str(tmp_path / "r.mcap")]):
        assert main(command) == 2, command
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "decompresses to more than" in err, (command, err)
    assert not (tmp_path / "x.csv").exists() and not (tmp_path / "r.mcap").exists()


@pytest.mark.slow
def test_the_resync_looks_at_each_candidate_in_constant_time(tmp_path, monkeypatch):
    """4 MB of would-be chunk starts, each with a length that stays inside the file: the old resync
    parsed every one of them over its whole length (hours); now none is even decompressed."""
    n = 4 << 20
    filler = bytearray(n)
    for q in range(0, n - 128, 16):
        filler[q] = 0x06
        filler[q + 1:q + 9] = struct.pack("<Q", n - q - 64)
    path = _write(tmp_path, "resync.mcap", _record(0x7F, b"x"), bytes(filler))
    calls = []
    real = reader._chunk_records
    monkeypatch.setattr(reader, "_chunk_records", lambda *a: calls.append(a[1]) or real(*a))
    rec = read_recording(path)
    assert rec.damaged and not rec.messages
    assert len(calls) <= 1


def test_a_fifo_and_a_device_are_refused_without_blocking(tmp_path, capsys):
    fifo = tmp_path / "x.mcap"
    os.mkfifo(fifo)
    for path in (str(fifo), "/dev/zero"):
        with pytest.raises(DataError, match="not a regular file"):
            read_recording(path)
        assert main(["replay", path]) == 2
        assert "not a regular file" in capsys.readouterr().err
