"""The recording reader: a recording read whole, or as far as a crash or damage lets it be read.

Every record is read on its own with its CRC checked, with the bytes it may take
bounded (a compression bomb is one line, not the memory); :func:`read_recording`
returns a :class:`Recording`, whose :meth:`~Recording.gaps` says what is missing.

Examples
--------
>>> from slipreflex.files.recording.reader import Recording
>>> Recording("x.mcap", complete=True).gaps()
''
"""

from __future__ import annotations

import io
import json
import os
import stat
import zlib
from dataclasses import dataclass, field
from typing import Any

from ...core.errors import DataError
from ...core.validation import LIMITS
from .format import CHECKSUM_KEY, METADATA_NAME, PLANNED_SAMPLES, RecordingError, verify

__all__ = ["Recording", "read_recording"]


@dataclass
class Recording:
    """What :func:`read_recording` found in a file.

    Attributes
    ----------
    path : str
    metadata : dict of str to dict of str to str
        Metadata records by name.
    messages : dict of str to list of dict
        Decoded messages per topic, in file order.
    log_times : dict of str to list of int
        Log times (ns) of those messages.
    complete : bool
        True if the file ended with its footer; False for a file cut short
        (e.g. by a crash), read up to its last complete chunk.
    damaged : list of (int, str)
        Byte offset and reason of every damaged record the reader skipped
        (a chunk whose CRC or compression fails, unreadable bytes).
    cut_at : int or None
        Byte offset of the record a crash cut short (the file ends inside it).
    before_damage : dict of str to int
        Messages per topic read before the first damaged record (all of them
        if nothing was damaged): the part a replay can check exactly.
    bad_metadata : list of str
        Metadata records whose checksum does not match (left out of ``metadata``).
    sealed : bool
        The writer sealed its metadata records with checksums (every recording
        of this version; older ones are read unchecked).

    Examples
    --------
    >>> Recording("x.mcap").topic("/chain/events")
    []
    """

    path: str
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    messages: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    log_times: dict[str, list[int]] = field(default_factory=dict)
    complete: bool = False
    damaged: list[tuple[int, str]] = field(default_factory=list)
    cut_at: int | None = None
    before_damage: dict[str, int] | None = None
    bad_metadata: list[str] = field(default_factory=list)
    sealed: bool = False

    def expected_samples(self) -> int | None:
        """How many samples the file should hold, when it says: its run summary, the count a run
        with ``--duration`` planned (:data:`PLANNED_SAMPLES`), or its last /stats; else None.

        Examples
        --------
        >>> Recording("x.mcap", messages={"/stats": [{"counters": {"samples": 40}}]}).expected_samples()
        40
        >>> Recording("x.mcap", metadata={METADATA_NAME: {PLANNED_SAMPLES: "6667"}}).expected_samples()
        6667
        >>> Recording("x.mcap").expected_samples() is None
        True
        """
        summary = self.metadata.get("run_summary", {})
        if str(summary.get("samples", "")).isdigit():
            return int(summary["samples"])
        planned = str(self.metadata.get(METADATA_NAME, {}).get(PLANNED_SAMPLES, ""))
        if planned.isdigit():
            return int(planned)
        stats = self.topic("/stats")
        if stats and self.cut_at is None and isinstance(stats[-1].get("counters", {}).get("samples"), int):
            return stats[-1]["counters"]["samples"]
        return None

    def gaps(self) -> str:
        """One line on what is missing, or "" for an intact file.

        Examples
        --------
        >>> Recording("x.mcap", complete=True).gaps()
        ''
        >>> Recording("x.mcap", damaged=[(2061, "CRC")]).gaps()
        'x.mcap: read 0 samples (how many it should hold is not recorded); chunk at byte 2061 damaged (CRC)'
        >>> Recording("x.mcap", complete=True, bad_metadata=["slipreflex"]).gaps()
        "x.mcap: damaged metadata: record 'slipreflex' fails its checksum"
        """
        parts = [f"damaged metadata: record {name!r} fails its checksum" for name in self.bad_metadata]
        parts += [f"chunk at byte {pos} damaged ({why})" for pos, why in self.damaged]
        if self.cut_at is not None:
            parts.append(f"cut short at byte {self.cut_at} (a crash?)")
        elif not self.complete and not self.damaged:
            parts.append("ends without its footer")
        if not parts:
            return ""
        got = len(self.topic("/daq/samples"))
        if not self.complete or self.damaged:
            want = self.expected_samples()
            head = (f"read {got} of the {want} samples it should hold" if want is not None else
                    f"read {got} samples (how many it should hold is not recorded)")
            parts.insert(len(self.bad_metadata), head)
        return f"{self.path}: " + "; ".join(parts)

    def topic(self, name: str) -> list[dict[str, Any]]:
        """Messages of one topic (empty list if none).

        Examples
        --------
        >>> Recording("x.mcap", messages={"/faults": [{"kind": "watchdog"}]}).topic("/faults")[0]["kind"]
        'watchdog'
        """
        return self.messages.get(name, [])


def read_recording(path: str | os.PathLike) -> Recording:
    """Read a recording, including one cut short by a crash or with damaged chunks.

    Every record is read on its own with its CRC checked; a damaged one is
    skipped (listed in :attr:`Recording.damaged`, reading goes on at the next
    whole chunk), and a record a crash cut short ends the reading
    (:attr:`Recording.cut_at`). :meth:`Recording.gaps` says what is missing.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    Recording

    Raises
    ------
    RecordingError
        The file cannot be opened.
    DataError
        The file is not an MCAP file, or a message is not JSON.

    Examples
    --------
    >>> read_recording("/nonexistent.mcap")
    Traceback (most recent call last):
    ...
    slipreflex.files.recording.RecordingError: /nonexistent.mcap: cannot open recording: No such file or directory
    """
    from mcap.records import Channel, Header, Message, Metadata  # deferred: heavy (mcap)

    path = os.fspath(path)
    rec = Recording(path=path)
    topics: dict[int, str] = {}
    for pos, record in _scan(path, rec):
        if isinstance(record, Header):
            rec.sealed = "metadata sha256" in str(record.library)
        elif isinstance(record, Channel):
            topics[record.id] = record.topic
        elif isinstance(record, Message):
            topic = topics.get(record.channel_id)
            if topic is None:
                continue
            try:
                msg = json.loads(record.data)
            except ValueError:
                rec.damaged.append((pos, f"message {record.sequence} on {topic} is not JSON"))
                continue
            rec.messages.setdefault(topic, []).append(msg)
            rec.log_times.setdefault(topic, []).append(record.log_time)
        elif isinstance(record, Metadata):
            data = dict(record.metadata)
            if rec.sealed and not verify(record.name, data):
                rec.bad_metadata.append(record.name)
                continue
            data.pop(CHECKSUM_KEY, None)
            rec.metadata[record.name] = data
    if rec.before_damage is None:
        rec.before_damage = {t: len(m) for t, m in rec.messages.items()}
    return rec


#: MCAP's file magic, its record opcodes (spec: Records) and the byte size of an opcode + length.
_MAGIC = b"\x89MCAP0\r\n"
_OPCODES = frozenset(range(0x01, 0x10))
_OP_CHUNK = 0x06
#: Attachment (0x09) and its index (0x0A): skipped whole, never parsed into memory.
_BULKY = frozenset((0x09,))
_RECORD_HEAD = 9


class _Budget:
    """Bytes a reading may still decompress: at most ``LIMITS["recording_chunk_bytes"]`` per chunk
    and, in all, ``LIMITS["recording_expansion"]`` times the file (the chunk limit at least), so a
    small file that claims or holds gigabytes (a compression bomb) is one line, not the memory."""

    def __init__(self, path: str, file_bytes: int) -> None:
        self.path = path
        self.chunk = int(LIMITS["recording_chunk_bytes"].hi)
        self.total = max(self.chunk, int(LIMITS["recording_expansion"].hi * file_bytes))
        self.left = self.total

    def take(self, n: int) -> None:
        self.left -= n
        if self.left < 0:
            raise DataError(f"{self.path}: decompresses to more than {self.total} bytes, "
                            f"{LIMITS['recording_expansion'].hi:g} times its size (docs/runtime.md, Limits)")


def _decompress(compression: str, raw: bytes, size: int) -> bytes | None:
    """At most ``size + 1`` bytes of a chunk's records (None: a compression this reader lacks)."""
    if compression == "":
        return raw[:size + 1]
    if compression == "zstd":
        import zstandard  # deferred: heavy (zstandard)

        out = bytearray()
        with zstandard.ZstdDecompressor().stream_reader(io.BytesIO(raw)) as reader:
            while len(out) <= size:
                got = reader.read(size + 1 - len(out))
                if not got:
                    break
                out += got
        return bytes(out)
    if compression == "lz4":
        import lz4.frame  # deferred: heavy (lz4)

        return lz4.frame.LZ4FrameDecompressor().decompress(raw, max_length=size + 1)
    return None


def _chunk_layout(data: bytes, pos: int, end: int) -> tuple[int, int, str, int, int] | None:
    """``(uncompressed size, crc, compression, records start, records end)`` of the chunk record at
    ``pos`` if its fields are consistent with its length (MCAP spec, Chunk), else None: O(1)."""
    body = pos + _RECORD_HEAD
    if end - body < 36 or end > len(data):
        return None
    size = int.from_bytes(data[body + 16:body + 24], "little")
    crc = int.from_bytes(data[body + 24:body + 28], "little")
    clen = int.from_bytes(data[body + 28:body + 32], "little")
    if clen > 16 or body + 40 + clen > end:
        return None
    try:
        compression = data[body + 32:body + 32 + clen].decode("ascii")
    except UnicodeDecodeError:
        return None
    rstart = body + 40 + clen
    if rstart + int.from_bytes(data[body + 32 + clen:rstart], "little") != end:
        return None
    return size, crc, compression, rstart, end


def _chunk_records(data: bytes, pos: int, end: int, budget: _Budget) -> tuple[list[Any] | None, str]:
    """The records inside the chunk at ``pos``, decompressed within ``budget``, CRC checked."""
    from mcap.exceptions import EndOfFile  # deferred: heavy (mcap)
    from mcap.stream_reader import StreamReader  # deferred: heavy (mcap)

    layout = _chunk_layout(data, pos, end)
    if layout is None:
        return None, "chunk fields do not match its length"
    size, crc, compression, rstart, rend = layout
    if size > budget.chunk:
        return None, (f"chunk declares {size} bytes uncompressed, more than the {budget.chunk} a chunk may "
                      f"have (docs/runtime.md, Limits)")
    budget.take(size)
    try:
        inner = _decompress(compression, data[rstart:rend], size)
    except Exception as err:  # noqa: BLE001 - any decoder's failure is damage in the file
        return None, f"{compression}: {type(err).__name__}: {err}"[:120]
    if inner is None:
        return None, f"unknown compression {compression!r}"
    if len(inner) != size:
        return None, f"chunk decompresses to {'more' if len(inner) > size else 'less'} than its declared {size} bytes"
    if crc and zlib.crc32(inner) != crc:
        return None, "chunk CRC does not match"
    why = _inner_layout(inner)
    if why:  # e.g. megabytes of zeros: millions of empty records, never handed to the parser
        return None, why
    out: list[Any] = []
    try:
        for r in StreamReader(io.BytesIO(inner), skip_magic=True, validate_crcs=True).records:
            out.append(r)
    except EndOfFile:
        pass
    except (NameError, AttributeError, ImportError):
        raise
    except Exception as err:  # noqa: BLE001 - a record inside the chunk is damaged
        return None, f"{type(err).__name__}: {err}"[:120]
    return out, ""


#: What a chunk may hold (MCAP spec, Chunk): schemas, channels and messages.
_IN_CHUNK = frozenset((0x03, 0x04, 0x05))


def _inner_layout(inner: bytes) -> str:
    """Why the records inside a chunk are not a chunk's (empty when they are): each must be a
    schema, a channel or a message, and together fill the chunk exactly."""
    q, n = 0, len(inner)
    while q < n:
        if q + _RECORD_HEAD > n:
            return "a record inside the chunk is cut"
        if inner[q] not in _IN_CHUNK:
            return f"record type 0x{inner[q]:02x} inside a chunk"
        q += _RECORD_HEAD + int.from_bytes(inner[q + 1:q + _RECORD_HEAD], "little")
    return "" if q == n else "a record inside the chunk runs past its end"


def _parse_record(data: bytes, pos: int, budget: _Budget) -> tuple[int, list[Any] | None, str]:
    """Parse the one record at ``pos`` (a chunk: its inner records, within ``budget``), checking CRCs.

    Returns ``(end, records, why)``: ``records`` is None when it is damaged or cut.
    """
    from mcap.exceptions import EndOfFile  # deferred: heavy (mcap)
    from mcap.stream_reader import StreamReader  # deferred: heavy (mcap)

    op = data[pos]
    end = pos + _RECORD_HEAD + int.from_bytes(data[pos + 1:pos + _RECORD_HEAD], "little")
    if op not in _OPCODES:
        return end, None, f"unknown record type 0x{op:02x}"
    if end > len(data):
        return end, None, "cut"
    if op == _OP_CHUNK:
        records, why = _chunk_records(data, pos, end, budget)
        return end, records, why
    if op in _BULKY:  # attachments and the like: nothing a reader of runs needs, and no memory for it
        return end, [], ""
    out: list[Any] = []
    try:
        for r in StreamReader(io.BytesIO(data[pos:end]), skip_magic=True, validate_crcs=True).records:
            out.append(r)
    except EndOfFile:
        pass
    except (NameError, AttributeError, ImportError):
        raise  # a bug here, not damage in the file
    except Exception as err:  # noqa: BLE001 - any decoding failure (CRC, zstd, struct) is damage
        return end, None, f"{type(err).__name__}: {err}"[:120]
    return end, out, ""


def _resync(data: bytes, pos: int, budget: _Budget) -> int | None:
    """The next offset after ``pos`` where a whole chunk parses (None if there is none).

    Linear: a candidate byte is first checked in O(1) (its chunk fields must add up to its
    length) and only a consistent one is decompressed, within the reading's ``budget``."""
    q = data.find(bytes([_OP_CHUNK]), pos + 1)
    while q >= 0:
        end = q + _RECORD_HEAD + int.from_bytes(data[q + 1:q + _RECORD_HEAD], "little")
        if _chunk_layout(data, q, end) is not None:
            records, _ = _chunk_records(data, q, end, budget)
            if records is not None:
                return q
        q = data.find(bytes([_OP_CHUNK]), q + 1)
    return None


def _read_bounded(path: str) -> bytes:
    """The file's bytes, its magic checked first and its size capped (``LIMITS["recording_bytes"]``):
    a device such as /dev/zero or a huge file is one line, not a MemoryError."""


    cap = int(LIMITS["recording_bytes"].hi)
    try:
        # O_NONBLOCK: a FIFO must not block the open; it is refused below like every non-regular file
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
        with os.fdopen(fd, "rb") as fh:
            st = os.fstat(fh.fileno())
            if stat.S_ISDIR(st.st_mode):
                raise RecordingError(f"{path}: is a directory, not a recording")
            if not stat.S_ISREG(st.st_mode):
                raise DataError(f"{path}: not a regular file (a device or a pipe is not a recording)")
            head = fh.read(len(_MAGIC))
            if head != _MAGIC:
                if head and _MAGIC.startswith(head) and stat.S_ISREG(st.st_mode):
                    raise DataError(f"{path}: cut short after {len(head)} bytes, before its first record")
                raise DataError(f"{path}: not an MCAP file (no MCAP magic at its start)")
            if stat.S_ISREG(st.st_mode) and st.st_size > cap:
                raise DataError(f"{path}: {st.st_size} bytes, more than the {cap} a recording may have "
                                f"(docs/runtime.md, Limits)")
            data = head + fh.read(cap + 1 - len(head))
    except OSError as err:
        if isinstance(err, RecordingError):
            raise
        raise RecordingError(f"{path}: cannot open recording: {err.strerror or err}") from None
    if len(data) > cap:
        raise DataError(f"{path}: more than the {cap} bytes a recording may have (docs/runtime.md, Limits)")
    return data


def _scan(path: str, rec: Recording) -> Any:
    """Yield ``(offset, record)`` for every readable record of an MCAP file, skipping damaged
    records (noted in ``rec.damaged``) and stopping at a record a crash cut (``rec.cut_at``)."""
    data = _read_bounded(path)
    if not data.startswith(_MAGIC):
        if data and _MAGIC.startswith(data):
            raise DataError(f"{path}: cut short after {len(data)} bytes, before its first record")
        raise DataError(f"{path}: not an MCAP file (no MCAP magic at its start)")
    pos = len(_MAGIC)
    budget = _Budget(path, len(data))
    while pos + _RECORD_HEAD <= len(data):
        end, records, why = _parse_record(data, pos, budget)
        if records is None:
            nxt = _resync(data, pos, budget)
            if nxt is None:
                if why == "cut" or end > len(data):
                    rec.cut_at = pos
                else:
                    rec.damaged.append((pos, why or "unreadable"))
                return
            if rec.before_damage is None:
                rec.before_damage = {t: len(m) for t, m in rec.messages.items()}
            rec.damaged.append((pos, why if why != "cut" else "bad record length"))
            pos = nxt
            continue
        for r in records:
            yield pos, r
        if data[pos] == 0x02:  # the footer: only the closing magic follows
            rec.complete = True
            return
        pos = end
    if pos < len(data):
        rec.cut_at = pos
