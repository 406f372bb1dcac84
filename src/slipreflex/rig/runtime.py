"""The real-time loop: DAQ samples in, reflex commands out, everything recorded.

:func:`run_loop` reads samples from any :class:`~slipreflex.core.interfaces.SampleSource`
(the serial DAQ, the virtual DAQ on a pty, anything with ``read``), feeds each
to the same reflex object used in simulation and replay, sends its commands to
any :class:`~slipreflex.core.interfaces.Hand`, and records every stream with a
:class:`~slipreflex.files.recording.Recorder`. One iteration is four named steps:
*read* (wait for bytes, decode), *process* (every sample through the reflex,
commands out at once; one :class:`SampleRecord` per sample), *record* (after
the commands are out) and *watchdog* (faults, holds, counters).

What it guarantees:

- **Grip only ever added** (:mod:`slipreflex.core.grip`): the fingers are first
  told to STOP where they are (:func:`safe_start`); after that the reflex's
  command reaches the hand only as the grip it *rises* by, sent as closing
  time (CLOSE at the hand's documented speed, then STOP when the time is up).
  The loop never sends OPEN or a position, so no ``p0`` can open the hand or
  make it jump shut; ``p0`` is the reflex's bookkeeping only. A hand that
  reports positions gives the reflex its measured slip-finger position and
  the start; the i-Limb reports none and refuses, while a reflex runs, any
  command that could open a finger (:meth:`slipreflex.rig.devices.ilimb.ILimb.reflex_running`).
- **Latency** is measured for every command sent, twice: from the moment the
  sample's bytes were read from the port (``source.last_arrival``) and from
  the frame's own arrival as its board time places it (so a backlog shows).
- **Watchdog**: when no valid sample arrives for ``watchdog`` seconds (20 to
  500 ms; 100 ms by default), or a sample is older than that when it is
  processed (a frozen or backlogged loop), the grasping fingers are told to
  hold where they are, and the hold is re-sent every ``watchdog`` seconds
  while the fault lasts (the i-Limb protocol has no acknowledgement). A guard
  thread holds the fingers if the loop itself stops iterating. The hand is
  never opened by a fault; the reflex resumes, unchanged, when fresh samples
  return.
- **Faults never stop the loop**: a DAQ or hand port that fails, a command
  the hand driver rejects, a recording that cannot be written any more, bursts
  of CRC errors, garbage, lost, duplicated or late frames, a DAQ reset - each
  becomes a :class:`Fault` (recorded, reported) and the loop goes on.
- **Stopping**: after ``duration`` seconds, when ``stop`` is set, or on
  Ctrl-C; the recording is always closed by the caller's ``with`` block.

Examples
--------
>>> from slipreflex.methods.chain import SlipReflex
>>> from slipreflex.core.interfaces import DaqSample
>>> class Source:                  # 64 samples of a still surface, then nothing; simulated time
...     def __init__(self): self.left, self.now = [DaqSample(k, k * 0.003, 0.4, None, 0) for k in range(64)], 0.0
...     def read(self, timeout):
...         self.now += 0.024 if self.left else timeout    # 8 samples take 24 ms
...         out, self.left = self.left[:8], self.left[8:]
...         return out
...     def clock(self): return self.now
...     def close(self): pass
>>> class Hand:
...     def set_positions(self, t): pass
...     def close_fingers(self, fingers, speed): pass
...     def hold(self, fingers): pass
...     def positions(self): return {}
>>> src = Source()
>>> res = run_loop(src, Hand(), SlipReflex(p0=200.0), duration=0.5, clock=src.clock)
>>> res.samples, res.commands, res.commands_sent, [f.kind for f in res.faults]
(64, 4, 0, ['watchdog'])
"""

from __future__ import annotations

import collections
import gc
import json
import math
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from ..core.errors import DeviceError, ParameterError
from ..core.grip import FINGER_SPEED_UNITS_S, TRAVEL, Grip, span
from ..core.hardware import FINGER_MAX, SLIP_FINGER, TRIPOD, Finger
from ..core.interfaces import DaqSample, Hand, Reflex, RunRecorder, SampleSource, missing, optional
from .loop_results import Fault, RunResult, SampleRecord, print_fault
from .loop_sink import _Sink, tactile_message
from .loop_start import _source_for, _warm_up, finger_offsets, reflex_start, safe_start, start_positions
from .loop_states import Age, Arrival, FirstFrame, HandPort, HoldRetry, LoopStates, Rise, StopRetry
from .privileges import drop_capabilities, realtime_priority

__all__ = ["Fault", "SampleRecord", "RunResult", "run_loop", "print_fault", "realtime_priority",
           "tactile_message", "drop_capabilities",
           "WATCHDOG_S", "WATCHDOG_MIN_S", "WATCHDOG_MAX_S", "start_positions", "safe_start",
           "finger_offsets", "reflex_start"]

#: Seconds without a valid sample after which the watchdog holds the fingers.
WATCHDOG_S: float = 0.1
#: Bounds of the watchdog (s): shorter trips on the DAQ's normal jitter, longer is no watchdog.
WATCHDOG_MIN_S: float = 0.02
WATCHDOG_MAX_S: float = 0.5
#: How fast (s per s) the estimate of a frame's arrival may follow the board's clock drifting
#: behind the PC's; a crystal is within 1e-4, so a real stall is never absorbed quickly.
_CLOCK_DRIFT = 1e-3
#: What the loop reads of every reflex (run_loop refuses one without them, before anything is sent).
_LOOP_READS_OF_REFLEX = ("name", "input_kind", "step", "last_event", "last_filtered", "last_threshold",
                         "last_count")
#: A valid frame should arrive within this many seconds of the start (else a warning).
_FIRST_FRAME_S = 1.0
#: Shortest interval (s) between two fault events of the same DAQ counter.
_COUNTER_EVENT_S = 1.0
#: DAQ counters whose increase is a fault event: counter -> (fault kind, what one count is).
_COUNTER_FAULTS: dict[str, tuple[str, str]] = {
    "crc_errors": ("daq-crc", "frames failed their CRC"),
    "truncated": ("daq-truncated", "frames cut short"),
    "invalid": ("daq-invalid", "frames with a good CRC but bad content"),
    "garbage_bytes": ("daq-garbage", "bytes of garbage between frames"),
    "frames_lost": ("daq-gap", "frames lost (sequence gaps)"),
    "duplicates": ("daq-duplicate", "duplicated frames dropped"),
    "reordered": ("daq-reordered", "late (out-of-order) frames dropped"),
    "resets": ("daq-reset", "DAQ sequence restarts (board reset): a new segment, time continues"),
    "reconnects": ("daq-port-restored", "DAQ port reopened"),
    "frames_discarded": ("daq-discarded", "frames discarded while the port reopened"),
}


def run_loop(source: SampleSource, hand: Hand, reflex: Reflex, *,
             p0: float | Mapping[Any, float] | None = None, recorder: Any = None,
             duration: float | None = None, watchdog: float = WATCHDOG_S, poll: float = 0.01,
             fingers: Sequence[Finger] = TRIPOD, stop: threading.Event | None = None,
             on_fault: Callable[[Fault], None] | None = None, stats_interval: float = 1.0,
             clock: Callable[[], float] = time.perf_counter, guard: bool = True,
             taps: Sequence[Any] = ()) -> RunResult:
    """Run the reflex in real time until ``duration``, ``stop`` or Ctrl-C.

    Parameters
    ----------
    source : SampleSource
        ``read(timeout) -> list[DaqSample]``; may raise :class:`~slipreflex.core.errors.DeviceError`
        (recorded, the loop goes on). Optional ``last_arrival`` (``perf_counter`` of the read),
        ``stats`` (``to_dict()``: recorded, returned, increases become fault events) and
        ``drop_buffered()``, called once just before the clock starts: the frames that arrived
        during the set-up are from before the run (else a stale backlog at the start).
    hand : Hand
        ``close_fingers(fingers, speed)``, ``hold(fingers)`` and ``positions()``
        (:class:`~slipreflex.core.interfaces.Hand`); an optional ``reflex_running(bool)``
        is switched on for the run (the i-Limb's grip-only guard).
    reflex : Reflex
        A slip reflex (``input_kind == "slip"``), e.g. :class:`slipreflex.methods.chain.SlipReflex`,
        reading ``source``'s samples; or a tactile one (``"tactile"``, e.g. NMSD) reading the
        frames of ``source``, then a :class:`~slipreflex.core.interfaces.TactileSource` (the Ability
        Hand's touch sites), recorded on ``/tactile/frames``.
    p0 : float or mapping of Finger to float, optional
        Position each finger holds at start, as the grasp left it (default: the reflex's
        initial command): bookkeeping only. The loop starts with :func:`safe_start`; each
        rise of the reflex's command is then sent as closing time (:mod:`slipreflex.core.grip`).
    recorder : Recorder, optional
    duration : float, optional
        Seconds to run (default: until stopped).
    watchdog, poll : float
        Seconds (0.02..0.5) without a fresh valid sample before the fingers are held;
        longest wait in one read (at most half the watchdog).
    fingers : sequence of Finger
        Fingers that close when the reflex's command rises (default: the tripod).
    stop : threading.Event, optional
    on_fault : callable, optional
        Called with each :class:`Fault` as it happens (e.g. to print it).
    stats_interval : float
        Seconds between /stats messages.
    clock : callable
        Monotonic clock (s); ``time.perf_counter`` if ``last_arrival`` is to be used.
    guard : bool
        Run the stall guard thread (holds the fingers if the loop stops iterating).
    taps : sequence of Tap
        Live publishers (:class:`slipreflex.core.taps.Tap`: the Foxglove view, LSL outlets): each
        gets every message the recording gets, after the commands are out, through its
        non-blocking ``put``; the caller starts and closes them.

    Returns
    -------
    RunResult

    Raises
    ------
    ParameterError
        For a reflex that does not read the slip sensor, a hand that cannot close and
        hold, a bad p0, watchdog or poll.

    Examples
    --------
    >>> from slipreflex.methods.chain import SlipReflex
    >>> class Silent:                      # simulated time: each read waits its whole timeout
    ...     now = 0.0
    ...     def read(self, timeout): self.now += timeout; return []
    ...     def close(self): pass
    >>> class Hand:
    ...     held = 0
    ...     def set_positions(self, t): pass
    ...     def close_fingers(self, fingers, speed): pass
    ...     def positions(self): return {}
    ...     def hold(self, fingers): self.held += 1
    >>> h, src = Hand(), Silent()
    >>> r = run_loop(src, h, SlipReflex(), duration=0.15, poll=0.01, clock=lambda: src.now)
    >>> [f.kind for f in r.faults], h.held >= 2      # the safe start's STOP, then the watchdog's
    (['watchdog'], True)
    """
    lacks = missing(reflex, Reflex, _LOOP_READS_OF_REFLEX)
    if lacks:
        raise ParameterError(f"run_loop: the reflex has no {', '.join(lacks)} (slipreflex.core.interfaces.Reflex)")
    source = _source_for(source, reflex)
    if not WATCHDOG_MIN_S <= watchdog <= WATCHDOG_MAX_S:
        raise ParameterError(f"run_loop: watchdog must be in {WATCHDOG_MIN_S:g}..{WATCHDOG_MAX_S:g} s, "
                             f"got {watchdog!r}")
    if not 0 < poll <= watchdog / 2:
        raise ParameterError(f"run_loop: poll must be in (0, watchdog / 2], got {poll!r}")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise ParameterError(f"run_loop: duration must be > 0 s, got {duration!r}")
    lacks = missing(hand, Hand, ("close_fingers", "hold", "positions"))
    if lacks:
        raise ParameterError(f"run_loop: the hand has no {', '.join(lacks)}: a reflex adds grip only by "
                             f"closing and holding (slipreflex.core.interfaces.Hand)")
    fingers = tuple(Finger(f) for f in fingers)
    ref0 = reflex_start(reflex)
    ref_ok = ref0 is not None
    if p0 is None and not ref_ok:
        raise ParameterError("run_loop: give p0 (the reflex has no initial command)")
    given = start_positions(p0 if p0 is not None else float(ref0 or 0.0), fingers)  # checked before anything is sent
    _warm_up(reflex)
    finger_offsets(reflex, fingers)
    try:
        start, start_error = safe_start(hand, given, fingers), None
    except DeviceError as err:  # the STOP did not go out: the fingers stay as the grasp left them
        start, start_error = given, err
    drop_buffered = optional(source, SampleSource, "drop_buffered")
    dropped = drop_buffered() if drop_buffered is not None else 0
    loop = _Loop(source, hand, reflex, start=start,
                 ref0=float(ref0) if ref_ok else start.get(SLIP_FINGER, next(iter(start.values()))),
                 recorder=recorder, duration=duration, watchdog=watchdog, poll=poll, stop=stop,
                 on_fault=on_fault, stats_interval=stats_interval, clock=clock, taps=taps)
    loop.check_room(loop.grip.levels[0] if loop.grip.levels else 0.0)
    if start_error is not None:
        loop.fault("hold-failed", f"safe start: {start_error}", "fingers stay where the grasp left them; "
                   "the watchdog holds again if samples stop")
    loop.res.dropped_at_start = dropped
    guard_on = optional(hand, Hand, "reflex_running")
    if callable(guard_on):
        guard_on(True)
    try:
        return loop.run(guard)
    finally:
        if callable(guard_on):
            guard_on(False)


class _Loop:
    """One run: the state the four steps share."""

    def __init__(self, source: Any, hand: Any, reflex: Any, *, start: dict[Finger, float],
                 ref0: float, recorder: Any, duration: float | None, watchdog: float, poll: float,
                 stop: threading.Event | None, on_fault: Callable[[Fault], None] | None,
                 stats_interval: float, clock: Callable[[], float], taps: Sequence[Any] = ()) -> None:
        self.source, self.hand, self.reflex = source, hand, reflex
        self.slip = reflex.input_kind == "slip"  # else a tactile frame per step
        self.fingers = tuple(start)
        self.finger_names = [f.name.lower() for f in self.fingers]
        self.start = start
        # grip only ever added: rises of the command become closing time per finger group; a
        # reflex's finger_offsets (authors-gui: middle + 20) are that group's extra first rise
        self.offsets = finger_offsets(reflex, self.fingers)
        # no group ever gets more than one finger travel above the grasp, whatever the command says
        self.grip = Grip(ref0, self.fingers, self.offsets, ceiling=ref0 + TRAVEL)
        self.speed = FINGER_SPEED_UNITS_S
        self.owed = [0.0] * len(self.grip.groups)  # grip not yet sent (stale, a cut closing, a lost port)
        self.until: list[float | None] = [None] * len(self.grip.groups)  # clock time each closing ends
        self.begun: list[float | None] = [None] * len(self.grip.groups)  # clock time each closing began
        self.unstopped: set[int] = set()  # groups whose ending STOP never reached the hand
        hi = optional(reflex, Reflex, "params.hi")
        self.ceiling = float(hi) if isinstance(hi, (int, float)) and math.isfinite(hi) else float(FINGER_MAX)
        self.top = min(self.ceiling, self.grip.ceiling)  # the command is clipped here before it is grip
        self.failed: str | None = None  # the reflex raised: the run ends, fingers held
        # the reflex's frame: its command ref0 is where the slip finger stood at start
        self.slip_shift = start.get(SLIP_FINGER, ref0) - ref0
        self.duration, self.watchdog_s, self.poll, self.stop = duration, watchdog, poll, stop
        self.on_fault, self.stats_interval, self.clock = on_fault, stats_interval, clock
        self.res = RunResult(start={f.name.lower(): v for f, v in start.items()},
                             initial_command="STOP " + ",".join(self.finger_names), ceiling=self.ceiling)
        self.t0 = clock()
        self.sink = _Sink(recorder, self.t0, self._recording_failed, taps)
        self.lock = threading.Lock()  # hand writes: the loop and the stall guard
        self.heartbeat = self.t0
        self.guard_faults: collections.deque[Fault] = collections.deque()
        self.latencies: list[float] = []
        self.frame_latencies: list[float] = []
        self.offset: float | None = None  # board time -> clock time of the earliest arrivals
        self.last_arrival = self.t0
        self.anchor_resets = 0  # the source's reset counter at the last re-anchoring
        self.last_valid = self.t0
        self.last_hold = self.last_retry = -math.inf
        self.states = LoopStates()  # the link and watchdog states (slipreflex.rig.loop_states)
        self.processed = 0
        self.last_flow: int | None = None
        self.counters: dict[str, int] = {}
        self.counter_pending: dict[str, int] = {}
        self.counter_emitted: dict[str, float] = {}
        self.next_stats = self.t0 + stats_interval
        self.next_counters = self.t0
        if recorder is not None:
            recorder.add_metadata("start", {"p0": json.dumps(self.res.start), "reflex_start": repr(ref0),
                                            "initial_command": self.res.initial_command,
                                            "finger_offsets": json.dumps({f.name.lower(): v for f, v
                                                                          in self.offsets.items()})})

    # -- the loop --------------------------------------------------------------------
    def run(self, guard: bool) -> RunResult:
        guard_thread = _Guard(self) if guard else None
        if guard_thread is not None:
            guard_thread.start()
        # Objects that exist now (the package, numpy, the chain, the drivers) are never
        # garbage; freezing them keeps the cyclic GC's occasional full passes short.
        gc.freeze()
        try:
            while not self.done():
                self.heartbeat = self.clock()
                samples, arrival = self.read()
                if samples:
                    records = self.process(samples, arrival)  # commands out first
                    self.end_closings()
                    self.record(records)
                self.end_closings()
                self.watchdog(bool(samples))
        except KeyboardInterrupt:
            self.res.interrupted = True
        finally:
            gc.unfreeze()
            if guard_thread is not None:
                guard_thread.close()
            self.end_closings(final=True)  # a run never ends with the fingers still closing
        return self.finish()

    def check_room(self, ref0: float) -> None:
        """A reflex whose command starts at its ceiling can add no grip: say so now, not never."""
        if self.top <= ref0:
            self.res.saturated_at = 0.0
            self.fault("no-grip-room", f"the reflex's command starts at {ref0:g}, at its ceiling "
                       f"{self.ceiling:g}: it can add no grip in this run", "fingers hold what they hold; "
                       "build the reflex with room above its start (slipreflex run does)")

    def done(self) -> bool:
        if self.failed is not None:
            return True
        if self.duration is not None and self.clock() - self.t0 >= self.duration:
            return True
        return self.stop is not None and self.stop.is_set()

    # -- step 1: read ----------------------------------------------------------------
    def read(self) -> tuple[list[DaqSample], float]:
        timeout = self.poll
        ends = [u for u in self.until if u is not None]
        if ends:  # wake up in time to end a closing
            timeout = min(timeout, max(1e-4, min(ends) - self.clock()))
        try:
            samples = self.source.read(timeout)
        except DeviceError as err:
            self.fault("daq-port", str(err), "fingers hold via the watchdog; reconnecting")
            return [], math.nan
        if not samples:
            return samples, math.nan
        arrival = optional(self.source, SampleSource, "last_arrival")
        if not (isinstance(arrival, float) and math.isfinite(arrival)):
            arrival = self.clock()
        self.anchor(samples[-1].t, arrival)
        return samples, arrival

    def anchor(self, t_newest: float, arrival: float) -> None:
        """Map board time to clock time by the earliest arrivals (the newest frame of a read
        has just arrived). A newest frame that looks older than the watchdog means the board's
        time was restarted (a reset continues at the next period), not a stall: re-anchor."""
        cand = arrival - t_newest
        if self.offset is None or (cand - self.offset > self.watchdog_s and self.board_restarted()):
            self.offset = cand
        else:
            self.offset = min(self.offset + _CLOCK_DRIFT * (arrival - self.last_arrival), cand)
        self.last_arrival = arrival

    def board_restarted(self) -> bool:
        """Whether the source counted a board reset since the last re-anchoring. A source
        without counters cannot tell a reset from a backlog, so any old frame counts as one;
        with counters, a backlog read in pieces keeps its age (it is stale, not a reset)."""
        if optional(self.source, SampleSource, "stats") is None:
            return True
        resets = int(self.source_stats().get("resets", 0))
        restarted, self.anchor_resets = resets > self.anchor_resets, resets
        return restarted

    # -- step 2: process (the time-critical part) -------------------------------------
    def process(self, samples: list[Any], arrival: float) -> list[SampleRecord]:
        reflex, hand, out = self.reflex, self.hand, []
        for s in samples:
            pos = None
            try:
                pos = hand.positions().get(SLIP_FINGER)
            except DeviceError:
                pass
            if pos is not None:
                pos -= self.slip_shift  # in the reflex's frame
            try:
                cmd = reflex.step(s.slip_volts if self.slip else s.frame, pos)
            except Exception as err:  # noqa: BLE001 - any method's failure ends the run held, recorded
                self.reflex_failed(s, err)
                break
            r = SampleRecord(s, arrival, self.clock() - (s.t + (self.offset or 0.0)), pos, cmd,
                             filtered=reflex.last_filtered, threshold=reflex.last_threshold,
                             event=bool(reflex.last_event), count=reflex.last_count,
                             board=optional(reflex, Reflex, "last_board"))
            mismatch = optional(reflex, Reflex, "last_mismatch")
            if mismatch:
                self.fault("board-mismatch", mismatch, "recorded; the twin's command is the one used")
            self.freshness(r)
            if cmd is not None:
                self.command(r, cmd)
            out.append(r)
        self.processed += len(samples)
        return out

    def reflex_failed(self, s: Any, err: Exception) -> None:
        """The method raised in ``step()``: hold the fingers, record it, end the run (its state is
        unknown, so no later command of it is trusted)."""
        name = self.reflex.name
        self.failed = f"method {name!r} raised in step() at sample seq {s.seq}: {type(err).__name__}: {err}"
        self.hold()
        self.fault("reflex-error", self.failed, "fingers held; the run ends (nothing more is sent)")

    def freshness(self, r: SampleRecord) -> None:
        if r.age > self.watchdog_s:
            self.res.stale_samples += 1
            if not self.states.stale:
                self.states.take(Age, "a sample older than the watchdog")
                self.hold()
                self.fault("stale", f"sample seq {r.sample.seq} was {r.age * 1e3:.0f} ms old when "
                           f"processed: the loop was frozen or fell behind", "fingers held; commands "
                           "wait for fresh samples")
        elif self.states.stale:
            owed = self.states.take(Age, "a fresh sample").source is Age.STALE_OWED
            self.fault("stale-clear", f"samples fresh again ({r.age * 1e3:.1f} ms old)", "reflex resumed")
            if owed:  # grip came while stale: send it now
                self.deliver(r, resend=True)

    def command(self, r: SampleRecord, cmd: float) -> None:
        try:
            rises = self.grip.rise(min(cmd, self.top) if isinstance(cmd, (int, float)) else cmd)
        except ParameterError as err:
            r.note = "rejected"
            self.fault("command-rejected", str(err), "no grip added; fingers keep what they hold")
            return
        r.grip = {f: g for (fs, _), g in zip(self.grip.groups, rises) for f in fs}
        at_top = cmd >= self.top or any(level >= self.grip.ceiling for level in self.grip.levels)  # an offset's too
        if at_top and self.res.saturated_at is None:
            self.res.saturated_at = r.sample.t
            self.fault("mpi-saturated", f"the reflex's command reached its ceiling {self.top:g} at "
                       f"t={r.sample.t:.3f} s", "it adds no grip after that; later slips cannot be answered")
        if not any(g > 0.0 for g in rises):
            r.note = "at start" if self.states[Rise] is Rise.AT_START else "no rise"  # the fingers stay held
            return
        if self.states[Rise] is Rise.AT_START:
            self.states.take(Rise, "the command first rises")
        for i, g in enumerate(rises):
            self.owed[i] += g
        if self.states.stale:
            r.note = "stale"
            if self.states[Age] is Age.STALE:
                self.states.take(Age, "grip comes while stale")
            return
        self.deliver(r)

    def deliver(self, r: SampleRecord | None, resend: bool = False) -> None:
        """Send the grip owed as closing time: CLOSE now, or a closing in progress made longer."""
        now = self.clock()
        self.stall_check(now)  # a finger the hand already reports stalled gets no grip counted
        sent = False
        for i, (fingers, _) in enumerate(self.grip.groups):
            g = self.owed[i]
            if g <= 0.0:
                continue
            until = self.until[i]
            begin, end = span(now, -math.inf if until is None else until, g, self.speed)
            if until is None or until <= now:
                try:
                    with self.lock:
                        self.hand.close_fingers(fingers, self.speed)
                except ParameterError as err:
                    self.owed[i] = 0.0
                    if r is not None:
                        r.note = "rejected"
                    self.fault("command-rejected", str(err), "no grip added; fingers keep what they hold")
                    continue
                except DeviceError as err:
                    if r is not None:
                        r.note = "hand-port"
                    if self.states.hand_up:
                        self.states.take(HandPort, "a CLOSE fails on the port")
                        self.fault("hand-port", str(err), "fingers keep what they hold; the grip is sent "
                                   "when the port is back")
                    return
                self.res.closes += 1
            self.until[i] = end
            self.owed[i] = 0.0
            for f in fingers:
                name = f.name.lower()
                # a stalled finger ignores closing (the hand's own rule): what is sent to it is not grip
                self.res.grip_added[name] = self.res.grip_added.get(name, 0.0) + (0.0 if name in self.res.stalled
                                                                                  else g)
            sent = True
        if not sent:
            return
        if not self.states.hand_up:
            self.states.take(HandPort, "a CLOSE goes out")
            self.fault("hand-port-restored", "hand port is back", "commands resumed")
        if resend or r is None:
            return
        now = self.clock()
        r.sent, r.latency = True, now - r.arrival
        r.frame_latency = now - (r.sample.t + (self.offset or 0.0))  # offset: set by the first read
        self.latencies.append(r.latency)
        self.frame_latencies.append(r.frame_latency)

    def end_closings(self, final: bool = False) -> None:
        """STOP each group whose closing time is up (all of them at the end of the run)."""
        now = self.clock()
        for i, (fingers, _) in enumerate(self.grip.groups):
            until = self.until[i]
            if until is None or (now < until and not final):
                continue
            try:
                with self.lock:
                    self.hand.hold(fingers)
            except (DeviceError, ParameterError) as err:
                self.unstopped.add(i)
                if self.states[StopRetry] is StopRetry.SENT:
                    self.states.take(StopRetry, "the STOP ending a closing fails")
                    names = ", ".join(f.name.lower() for f in fingers)
                    self.fault("stop-failed", f"{err}: the closing of {names} did not end; they may close "
                               f"to their end stops", "the STOP that ends a closing is retried")
                continue
            if self.states[StopRetry] is StopRetry.FAILING:
                self.states.take(StopRetry, "a STOP ending a closing goes out")
            self.unstopped.discard(i)
            self.until[i] = None
            self.res.stops += 1
            if until > now:  # the run ended first: that part of the grip was not added
                for f in fingers:
                    self.res.grip_added[f.name.lower()] -= (until - now) * self.speed

    # -- step 3: record (after the commands are out) -----------------------------------
    def record(self, records: list[SampleRecord]) -> None:
        res = self.res
        for r in records:
            res.samples += 1
            res.events += r.event
            if r.count is not None:
                res.windows += 1
                if res.saturated_at is not None and r.count > 0 and r.sample.t > res.saturated_at:
                    res.saturated_windows += 1
            if r.command is not None:
                res.commands += 1
                res.commands_sent += r.sent
        self.last_flow = self.sink.samples(records, self.finger_names, self.last_flow)

    # -- step 4: watchdog, counters, housekeeping ---------------------------------------
    def watchdog(self, got: bool) -> None:
        now = self.clock()
        if got:
            if self.states.silent:
                self.states.take(Arrival, "samples again")
                self.fault("watchdog-clear", f"samples resumed after {now - self.last_valid:.3f} s",
                           "reflex resumed")
                if any(g > 0.0 for g in self.owed) and not self.states.stale:
                    self.deliver(None)  # the rest of a closing the hold cut short
            self.last_valid = now
        elif not self.states.silent and now - self.last_valid > self.watchdog_s:
            self.states.take(Arrival, "no valid sample for the watchdog time")
            self.hold()
            self.fault("watchdog", f"no valid DAQ sample for {(now - self.last_valid) * 1e3:.0f} ms",
                       "fingers held where they are; the hold is re-sent while it lasts")
        held = self.states.silent or self.states.stale
        if held and now - self.last_hold >= self.watchdog_s:
            self.hold()  # the i-Limb protocol has no acknowledgement: say it again
        elif (not self.states.hand_up and not held and any(g > 0.0 for g in self.owed)
              and now - self.last_retry >= self.watchdog_s):
            self.last_retry = now
            self.deliver(None)  # grip owed since the hand port failed: try again
        if self.states[FirstFrame] is FirstFrame.WAITING and self.processed == 0 and now - self.t0 >= _FIRST_FRAME_S:
            self.states.take(FirstFrame, "no valid frame within a second of the start")
            self.fault("no-data", self.no_data_message(), "fingers held; still waiting")
        while self.guard_faults:
            self.emit(self.guard_faults.popleft())
        self.housekeeping(now)

    def no_data_message(self) -> str:
        st = self.source_stats()
        got = st.get("garbage_bytes", 0) + st.get("crc_errors", 0)
        port = optional(self.source, SampleSource, "port_name")
        if got:
            return (f"no valid DAQ frame within {_FIRST_FRAME_S:g} s of start, but {port} delivers bytes "
                    f"({st.get('garbage_bytes', 0)} garbage, {st.get('crc_errors', 0)} CRC errors): "
                    f"wrong baud rate, swapped ports (--daq/--hand) or not the slipreflex firmware?")
        return (f"no valid DAQ frame within {_FIRST_FRAME_S:g} s of start and no bytes at all from {port}: "
                f"wrong port, swapped ports (--daq/--hand), board not powered or not flashed?")

    def hold(self) -> None:
        now = self.last_hold = self.clock()
        try:
            with self.lock:
                self.hand.hold(self.fingers)
        except (DeviceError, ParameterError) as err:
            if self.states[HoldRetry] is HoldRetry.SENT:
                self.states.take(HoldRetry, "a hold fails")
                self.fault("hold-failed", str(err), "hand keeps its last command; the hold is retried")
            return
        if self.states[HoldRetry] is HoldRetry.FAILING:
            self.states.take(HoldRetry, "a hold goes out")
        self.res.holds_sent += 1
        for i, until in enumerate(self.until):  # a closing cut short: its rest is owed
            if until is not None:
                if until > now:
                    self.owed[i] += (until - now) * self.speed
                    for f in self.grip.groups[i][0]:
                        name = f.name.lower()
                        self.res.grip_added[name] -= (until - now) * self.speed
                self.until[i] = None

    def source_stats(self) -> dict[str, int]:
        st = optional(self.source, SampleSource, "stats")
        return {} if st is None else dict(st.to_dict())

    def housekeeping(self, now: float) -> None:
        if now >= self.next_counters:
            self.next_counters = now + 0.05
            self.counter_faults(now)
            self.stall_check(now)
        if now >= self.next_stats:
            self.next_stats = now + self.stats_interval
            self.sink.write("/stats", {"time": now - self.t0, "counters": self.stats_counters()}, now)
        if self.sink.ok:
            self.sink.recorder.maybe_flush()
            self.sink.check()

    def stall_check(self, now: float) -> None:
        """Fingers the hand newly reports stalled (optional ``Hand.stalled()``): a fault each, and
        the rest of a closing in progress is not counted as grip."""
        report: Callable[[], Any] | None = optional(self.hand, Hand, "stalled")
        if not callable(report):
            return
        try:
            stalled = {Finger(f).name.lower() for f in report()}
        except (DeviceError, ValueError, TypeError):
            return
        for name in sorted(stalled - set(self.res.stalled)):
            self.res.stalled.append(name)
            for i, (fingers, _) in enumerate(self.grip.groups):
                until = self.until[i]
                if until is not None and until > now and name in {f.name.lower() for f in fingers}:
                    self.res.grip_added[name] -= (until - now) * self.speed
            self.fault("finger-stalled", f"the hand reports {name} stalled: it ignores closing until opened",
                       "grip sent to it is no longer counted; the reflex cannot add grip there")

    def counter_faults(self, now: float, final: bool = False) -> None:
        """Increases of the DAQ's counters become fault events: the first at once, then at
        most one per counter per second, carrying what accumulated."""
        st = self.source_stats()
        for key, (kind, what) in _COUNTER_FAULTS.items():
            if key not in st:
                continue
            delta = st[key] - self.counters.get(key, 0)
            self.counters[key] = st[key]
            pending = self.counter_pending.get(key, 0) + max(delta, 0)
            if pending and (final or now - self.counter_emitted.get(key, -math.inf) >= _COUNTER_EVENT_S):
                self.counter_emitted[key] = now
                pending, n = 0, pending
                self.fault(kind, f"{n} {what} (total {st[key]})", "recorded; the loop goes on")
            self.counter_pending[key] = pending

    def stats_counters(self) -> dict[str, Any]:
        return {**self.source_stats(), "samples": self.res.samples, "commands": self.res.commands,
                "faults": len(self.res.faults), "holds_sent": self.res.holds_sent}

    # -- faults -----------------------------------------------------------------------
    def fault(self, kind: str, message: str, action: str) -> None:
        self.emit(Fault(round(self.clock() - self.t0, 6), kind, message, action))

    def emit(self, f: Fault) -> None:
        self.res.faults.append(f)
        if self.on_fault is not None:
            self.on_fault(f)
        self.sink.write("/faults", f.to_dict(), self.t0 + f.time)

    def _recording_failed(self, error: str) -> None:
        self.res.recording_error = error
        self.fault("recording", f"recording failed, later data is not recorded: {error}",
                   "reflex kept running")

    def finish(self) -> RunResult:
        res = self.res
        now = self.clock()
        self.counter_faults(now, final=True)
        self.stall_check(now)
        while self.guard_faults:
            self.emit(self.guard_faults.popleft())
        res.duration = now - self.t0
        res.latencies = np.asarray(self.latencies, dtype=float)
        res.frame_latencies = np.asarray(self.frame_latencies, dtype=float)
        res.daq_stats = self.source_stats()
        res.error = self.failed
        res.grip_unknown = [f.name.lower() for i in sorted(self.unstopped) for f in self.grip.groups[i][0]]
        if res.grip_unknown:
            self.fault("grip-unknown", f"the STOP ending the closing of {', '.join(res.grip_unknown)} never "
                       f"reached the hand: their grip is at least what the summary says, up to their end "
                       f"stops", "hand it to the user: check the hand")
        if self.sink.ok:
            self.sink.write("/stats", {"time": res.duration, "counters": self.stats_counters()}, now)
            self.sink.recorder.add_metadata("run_summary", res.summary_metadata())
        rec = self.sink.recorder
        if rec is not None and rec.error is not None and res.recording_error is None:
            res.recording_error = f"{optional(rec, RunRecorder, 'path')}: {rec.error}"
        return res


class _Guard(threading.Thread):
    """Outside the loop's thread: holds the fingers when the loop stops iterating (stuck in a
    call, a long pause) for longer than the watchdog. A stopped process stops this too; the
    loop's staleness check catches that when it resumes."""

    def __init__(self, loop: _Loop) -> None:
        super().__init__(name="slipreflex-stall-guard", daemon=True)
        self.loop = loop
        self.closing = threading.Event()
        self.holding = False

    def run(self) -> None:
        loop = self.loop
        while not self.closing.wait(loop.watchdog_s / 4):
            stalled = loop.clock() - loop.heartbeat
            if stalled <= loop.watchdog_s:
                self.holding = False
                continue
            if self.holding:
                continue
            self.holding = True
            ok = loop.lock.acquire(timeout=loop.watchdog_s)
            try:
                if ok:
                    loop.hand.hold(loop.fingers)
                    action = "fingers held by the guard"
                else:
                    action = "could not hold (the hand port is busy)"
            except (DeviceError, ParameterError) as err:
                action = f"hold failed: {err}"
            finally:
                if ok:
                    loop.lock.release()
            loop.guard_faults.append(Fault(round(loop.clock() - loop.t0, 6), "loop-stalled",
                                           f"the loop has not iterated for {stalled * 1e3:.0f} ms", action))

    def close(self) -> None:
        self.closing.set()
        self.join(timeout=1.0)
