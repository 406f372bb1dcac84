"""Recordings of runs: MCAP files of JSON messages with JSON schemas (open in Foxglove).

The one definition of the recording format: its topics, their fields
(:data:`TOPICS`), the metadata record that stores the chain's parameters, a
crash-tolerant writer (:class:`Recorder`) and a reader that also reads a file
cut short by a crash (:func:`read_recording`). One module per job:

=================  ===========================================================
``format``         topics, fields, schemas, metadata records and checksums
``writer``         :class:`Recorder`
``reader``         :class:`Recording`, :func:`read_recording` (bounded, damage-tolerant)
``export``         :func:`export_csv`, :func:`export_preamble`
``recover``        :func:`recover_recording`
=================  ===========================================================

Every public name of these modules is importable from here. Replaying a
recording's chain (:func:`slipreflex.rig.replay.replay`, :func:`slipreflex.rig.replay.chain_params_of`)
needs the chain and the board's twin, so it lives above, in :mod:`slipreflex.rig.replay`: this package
imports nothing of the chain or the board.

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
(``counters``) is a scalar: what a live plot (``--live``, :mod:`slipreflex.rig.live`) draws as
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

from .export import EXPORT_FORMAT, export_csv, export_preamble
from .format import (
    CHECKSUM_KEY,
    FINGER_FIELDS,
    LIBRARY,
    METADATA_NAME,
    PART_SUFFIX,
    PLANNED_SAMPLES,
    TOPICS,
    RecordingError,
    schema,
    sealed,
    verify,
)
from .reader import Recording, read_recording
from .recover import RecoverResult, recover_recording
from .writer import Recorder

__all__ = [
    "TOPICS", "METADATA_NAME", "RecordingError", "Recorder", "Recording", "read_recording", "schema",
    "FINGER_FIELDS", "PART_SUFFIX", "CHECKSUM_KEY", "LIBRARY", "sealed", "verify", "PLANNED_SAMPLES",
    "export_csv", "export_preamble", "EXPORT_FORMAT", "RecoverResult", "recover_recording",
]
