"""Recordings of runs: MCAP files of JSON messages with JSON schemas (open in Foxglove).

The one definition of the recording format: its topics, their fields
(:data:`TOPICS`), the metadata record that stores the chain's parameters, a
crash-tolerant writer (:class:`Recorder`) and a reader that also reads a file
cut short by a crash (:func:`read_recording`).

Crash tolerance: messages go into small chunks, and the writer finishes the
current chunk and flushes the file at least every ``flush_interval`` seconds
(0.25 s by default). A process killed mid-run leaves a file without summary or
footer whose complete chunks (everything up to the last flush) are readable
with mcap's streaming reader, which is what :func:`read_recording` uses.

Topics (``t`` is the sample time on the board's clock in seconds, ``seq`` the
sample's sequence number as sent; ``arrival`` is seconds since the run
started, on the PC's clock):

=================  ===========================================================
/daq/samples       every sample: seq, t, slip_volts, flow_pulses, arrival and
                   ``position``, the slip-finger position given to the reflex
/daq/imu           accelerometer x, y, z in g, when the board sent a fresh reading
/daq/flow          cumulative flow-sensor pulses, when they change
/chain/state       per sample: filtered value, threshold in force, event (bool)
/chain/events      one message per spike
/chain/windows     one message per complete window: spike count
/hand/commands     reflex commands: target (the reflex's output), fingers, targets (empty:
                   the loop sends no positions), grip (the grip, units, the command adds
                   to each finger, sent as closing time), sent (bool), note (why
                   not sent: "at start", "no rise", "stale", "rejected", "hand-port"), latency
                   (s from reading the bytes) and frame_latency (s from the frame's
                   own arrival)
/board/state       (``run --board-reflex``) per sample: what the board's own chain sent
                   (spike, window, fault, hand, v, command, x in Q16 counts) and
                   ``match``, whether its Python twin agreed
/hand/grip         with every command, the grip (units) it adds to each finger as flat
                   fields (``thumb``, ``index``, ``middle``, ...; null for a finger not
                   commanded): the per-finger form of /hand/commands' ``grip``, one plot
                   line per finger
/tactile/frames    (a tactile method) every frame as flat fields: ``total`` and ``peak`` (N),
                   ``position`` (as /daq/samples), then one ``taxel_K`` per taxel (C order)
/rig/truth         (``virtual-rig --live``) the simulated rig's truth per sample: the
                   object's displacement and slip (m), velocity (m/s), the normal force
                   per contact (N), its load (kg), slipping, fallen, and the measured
                   finger positions
/faults            watchdog, device and recording faults, with the action taken
/stats             periodic DAQ and loop counters
=================  ===========================================================

Every field of a topic but ``/hand/commands`` (``fingers``, ``targets``) and ``/stats``
(``counters``) is a scalar: what a live plot (``--live``, :mod:`slipreflex.live`) draws as
one line. :func:`schema` gives a topic's schema, the one the recording and the live view share.

Examples
--------
>>> import tempfile, os
>>> path = os.path.join(tempfile.mkdtemp(), "demo.mcap")
>>> with Recorder(path, metadata={"run": {"note": "demo"}}) as rec:
...     _ = rec.write("/chain/events", {"t": 0.003, "seq": 1}, 0)
>>> r = read_recording(path)
>>> r.messages["/chain/events"], r.metadata["run"]["note"], r.complete
([{'t': 0.003, 'seq': 1}], 'demo', True)
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import stat
import time
import zlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from .board import BoardReflex, board_params_from_json
from .chain import ReflexParams, SlipReflex
from .csvfiles import write_columns
from .errors import DataError, SlipreflexError
from .paths import create_new, new_file, publish
from .validation import LIMITS

__all__ = [
    "TOPICS", "METADATA_NAME", "RecordingError", "Recorder", "Recording", "read_recording", "schema",
    "FINGER_FIELDS", "PART_SUFFIX", "CHECKSUM_KEY", "LIBRARY", "sealed", "verify", "PLANNED_SAMPLES",
]

#: Key, in the :data:`METADATA_NAME` record, of the number of samples a run with a planned
#: duration should record (``run --duration``): a reader then knows what a cut file misses.
PLANNED_SAMPLES: str = "planned_samples"

#: Name of the metadata record holding the chain parameters and run facts.
METADATA_NAME: str = "slipreflex"

#: A recording is written as ``NAME.part`` and named ``NAME`` when closed (a run killed mid-way
#: leaves the ``.part``: ``slipreflex recover`` reads it).
PART_SUFFIX: str = ".part"

#: The writer's library string; it says the metadata records carry :data:`CHECKSUM_KEY`.
LIBRARY: str = "slipreflex; metadata sha256"

#: Key, in every metadata record this writer makes, of the record's checksum (MCAP metadata
#: records have no CRC of their own): sha256 of the name and the other entries, 16 hex digits.
CHECKSUM_KEY: str = "_sha256"


def _digest(name: str, data: Mapping[str, str]) -> str:

    doc = json.dumps([name, sorted((k, v) for k, v in data.items() if k != CHECKSUM_KEY)])
    return hashlib.sha256(doc.encode()).hexdigest()[:16]


def sealed(name: str, data: Mapping[str, Any]) -> dict[str, str]:
    """A metadata record's entries as strings, with their checksum added.

    Examples
    --------
    >>> rec = sealed("run", {"p0": 147}); verify("run", rec), verify("run", {**rec, "p0": "157"})
    (True, False)
    """
    out = {str(k): str(v) for k, v in data.items()}
    out[CHECKSUM_KEY] = _digest(name, out)
    return out


def verify(name: str, data: Mapping[str, str]) -> bool:
    """True if the record carries its checksum and it matches.

    Examples
    --------
    >>> verify("run", {"p0": "147"})
    False
    """
    return data.get(CHECKSUM_KEY) == _digest(name, data)

_N, _I, _B, _S = (["number", "null"], "integer", "boolean", "string")
_ACCEL = {"ax": "number", "ay": "number", "az": "number"}
#: The per-finger fields of /hand/grip and /rig/truth (the hand's fingers by name, lower case).
FINGER_FIELDS: tuple[str, ...] = ("thumb", "index", "middle", "ring", "little", "thumb_rotator")
_TAXEL = {"type": "number"}

#: Every topic: its schema name and its fields with JSON-schema types.
TOPICS: dict[str, tuple[str, dict[str, Any]]] = {
    "/daq/samples": ("slipreflex.DaqSample", {"seq": _I, "t": "number", "slip_volts": "number",
                                              "flow_pulses": _I, "arrival": "number",
                                              "position": _N}),
    "/daq/imu": ("slipreflex.Imu", {"seq": _I, "t": "number", **_ACCEL}),
    "/daq/flow": ("slipreflex.Flow", {"seq": _I, "t": "number", "pulses": _I}),
    "/chain/state": ("slipreflex.ChainState", {"seq": _I, "t": "number", "filtered": _N,
                                               "threshold": "number", "event": _B}),
    "/chain/events": ("slipreflex.Event", {"seq": _I, "t": "number"}),
    "/chain/windows": ("slipreflex.Window", {"seq": _I, "t": "number", "count": _I}),
    "/hand/commands": ("slipreflex.Command", {"seq": _I, "t": "number", "target": "number",
                                              "fingers": {"type": "array", "items": {"type": _S}},
                                              "targets": {"type": "object"}, "grip": {"type": "object"},
                                              "sent": _B, "note": _S, "latency": _N,
                                              "frame_latency": _N}),
    "/board/state": ("slipreflex.BoardState", {"seq": _I, "t": "number", "spike": _B, "window": _B,
                                               "fault": _B, "hand": _B, "v": _I, "command": _I,
                                               "x": _I, "match": _B}),
    "/hand/grip": ("slipreflex.FingerGrip", {"seq": _I, "t": "number", "sent": _B,
                                                   **{f: _N for f in FINGER_FIELDS}}),
    "/tactile/frames": ("slipreflex.TactileFrame", {"seq": _I, "t": "number", "total": "number",
                                                    "peak": "number", "position": _N}),
    "/rig/truth": ("slipreflex.RigTruth", {"t": "number", "displacement": "number", "slip": "number",
                                           "velocity": "number", "normal_force": "number",
                                           "load_mass": "number", "slipping": _B, "fallen": _B,
                                           **{f: _N for f in FINGER_FIELDS}}),
    "/faults": ("slipreflex.Fault", {"time": "number", "kind": _S, "message": _S, "action": _S}),
    "/stats": ("slipreflex.Stats", {"time": "number", "counters": {"type": "object"}}),
}


class RecordingError(SlipreflexError, OSError):
    """A recording cannot be created, written or read; the message names the file.

    Examples
    --------
    >>> isinstance(RecordingError("x.mcap: disk full"), OSError)
    True
    """


def _schema(name: str, fields: dict[str, Any], extra: dict[str, Any] | None = None) -> bytes:
    props = {k: (v if isinstance(v, dict) else {"type": v}) for k, v in fields.items()}
    return json.dumps({"$schema": "http://json-schema.org/draft-07/schema#", "title": name,
                       "type": "object", "properties": props, **(extra or {})}).encode()


#: Topics with fields beyond their listed ones: /tactile/frames has one number per taxel.
_EXTRA: dict[str, dict[str, Any]] = {
    "/tactile/frames": {"patternProperties": {"^taxel_[0-9]+$": _TAXEL}},
}


def schema(topic: str) -> tuple[str, bytes]:
    """The name and JSON schema (bytes) of a topic: the one definition the recording and the
    live view (:mod:`slipreflex.live`) both use.

    Parameters
    ----------
    topic : str
        One of :data:`TOPICS`.

    Returns
    -------
    (str, bytes)

    Raises
    ------
    RecordingError
        For an unknown topic.

    Examples
    --------
    >>> name, data = schema("/chain/windows")
    >>> name, json.loads(data)["properties"]["count"]
    ('slipreflex.Window', {'type': 'integer'})
    """
    if topic not in TOPICS:
        raise RecordingError(f"unknown topic {topic!r} (known: {', '.join(TOPICS)})")
    name, fields = TOPICS[topic]
    return name, _schema(name, fields, _EXTRA.get(topic))


class Recorder:
    """Write a run to an MCAP file, crash-tolerantly.

    The file is created, and its header, schemas, channels and metadata are
    written and flushed, in the constructor: an unwritable path or a full
    disk is a :class:`RecordingError` before any run starts. A write error
    later (disk full mid-run) does not raise: the recorder stops writing,
    keeps the error in :attr:`error`, and :meth:`write` returns False, so a
    real-time loop can report the fault and keep running.

    Parameters
    ----------
    path : str or os.PathLike or binary file object
        Where to write. A file object is not closed by :meth:`close`.
    metadata : mapping of str to mapping of str to str, optional
        Metadata records (name -> string map) written at the start.
    chunk_size : int
        Bytes after which a chunk is finished.
    flush_interval : float
        Maximum seconds between flushes (see :meth:`maybe_flush`).
    compression : {"zstd", "lz4", "none"}
        Chunk compression.

    Attributes
    ----------
    error : OSError or None
        The write error that stopped the recorder, if any.
    messages : int
        Messages accepted.

    Raises
    ------
    RecordingError
        The file cannot be created or its start cannot be written.

    Examples
    --------
    >>> import io
    >>> buf = io.BytesIO()
    >>> rec = Recorder(buf)
    >>> rec.write("/faults", {"time": 0.0, "kind": "demo", "message": "m", "action": "none"}, 1)
    True
    >>> rec.close(); buf.getvalue()[:5]
    b'\\x89MCAP'
    """

    def __init__(self, path: str | os.PathLike | IO[bytes], *,
                 metadata: Mapping[str, Mapping[str, str]] | None = None,
                 chunk_size: int = 16 * 1024, flush_interval: float = 0.25,
                 compression: str = "zstd") -> None:
        from mcap.writer import CompressionType, Writer  # deferred: heavy (mcap)

        comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4,
                "none": CompressionType.NONE}.get(compression)
        if comp is None:
            raise RecordingError(f"unknown compression {compression!r} (zstd, lz4 or none)")
        self.flush_interval = flush_interval
        self.error: OSError | None = None
        self.messages = 0
        self._closed = False
        self.part_path: str | None = None
        if isinstance(path, (str, os.PathLike)):

            self.path = os.fspath(path)
            self.part_path = self.path + PART_SUFFIX
            for name in (self.path, self.part_path):
                if os.path.lexists(name):
                    raise RecordingError(f"{name}: exists; a recording is always a new file (give another "
                                         f"name, or move the old one)")
            try:
                self._fh: IO[bytes] = create_new(self.part_path)
            except FileExistsError:
                raise RecordingError(f"{self.part_path}: exists; a recording is always a new file") from None
            except OSError as err:
                raise RecordingError(f"{self.path}: cannot create recording: "
                                     f"{err.strerror or err}") from None
            st = os.fstat(self._fh.fileno())
            self._identity = (st.st_dev, st.st_ino)
            self._owns = True
        else:
            self.path = str(getattr(path, "name", "<stream>"))
            self._fh = path
            self._owns = False
        try:
            self._writer = Writer(self._fh, chunk_size=chunk_size, compression=comp)
            self._writer.start(profile="", library=LIBRARY)
            self._channels: dict[str, int] = {}
            for topic in TOPICS:
                name, data = schema(topic)
                sid = self._writer.register_schema(name=name, encoding="jsonschema", data=data)
                self._channels[topic] = self._writer.register_channel(
                    topic=topic, message_encoding="json", schema_id=sid)
            for name, data in (metadata or {}).items():
                self._writer.add_metadata(name, sealed(name, data))
            self._writer.flush()
        except OSError as err:
            self._close_file()
            self._remove_part()
            raise RecordingError(f"{self.path}: cannot write recording: {err.strerror or err}") from None
        self._last_flush = time.monotonic()
        self._seq = 0

    @property
    def ok(self) -> bool:
        """True while the recorder can write.

        Examples
        --------
        >>> import io; Recorder(io.BytesIO()).ok
        True
        """
        return self.error is None and not self._closed

    def _failed(self, err: OSError) -> bool:
        if self.error is None:
            self.error = err
        return False

    def write(self, topic: str, message: Mapping[str, Any], log_time_ns: int) -> bool:
        """Write one message (a JSON-able dict) on ``topic``.

        Parameters
        ----------
        topic : str
            One of :data:`TOPICS`.
        message : mapping
            The message fields.
        log_time_ns : int
            Log time in nanoseconds (wall clock, as Foxglove expects).

        Returns
        -------
        bool
            False when the recorder has failed (see :attr:`error`) or is closed.

        Raises
        ------
        RecordingError
            For an unknown topic (a programming error, not a runtime fault).

        Examples
        --------
        >>> import io; rec = Recorder(io.BytesIO())
        >>> rec.write("/nope", {}, 0)
        Traceback (most recent call last):
        ...
        slipreflex.recording.RecordingError: <stream>: unknown topic '/nope'
        """
        channel = self._channels.get(topic)
        if channel is None:
            raise RecordingError(f"{self.path}: unknown topic {topic!r}")
        if not self.ok:
            return False
        data = json.dumps(message, separators=(",", ":")).encode()
        try:
            self._writer.add_message(channel_id=channel, log_time=log_time_ns, data=data,
                                     publish_time=log_time_ns, sequence=self._seq)
        except OSError as err:
            return self._failed(err)
        self._seq += 1
        self.messages += 1
        return True

    def flush(self) -> bool:
        """Finish the current chunk and flush the file.

        Returns
        -------
        bool
            False when the recorder has failed.

        Examples
        --------
        >>> import io; Recorder(io.BytesIO()).flush()
        True
        """
        if not self.ok:
            return False
        try:
            self._writer.flush()
        except OSError as err:
            return self._failed(err)
        self._last_flush = time.monotonic()
        return True

    def maybe_flush(self) -> bool:
        """Flush if ``flush_interval`` seconds passed since the last flush.

        Returns
        -------
        bool
            True if a flush happened.

        Examples
        --------
        >>> import io; Recorder(io.BytesIO(), flush_interval=3600).maybe_flush()
        False
        """
        if self.ok and time.monotonic() - self._last_flush >= self.flush_interval:
            return self.flush()
        return False

    def add_metadata(self, name: str, data: Mapping[str, Any]) -> bool:
        """Add a metadata record (values are converted to str).

        Examples
        --------
        >>> import io; Recorder(io.BytesIO()).add_metadata("summary", {"p99": 0.5})
        True
        """
        if not self.ok:
            return False
        try:
            self._writer.add_metadata(name, sealed(name, data))
        except OSError as err:
            return self._failed(err)
        return True

    def _close_file(self) -> None:
        if self._owns:
            try:
                self._fh.close()
            except OSError as err:
                self._failed(err)

    def close(self) -> None:
        """Write the summary and footer and close the file (idempotent).

        A recorder that failed only closes the file.

        Examples
        --------
        >>> import io; rec = Recorder(io.BytesIO()); rec.close(); rec.close(); rec.ok
        False
        """
        if self._closed:
            return
        if self.error is None:
            try:
                self._writer.finish()
                self._fh.flush()
            except OSError as err:
                self._failed(err)
        self._closed = True
        self._close_file()
        if self.part_path is not None and self._owns:

            try:
                publish(self.part_path, self.path)
            except FileExistsError:   # someone made the name meanwhile: the recording keeps its .part name
                self._failed(FileExistsError(f"{self.path} appeared during the run; the recording is "
                                             f"{self.part_path}"))
                self.path = self.part_path
            except OSError as err:
                self._failed(err)
                self.path = self.part_path

    def _remove_part(self) -> None:
        """Remove the file this recorder created, if it is still the one it created."""
        if self.part_path is None:
            return
        try:
            st = os.lstat(self.part_path)
        except OSError:
            return
        if (st.st_dev, st.st_ino) == getattr(self, "_identity", None):
            os.unlink(self.part_path)

    def discard(self) -> None:
        """Close and remove the recording: for a run that never started (its ports did not open).

        Only the file this recorder created in this run is removed, never another.

        Examples
        --------
        >>> import tempfile, os
        >>> p = os.path.join(tempfile.mkdtemp(), "r.mcap")
        >>> rec = Recorder(p); rec.discard(); os.listdir(os.path.dirname(p))
        []
        """
        if not self._closed:
            self._closed = True
            self._close_file()
        self._remove_part()

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


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
    slipreflex.recording.RecordingError: /nonexistent.mcap: cannot open recording: No such file or directory
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


def chain_params_of(rec: Recording):
    """The :class:`~slipreflex.chain.ReflexParams` stored in a recording's metadata.

    Parameters
    ----------
    rec : Recording

    Returns
    -------
    ReflexParams

    Raises
    ------
    DataError
        The metadata is missing or malformed.

    Examples
    --------
    >>> import json
    >>> from slipreflex.chain import ReflexParams
    >>> meta = {METADATA_NAME: {"reflex_params": json.dumps(ReflexParams(dath=True).to_dict())}}
    >>> chain_params_of(Recording("r.mcap", metadata=meta)).dath
    True
    """

    raw = rec.metadata.get(METADATA_NAME, {}).get("reflex_params")
    if raw is None and rec.bad_metadata:
        raise DataError(f"{rec.path}: damaged metadata: record(s) {', '.join(map(repr, rec.bad_metadata))} "
                        f"fail their checksum; the chain parameters cannot be trusted (nothing to replay)")
    if raw is None and not rec.complete:
        where = f"at byte {rec.cut_at}" if rec.cut_at is not None else "before its parameters"
        raise DataError(f"{rec.path}: cut short {where}, before the chain parameters were written "
                        f"(nothing to replay)")
    if raw is None:
        raise DataError(f"{rec.path}: no chain parameters in the metadata record {METADATA_NAME!r} "
                        f"(not a slipreflex run recording?)")
    try:
        return ReflexParams.from_dict(json.loads(raw))
    except (ValueError, TypeError) as err:
        raise DataError(f"{rec.path}: bad chain parameters in the metadata: {err}") from None


@dataclass
class ReplayResult:
    """Outcome of :func:`replay`: the recorded and the re-computed events and commands.

    Events are ``(seq, t)`` of the spiking samples; commands ``(seq, t, target)``.

    Attributes
    ----------
    samples : int
    recorded_events, replayed_events : list of tuple
    recorded_commands, replayed_commands : list of tuple
    complete : bool
        Whether the recording was complete (see :attr:`Recording.complete`) and undamaged.
    gaps : str
        What the recording misses (:meth:`Recording.gaps`), "" if nothing.
    board_events, board_commands : list of tuple or None
        For a ``run --board-reflex`` recording: the spikes and window commands the
        board itself sent (``/board/state``), which the replayed twin must match too.

    Examples
    --------
    >>> r = ReplayResult(3, [(1, 0.003)], [(1, 0.003)], [], [], True)
    >>> r.identical
    True
    """

    samples: int
    recorded_events: list[tuple]
    replayed_events: list[tuple]
    recorded_commands: list[tuple]
    replayed_commands: list[tuple]
    complete: bool
    gaps: str = ""
    board_events: list[tuple] | None = None
    board_commands: list[tuple] | None = None

    def _pairs(self) -> list[tuple[str, list, list]]:
        out = [("events", self.recorded_events, self.replayed_events),
               ("commands", self.recorded_commands, self.replayed_commands)]
        if self.board_events is not None:
            out += [("board events", self.board_events, self.replayed_events),
                    ("board commands", self.board_commands or [], self.replayed_commands)]
        return out

    @property
    def identical(self) -> bool:
        """True if replay reproduced the recorded events and commands exactly.

        For a recording cut short, the recorded lists must be a prefix of the
        replayed ones (the crash may have cut derived messages of the last
        samples).

        Examples
        --------
        >>> ReplayResult(1, [], [(0, 0.0)], [], [], complete=False).identical
        True
        """
        if self.complete:
            return all(a == b for _, a, b in self._pairs())
        return all(b[:len(a)] == a for _, a, b in self._pairs())

    def summary(self) -> str:
        """One line per stream: counts and whether they match.

        Examples
        --------
        >>> print(ReplayResult(1, [], [], [], [], True).summary())
        samples 1
        events: recorded 0, replayed 0 - identical
        commands: recorded 0, replayed 0 - identical
        """
        def line(name: str, a: list, b: list) -> str:
            same = a == b if self.complete else b[:len(a)] == a
            if same:
                verdict = "identical"
            else:
                k = next((i for i, (x, y) in enumerate(zip(a, b)) if x != y), min(len(a), len(b)))
                verdict = (f"DIFFERENT from #{k}: recorded {a[k] if k < len(a) else None}, "
                           f"replayed {b[k] if k < len(b) else None}")
            return f"{name}: recorded {len(a)}, replayed {len(b)} - {verdict}"
        return "\n".join([f"samples {self.samples}" + ("" if self.complete else
                                                      " (recording cut short or damaged: checked up to the first gap)")]
                         + [line(name, a, b) for name, a, b in self._pairs()])


def replay(path: str | os.PathLike | Recording) -> ReplayResult:
    """Re-run the recorded chain offline over the recorded samples.

    A fresh :class:`~slipreflex.chain.SlipReflex` built from the parameters in
    the metadata gets every recorded sample, in order, with the slip-finger
    position the loop gave it; its events and commands are compared with
    the recorded ones. A ``run --board-reflex`` recording (metadata
    ``board_params``) replays its Python twin (:class:`slipreflex.board.BoardReflex`)
    and compares it with the board's own recorded output too.

    Parameters
    ----------
    path : path-like or Recording

    Returns
    -------
    ReplayResult

    Raises
    ------
    DataError
        Not a slipreflex run recording.

    Examples
    --------
    >>> import io, json, tempfile, os
    >>> from slipreflex.chain import ReflexParams
    >>> path = os.path.join(tempfile.mkdtemp(), "r.mcap")
    >>> meta = {METADATA_NAME: {"reflex_params": json.dumps(ReflexParams(p0=100.0).to_dict())}}
    >>> with Recorder(path, metadata=meta) as rec:
    ...     for k in range(16):
    ...         _ = rec.write("/daq/samples", {"seq": k, "t": k * 0.003, "slip_volts": 0.4,
    ...                       "flow_pulses": 0, "arrival": 0.0, "position": None}, k)
    ...     _ = rec.write("/hand/commands", {"seq": 15, "t": 15 * 0.003, "target": 100.0,
    ...                   "fingers": ["middle"], "sent": True, "latency": 1e-4}, 16)
    >>> replay(path).identical
    True
    """

    rec = path if isinstance(path, Recording) else read_recording(path)
    board_params = rec.metadata.get(METADATA_NAME, {}).get("board_params")
    if board_params is not None:

        reflex: Any = BoardReflex(board_params_from_json(board_params, rec.path))
    else:
        reflex = SlipReflex.from_params(chain_params_of(rec))
    upto = rec.before_damage or {}
    samples = rec.topic("/daq/samples")[:upto.get("/daq/samples", 0)]  # exact up to the first damage
    if not samples:
        raise DataError(f"{rec.path}: no samples before {'the first damaged chunk' if rec.damaged else 'its end'}"
                        f": nothing to replay")
    events: list[tuple] = []
    commands: list[tuple] = []
    for s in samples:
        cmd = reflex.step(s["slip_volts"], s.get("position"))
        if reflex.last_event:
            events.append((s["seq"], s["t"]))
        if cmd is not None:
            commands.append((s["seq"], s["t"], float(cmd)))
    return ReplayResult(
        samples=len(samples),
        recorded_events=[(m["seq"], m["t"]) for m in rec.topic("/chain/events")[:upto.get("/chain/events", 0)]],
        replayed_events=events,
        recorded_commands=[(m["seq"], m["t"], float(m["target"]))
                           for m in rec.topic("/hand/commands")[:upto.get("/hand/commands", 0)]],
        replayed_commands=commands, complete=rec.complete and not rec.damaged, gaps=rec.gaps(),
        **(_board_outputs(rec, upto.get("/board/state", 0)) if board_params is not None else {}))


def _board_outputs(rec: Recording, upto: int) -> dict[str, list[tuple]]:
    board = rec.topic("/board/state")[:upto]
    return {"board_events": [(m["seq"], m["t"]) for m in board if m["spike"]],
            "board_commands": [(m["seq"], m["t"], float(m["command"])) for m in board if m["window"]]}


def export_csv(path: str | os.PathLike | Recording, out: str | os.PathLike | None = None, *,
               all_streams: bool = False) -> list[str]:
    """Write a recording's slip-sensor samples as a CSV that ``slipreflex detect`` reads.

    The main file has columns ``t`` (board time, s) and ``x`` (volts). With
    ``all_streams`` companions are written next to it: ``-imu`` (t, ax, ay,
    az), ``-flow`` (t, pulses), ``-events`` (t), ``-windows`` (t, count),
    ``-commands`` (t, target, sent, latency) and ``-faults`` (time, kind).

    Parameters
    ----------
    path : path-like
        The MCAP recording.
    out : path-like, optional
        Main CSV path (default: the recording's path with ``.csv``).
    all_streams : bool
        Also write the companion CSVs.

    Returns
    -------
    list of str
        The files written, main first.

    Raises
    ------
    DataError
        The recording has no samples.

    Examples
    --------
    >>> import tempfile, os
    >>> from slipreflex.csvfiles import read_slip_csv
    >>> path = os.path.join(tempfile.mkdtemp(), "r.mcap")
    >>> with Recorder(path) as rec:
    ...     for k in range(3):
    ...         _ = rec.write("/daq/samples", {"seq": k, "t": k * 0.003, "slip_volts": 0.4 + k,
    ...                       "flow_pulses": 0, "arrival": 0.0, "position": None}, k)
    >>> files = export_csv(path)
    >>> read_slip_csv(files[0])[1].tolist()
    [0.4, 1.4, 2.4]
    """

    rec = path if isinstance(path, Recording) else read_recording(path)
    samples = rec.topic("/daq/samples")
    if not samples:
        raise DataError(f"{rec.path}: no slip-sensor samples to export")
    src = str(rec.path)[:-len(PART_SUFFIX)] if str(rec.path).endswith(PART_SUFFIX) else str(rec.path)
    main = Path(out) if out is not None else Path(src).with_suffix(".csv")   # run.mcap(.part) -> run.csv
    companions = {
        "imu": ("/daq/imu", ("t", "ax", "ay", "az")),
        "flow": ("/daq/flow", ("t", "pulses")),
        "events": ("/chain/events", ("t",)),
        "windows": ("/chain/windows", ("t", "count")),
        "commands": ("/hand/commands", ("t", "target", "sent", "latency")),
        "faults": ("/faults", ("time", "kind", "message", "action")),
    } if all_streams else {}
    targets = [main] + [main.with_name(f"{main.stem}-{suffix}.csv") for suffix in companions]
    for target in targets:  # every destination checked before the first file is written
        _check_output(target)
        if os.path.lexists(target):
            raise RecordingError(f"{target}: exists; export writes new files only (give another --out, "
                                 f"or move it)")
    _write_csv(main, {"t": [s["t"] for s in samples], "x": [s["slip_volts"] for s in samples]},
               preamble=export_preamble(rec))
    written = [str(main)]
    if all_streams:
        for target, (topic, cols) in zip(targets[1:], companions.values()):
            msgs = rec.topic(topic)
            _write_csv(target, {c: ["" if m.get(c) is None else m.get(c) for m in msgs] for c in cols})
            written.append(str(target))
    return written


#: Version of the ``# key: value`` preamble that :func:`export_csv` writes (docs/runtime.md).
EXPORT_FORMAT: str = "slipreflex-export 1"


def export_preamble(rec: Recording) -> dict[str, str]:
    """The facts an exported CSV carries in its ``# key: value`` preamble.

    ``format`` (:data:`EXPORT_FORMAT`), ``source`` (the recording),
    ``reflex`` (method), ``reflex_params`` (the run's
    :class:`~slipreflex.chain.ReflexParams` as JSON, ``ReflexParams.from_dict``
    rebuilds it, p0 included) and ``p0`` (JSON, the start position of each
    finger) - each only when the recording has it.

    Examples
    --------
    >>> import json
    >>> meta = {METADATA_NAME: {"reflex": "dath", "p0": json.dumps({"middle": 147.0})}}
    >>> export_preamble(Recording("r.mcap", metadata=meta))["p0"]
    '{"middle": 147.0}'
    """
    meta = rec.metadata.get(METADATA_NAME, {})
    start = rec.metadata.get("start", {})
    out = {"format": EXPORT_FORMAT, "source": os.path.basename(str(rec.path))}
    for key in ("reflex", "reflex_params"):
        if key in meta:
            out[key] = meta[key]
    p0 = start.get("p0", meta.get("p0"))
    if p0 is not None:
        out["p0"] = p0
    return out


def _check_output(target: Any) -> None:
    """Refuse a destination that is a folder, a device or another non-regular file, or whose
    folder does not exist."""
    if target.exists() and not target.is_file():
        raise RecordingError(f"{target}: exists and is not a regular file; refusing to replace it")
    if not target.parent.is_dir():
        raise RecordingError(f"{target}: folder {target.parent} does not exist")


def _write_csv(target: Any, columns: Mapping[str, Any], **kw: Any) -> None:

    try:
        write_columns(target, columns, replace=False, **kw)
    except FileExistsError:
        raise RecordingError(f"{target}: appeared meanwhile; export writes new files only") from None
    except OSError as err:
        raise RecordingError(f"{target}: cannot write: {err.strerror or err}") from None


__all__ += ["chain_params_of", "ReplayResult", "replay", "export_csv", "export_preamble", "EXPORT_FORMAT"]


@dataclass(frozen=True)
class RecoverResult:
    """What :func:`recover_recording` wrote.

    Attributes
    ----------
    messages : int
        Messages written (at least one: a file with none is an error).
    metadata : tuple of str
        Names of the metadata records written.
    gaps : str
        What the original misses (:meth:`Recording.gaps`), "" if it was intact.

    Examples
    --------
    >>> RecoverResult(3, ("slipreflex",), "").messages
    3
    """

    messages: int
    metadata: tuple[str, ...]
    gaps: str


def recover_recording(path: str | os.PathLike, out: str | os.PathLike) -> RecoverResult:
    """Rewrite every readable record of a recording as a complete MCAP file.

    A file cut by a crash has no summary or footer, which mcap's standard
    readers need. This reads it the way :func:`read_recording` does
    (damaged chunks skipped, up to the last complete chunk) and writes the
    schemas, channels, messages (same log times, publish times and sequence
    numbers) and metadata to ``out``, with a summary and footer. The file
    appears under its name only when complete; ``path`` is never changed.

    Parameters
    ----------
    path : path-like
        The recording.
    out : path-like
        The complete file to write (not ``path``; never replaces a non-regular file).

    Returns
    -------
    RecoverResult

    Raises
    ------
    RecordingError
        ``out`` is ``path``, not a regular file, in a missing folder, or cannot be written.
    DataError
        ``path`` is not an MCAP file.

    Examples
    --------
    >>> import tempfile, os
    >>> d = tempfile.mkdtemp(); path = os.path.join(d, "r.mcap")
    >>> with Recorder(path) as rec:
    ...     _ = rec.write("/chain/events", {"seq": 1, "t": 0.003}, 1)
    >>> res = recover_recording(path, os.path.join(d, "copy.mcap"))
    >>> res.messages, res.gaps
    (1, '')
    """

    from mcap.records import Channel, Header, Message, Metadata, Schema  # deferred: heavy (mcap)
    from mcap.writer import CompressionType, Writer  # deferred: heavy (mcap)


    src, dst = Path(path), Path(out)
    if dst.exists() and src.exists() and dst.resolve() == src.resolve():
        raise RecordingError(f"{dst}: recover writes a new file; give another --out than the recording")
    _check_output(dst)
    if os.path.lexists(dst):
        raise RecordingError(f"{dst}: exists; recover writes a new file (give another --out)")
    rec = Recording(path=os.fspath(path))
    messages, names = 0, []
    counted = ("/daq/samples", "/stats")   # what the summary line counts (Recording.gaps)
    try:
        with new_file(dst, "wb") as fh:
            writer = Writer(fh, chunk_size=64 * 1024, compression=CompressionType.ZSTD)
            writer.start(profile="", library="slipreflex recover; metadata sha256")
            schemas: dict[int, int] = {}
            channels: dict[int, int] = {}
            topics: dict[int, str] = {}
            for _, r in _scan(os.fspath(path), rec):
                if isinstance(r, Header):
                    rec.sealed = "metadata sha256" in str(r.library)
                elif isinstance(r, Schema) and r.id not in schemas:
                    schemas[r.id] = writer.register_schema(name=r.name, encoding=r.encoding, data=r.data)
                elif isinstance(r, Channel) and r.id not in channels:
                    topics[r.id] = r.topic
                    channels[r.id] = writer.register_channel(
                        topic=r.topic, message_encoding=r.message_encoding,
                        schema_id=schemas.get(r.schema_id, 0), metadata=dict(r.metadata))
                elif isinstance(r, Message) and r.channel_id in channels:
                    writer.add_message(channel_id=channels[r.channel_id], log_time=r.log_time,
                                       data=r.data, publish_time=r.publish_time, sequence=r.sequence)
                    messages += 1
                    if topics[r.channel_id] in counted:
                        try:
                            rec.messages.setdefault(topics[r.channel_id], []).append(json.loads(r.data))
                        except ValueError:
                            pass
                elif isinstance(r, Metadata):
                    data = dict(r.metadata)
                    if rec.sealed and not verify(r.name, data):
                        rec.bad_metadata.append(r.name)   # copied as it is; the reader flags it again
                    else:
                        rec.metadata[r.name] = {k: v for k, v in data.items() if k != CHECKSUM_KEY}
                    writer.add_metadata(r.name, data)
                    names.append(r.name)
            if messages == 0:
                raise DataError(f"{path}: no readable message to recover"
                                + (f" ({rec.gaps().split(': ', 1)[-1]})" if rec.gaps() else "")
                                + f"; {dst} not written")
            writer.finish()
    except FileExistsError:
        raise RecordingError(f"{dst}: appeared meanwhile; recover writes a new file (give another --out)") from None
    except OSError as err:
        if isinstance(err, RecordingError):
            raise
        raise RecordingError(f"{dst}: cannot write: {err.strerror or err}") from None
    return RecoverResult(messages, tuple(names), rec.gaps())


__all__ += ["RecoverResult", "recover_recording"]
