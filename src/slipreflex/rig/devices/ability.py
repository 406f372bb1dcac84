"""The PSYONIC Ability Hand on its UART: the extended API, a driver, and its touch sensors.

Written from the hand's published interface control document (the Ability Hand ICD,
sections 3.3-3.5: extended API frames, position data, touch sensor data, checksums,
PPP byte stuffing); nothing here depends on PSYONIC's own Python wrapper. The frames (byte
stuffing, the commands, the replies, the touch sensors' conversion) are encoded, decoded and
described in :mod:`slipreflex.rig.devices.ability_wire`; every name of it is importable from here too.

Positions in this package are finger units, 0 (open) .. 500 (closed), the same for every
hand (:data:`slipreflex.core.hardware.FINGER_MAX`); this driver maps them linearly onto
0 .. :data:`FULL_CLOSE_DEG` degrees of flexion (the thumb rotator onto 0 .. minus that).

Examples
--------
>>> frame = encode_positions([30.0, 30.0, 30.0, 30.0, 30.0, -30.0])
>>> frame[0], frame[-1], len(unstuff(frame)[0])          # delimiters; address + header + 12 + sum
(126, 126, 15)
>>> round(decode_command(unstuff(frame)[0])[2][0], 2)
30.0
>>> reply = decode_reply(unstuff(encode_reply([10.0] * 5 + [-10.0], touch=[0, 2048] * 15))[0])
>>> round(reply.positions[0], 2), reply.touch[:2]
(10.0, (0, 2048))
"""

from __future__ import annotations

import collections
import math
import threading
import time
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from ...core.errors import DataError, DeviceError, ParameterError
from ...core.hardware import FINGER_MAX, FINGER_MIN, PWM_MAX, Finger, HandCommand
from ...core.interfaces import TactileSample
from .ability_wire import (
    _FSR_C2,
    _POSITION,
    ABILITY_BAUD,
    ADDRESS,
    FULL_CLOSE_DEG,
    ORDER,
    SITES,
    TOUCH_FINGERS,
    AbilityReply,
    Unstuffer,
    checksum,
    decode_command,
    decode_reply,
    degrees_of,
    encode_positions,
    encode_read,
    encode_reply,
    encode_velocities,
    stuff,
    touch_counts,
    touch_newtons,
    units_of,
    unstuff,
)
from .port import ReconnectingPort

__all__ = ["ABILITY_BAUD", "ADDRESS", "ORDER", "TOUCH_FINGERS", "SITES", "FULL_CLOSE_DEG",
           "checksum", "stuff", "unstuff", "Unstuffer", "encode_positions", "encode_velocities", "encode_read",
           "decode_command", "AbilityReply", "decode_reply", "encode_reply", "touch_newtons",
           "touch_counts", "degrees_of", "units_of", "AbilityHand", "API_TIMEOUT_S", "KEEPALIVE_S",
           "stalled_fingers"]


#: Seconds of silence after which the hand leaves API mode (PSYONIC's manual: about 300 ms,
#: "may be accompanied by undesired finger movements").
API_TIMEOUT_S: float = 0.3
#: The driver's longest silence (s): a read-only request at least this often, a sixth of the timeout.
KEEPALIVE_S: float = 0.05
#: Frames the driver keeps for :meth:`AbilityHand.read_frames` (about 15 s at 260 Hz).
_FRAME_BACKLOG = 4096


class AbilityHand:
    """The Ability Hand on a serial port: a :class:`~slipreflex.core.interfaces.Hand` and a
    :class:`~slipreflex.core.interfaces.TactileSource` (one finger's 6 touch sites per frame).

    As PSYONIC's own wrapper runs it: a thread of the driver (the pump) reads the replies
    continuously and, whenever nothing was written for one period (``1 / fs``, at most
    ``keepalive``), writes a read-only request, so the hand hears from the host well inside its
    API timeout (:data:`API_TIMEOUT_S`) whether or not the loop sends anything, and
    :meth:`positions` is the newest reply's in every run, not only when tactile frames are
    read. Every reply is a frame (it carries the touch sites), so a command's reply stands
    for that period's request and the frames stay near ``fs``.

    At construction it asks the hand for one reply (read-only mode) and fails unless one
    comes: every later command then starts from the fingers' measured positions, so a
    command never moves a finger it does not name. The reply's status byte is read: a
    finger whose bit is set has stalled (collision): the hand ignores further closing of it
    until it is opened (:meth:`stalled`).

    Parameters
    ----------
    port : str or serial.Serial
    fs : float
        Rate (Hz) of the read-only requests.
    tactile_finger : Finger
        The finger whose touch sites are the tactile frame (index by default, as the
        paper's tactile array).
    reply_timeout : float
        Seconds to wait for the first reply.
    write_timeout, reconnect_interval : float
        As :class:`~slipreflex.rig.devices.ilimb.ILimb`.
    keepalive : float
        Longest silence (s) the driver leaves the hand in (0 < keepalive <= API_TIMEOUT_S / 3).

    Attributes
    ----------
    shape : tuple of int
        Shape of a tactile frame: ``(6,)``.
    replies, bad_replies, requests : int

    Raises
    ------
    DeviceError
        The port cannot be opened, or the hand does not reply (the message names the port).

    Examples
    --------
    >>> AbilityHand("/nonexistent/tty")           # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.DeviceError: /nonexistent/tty: cannot open Ability Hand port: ...
    """

    def __init__(self, port: Any, *, fs: float = 260.0, tactile_finger: Finger = Finger.INDEX,
                 reply_timeout: float = 1.0, write_timeout: float = 0.01,
                 reconnect_interval: float = 0.2, keepalive: float = KEEPALIVE_S) -> None:
        if not (math.isfinite(fs) and fs > 0):
            raise ParameterError(f"Ability Hand: fs must be > 0 Hz, got {fs!r}")
        if not (math.isfinite(keepalive) and 0 < keepalive <= API_TIMEOUT_S / 3):
            raise ParameterError(f"Ability Hand: keepalive must be in (0, {API_TIMEOUT_S / 3:g}] s "
                                 f"(well inside the hand's API timeout), got {keepalive!r}")
        if Finger(tactile_finger) not in TOUCH_FINGERS:
            raise ParameterError(f"Ability Hand: {Finger(tactile_finger).name.lower()} has no touch sites")
        self._port = ReconnectingPort(port, what="Ability Hand", baudrate=ABILITY_BAUD,
                                      write_timeout=write_timeout, reconnect_interval=reconnect_interval)
        self.port_name = self._port.port_name
        self.fs = float(fs)
        self.shape = (SITES,)
        self._period = min(1.0 / self.fs, float(keepalive))
        self._site0 = TOUCH_FINGERS.index(Finger(tactile_finger)) * SITES
        self._unstuffer = Unstuffer()
        self._measured: dict[Finger, float] = {}
        self._stalled: frozenset[Finger] = frozenset()
        self._targets: dict[Finger, float] = {}
        self._closing: dict[Finger, float] = {}  # finger -> closing speed, degrees/s
        self._reflex = False  # the grip-only guard (reflex_running)
        self._wlock = threading.Lock()  # writes: the loop's commands and the pump's requests
        self._arrived = threading.Condition()
        self._frames: collections.deque[TactileSample] = collections.deque(maxlen=_FRAME_BACKLOG)
        self._error: DeviceError | None = None
        self._stop = threading.Event()
        self._last_write = -math.inf
        self._t0 = time.perf_counter()
        self._seq = 0
        self.replies = self.bad_replies = self.requests = 0
        self.last_reply: AbilityReply | None = None
        self.last_arrival = math.nan
        deadline = time.monotonic() + reply_timeout
        try:
            self._write(encode_read())
            while self.last_reply is None and time.monotonic() < deadline:
                self._receive(0.02)
        except DeviceError:
            self._port.close()
            raise
        if self.last_reply is None:
            self._port.close()
            raise DeviceError(f"{self.port_name}: no reply from an Ability Hand within {reply_timeout:g} s "
                              f"(UART API with byte stuffing on, {ABILITY_BAUD} baud?)")
        self._pump = threading.Thread(target=self._pump_run, name="ability-hand-pump", daemon=True)
        self._pump.start()

    # -- bytes ------------------------------------------------------------------------
    def _write(self, frame: bytes) -> None:
        import serial  # deferred: heavy (serial)

        with self._wlock:
            if self._port.serial is None and not self._port.ensure_open():
                raise DeviceError(f"{self.port_name}: Ability Hand port is not connected")
            try:
                self._port.write(frame)
            except (serial.SerialException, OSError) as err:
                raise self._port.fail(err, "write failed") from None
            self._last_write = time.perf_counter()

    def _receive(self, timeout: float) -> list[TactileSample]:
        import serial  # deferred: heavy (serial)

        ser = self._port.serial
        if ser is None:
            return []
        try:
            if ser.timeout != timeout:
                ser.timeout = timeout
            data = ser.read(ser.in_waiting or 1)
            if data and ser.in_waiting:
                data += ser.read(ser.in_waiting)
        except (serial.SerialException, OSError, TypeError) as err:
            raise self._port.fail(err) from None
        if not data:
            return []
        arrival = time.perf_counter()
        out = []
        for frame in self._unstuffer.feed(data):
            try:
                reply = decode_reply(frame)
            except DataError:
                self.bad_replies += 1
                continue
            self.replies += 1
            self.last_reply, self.last_arrival = reply, arrival
            self._measured = {f: units_of(f, d) for f, d in zip(ORDER, reply.positions)}
            self._stalled = stalled_fingers(reply.status)
            site = touch_newtons(reply.touch[self._site0:self._site0 + SITES])
            out.append(TactileSample(self._seq, arrival - self._t0, site))
            self._seq += 1
        return out

    def _pump_run(self) -> None:
        """The driver's own thread: a read-only request whenever nothing was written for a period,
        and every reply read as it comes (frames queued for :meth:`read_frames`)."""
        while not self._stop.is_set():
            try:
                if time.perf_counter() - self._last_write >= self._period:
                    self._write(encode_read())
                    self.requests += 1
                frames = self._receive(self._period / 2)
            except DeviceError as err:
                with self._arrived:
                    self._error = err
                    self._arrived.notify_all()
                self._stop.wait(self._period)
                continue
            if frames:
                with self._arrived:
                    self._frames.extend(frames)
                    self._arrived.notify_all()
            elif self._port.serial is None or not hasattr(self._port.serial, "fileno"):
                self._stop.wait(self._period / 4)  # a port without a blocking read: do not spin

    # -- Hand -------------------------------------------------------------------------
    def _command(self, targets: Mapping[Finger, float]) -> tuple[bytes, dict[Finger, float]]:
        if self._reflex:  # every position frame, an empty one included, carries every finger's angle
            raise ParameterError("Ability Hand: position command refused while a reflex runs (a position "
                                 "frame moves every finger to an angle; the reflex adds grip only by "
                                 "closing and holding)")
        full = {**self._measured, **self._targets}
        for f, v in targets.items():
            f = Finger(f)
            if f not in ORDER:
                raise ParameterError(f"Ability Hand has no {f.name.lower()} finger")
            v = float(v)
            if not (math.isfinite(v) and FINGER_MIN <= v <= FINGER_MAX):
                raise ParameterError(f"Ability Hand: {f.name} position must be in {FINGER_MIN}..{FINGER_MAX}, "
                                     f"got {v!r}")
            full[f] = v
        return encode_positions([degrees_of(f, full.get(f, 0.0)) for f in ORDER]), full

    def set_positions(self, targets: Mapping[Finger, float]) -> None:
        """Send position targets (finger units); the fingers not named keep their last
        target, or their measured position if they never had one.

        Raises
        ------
        ParameterError
            A finger the hand lacks, a position outside 0..500, or any position frame while
            a reflex runs (nothing is written).
        DeviceError
            The port is gone.
        """
        frame, full = self._command(targets)
        self._write(frame)
        self._targets = {f: v for f, v in full.items()}

    def close_fingers(self, fingers: Iterable[Finger], speed: float) -> None:
        """Start closing ``fingers`` at ``speed`` finger units per second, until :meth:`hold`.

        Sent in velocity mode (ICD 3.4.2): the named fingers at ``speed`` (in degrees per
        second, :func:`degrees_of`), every other finger at 0, which holds it.

        Raises
        ------
        ParameterError
            A finger the hand lacks, or a speed that is not > 0 (nothing is written).
        """
        fs = [Finger(f) for f in fingers]
        bad = [f for f in fs if f not in ORDER]
        if bad or not (math.isfinite(speed) and speed > 0):
            raise ParameterError(f"Ability Hand: cannot close {[f.name.lower() for f in bad] or fs} at {speed!r} "
                                 f"units/s (fingers of the hand, speed > 0)")
        closing = {**self._closing, **{f: abs(degrees_of(f, speed)) for f in fs}}
        self._write(encode_velocities([closing.get(f, 0.0) * (-1 if f == Finger.THUMB_ROTATOR else 1)
                                       for f in ORDER]))
        self._closing = closing

    def hold(self, fingers: Iterable[Finger] = ()) -> None:
        """Stop ``fingers`` where they are: velocity 0 (never opens the hand); fingers still
        closing keep closing.

        Not a position at the last measurement: a finger that closed since that reply would
        be sent back, i.e. opened.
        """
        fs = [Finger(f) for f in fingers]
        closing = {f: v for f, v in self._closing.items() if f not in fs}
        self._write(encode_velocities([closing.get(f, 0.0) * (-1 if f == Finger.THUMB_ROTATOR else 1)
                                       for f in ORDER]))
        self._closing = closing

    def reflex_running(self, running: bool = True) -> None:
        """Switch the grip-only guard on (a reflex runs) or off: while on, every position frame
        is refused before a byte is written (a reflex adds grip only by closing and holding).
        """
        self._reflex = bool(running)

    def positions(self) -> dict[Finger, float]:
        """The positions of the newest reply (the pump reads them continuously), in finger units."""
        return dict(self._measured)

    def stalled(self) -> frozenset[Finger]:
        """Fingers the newest reply's status byte reports stalled: the hand ignores closing them
        until they are opened, so grip sent to them is not grip added."""
        return self._stalled

    # -- TactileSource ---------------------------------------------------------------
    def read_frames(self, timeout: float) -> list[TactileSample]:
        """The frames of the replies that came since the last call (waiting at most ``timeout``).

        Raises
        ------
        DeviceError
            The port failed and no frame came (the pump keeps trying to reopen it).
        """
        with self._arrived:
            if not self._frames and self._error is None:
                self._arrived.wait(max(0.0, timeout))
            out = list(self._frames)
            self._frames.clear()
            err, self._error = self._error, None
        if err is not None and not out:
            raise err
        return out

    def drop_buffered(self) -> int:
        """Drop the frames the pump queued and no one has read yet.

        ``run_loop`` calls this once just before its clock starts: frames that came while the
        run set up (the chain warmed up, the safe start's STOP) are from before the run and
        would otherwise be processed as a stale backlog, as :meth:`SerialDaq.drop_buffered
        <slipreflex.rig.devices.daq.SerialDaq.drop_buffered>` drops the DAQ's.

        Returns
        -------
        int
            Frames dropped.
        """
        with self._arrived:
            dropped = len(self._frames)
            self._frames.clear()
        return dropped

    def close(self) -> None:
        """Stop the pump and close the port if this driver opened it."""
        self._stop.set()
        if self._pump.is_alive() and self._pump is not threading.current_thread():
            self._pump.join(timeout=1.0)
        self._port.close()

    def __enter__(self) -> AbilityHand:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def stalled_fingers(status: int) -> frozenset[Finger]:
    """The fingers a reply's status byte reports stalled: bit ``k`` is finger ``ORDER[k]``.

    PSYONIC's wrapper logs any non-zero value as a collision; this driver reads it per
    finger, in the frame's finger order.

    Examples
    --------
    >>> sorted(f.name for f in stalled_fingers(0b000011))
    ['INDEX', 'MIDDLE']
    """
    return frozenset(f for k, f in enumerate(ORDER) if status >> k & 1)


#: How the virtual hand spreads a 4 x 4 tactile frame over a fingertip's 6 sites:
#: 3 bands of rows (0, 1-2, 3) by 2 halves of columns, each site the sum of its taxels
#: (a stand-in layout for tests: the total force is kept, the site geometry is not the hand's).
_SITE_ROWS = ((0,), (1, 2), (3,))
#: A site with less force than this (N) is untouched (reads 0) in the virtual hand.
_TOUCHED_N = 1e-3


def sites_from_array(frame: np.ndarray) -> np.ndarray:
    """Six site forces from a ``(4, 4)`` frame (see :data:`_SITE_ROWS`).

    Examples
    --------
    >>> sites_from_array(np.ones((4, 4))).tolist()
    [2.0, 2.0, 4.0, 4.0, 2.0, 2.0]
    """
    f = np.asarray(frame, dtype=np.float64)
    return np.array([f[list(rows)][:, half * 2:half * 2 + 2].sum() for rows in _SITE_ROWS for half in (0, 1)])


class VirtualAbilityHand:
    """The hand's side of the UART, on a rig: what the virtual devices run behind a pty.

    :meth:`feed` takes the bytes the host wrote; each position command is applied to
    ``rig.hand`` (finger units, :func:`units_of`) and each command, position or read-only,
    is answered with a variant-0 reply: the measured positions and, for each finger the rig
    has a tactile array on (``rig.tactile(finger)``, a ``(4, 4)`` frame in newtons), its
    six sites (:func:`sites_from_array`) as raw FSR values (:func:`touch_counts`). The ICD's
    placeholder law reads no touch below its offset C2 (0.88 N) and at least C2 on any
    touched site, so a site the rig presses with f newtons is sent as f + C2: the driver
    reads the rig's force plus a constant on touched sites, which a method that looks at
    changes (NMSD, SWT-SD) does not see.

    It models the two behaviours of the hand a host can get wrong: its API timeout (after
    ``api_timeout`` seconds without a frame, checked by :meth:`tick`, it leaves API mode:
    ``api_timeouts`` counts it and the fingers go open, the "undesired finger movements" of
    PSYONIC's manual at their worst for a grasp) and the stall (:meth:`stall` a finger: its
    status bit is set in every reply and closing it does nothing until it is opened).

    Attributes
    ----------
    commands, rejected, api_timeouts : int

    Examples
    --------
    >>> class Rig:
    ...     class hand:
    ...         pos = {}
    ...         def set_positions(t): Rig.hand.pos.update(t)
    ...         def positions(): return dict(Rig.hand.pos)
    ...     def tactile(self, finger): return np.full((4, 4), 0.1)
    >>> v = VirtualAbilityHand(Rig())
    >>> reply = v.feed(encode_positions([degrees_of(f, 100.0) for f in ORDER]))
    >>> sites = touch_newtons(decode_reply(unstuff(reply)[0]).touch)[:6] - 0.878894
    >>> round(Rig.hand.pos[Finger.INDEX], 1), sites.round(2).tolist()
    (100.0, [0.2, 0.2, 0.4, 0.4, 0.2, 0.2])
    """

    def __init__(self, rig: Any, tactile: Iterable[Finger] = (Finger.THUMB, Finger.INDEX, Finger.MIDDLE), *,
                 api_timeout: float = API_TIMEOUT_S, clock: Any = time.perf_counter) -> None:
        self.rig = rig
        self.tactile = tuple(f for f in tactile if f in TOUCH_FINGERS) if hasattr(rig, "tactile") else ()
        self._unstuffer = Unstuffer()
        self.commands = self.rejected = self.api_timeouts = 0
        self.api_timeout, self.clock = float(api_timeout), clock
        self.in_api = False
        self._heard = -math.inf
        self._stalled: set[Finger] = set()

    def stall(self, finger: Finger) -> None:
        """Stall ``finger`` (a collision): reported in the status byte, closing ignored until opened."""
        self._stalled.add(Finger(finger))

    def tick(self) -> None:
        """Leave API mode if the host has been silent for longer than the API timeout."""
        if self.in_api and self.clock() - self._heard > self.api_timeout:
            self.in_api = False
            self.api_timeouts += 1
            self.rig.hand.set_positions({f: 0.0 for f in ORDER if f != Finger.THUMB_ROTATOR})

    def _touch(self) -> list[int]:
        counts = [0] * (len(TOUCH_FINGERS) * SITES)
        for f in self.tactile:
            k = TOUCH_FINGERS.index(f) * SITES
            force = sites_from_array(self.rig.tactile(f))
            # the placeholder law reads at least C2 on any touched site: a touch of f reads f + C2
            counts[k:k + SITES] = touch_counts(np.where(force > _TOUCHED_N, force + _FSR_C2, 0.0)).tolist()
        return counts

    def _velocities(self, deg_s: dict[Finger, float]) -> None:
        """Velocity mode on the rig's hand: a closing finger closes at that speed, a finger at
        0 holds, an opening one goes to 0 (the simulated hand speaks i-Limb commands)."""

        hand = self.rig.hand
        full = getattr(getattr(hand, "params", None), "speed_units_s", None)
        for f, v in deg_s.items():
            if f == Finger.THUMB_ROTATOR:
                continue
            units = units_of(f, v)
            if f in self._stalled:
                if units >= 0:
                    units = 0.0  # a stalled finger ignores closing
                else:
                    self._stalled.discard(f)
            if units > 0 and hasattr(hand, "command") and full:
                hand.command(HandCommand.CLOSE, [f], min(float(PWM_MAX), units / full * PWM_MAX))
            elif units == 0 and hasattr(hand, "command"):
                hand.command(HandCommand.STOP, [f], 0.0)
            elif units < 0:
                hand.set_positions({f: 0.0})
            elif units > 0:
                hand.set_positions({f: float(FINGER_MAX)})

    def reply(self) -> bytes:
        """The reply to a command now: measured positions and touch values."""
        pos = self.rig.hand.positions()
        status = sum(1 << k for k, f in enumerate(ORDER) if f in self._stalled)
        return encode_reply([degrees_of(f, float(pos.get(f, 0.0))) for f in ORDER], touch=self._touch(),
                            status=status)

    def feed(self, data: bytes) -> bytes:
        """Apply the commands in ``data``; return the replies to write back."""
        out = bytearray()
        for frame in self._unstuffer.feed(data):
            try:
                _, header, degrees = decode_command(frame)
            except DataError:
                self.rejected += 1
                continue
            self.commands += 1
            self._heard, self.in_api = self.clock(), True
            if degrees is not None and header & 0xF0 == _POSITION:
                targets = {f: min(max(units_of(f, d), FINGER_MIN), FINGER_MAX)
                           for f, d in zip(ORDER, degrees) if f != Finger.THUMB_ROTATOR}
                now = self.rig.hand.positions()
                self._stalled -= {f for f, v in targets.items() if v < float(now.get(f, 0.0))}  # opened
                self.rig.hand.set_positions({f: v for f, v in targets.items()
                                             if f not in self._stalled or v <= float(now.get(f, 0.0))})
            elif degrees is not None:
                self._velocities(dict(zip(ORDER, degrees)))
            out += self.reply()
        return bytes(out)


__all__ += ["sites_from_array", "VirtualAbilityHand"]
