"""Export of a recording's samples (and, on request, every stream) as CSV files ``slipreflex detect`` reads.

Examples
--------
>>> from slipreflex.files.recording.export import EXPORT_FORMAT
>>> EXPORT_FORMAT
'slipreflex-export 1'
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ...core.errors import DataError
from ..csvfiles import write_columns
from .format import METADATA_NAME, PART_SUFFIX, RecordingError
from .reader import Recording, read_recording

__all__ = ["export_csv", "export_preamble", "EXPORT_FORMAT"]


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
    >>> from slipreflex.files.csvfiles import read_slip_csv
    >>> from slipreflex.files.recording import Recorder
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
    :class:`~slipreflex.methods.chain.ReflexParams` as JSON, ``ReflexParams.from_dict``
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
