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
/hand/commands     reflex commands: target, fingers, sent (bool), latency (s)
/faults            watchdog, device and recording faults, with the action taken
/stats             periodic DAQ and loop counters
=================  ===========================================================

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

import json
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import IO, Any

from .errors import DataError, SlipreflexError

__all__ = [
    "TOPICS", "METADATA_NAME", "RecordingError", "Recorder", "Recording", "read_recording",
]

#: Name of the metadata record holding the chain parameters and run facts.
METADATA_NAME: str = "slipreflex"

_N, _I, _B, _S = (["number", "null"], "integer", "boolean", "string")
_ACCEL = {"ax": "number", "ay": "number", "az": "number"}

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
                                              "sent": _B, "latency": _N}),
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


def _schema(name: str, fields: dict[str, Any]) -> bytes:
    props = {k: (v if isinstance(v, dict) else {"type": v}) for k, v in fields.items()}
    return json.dumps({"$schema": "http://json-schema.org/draft-07/schema#", "title": name,
                       "type": "object", "properties": props}).encode()


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
        from mcap.writer import CompressionType, Writer

        comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4,
                "none": CompressionType.NONE}.get(compression)
        if comp is None:
            raise RecordingError(f"unknown compression {compression!r} (zstd, lz4 or none)")
        self.flush_interval = flush_interval
        self.error: OSError | None = None
        self.messages = 0
        self._closed = False
        if isinstance(path, (str, os.PathLike)):
            self.path = os.fspath(path)
            try:
                self._fh: IO[bytes] = open(self.path, "wb")
            except OSError as err:
                raise RecordingError(f"{self.path}: cannot create recording: "
                                     f"{err.strerror or err}") from None
            self._owns = True
        else:
            self.path = str(getattr(path, "name", "<stream>"))
            self._fh = path
            self._owns = False
        try:
            self._writer = Writer(self._fh, chunk_size=chunk_size, compression=comp)
            self._writer.start(profile="", library="slipreflex")
            self._channels: dict[str, int] = {}
            for topic, (name, fields) in TOPICS.items():
                sid = self._writer.register_schema(name=name, encoding="jsonschema",
                                                   data=_schema(name, fields))
                self._channels[topic] = self._writer.register_channel(
                    topic=topic, message_encoding="json", schema_id=sid)
            for name, data in (metadata or {}).items():
                self._writer.add_metadata(name, {str(k): str(v) for k, v in data.items()})
            self._writer.flush()
        except OSError as err:
            self._close_file()
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
            self._writer.add_metadata(name, {str(k): str(v) for k, v in data.items()})
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

    def __enter__(self) -> "Recorder":
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

    def topic(self, name: str) -> list[dict[str, Any]]:
        """Messages of one topic (empty list if none).

        Examples
        --------
        >>> Recording("x.mcap", messages={"/faults": [{"kind": "watchdog"}]}).topic("/faults")[0]["kind"]
        'watchdog'
        """
        return self.messages.get(name, [])


def read_recording(path: str | os.PathLike) -> Recording:
    """Read a recording, including one cut short by a crash.

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
    import struct

    from mcap.exceptions import InvalidMagic, McapError
    from mcap.records import Channel, Footer, Message, Metadata
    from mcap.stream_reader import StreamReader

    path = os.fspath(path)
    rec = Recording(path=path)
    try:
        fh = open(path, "rb")
    except OSError as err:
        raise RecordingError(f"{path}: cannot open recording: {err.strerror or err}") from None
    topics: dict[int, str] = {}
    with fh:
        records = StreamReader(fh).records
        while True:
            try:
                record = next(records)
            except StopIteration:
                break
            except InvalidMagic as err:
                if not topics and not rec.metadata:
                    raise DataError(f"{path}: not an MCAP file ({err})") from None
                break  # a file cut right after its footer's start
            except (McapError, EOFError, struct.error, ValueError, KeyError):
                break  # cut short: keep what was read
            except Exception:  # noqa: BLE001 - e.g. a decompression error in a torn chunk
                break
            if isinstance(record, Channel):
                topics[record.id] = record.topic
            elif isinstance(record, Message):
                topic = topics.get(record.channel_id)
                if topic is None:
                    continue
                try:
                    msg = json.loads(record.data)
                except ValueError:
                    raise DataError(f"{path}: message {record.sequence} on {topic} is not JSON") from None
                rec.messages.setdefault(topic, []).append(msg)
                rec.log_times.setdefault(topic, []).append(record.log_time)
            elif isinstance(record, Metadata):
                rec.metadata[record.name] = dict(record.metadata)
            elif isinstance(record, Footer):
                rec.complete = True
    return rec
