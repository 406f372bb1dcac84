"""The recording writer: a run to an MCAP file, crash-tolerantly (:class:`Recorder`).

Messages go into small chunks, and the writer finishes the current chunk and
flushes the file at least every ``flush_interval`` seconds, so a process killed
mid-run leaves a file whose complete chunks the reader
(:func:`slipreflex.files.recording.read_recording`) reads.

Examples
--------
>>> import io
>>> from slipreflex.files.recording.writer import Recorder
>>> Recorder(io.BytesIO()).ok
True
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Mapping
from typing import IO, Any

from ..paths import create_new, publish
from .format import LIBRARY, PART_SUFFIX, TOPICS, RecordingError, schema, sealed

__all__ = ["Recorder"]


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
        slipreflex.files.recording.RecordingError: <stream>: unknown topic '/nope'
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
