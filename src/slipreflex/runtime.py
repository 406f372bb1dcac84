"""The real-time loop: DAQ samples in, reflex commands out, everything recorded.

:func:`run_loop` reads samples from any :class:`~slipreflex.interfaces.SampleSource`
(the serial DAQ, the virtual DAQ on a pty, anything with ``read``), feeds each
to the same reflex object used in simulation and replay, sends its commands to
any :class:`~slipreflex.interfaces.Hand`, and records every stream with a
:class:`~slipreflex.recording.Recorder`.

What it guarantees:

- **Latency** from a sample's arrival (the moment its bytes were read from the
  port, ``source.last_arrival`` when the source provides it) to its command
  being written is measured for every command; :class:`RunResult` reports
  p50, p99 and max.
- **Watchdog**: when no valid sample arrives for ``watchdog`` seconds (100 ms
  by default) the grasping fingers are told to hold where they are
  (``hand.hold()`` if the hand has it, else its last target is re-sent); the
  hand is never opened by a fault. The fault is reported and recorded, and
  the reflex resumes, unchanged, when samples return.
- **Faults never stop the loop**: a DAQ or hand port that fails, a command
  the hand driver rejects, a recording that cannot be written any more - each
  becomes a :class:`Fault` (recorded, reported) and the loop goes on.
- **Stopping**: after ``duration`` seconds, when ``stop`` is set, or on
  Ctrl-C; the recording is always closed by the caller's ``with`` block.

Examples
--------
>>> from slipreflex.chain import SlipReflex
>>> from slipreflex.interfaces import DaqSample
>>> class Source:                          # 64 samples of a still surface, then nothing
...     def __init__(self): self.left = [DaqSample(k, k * 0.003, 0.4, None, 0) for k in range(64)]
...     def read(self, timeout):
...         out, self.left = self.left[:8], self.left[8:]
...         return out
...     def close(self): pass
>>> class Hand:
...     def __init__(self): self.targets = {}
...     def set_positions(self, t): self.targets.update(t)
...     def positions(self): return dict(self.targets)
>>> res = run_loop(Source(), Hand(), SlipReflex(p0=200.0), duration=0.5)
>>> res.samples, res.commands, [f.kind for f in res.faults]
(64, 4, ['watchdog'])
"""

from __future__ import annotations

import gc
import json
import math
import os
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import DeviceError, ParameterError
from .hardware import FINGER_MAX, FINGER_MIN, SLIP_FINGER, THUMB_ROTATOR_MAX, TRIPOD, Finger
from .interfaces import DaqSample, Hand

__all__ = ["Fault", "RunResult", "run_loop", "print_fault", "realtime_priority", "WATCHDOG_S",
           "start_positions", "safe_start", "WATCHDOG_MIN_S", "WATCHDOG_MAX_S"]

#: Seconds without a valid sample after which the watchdog holds the fingers.
WATCHDOG_S: float = 0.1
#: Bounds of the watchdog (s): shorter trips on the DAQ's normal jitter, longer is no watchdog.
WATCHDOG_MIN_S: float = 0.02
WATCHDOG_MAX_S: float = 0.5


@dataclass(frozen=True, slots=True)
class Fault:
    """One fault seen by the loop.

    Attributes
    ----------
    time : float
        Seconds since the run started.
    kind : str
        ``"watchdog"``, ``"watchdog-clear"``, ``"daq-port"``, ``"hand-port"``,
        ``"hand-port-restored"``, ``"command-rejected"``, ``"hold-failed"``
        or ``"recording"``.
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
        Seconds from sample arrival to command written, per sent command.
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
        safe start's STOP: no command the loop sent was below it.
    initial_command : str
        What the loop sent first (the STOP of the safe start).

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
    faults: list[Fault] = field(default_factory=list)
    daq_stats: dict[str, int] = field(default_factory=dict)
    duration: float = 0.0
    interrupted: bool = False
    recording_error: str | None = None
    start: dict[str, float] = field(default_factory=dict)
    initial_command: str = ""

    def latency_ms(self) -> dict[str, float]:
        """p50, p99 and max of the command latency in milliseconds (NaN if none).

        Examples
        --------
        >>> RunResult().latency_ms()["p99"]
        nan
        """
        if self.latencies.size == 0:
            return {"p50": math.nan, "p99": math.nan, "max": math.nan}
        ms = self.latencies * 1e3
        return {"p50": float(np.percentile(ms, 50)), "p99": float(np.percentile(ms, 99)),
                "max": float(ms.max())}

    def summary(self) -> str:
        """A few human-readable lines for the end of a run.

        Examples
        --------
        >>> print(RunResult(samples=3).summary().splitlines()[0])
        samples 3, events 0, windows 0, commands 0 (0 sent) in 0.0 s
        """
        lat = self.latency_ms()
        lines = [f"samples {self.samples}, events {self.events}, windows {self.windows}, "
                 f"commands {self.commands} ({self.commands_sent} sent) in {self.duration:.1f} s",
                 f"latency sample->command: p50 {lat['p50']:.3f} ms, p99 {lat['p99']:.3f} ms, "
                 f"max {lat['max']:.3f} ms (n={self.latencies.size})"]
        if self.daq_stats:
            d = self.daq_stats
            lines.append("daq: " + ", ".join(f"{k} {d[k]}" for k in
                                              ("frames", "seq_gaps", "frames_lost", "crc_errors",
                                               "truncated", "resyncs", "garbage_bytes",
                                               "disconnects", "reconnects") if k in d))
        kinds: dict[str, int] = {}
        for f in self.faults:
            kinds[f.kind] = kinds.get(f.kind, 0) + 1
        lines.append("faults: " + (", ".join(f"{k} x{n}" for k, n in kinds.items()) or "none"))
        if self.recording_error:
            lines.append(f"recording stopped early: {self.recording_error}")
        return "\n".join(lines)


def _num(x: Any) -> float | None:
    """JSON-safe float: NaN/inf/None -> None."""
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def start_positions(p0: float | Mapping[Any, float], fingers: Sequence[Finger] = TRIPOD,
                    *, where: str = "p0") -> dict[Finger, float]:
    """Validate ``p0`` and give one start position per finger.

    Parameters
    ----------
    p0 : float or mapping of Finger (or finger name) to float
        One position for every finger, or one per finger (every finger of
        ``fingers`` must be given). Positions are whole i-Limb units in the
        finger's range (0..500).
    fingers : sequence of Finger
    where : str
        Name used in error messages (e.g. ``"--p0"``).

    Returns
    -------
    dict of Finger to float

    Raises
    ------
    ParameterError
        A missing or unknown finger, or a position that is not a whole
        number in range; the message names ``where`` and the finger.

    Examples
    --------
    >>> start_positions({"thumb": 149, "index": 147, "middle": 147})[Finger.THUMB]
    149.0
    >>> start_positions(600)
    Traceback (most recent call last):
    ...
    slipreflex.errors.ParameterError: p0: THUMB must be a whole position in 0..500, got 600
    """
    fingers = tuple(Finger(f) for f in fingers)
    if isinstance(p0, Mapping):
        given: dict[Finger, Any] = {}
        for k, v in p0.items():
            try:
                f = Finger[k.upper()] if isinstance(k, str) else Finger(k)
                if f not in fingers:
                    raise KeyError(k)
            except (KeyError, ValueError):
                raise ParameterError(f"{where}: finger {k!r} is not one of the grasping fingers "
                                     f"(fingers: {', '.join(x.name.lower() for x in fingers)})") from None
            given[f] = v
        missing = [f.name.lower() for f in fingers if f not in given]
        if missing:
            raise ParameterError(f"{where}: no position for {', '.join(missing)} "
                                 f"(give every finger, e.g. thumb=149,index=147,middle=147)")
    else:
        given = {f: p0 for f in fingers}
    out: dict[Finger, float] = {}
    for f in fingers:
        v = given[f]
        hi = THUMB_ROTATOR_MAX if f == Finger.THUMB_ROTATOR else FINGER_MAX
        ok = (not isinstance(v, bool) and isinstance(v, (int, float, np.integer, np.floating))
              and math.isfinite(v) and float(v).is_integer() and FINGER_MIN <= v <= hi)
        if not ok:
            raise ParameterError(f"{where}: {f.name} must be a whole position in {FINGER_MIN}..{hi}, "
                                 f"got {v!r}")
        out[f] = float(v)
    return out


def safe_start(hand: Hand, p0: float | Mapping[Any, float],
               fingers: Sequence[Finger] = TRIPOD) -> dict[Finger, float]:
    """Hold the fingers where they are, then tell where each one holds.

    The hand is told to STOP (``hand.hold(fingers)``; a hand without
    ``hold`` is sent nothing): the fingers are never moved to a value at
    start. Each finger's start position is the larger of its ``p0`` and the
    position the hand reports for it (a hand that measures its fingers, or a
    driver that remembers the targets it wrote), so that a ``p0`` given too
    low can never make a later command open a finger the hand reports
    closed further. The i-Limb reports no positions over its serial
    protocol, so for it the start is the ``p0`` given, per finger, as the
    grasp routine found it.

    Parameters
    ----------
    hand : Hand
    p0 : float or mapping
        See :func:`start_positions`.
    fingers : sequence of Finger

    Returns
    -------
    dict of Finger to float
        Start position per finger: no command ``run_loop`` sends is below it.

    Raises
    ------
    ParameterError
        A bad ``p0`` (before anything is sent).

    Examples
    --------
    >>> class Hand:                        # a hand that measures its fingers
    ...     def __init__(self): self.sent = []
    ...     def set_positions(self, t): self.sent.append(t)
    ...     def positions(self): return {Finger.THUMB: 149.0, Finger.INDEX: 147.0, Finger.MIDDLE: 147.0}
    ...     def hold(self, fingers): self.sent.append("stop")
    >>> h = Hand()
    >>> safe_start(h, 0)[Finger.THUMB], h.sent
    (149.0, ['stop'])
    """
    start = start_positions(p0, fingers)
    if hasattr(hand, "hold"):
        hand.hold(tuple(start))
    reported = hand.positions()
    for f, v in reported.items():
        if f in start and v is not None and math.isfinite(v) and v > start[f]:
            start[f] = float(v)
    return start


def run_loop(source: Any, hand: Any, reflex: Any, *, p0: float | Mapping[Any, float] | None = None,
             recorder: Any = None,
             duration: float | None = None, watchdog: float = WATCHDOG_S, poll: float = 0.01,
             fingers: Sequence[Finger] = TRIPOD, stop: threading.Event | None = None,
             on_fault: Callable[[Fault], None] | None = None, stats_interval: float = 1.0,
             clock: Callable[[], float] = time.perf_counter) -> RunResult:
    """Run the reflex in real time until ``duration``, ``stop`` or Ctrl-C.

    Parameters
    ----------
    source : SampleSource
        ``read(timeout) -> list[DaqSample]``; may raise
        :class:`~slipreflex.errors.DeviceError` (recorded, the loop goes on).
        If it has ``last_arrival`` (a ``time.perf_counter()`` value) that is
        the arrival time of the samples just read; if it has ``stats`` (with
        ``to_dict()``), the counters are recorded and returned.
    hand : Hand
        ``set_positions(targets)``; optional ``hold(fingers)``.
    reflex : Reflex
        A slip reflex (``input_kind == "slip"``), e.g. :class:`slipreflex.chain.SlipReflex`.
    p0 : float or mapping of Finger to float, optional
        Position each finger holds at start, as the grasp routine left it (one
        value or one per finger; default: the reflex's initial command). The
        loop starts with :func:`safe_start` (STOP, never a move) and sends
        each finger the reflex's command shifted by that finger's start
        relative to the reflex's own start, never below the finger's start.
    recorder : Recorder, optional
        Where every stream goes.
    duration : float, optional
        Seconds to run (default: until stopped).
    watchdog : float
        Seconds without a valid sample before the fingers are held.
    poll : float
        Longest wait for input in one read (s); bounds the watchdog's reaction.
    fingers : sequence of Finger
        Fingers that get the reflex's command (default: the tripod).
    stop : threading.Event, optional
        Set it (e.g. from a signal handler) to stop the loop.
    on_fault : callable, optional
        Called with each :class:`Fault` as it happens (e.g. to print it).
    stats_interval : float
        Seconds between /stats messages.
    clock : callable
        Monotonic clock in seconds; must be ``time.perf_counter`` if the
        source's ``last_arrival`` is to be used.

    Returns
    -------
    RunResult

    Raises
    ------
    ParameterError
        For a reflex that does not read the slip sensor, or a bad watchdog/poll.

    Examples
    --------
    >>> from slipreflex.chain import SlipReflex
    >>> class Silent:
    ...     def read(self, timeout): return []
    ...     def close(self): pass
    >>> class Hand:
    ...     held = 0
    ...     def set_positions(self, t): pass
    ...     def positions(self): return {}
    ...     def hold(self, fingers): self.held += 1
    >>> h = Hand()
    >>> r = run_loop(Silent(), h, SlipReflex(), duration=0.3, poll=0.01)
    >>> [f.kind for f in r.faults], h.held      # the safe start's STOP, then the watchdog's
    (['watchdog'], 2)
    """
    if getattr(reflex, "input_kind", "slip") != "slip":
        raise ParameterError(f"run_loop: reflex {getattr(reflex, 'name', reflex)!r} reads "
                             f"{reflex.input_kind!r}, but the DAQ provides the slip sensor")
    if not WATCHDOG_MIN_S <= watchdog <= WATCHDOG_MAX_S:
        raise ParameterError(f"run_loop: watchdog must be in {WATCHDOG_MIN_S:g}..{WATCHDOG_MAX_S:g} s, "
                             f"got {watchdog!r}")
    if not 0 < poll <= watchdog:
        raise ParameterError(f"run_loop: poll must be in (0, watchdog], got {poll!r}")
    fingers = tuple(Finger(f) for f in fingers)
    finger_names = [f.name.lower() for f in fingers]
    ref0 = getattr(reflex, "command", None)  # the reflex's own start (SlipReflex: clip(p0))
    if p0 is None:
        if not isinstance(ref0, (int, float)) or not math.isfinite(ref0):
            raise ParameterError("run_loop: give p0 (the reflex has no initial command)")
        p0 = ref0
    start = safe_start(hand, p0, fingers)  # STOP first: nothing moves before the reflex asks
    if not isinstance(ref0, (int, float)) or not math.isfinite(ref0):
        ref0 = start.get(SLIP_FINGER, next(iter(start.values())))
    shift = {f: start[f] - ref0 for f in fingers}  # reflex frame -> each finger's own
    slip_shift = start[SLIP_FINGER] - ref0 if SLIP_FINGER in start else 0.0
    res = RunResult(start={f.name.lower(): v for f, v in start.items()},
                    initial_command="STOP " + ",".join(finger_names))
    latencies: list[float] = []
    t0 = clock()
    wall0 = time.time_ns()
    rec_ok = recorder is not None

    def ns(t: float) -> int:
        return wall0 + int((t - t0) * 1e9)

    def targets_for(cmd: float) -> dict[Finger, float]:
        # never below a finger's start; a NaN passes through for the driver to reject
        return {f: (start[f] if cmd + shift[f] < start[f] else cmd + shift[f]) for f in fingers}

    def record(topic: str, msg: dict[str, Any], t: float) -> None:
        if rec_ok and not recorder.write(topic, msg, ns(t)):
            check_recorder()

    def check_recorder() -> None:
        nonlocal rec_ok
        if rec_ok and recorder.error is not None:
            rec_ok = False
            res.recording_error = f"{getattr(recorder, 'path', 'recording')}: {recorder.error}"
            fault("recording", f"recording failed, later data is not recorded: {res.recording_error}",
                  "reflex kept running")

    def fault(kind: str, message: str, action: str) -> None:
        f = Fault(round(clock() - t0, 6), kind, message, action)
        res.faults.append(f)
        if on_fault is not None:
            on_fault(f)
        record("/faults", f.to_dict(), clock())

    last_target: dict[Finger, float] | None = None

    def hold() -> None:
        try:
            if hasattr(hand, "hold"):
                hand.hold(fingers)
            elif last_target is not None:
                hand.set_positions(last_target)
        except (DeviceError, ParameterError) as err:
            fault("hold-failed", str(err), "hand keeps its last target")

    def source_stats() -> dict[str, int]:
        st = getattr(source, "stats", None)
        if st is None:
            return {}
        return dict(st.to_dict()) if hasattr(st, "to_dict") else dict(vars(st))

    # Objects that exist now (the package, numpy, the chain, the drivers) are never
    # garbage; freezing them keeps the cyclic GC's occasional full passes short.
    if recorder is not None and hasattr(recorder, "add_metadata"):
        recorder.add_metadata("start", {"p0": json.dumps(res.start), "reflex_start": repr(ref0),
                                        "initial_command": res.initial_command})
    gc.freeze()
    last_valid = t0
    stalled = False
    hand_ok = True
    risen = False
    last_flow: int | None = None
    next_stats = t0 + stats_interval
    pending: list[tuple[DaqSample, float, float | None, float | None, Any, bool, int | None,
                        float | None, bool, float | None]] = []
    try:
        while True:
            now = clock()
            if duration is not None and now - t0 >= duration:
                break
            if stop is not None and stop.is_set():
                break
            try:
                samples = source.read(poll)
            except DeviceError as err:
                fault("daq-port", str(err), "fingers hold via the watchdog; reconnecting")
                samples = []
            if samples:
                arrival = getattr(source, "last_arrival", math.nan)
                if not (isinstance(arrival, float) and math.isfinite(arrival)):
                    arrival = clock()
                # 1. the time-critical part: every sample through the reflex, commands out.
                for s in samples:
                    pos = None
                    try:
                        pos = hand.positions().get(SLIP_FINGER)
                    except DeviceError:
                        pass
                    if pos is not None:
                        pos -= slip_shift  # in the reflex's frame
                    cmd = reflex.step(s.slip_volts, pos)
                    sent = False
                    lat = None
                    if cmd is not None:
                        targets = targets_for(cmd)
                        # Until the reflex first asks for more grip than at start, nothing is sent:
                        # the fingers stay held (STOP) where they are.
                        risen = risen or any(targets[f] > start[f] or not math.isfinite(targets[f])
                                             for f in fingers)
                    if cmd is not None and risen:
                        try:
                            hand.set_positions(targets)
                        except ParameterError as err:
                            fault("command-rejected", str(err), "not sent; fingers hold their last target")
                        except DeviceError as err:
                            if hand_ok:
                                fault("hand-port", str(err), "hand keeps its last target; reconnecting")
                            hand_ok = False
                        else:
                            lat = clock() - arrival
                            latencies.append(lat)
                            sent = True
                            last_target = targets
                            if not hand_ok:
                                hand_ok = True
                                fault("hand-port-restored", "hand port is back", "commands resumed")
                    pending.append((s, arrival, pos, cmd, getattr(reflex, "last_filtered", None),
                                    bool(getattr(reflex, "last_event", False)),
                                    getattr(reflex, "last_count", None),
                                    getattr(reflex, "last_threshold", None), sent, lat))
                t_now = clock()
                if stalled:
                    stalled = False
                    fault("watchdog-clear", f"samples resumed after {t_now - last_valid:.3f} s",
                          "reflex resumed")
                last_valid = t_now
                # 2. bookkeeping and recording, after the commands are out.
                for (s, arr, pos, cmd, filt, ev, count, thr, sent, lat) in pending:
                    res.samples += 1
                    res.events += ev
                    if count is not None:
                        res.windows += 1
                    if cmd is not None:
                        res.commands += 1
                        res.commands_sent += sent
                    if not rec_ok:
                        continue
                    ta = arr - t0
                    record("/daq/samples", {"seq": s.seq, "t": s.t, "slip_volts": s.slip_volts,
                                            "flow_pulses": s.flow_pulses, "arrival": ta,
                                            "position": _num(pos)}, arr)
                    if s.accel_g is not None:
                        ax, ay, az = s.accel_g
                        record("/daq/imu", {"seq": s.seq, "t": s.t, "ax": ax, "ay": ay, "az": az}, arr)
                    if s.flow_pulses != last_flow:
                        record("/daq/flow", {"seq": s.seq, "t": s.t, "pulses": s.flow_pulses}, arr)
                    record("/chain/state", {"seq": s.seq, "t": s.t, "filtered": _num(filt),
                                            "threshold": _num(thr) or 0.0, "event": ev}, arr)
                    if ev:
                        record("/chain/events", {"seq": s.seq, "t": s.t}, arr)
                    if count is not None:
                        record("/chain/windows", {"seq": s.seq, "t": s.t, "count": int(count)}, arr)
                    if cmd is not None:
                        record("/hand/commands", {"seq": s.seq, "t": s.t, "target": float(cmd),
                                                  "fingers": finger_names, "targets": {
                                                      f.name.lower(): _num(v)
                                                      for f, v in targets_for(cmd).items()},
                                                  "sent": sent, "latency": lat}, arr)
                for item in pending:
                    last_flow = item[0].flow_pulses
                pending.clear()
            else:
                t_now = clock()
                if not stalled and t_now - last_valid > watchdog:
                    stalled = True
                    hold()
                    fault("watchdog", f"no valid DAQ sample for {(t_now - last_valid) * 1e3:.0f} ms",
                          "fingers held where they are")
            if rec_ok:
                recorder.maybe_flush()
                check_recorder()
                t_now = clock()
                if t_now >= next_stats:
                    next_stats = t_now + stats_interval
                    record("/stats", {"time": t_now - t0, "counters": {
                        **source_stats(), "samples": res.samples, "commands": res.commands,
                        "faults": len(res.faults)}}, t_now)
    except KeyboardInterrupt:
        res.interrupted = True
    finally:
        gc.unfreeze()
    res.duration = clock() - t0
    res.latencies = np.asarray(latencies, dtype=float)
    res.daq_stats = source_stats()
    if rec_ok:
        record("/stats", {"time": res.duration, "counters": {
            **res.daq_stats, "samples": res.samples, "commands": res.commands,
            "faults": len(res.faults)}}, clock())
        lat = res.latency_ms()
        recorder.add_metadata("run_summary", {
            "samples": res.samples, "commands": res.commands, "events": res.events,
            "duration_s": f"{res.duration:.3f}", "latency_p50_ms": f"{lat['p50']:.4f}",
            "latency_p99_ms": f"{lat['p99']:.4f}", "latency_max_ms": f"{lat['max']:.4f}",
            "faults": len(res.faults)})
    if recorder is not None and recorder.error is not None and res.recording_error is None:
        res.recording_error = f"{getattr(recorder, 'path', 'recording')}: {recorder.error}"
    return res


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



def realtime_priority(priority: int = 50) -> str:
    """Ask the OS to run this process under SCHED_FIFO real-time scheduling.

    On Linux with the right privileges (root or ``CAP_SYS_NICE`` / an
    ``rtprio`` limit) the loop then preempts ordinary processes, which keeps
    its latency low on a busy machine. The loop blocks in ``select`` between
    samples, so it does not starve anything.

    Parameters
    ----------
    priority : int
        SCHED_FIFO priority, 1..99.

    Returns
    -------
    str
        What happened, for the user (never raises).

    Examples
    --------
    >>> isinstance(realtime_priority.__doc__, str)
    True
    """
    if not hasattr(os, "sched_setscheduler"):
        return "real-time scheduling not available on this platform; running at normal priority"
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except (OSError, ValueError) as err:
        return f"could not get SCHED_FIFO ({err}); running at normal priority"
    return f"running under SCHED_FIFO priority {priority}"
