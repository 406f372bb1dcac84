"""Recovery: every readable record of a recording cut by a crash, rewritten as a complete MCAP file.

Examples
--------
>>> from slipreflex.files.recording.recover import RecoverResult
>>> RecoverResult(1, (), "").gaps
''
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

from ...core.errors import DataError
from ..paths import new_file
from .export import _check_output
from .format import CHECKSUM_KEY, RecordingError, verify
from .reader import Recording, _scan

__all__ = ["RecoverResult", "recover_recording"]


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
    >>> from slipreflex.files.recording import Recorder
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
