"""What the real-time loop reports: one :class:`Fault`, one :class:`SampleRecord`, the :class:`RunResult`.

:func:`slipreflex.rig.runtime.run_loop` fills them; they are importable from
:mod:`slipreflex.rig.runtime` too.

Examples
--------
>>> RunResult(samples=3).samples
3
"""

from __future__ import annotations

import collections
import json
import math
import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.errors import ParameterError
from ..core.hardware import FINGER_MAX, Finger
from ..core.interfaces import DaqSample

__all__ = ["Fault", "SampleRecord", "RunResult", "print_fault"]


@dataclass(frozen=True, slots=True)
class Fault:
    """One fault seen by the loop.

    Attributes
    ----------
    time : float
        Seconds since the run started.
    kind : str
        ``"watchdog"``, ``"watchdog-clear"``, ``"stale"``, ``"stale-clear"``,
        ``"loop-stalled"``, ``"no-data"``, ``"daq-port"``, ``"daq-port-restored"``,
        ``"daq-crc"``, ``"daq-truncated"``, ``"daq-invalid"``, ``"daq-garbage"``,
        ``"daq-gap"``, ``"daq-duplicate"``, ``"daq-reordered"``, ``"daq-reset"``,
        ``"daq-discarded"``, ``"hand-port"``, ``"hand-port-restored"``,
        ``"command-rejected"``, ``"hold-failed"``, ``"stop-failed"``, ``"mpi-saturated"``,
        ``"recording"`` or
        ``"board-mismatch"`` (``run --board-reflex``: the board's chain output differs
        from its Python twin's on the same sample).
    message : str
        What happened, naming the port or file.
    action : str
        What the loop did about it.

    Examples
    --------
    >>> Fault(0.5, "watchdog", "no valid sample for 100 ms", "fingers held").kind
    'watchdog'
    """

    time: float
    kind: str
    message: str
    action: str

    def to_dict(self) -> dict[str, Any]:
        """Fields as a dict (the /faults message).

        Examples
        --------
        >>> Fault(1.0, "k", "m", "a").to_dict()["action"]
        'a'
        """
        return {"time": self.time, "kind": self.kind, "message": self.message, "action": self.action}


@dataclass(slots=True)
class SampleRecord:
    """What the loop did with one sample (the typed record of the *process* step).

    Attributes
    ----------
    sample : DaqSample
        The decoded sample.
    arrival : float
        Clock time at which its bytes were read from the port.
    age : float
        Seconds since the frame arrived, as its board time places it, when the
        reflex processed it (large for a backlog).
    position : float or None
        Slip-finger position given to the reflex (in the reflex's frame).
    command : float or None
        The reflex's command, when this sample completed a window.
    grip : dict of Finger to float or None
        The grip (units) the command adds to each finger: how far it rose.
    filtered, threshold : float or None
    event : bool
    count : int or None
        The window's spike count, when this sample completed a window.
    sent : bool
        Whether the hand was told to close (or to close longer) for it.
    note : str
        Why a command was not sent: ``"at start"`` (no rise yet), ``"no rise"``, ``"stale"``,
        ``"rejected"``, ``"hand-port"``.
    latency, frame_latency : float or None
        Seconds from ``arrival`` (read) and from the frame's own arrival to the write.
    board : dict or None
        With a board that runs the reflex (``slipreflex.methods.board.CheckedBoardReflex``):
        the board's own output for this sample and whether the twin agreed.

    Examples
    --------
    >>> r = SampleRecord(DaqSample(0, 0.0, 0.4, None, 0), arrival=1.0, age=0.001)
    >>> r.sent, r.command
    (False, None)
    """

    sample: DaqSample
    arrival: float
    age: float
    position: float | None = None
    command: float | None = None
    grip: dict[Finger, float] | None = None
    filtered: float | None = None
    threshold: float | None = None
    event: bool = False
    count: int | None = None
    sent: bool = False
    note: str = ""
    latency: float | None = None
    frame_latency: float | None = None
    board: dict[str, Any] | None = None


def _percentiles_ms(x: np.ndarray) -> dict[str, float]:
    if x.size == 0:
        return {"p50": math.nan, "p99": math.nan, "max": math.nan}
    ms = x * 1e3
    return {"p50": float(np.percentile(ms, 50)), "p99": float(np.percentile(ms, 99)),
            "max": float(ms.max())}


@dataclass
class RunResult:
    """What a run did.

    Attributes
    ----------
    samples, events, windows, commands : int
        Samples processed, spikes, windows and reflex commands.
    commands_sent : int
        Commands the hand driver accepted and wrote.
    latencies : numpy.ndarray
        Seconds from reading the sample's bytes to the command written, per sent command.
    frame_latencies : numpy.ndarray
        Seconds from the frame's own arrival (its board time, anchored to the
        earliest-arriving frames) to the command written, per sent command.
    faults : list of Fault
    daq_stats : dict
        The source's counters at the end (``seq_gaps``, ``crc_errors``, ...), if it has any.
    duration : float
        Seconds the loop ran.
    interrupted : bool
        True if stopped by Ctrl-C.
    recording_error : str or None
        Why the recording stopped early, if it did.
    start : dict
        Position (finger name -> units) each finger held at start, after the
        safe start's STOP: measured where the hand reports it, else ``p0``
        (bookkeeping only: the loop sends no positions).
    initial_command : str
        What the loop sent first (the STOP of the safe start).
    holds_sent : int
        Holds (STOP) sent by the watchdog, its re-sends and the stall guard.
    stale_samples : int
        Samples older than the watchdog when processed (their commands were held back).
    dropped_at_start : int
        Frames the source buffered while the run set up (warm-up, safe start), dropped
        before the clock started (the source's optional ``drop_buffered()``).
    saturated_at : float or None
        Board time (s) at which the reflex's command first reached its ceiling
        (``ceiling``): from then on it adds no grip.
    saturated_windows : int
        Windows with spikes after that: slips the command could not answer.
    ceiling : float
        The reflex's command ceiling (``params.hi``; 500 when it declares none).
    grip_added : dict
        Grip (finger name -> units) the loop told each finger to add.
    closes, stops : int
        CLOSE commands sent, and the STOPs that ended a closing.
    grip_unknown : list of str
        Fingers whose closing's STOP never reached the hand (a lost port): their grip is at
        least ``grip_added`` and may be up to their end stop.
    stalled : list of str
        Fingers the hand reported stalled (it ignores closing until opened): grip sent to
        them afterwards is not counted in ``grip_added``.
    error : str or None
        Why the run ended early: the method raised in ``step()`` (fingers held first).

    Examples
    --------
    >>> r = RunResult(latencies=np.array([1e-4, 2e-4, 3e-4]))
    >>> {k: round(v, 3) for k, v in r.latency_ms().items()}
    {'p50': 0.2, 'p99': 0.298, 'max': 0.3}
    """

    samples: int = 0
    events: int = 0
    windows: int = 0
    commands: int = 0
    commands_sent: int = 0
    latencies: np.ndarray = field(default_factory=lambda: np.zeros(0))
    frame_latencies: np.ndarray = field(default_factory=lambda: np.zeros(0))
    faults: list[Fault] = field(default_factory=list)
    daq_stats: dict[str, int] = field(default_factory=dict)
    duration: float = 0.0
    interrupted: bool = False
    recording_error: str | None = None
    start: dict[str, float] = field(default_factory=dict)
    initial_command: str = ""
    holds_sent: int = 0
    stale_samples: int = 0
    dropped_at_start: int = 0
    saturated_at: float | None = None
    saturated_windows: int = 0
    ceiling: float = float(FINGER_MAX)
    grip_added: dict[str, float] = field(default_factory=dict)
    closes: int = 0
    stops: int = 0
    grip_unknown: list[str] = field(default_factory=list)
    stalled: list[str] = field(default_factory=list)
    error: str | None = None

    def latency_ms(self, since: str = "read") -> dict[str, float]:
        """p50, p99 and max of the command latency in milliseconds (NaN if none).

        Parameters
        ----------
        since : {"read", "frame"}
            From reading the bytes, or from the frame's own arrival.

        Examples
        --------
        >>> RunResult().latency_ms()["p99"]
        nan
        """
        if since not in ("read", "frame"):
            raise ParameterError(f"latency_ms: since must be 'read' or 'frame', got {since!r}")
        return _percentiles_ms(self.latencies if since == "read" else self.frame_latencies)

    def summary(self) -> str:
        """A few human-readable lines for the end of a run.

        Examples
        --------
        >>> print(RunResult(samples=3).summary().splitlines()[0])
        samples 3, events 0, windows 0, commands 0 (0 sent) in 0.0 s
        """
        lines = [f"samples {self.samples}, events {self.events}, windows {self.windows}, "
                 f"commands {self.commands} ({self.commands_sent} sent) in {self.duration:.1f} s"]
        for since, what in (("read", "sample read"), ("frame", "frame arrival")):
            lat = self.latency_ms(since)
            lines.append(f"latency {what}->command: p50 {lat['p50']:.3f} ms, p99 {lat['p99']:.3f} ms, "
                         f"max {lat['max']:.3f} ms (n={self.latencies.size})")
        if self.daq_stats:
            d = self.daq_stats
            lines.append("daq: " + ", ".join(f"{k} {d[k]}" for k in (
                "frames", "seq_gaps", "frames_lost", "crc_errors", "truncated", "resyncs",
                "garbage_bytes", "duplicates", "reordered", "resets", "disconnects", "reconnects",
                "frames_discarded") if k in d))
        if self.grip_added:
            lines.append("grip added: " + ", ".join(f"{k} {'>= ' * (k in self.grip_unknown)}{v:.1f}"
                                                     for k, v in self.grip_added.items())
                         + f" units ({self.closes} closings)")
        if self.grip_unknown:
            lines.append(f"STOP never reached {', '.join(self.grip_unknown)}: they may have closed to their "
                         f"end stops (grip at least as above)")
        if self.stalled:
            lines.append(f"stalled (the hand ignores closing until opened): {', '.join(self.stalled)}; "
                         f"grip sent to them after the stall is not counted")
        if self.error:
            lines.append(f"ended early: {self.error}")
        if self.saturated_at is not None:
            lines.append(f"reflex command at its ceiling {self.ceiling:g} from t={self.saturated_at:.3f} s: it "
                         f"adds no grip after that; {self.saturated_windows} later windows with spikes "
                         f"added none")
        kinds = collections.Counter(f.kind for f in self.faults)
        lines.append("faults: " + (", ".join(f"{k} x{n}" for k, n in kinds.items()) or "none")
                     + (f"; holds sent {self.holds_sent}" if self.holds_sent else "")
                     + (f"; stale samples {self.stale_samples}" if self.stale_samples else "")
                     + (f"; {self.dropped_at_start} frames from before the start dropped"
                        if self.dropped_at_start else ""))
        if self.recording_error:
            lines.append(f"recording stopped early: {self.recording_error}")
        return "\n".join(lines)

    def summary_metadata(self) -> dict[str, str]:
        """The summary as a metadata record (``run_summary`` in a recording).

        Examples
        --------
        >>> RunResult(samples=2).summary_metadata()["samples"]
        '2'
        """
        out = {"samples": self.samples, "commands": self.commands, "commands_sent": self.commands_sent,
               "events": self.events, "duration_s": f"{self.duration:.3f}",
               "faults": len(self.faults), "holds_sent": self.holds_sent,
               "stale_samples": self.stale_samples, "dropped_at_start": self.dropped_at_start,
               "saturated_at": "" if self.saturated_at is None else f"{self.saturated_at:.6f}",
               "saturated_windows": self.saturated_windows, "ceiling": self.ceiling,
               "grip_added": json.dumps(self.grip_added), "closes": self.closes, "stops": self.stops,
               "grip_unknown": json.dumps(self.grip_unknown), "stalled": json.dumps(self.stalled),
               "error": self.error or ""}
        for since, key in (("read", "latency"), ("frame", "frame_latency")):
            for q, v in self.latency_ms(since).items():
                out[f"{key}_{q}_ms"] = f"{v:.4f}"
        return {k: str(v) for k, v in out.items()}



def print_fault(fault: Fault, file: Any = None) -> None:
    """Print a fault as one line on stderr (the CLI's ``on_fault``).

    Examples
    --------
    >>> import io; buf = io.StringIO()
    >>> print_fault(Fault(1.25, "watchdog", "no sample", "held"), file=buf); buf.getvalue()
    '[   1.250 s] watchdog: no sample -> held\\n'
    """
    print(f"[{fault.time:8.3f} s] {fault.kind}: {fault.message} -> {fault.action}",
          file=file if file is not None else sys.stderr, flush=True)
