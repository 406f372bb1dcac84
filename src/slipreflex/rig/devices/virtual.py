"""Virtual devices: a rig behind two pseudo-terminals, in real time.

:class:`PtyPort` is one pseudo-terminal whose far end (the *slave* path, or a
stable symlink to it) a program opens like a serial device. :class:`VirtualDevices`
runs a rig in real time behind two of them: the DAQ port emits the
firmware's frames (:mod:`slipreflex.rig.devices.wire`) one sample period apart,
and the hand port accepts i-Limb packets (:mod:`slipreflex.rig.devices.ilimb`)
and drives the rig's hand. ``slipreflex run`` cannot tell them from the real
devices: it runs exactly the same code.

A *rig* here is anything with ``advance_to(t) -> list[DaqSample]`` (the
samples up to time ``t`` seconds), a ``hand`` implementing
:class:`~slipreflex.core.interfaces.Hand`, and ``perturb(kind)`` for the named
perturbations ("drop", "pour"); :class:`slipreflex.rig.devices.simrig.SimRig`
adapts the simulated rig to it.

For fault tests the devices can misbehave on request: inject bytes into the
DAQ stream, pause it, restart it (sequence numbers from 0, like a reset
board), and unplug / replug either port (with ``link_dir`` the replugged port
appears at the same path, as udev does for a real device).

Examples
--------
>>> import serial
>>> from slipreflex.rig.devices.wire import FrameParser
>>> from slipreflex.core.interfaces import DaqSample
>>> class Still:                       # a rig whose sensor sees a constant 0.4 V
...     def __init__(self): self.k, self.hand = 0, None
...     def advance_to(self, t):
...         out = []
...         while (self.k + 1) * 0.003 <= t:
...             out.append(DaqSample(self.k, self.k * 0.003, 0.4, None, 0)); self.k += 1
...         return out
>>> with VirtualDevices(Still()) as dev:
...     with serial.Serial(dev.daq_path, timeout=0.5) as port:
...         data = port.read(200)
>>> len(FrameParser().feed(data)) >= 1
True
"""

from __future__ import annotations

import dataclasses
import math
import os
import queue
import select
import threading
import time
import tty
from collections.abc import Iterable
from typing import Any

from ...core import experiment_specs
from ...core.errors import DeviceError, ParameterError
from ...core.hardware import DAQ_PERIOD_S, FINGER_SPEED_UNITS_S, PWM_MAX, Finger, HandCommand
from ..hands import get_hand
from . import wire
from .ilimb import PacketParser, value_range

__all__ = ["PtyPort", "VirtualDevices", "parse_schedule", "SCHEDULE_FROM"]

#: What a schedule's times may count from: the rig's start or the client's first hand packet.
SCHEDULE_FROM: tuple[str, ...] = ("connect", "start")


class PtyPort:
    """One pseudo-terminal standing in for a serial device.

    The master side stays here (non-blocking); :attr:`path` is what a
    program opens. The slave is kept open and in raw mode, so data written
    before the program opens the port is neither echoed nor translated.

    Parameters
    ----------
    link : str, optional
        Also make this symlink point to the slave (kept up to date across
        :meth:`unplug` / :meth:`replug`); :attr:`path` is then the link. It is
        created new (anything already there is an error, never replaced) and
        removed at the end only while it is still this port's symlink.

    Examples
    --------
    >>> import serial
    >>> port = PtyPort()
    >>> with serial.Serial(port.path, timeout=1) as s:
    ...     port.write(b"hi"), s.read(2)
    (True, b'hi')
    >>> port.close()
    """

    def __init__(self, link: str | None = None) -> None:
        self.link = link
        self.master: int | None = None
        self._slave: int | None = None
        self.slave_name = ""
        self.dropped_bytes = 0
        self.replug()

    @property
    def path(self) -> str:
        """The device path to open (the link if there is one).

        Examples
        --------
        >>> p = PtyPort(); p.path.startswith("/dev/pts/"); p.close()
        True
        """
        return self.link or self.slave_name

    @property
    def plugged(self) -> bool:
        """True while the port exists.

        Examples
        --------
        >>> p = PtyPort(); p.unplug(); p.plugged
        False
        >>> p.close()
        """
        return self.master is not None

    def replug(self) -> None:
        """(Re)create the pseudo-terminal (and repoint the link).

        Examples
        --------
        >>> p = PtyPort(); p.unplug(); p.replug(); p.plugged; p.close()
        True
        """
        if self.master is not None:
            return
        master, slave = os.openpty()
        tty.setraw(slave)
        os.set_blocking(master, False)
        self.master, self._slave = master, slave
        old_slave, self.slave_name = self.slave_name, os.ttyname(slave)
        if self.link:
            try:
                os.symlink(self.slave_name, self.link)   # never replaces what is there
            except FileExistsError:
                if not self._is_our_link(old_slave):
                    self.close()
                    raise ParameterError(f"{self.link}: exists and is not this rig's link; move it or "
                                         f"choose another --link-dir") from None
                tmp = f"{self.link}.tmp{os.getpid()}"
                os.symlink(self.slave_name, tmp)
                os.replace(tmp, self.link)

    def unplug(self) -> None:
        """Make the device vanish: close the pty (and remove the link).

        A program holding the port open then gets I/O errors.

        Examples
        --------
        >>> p = PtyPort(); p.unplug(); p.write(b"x")
        False
        >>> p.close()
        """
        if self.link and self._is_our_link(self.slave_name):
            os.unlink(self.link)   # only the symlink this port made, never a file put there since
        for fd in (self.master, self._slave):
            if fd is not None:
                os.close(fd)
        self.master = self._slave = None

    def _is_our_link(self, target: str) -> bool:
        try:
            return bool(target and self.link) and os.readlink(str(self.link)) == target
        except OSError:   # gone, or not a symlink
            return False

    def write(self, data: bytes) -> bool:
        """Write without blocking; bytes that do not fit are dropped and counted.

        Returns
        -------
        bool
            True if everything was written.

        Examples
        --------
        >>> p = PtyPort(); p.write(b"abc"); p.close()
        True
        """
        if self.master is None:
            self.dropped_bytes += len(data)
            return False
        try:
            n = os.write(self.master, data)
        except (BlockingIOError, InterruptedError):
            n = 0
        except OSError:
            n = 0
        if n < len(data):
            self.dropped_bytes += len(data) - n
            return False
        return True

    def read(self) -> bytes:
        """Whatever the program wrote, without blocking (b"" if nothing).

        Examples
        --------
        >>> p = PtyPort(); p.read(); p.close()
        b''
        """
        if self.master is None:
            return b""
        try:
            return os.read(self.master, 4096)
        except (BlockingIOError, InterruptedError):
            return b""
        except OSError:  # EIO: no process has the slave open (cannot happen: we keep it)
            return b""

    def close(self) -> None:
        """Close for good (idempotent).

        Examples
        --------
        >>> p = PtyPort(); p.close(); p.close()
        """
        self.unplug()


def parse_schedule(text: str) -> list[tuple[str, float]]:
    """Parse a perturbation schedule such as ``"drop@2.0,pour@5.0"``.

    Parameters
    ----------
    text : str
        Comma-separated ``kind@seconds`` items; kinds are ``drop`` and ``pour``.

    Returns
    -------
    list of (str, float)
        Sorted by time.

    Raises
    ------
    ParameterError
        A malformed item, an unknown kind or a negative time.

    Examples
    --------
    >>> parse_schedule("pour@5, drop@2.0")
    [('drop', 2.0), ('pour', 5.0)]
    >>> parse_schedule("jump@1")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: schedule item 'jump@1': kind must be one of drop, pour
    """
    out = []
    for item in (s.strip() for s in text.split(",")):
        if not item:
            continue
        kind, sep, at = item.partition("@")
        kind = kind.strip().lower()
        if not sep:
            raise ParameterError(f"schedule item {item!r}: expected kind@seconds, e.g. drop@2.0")
        if kind not in experiment_specs.names():
            raise ParameterError(f"schedule item {item!r}: kind must be one of {', '.join(experiment_specs.names())}")
        try:
            t = float(at)
        except ValueError:
            raise ParameterError(f"schedule item {item!r}: time {at.strip()!r} is not a number") from None
        if not (math.isfinite(t) and t >= 0):
            raise ParameterError(f"schedule item {item!r}: time must be >= 0")
        out.append((kind, t))
    return sorted(out, key=lambda x: x[1])


class VirtualDevices:
    """A rig running in real time behind a virtual DAQ port and a virtual hand port.

    A background thread advances the rig to the wall-clock time since
    :meth:`start`, writes each new sample's frame to the DAQ port, and
    applies every i-Limb packet that arrives on the hand port to
    ``rig.hand``: through ``rig.hand.command(kind, fingers, value)`` if the
    hand has it (the simulated i-Limb does), else through its
    :class:`~slipreflex.core.interfaces.Hand` methods (position: ``set_positions``;
    close: ``close_fingers`` at the PWM's share of the documented speed; stop:
    ``hold``), falling back to position targets for a hand without them (stop:
    hold the measured position; close/open: move to the end of the range).
    Perturbations run when :meth:`trigger` is called or their scheduled time comes.

    Parameters
    ----------
    rig : rig
        See the module docstring.
    link_dir : str, optional
        Directory in which ``daq`` and ``hand`` symlinks name the ports.
    schedule : iterable of (kind, seconds), optional
        Perturbations at fixed times after ``schedule_from``.
    schedule_from : {"start", "connect"}
        What the schedule's times count from: :meth:`start`, or the first packet on the
        hand port (a client such as ``slipreflex run`` connected: it sends STOP first).
    on_event : callable, optional
        ``on_event(text)`` is called in the rig's thread with one line for each
        perturbation as it starts (``"drop at 5.00 s (schedule)"``) and when the client
        connects.
    period : float
        Sample period (s) used to wake up; the rig decides the sample times.
    script : iterable of (seconds, callable), optional
        Actions ``fn(devices)`` run in the rig's thread at fixed times after
        :meth:`start` (e.g. ``(1.0, lambda d: d.unplug("hand"))``), for
        scripted fault tests.
    hand_type : str
        The hand behind the hand port, a name of :mod:`slipreflex.rig.hands` ("ilimb": i-Limb
        packets applied to ``rig.hand``; "ability": the Ability Hand's UART, each command
        answered with the measured positions and touch sites).
    on_advance : callable, optional
        ``on_advance(rig)``, called in the rig's thread after each advance (``virtual-rig
        --live`` puts the rig's truth on its live view); it must not block.

    Attributes
    ----------
    daq, hand : PtyPort
    frames_written, hand_packets : int
    hand_parser : PacketParser
        Its counters show rejected packets and skipped bytes.
    triggered : list of (str, float)
        Perturbations started, with the time since :meth:`start`.

    Examples
    --------
    >>> import serial
    >>> from slipreflex.rig.devices.ilimb import ILimb
    >>> from slipreflex.core.hardware import Finger
    >>> class Rig:                     # no samples; a hand that remembers its targets
    ...     class hand:
    ...         got = {}
    ...         def set_positions(targets): Rig.hand.got.update(targets)
    ...         def positions(): return dict(Rig.hand.got)
    ...     def advance_to(self, t): return []
    >>> with VirtualDevices(Rig()) as dev:
    ...     with ILimb(dev.hand_path) as hand:
    ...         hand.set_positions({Finger.MIDDLE: 321})
    ...     deadline = time.monotonic() + 5
    ...     while dev.hand_packets < 1 and time.monotonic() < deadline:
    ...         time.sleep(0.01)
    >>> Rig.hand.got
    {<Finger.MIDDLE: 2>: 321.0}
    """

    def __init__(self, rig: Any, *, link_dir: str | None = None,
                 schedule: Iterable[tuple[str, float]] = (), period: float = DAQ_PERIOD_S,
                 script: Iterable[tuple[float, Any]] = (), schedule_from: str = "start",
                 on_event: Any = None, on_advance: Any = None, hand_type: str = "ilimb") -> None:

        if schedule_from not in SCHEDULE_FROM:
            raise ParameterError(f"schedule_from must be one of {', '.join(SCHEDULE_FROM)}, got {schedule_from!r}")
        self.schedule_from = schedule_from
        self.on_event = on_event
        #: Seconds since :meth:`start` when the client connected (its first hand packet), NaN before.
        self.connected_at = math.nan
        spec = get_hand(hand_type)
        self.hand_type = spec.name
        #: the hand's side of its protocol (None: the i-Limb's packets, applied below)
        self.emulator = spec.virtual(rig) if spec.virtual is not None else None
        self.rig = rig
        self.on_advance = on_advance
        self.period = period
        self.daq = PtyPort(os.path.join(link_dir, "daq") if link_dir else None)
        try:
            self.hand = PtyPort(os.path.join(link_dir, "hand") if link_dir else None)
        except BaseException:
            self.daq.close()      # removes only the daq link it made
            raise
        self.hand_parser = PacketParser()
        self.frames_written = 0
        self.hand_packets = 0
        self.hand_errors = 0
        self.triggered: list[tuple[str, float]] = []
        self._schedule = sorted([(t, ("perturb", kind, "schedule")) for kind, t in schedule], key=lambda x: x[0])
        self._script = sorted([(t, ("script", fn)) for t, fn in script], key=lambda x: x[0])
        self._requests: queue.SimpleQueue = queue.SimpleQueue()
        self._stop = threading.Event()
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_r, False)
        self._thread: threading.Thread | None = None
        self._t0 = math.nan
        self._daq_paused = False
        self._seq_offset = 0
        self._last_seq: int | None = None
        self._error: BaseException | None = None

    # -- paths and lifetime --------------------------------------------------
    @property
    def daq_path(self) -> str:
        """Path of the virtual DAQ port."""
        return self.daq.path

    @property
    def hand_path(self) -> str:
        """Path of the virtual hand port."""
        return self.hand.path

    @property
    def elapsed(self) -> float:
        """Seconds since :meth:`start` (NaN before)."""
        return time.perf_counter() - self._t0

    def start(self) -> VirtualDevices:
        """Start the real-time thread (idempotent); returns self."""
        if self._thread is None:
            self._t0 = time.perf_counter()
            self._thread = threading.Thread(target=self._run, name="virtual-rig", daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        """Carry out the requests already made, stop the thread and close the ports (idempotent).

        Raises
        ------
        DeviceError
            If the rig raised in the thread (the error is re-raised here).
        """
        self._stop.set()
        self._wake()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        for fd in (self._wake_r, self._wake_w):
            try:
                os.close(fd)
            except OSError:
                pass
        self._wake_r = self._wake_w = -1
        self.daq.close()
        self.hand.close()
        err, self._error = self._error, None
        if err is not None:
            raise DeviceError(f"virtual rig failed: {err!r}") from err

    @property
    def running(self) -> bool:
        """True while the thread runs."""
        return self._thread is not None and self._thread.is_alive()

    def __enter__(self) -> VirtualDevices:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _wake(self) -> None:
        try:
            os.write(self._wake_w, b"x")
        except OSError:
            pass

    # -- requests from other threads ----------------------------------------
    def _request(self, *item: Any) -> None:
        self._requests.put(item)
        self._wake()

    def trigger(self, kind: str, source: str = "key") -> None:
        """Start a perturbation ("drop" or "pour") now; ``source`` names who asked (announced).

        Raises
        ------
        ParameterError
            For another kind.
        """
        if kind not in experiment_specs.names():
            raise ParameterError(f"unknown perturbation {kind!r} (known: {', '.join(experiment_specs.names())})")
        self._request("perturb", kind, source)

    def inject_daq(self, data: bytes) -> None:
        """Send raw bytes on the DAQ port between frames (garbage, torn frames)."""
        self._request("inject", bytes(data))

    def pause_daq(self, paused: bool = True) -> None:
        """Stop (or resume) sending frames; the rig keeps running."""
        self._request("pause", paused)

    def restart_daq(self) -> None:
        """Resume sending with sequence numbers from 0, like a board that was reset."""
        self._request("restart")

    def unplug(self, which: str) -> None:
        """Make the "daq" or "hand" port vanish."""
        self._request("unplug", which)

    def replug(self, which: str) -> None:
        """Bring the "daq" or "hand" port back (at the same link path)."""
        self._request("replug", which)

    def call(self, fn: Any) -> None:
        """Run ``fn(rig)`` in the rig's thread (e.g. to read its state safely)."""
        self._request("call", fn)

    # -- the real-time thread ------------------------------------------------
    def _handle(self, item: tuple) -> None:
        kind = item[0]
        if kind == "perturb":
            self.rig.perturb(item[1])
            self.triggered.append((item[1], self.elapsed))
            self._announce(f"{item[1]} at {self.elapsed:.2f} s ({item[2] if len(item) > 2 else 'key'})")
        elif kind == "inject":
            self.daq.write(item[1])
        elif kind == "pause":
            self._daq_paused = bool(item[1])
        elif kind == "restart":
            self._daq_paused = False
            self._seq_offset = (self._last_seq + 1) if self._last_seq is not None else 0
        elif kind in ("unplug", "replug"):
            port = {"daq": self.daq, "hand": self.hand}[item[1]]
            port.unplug() if kind == "unplug" else port.replug()
        elif kind == "call":
            item[1](self.rig)
        elif kind == "script":
            item[1](self)

    def _announce(self, text: str) -> None:
        if self.on_event is not None:
            self.on_event(text)

    def _apply_packet(self, cmds: tuple) -> None:
        hand = self.rig.hand
        try:
            if hasattr(hand, "command"):  # a hand that speaks i-Limb commands (the simulated one)
                for c in cmds:
                    hand.command(c.command, [c.finger], float(c.value))
                return
            targets: dict[Finger, float] = {}
            hold = [c.finger for c in cmds if c.command == HandCommand.STOP]
            measured = hand.positions() if hold else {}
            for c in cmds:
                if c.command == HandCommand.STOP and hasattr(hand, "hold"):
                    hand.hold([c.finger])
                elif c.command == HandCommand.CLOSE and hasattr(hand, "close_fingers"):
                    hand.close_fingers([c.finger], FINGER_SPEED_UNITS_S * c.value / PWM_MAX)
                elif c.command == HandCommand.POSITION:
                    targets[c.finger] = float(c.value)
                elif c.command == HandCommand.STOP:
                    if c.finger in measured:
                        targets[c.finger] = float(measured[c.finger])
                elif c.finger != Finger.WRIST:
                    lo, hi = value_range(c.finger, HandCommand.POSITION)
                    targets[c.finger] = float(hi if c.command == HandCommand.CLOSE else lo)
            if targets:
                hand.set_positions(targets)
        except (ParameterError, ValueError, KeyError):
            self.hand_errors += 1

    def _run(self) -> None:
        try:
            self._loop()
            self._drain()  # requests made before stop() are carried out, never dropped
        except BaseException as err:  # noqa: BLE001 - reported by stop()
            self._error = err

    def _drain(self) -> None:
        while True:
            try:
                self._handle(self._requests.get_nowait())
            except queue.Empty:
                return

    def _connected(self, schedule: list) -> None:
        """The client's first hand packet: the clock a ``connect`` schedule counts from starts now."""
        self.connected_at = self.elapsed
        waiting = " (the schedule starts now)" if self.schedule_from == "connect" and schedule else ""
        self._announce(f"client connected at {self.connected_at:.2f} s{waiting}")

    def _loop(self) -> None:
        schedule, script = list(self._schedule), list(self._script)
        while not self._stop.is_set():
            t = time.perf_counter() - self._t0
            origin = 0.0 if self.schedule_from == "start" else self.connected_at
            while schedule and schedule[0][0] <= t - origin:      # NaN origin: not yet connected
                self._handle(schedule.pop(0)[1])
            while script and script[0][0] <= t:
                self._handle(script.pop(0)[1])
            self._drain()
            samples = self.rig.advance_to(t)
            tick = getattr(self.emulator, "tick", None)
            if tick is not None:  # the hand's own clock: its API timeout
                tick()
            for s in samples:
                self._last_seq = s.seq
                if self._daq_paused:
                    continue
                seq = s.seq - self._seq_offset
                self.daq.write(wire.encode_sample(dataclasses.replace(s, seq=seq)))
                self.frames_written += 1
            if samples and self.on_advance is not None:
                self.on_advance(self.rig)
            # Sleep until the next sample is due, waking early for hand packets.
            t = time.perf_counter() - self._t0
            timeout = max(0.0, (math.floor(t / self.period) + 1) * self.period - t)
            fds = [self._wake_r] + ([self.hand.master] if self.hand.master is not None else [])
            try:
                ready, _, _ = select.select(fds, [], [], timeout)
            except (OSError, ValueError):  # a port closed under us by unplug
                continue
            if self._wake_r in ready:
                try:
                    os.read(self._wake_r, 4096)
                except OSError:
                    pass
            if self.hand.master is not None and self.hand.master in ready:
                data = self.hand.read()
                if self.emulator is not None:
                    reply = self.emulator.feed(data)
                    self.hand_packets = self.emulator.commands
                    if self.hand_packets and math.isnan(self.connected_at):
                        self._connected(schedule)
                    if reply:
                        self.hand.write(reply)
                    continue
                for cmds in self.hand_parser.feed(data):
                    self.hand_packets += 1
                    if self.hand_packets == 1:
                        self._connected(schedule)
                    self._apply_packet(cmds)
