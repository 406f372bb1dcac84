"""The DAQ board on a serial port: a :class:`~slipreflex.core.interfaces.SampleSource`.

:class:`SerialDaq` reads whatever bytes have arrived, feeds them to the one
parser of the firmware's wire protocol (:class:`slipreflex.rig.devices.wire.FrameParser`,
which resynchronises after garbage and counts CRC failures, truncated frames
and sequence gaps) and returns the decoded samples. ``read(timeout)`` never
blocks longer than ``timeout``; a port that disappears is closed, reported
once as a :class:`~slipreflex.core.errors.DeviceError`, and reopened on later
reads.

Examples
--------
:meth:`SerialDaq.read` reads a loopback port fed garbage, a sequence gap and a frame split
across two reads.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, fields
from typing import Any

from ...core.interfaces import DaqSample
from . import wire
from .port import ReconnectingPort

__all__ = ["SerialDaq", "DaqStats"]


@dataclass(frozen=True, slots=True)
class DaqStats:
    """Counters of a :class:`SerialDaq`: the parser's (one :class:`~slipreflex.rig.devices.wire.ParserStats`)
    plus the port's.

    The parser's counters read as attributes too (``stats.seq_gaps``).

    Attributes
    ----------
    parser : ParserStats
        Frames, CRC errors, truncated and invalid frames, garbage, resyncs,
        sequence gaps, lost frames, duplicates, late frames and sequence restarts.
    disconnects : int
        Times the port failed and was closed.
    reconnects : int
        Times it was reopened after a failure.

    Examples
    --------
    >>> DaqStats().seq_gaps, DaqStats(reconnects=2).to_dict()["reconnects"]
    (0, 2)
    """

    parser: wire.ParserStats = field(default_factory=wire.ParserStats)
    disconnects: int = 0
    reconnects: int = 0

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self.parser, name)

    def to_dict(self) -> dict[str, int]:
        """All counters as one flat dict (the parser's, then the port's).

        Examples
        --------
        >>> DaqStats().to_dict()["frames"]
        0
        """
        out = {f.name: getattr(self.parser, f.name) for f in fields(self.parser)}
        out.update(disconnects=self.disconnects, reconnects=self.reconnects)
        return out


class SerialDaq:
    """Read the DAQ board's frames from a serial port.

    Parameters
    ----------
    port : str or serial.Serial
        A device path or pyserial URL (opened here at ``wire.BAUD``), or an
        open port (not closed or reopened by this reader).
    reconnect_interval : float
        Minimum seconds between reopen attempts after the port failed.

    Attributes
    ----------
    last_arrival : float
        ``time.perf_counter()`` just after the bytes of the latest samples were
        read from the port (the samples' arrival time), or NaN.
    port_name : str
    last_frames : list of wire.Frame
        The decoded frames of the samples the latest non-empty ``read`` returned
        (version-2 frames carry the board's reflex output: ``slipreflex.methods.board.BoardSource``).

    Raises
    ------
    DeviceError
        The port cannot be opened at construction; the message gives the system's
        reason (no such device, no permission).

    Examples
    --------
    >>> daq = SerialDaq("loop://")
    >>> daq.port_name, daq.last_frames, daq.read(0.0)
    ('loop://', [], [])
    >>> daq.close()
    """

    def __init__(self, port: Any, *, reconnect_interval: float = 0.2) -> None:
        self._port = ReconnectingPort(port, what="DAQ", baudrate=wire.BAUD,
                                      reconnect_interval=reconnect_interval)
        self.port_name = self._port.port_name
        self._parser = wire.FrameParser()
        self._timeout: float | None = None  # set on the first read (a port given open may block)
        self.last_arrival = math.nan
        self.last_frames: list[wire.Frame] = []

    @property
    def connected(self) -> bool:
        """True while the port is open.

        Examples
        --------
        >>> d = SerialDaq("loop://"); d.connected
        True
        >>> d.close(); d.connected
        False
        """
        return self._port.connected

    @property
    def stats(self) -> DaqStats:
        """Snapshot of the counters.

        Examples
        --------
        >>> SerialDaq("loop://").stats.frames
        0
        """
        return DaqStats(self._parser.stats, self._port.disconnects, self._port.reconnects)

    def _reopen(self, timeout: float) -> bool:
        """Reopen a lost port; while it is gone, wait out ``timeout`` (read never spins)."""
        wait = self._port.wait_before_retry() if self._port.owns else timeout
        if wait > 0:
            time.sleep(min(wait, timeout))
            return False
        if self._port.ensure_open():
            self._timeout = 0.0
            return True
        time.sleep(timeout)
        return False

    def read(self, timeout: float) -> list[DaqSample]:
        """Return the samples that arrived, waiting at most ``timeout`` seconds for the first byte.

        Parameters
        ----------
        timeout : float
            Seconds (>= 0).

        Returns
        -------
        list of DaqSample
            Possibly empty.

        Raises
        ------
        DeviceError
            Once, when the port fails; later calls try to reopen it and return
            ``[]`` meanwhile.

        Examples
        --------
        >>> import serial
        >>> from slipreflex.rig.devices import wire
        >>> loop = serial.serial_for_url("loop://")
        >>> daq = SerialDaq(loop)
        >>> frame = wire.encode_frame(seq=9, adc=1)
        >>> _ = loop.write(b"noise" + wire.encode_frame(seq=7, adc=100) + frame[:5])
        >>> [s.seq for s in daq.read(0.0)]          # garbage skipped, half a frame kept
        [7]
        >>> _ = loop.write(frame[5:]); [s.seq for s in daq.read(0.0)]
        [9]
        >>> daq.stats.seq_gaps, daq.stats.garbage_bytes    # seq 8 missing; 5 bytes of noise
        (1, 5)
        >>> daq.close(); loop.close()
        """
        import serial  # deferred: heavy (serial)

        ser = self._port.serial
        if ser is None:
            if not self._reopen(timeout):
                return []
            ser = self._port.serial
        try:
            if timeout != self._timeout:
                ser.timeout = timeout
                self._timeout = timeout
            data = ser.read(ser.in_waiting or 1)
            if data:
                more = ser.in_waiting
                if more:
                    data += ser.read(more)
        except (serial.SerialException, OSError) as err:
            self._parser.flush()  # a frame cut by the loss counts as truncated
            raise self._port.fail(err) from None
        if not data:
            return []
        self.last_arrival = time.perf_counter()
        self.last_frames = self._parser.feed(data)
        return [f.to_sample() for f in self.last_frames]

    def drop_buffered(self) -> int:
        """Read and drop the frames the port holds now; the parser keeps its place and counts.

        ``run_loop`` calls this once just before its clock starts: what arrived
        while the run set up (the port opened, the chain warmed up, the safe
        start's STOP) is from before the run, like what pyserial's ``open()``
        flushes, and would otherwise be processed as a stale backlog. A frame
        cut at the end stays in the parser and completes on the next read.

        Returns
        -------
        int
            Frames dropped (0 while the port is gone; a failure shows on the next read).

        Examples
        --------
        >>> from serial import serial_for_url
        >>> from slipreflex.rig.devices.wire import encode_frame
        >>> loop = serial_for_url("loop://"); daq = SerialDaq(loop)
        >>> _ = loop.write(encode_frame(seq=3, adc=1) + encode_frame(seq=4, adc=1))
        >>> daq.drop_buffered(), daq.read(0.0), daq.stats.frames
        (2, [], 2)
        >>> _ = loop.write(encode_frame(seq=5, adc=1)); [s.seq for s in daq.read(0.0)]
        [5]
        >>> daq.stats.seq_gaps                         # dropped, not lost: no gap
        0
        >>> daq.close(); loop.close()
        """
        import serial  # deferred: heavy (serial)

        ser, dropped = self._port.serial, 0
        try:
            while ser is not None and (waiting := ser.in_waiting):
                dropped += len(self._parser.feed(ser.read(waiting)))
        except (serial.SerialException, OSError):
            pass  # the next read() reports it and reconnects
        return dropped

    def close(self) -> None:
        """Close the port if this reader opened it.

        Examples
        --------
        >>> d = SerialDaq("loop://"); d.close(); d.close()
        """
        self._port.close()

    def __enter__(self) -> SerialDaq:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
