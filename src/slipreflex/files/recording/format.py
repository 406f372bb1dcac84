"""The recording format: its topics and their fields, the schemas, the metadata records and their checksums.

The one definition of what a recording holds (the topics are listed in
:mod:`slipreflex.files.recording`); the writer, the reader and the live view
(:mod:`slipreflex.rig.live`) read it. It imports nothing of the chain or the board.

Examples
--------
>>> from slipreflex.files.recording.format import TOPICS, schema
>>> schema("/chain/events")[0], "/daq/samples" in TOPICS
('slipreflex.Event', True)
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from typing import Any

from ...core.errors import SlipreflexError

__all__ = [
    "TOPICS", "METADATA_NAME", "RecordingError", "schema", "FINGER_FIELDS", "PART_SUFFIX", "CHECKSUM_KEY",
    "LIBRARY", "sealed", "verify", "PLANNED_SAMPLES",
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


RecordingError.__module__ = "slipreflex.files.recording"   # where users import it from: tracebacks name it so


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
    live view (:mod:`slipreflex.rig.live`) both use.

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
