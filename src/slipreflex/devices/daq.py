"""The DAQ board on a serial port: a :class:`~slipreflex.interfaces.SampleSource`.

:class:`SerialDaq` reads whatever bytes have arrived, feeds them to the one
parser of the firmware's wire protocol (:class:`slipreflex.devices.wire.FrameParser`,
which resynchronises after garbage and counts CRC failures, truncated frames
and sequence gaps) and returns the decoded samples. ``read(timeout)`` never
blocks longer than ``timeout``; a port that disappears is closed, reported
once as a :class:`~slipreflex.errors.DeviceError`, and reopened on later
reads.

Examples
--------
>>> import serial
>>> from slipreflex.devices import wire
>>> loop = serial.serial_for_url("loop://")
>>> daq = SerialDaq(loop)
>>> _ = loop.write(b"noise" + wire.encode_frame(seq=0, adc=100) + wire.encode_frame(seq=2, adc=101))
>>> [s.seq for s in daq.read(0.1)]
[0, 2]
>>> daq.stats.seq_gaps, daq.stats.garbage_bytes
(1, 5)
>>> daq.close(); loop.close()
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

from ..errors import DeviceError
from ..interfaces import DaqSample
from . import wire

__all__ = ["SerialDaq", "DaqStats"]


@dataclass(frozen=True, slots=True)
class DaqStats:
    """Counters of a :class:`SerialDaq`: the parser's plus the port's.

    Attributes
    ----------
    frames, crc_errors, truncated, invalid, garbage_bytes, resyncs, seq_gaps, frames_lost : int
        As in :class:`slipreflex.devices.wire.ParserStats`.
    disconnects : int
        Times the port failed and was closed.
    reconnects : int
        Times it was reopened after a failure.

    Examples
    --------
    >>> DaqStats().seq_gaps
    0
    """

    frames: int = 0
    crc_errors: int = 0
    truncated: int = 0
    invalid: int = 0
    garbage_bytes: int = 0
    resyncs: int = 0
    seq_gaps: int = 0
    frames_lost: int = 0
    disconnects: int = 0
    reconnects: int = 0

    def to_dict(self) -> dict[str, int]:
        """The counters as a plain dict.

        Examples
        --------
        >>> DaqStats(frames=3).to_dict()["frames"]
        3
        """
        return {name: getattr(self, name) for name in self.__slots__}  # type: ignore[attr-defined]


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

    Raises
    ------
    DeviceError
        The port cannot be opened at construction.

    Examples
    --------
    >>> daq = SerialDaq("loop://")
    >>> daq.read(0.0)
    []
    >>> daq.close()
    """

    def __init__(self, port: Any, *, reconnect_interval: float = 0.2) -> None:
        self._owns = isinstance(port, str)
        self.port_name: str = port if isinstance(port, str) else str(getattr(port, "port", None) or port)
        self.reconnect_interval = reconnect_interval
        self._parser = wire.FrameParser()
        self._timeout: float | None = None
        self._last_attempt = -math.inf
        self._disconnects = 0
        self._reconnects = 0
        self.last_arrival = math.nan
        self._ser: Any = self._open() if self._owns else port

    def _open(self) -> Any:
        import serial

        try:
            ser = serial.serial_for_url(self.port_name, baudrate=wire.BAUD, timeout=0,
                                        exclusive="://" not in self.port_name)
        except (serial.SerialException, OSError, ValueError) as err:
            raise DeviceError(f"{self.port_name}: cannot open DAQ port: {err}") from None
        self._timeout = 0.0
        return ser

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
        return self._ser is not None

    @property
    def stats(self) -> DaqStats:
        """Snapshot of the counters.

        Examples
        --------
        >>> SerialDaq("loop://").stats.frames
        0
        """
        p = self._parser.stats
        return DaqStats(frames=p.frames, crc_errors=p.crc_errors, truncated=p.truncated,
                        invalid=p.invalid, garbage_bytes=p.garbage_bytes, resyncs=p.resyncs,
                        seq_gaps=p.seq_gaps, frames_lost=p.frames_lost,
                        disconnects=self._disconnects, reconnects=self._reconnects)

    def _reopen(self, timeout: float) -> bool:
        if not self._owns:
            time.sleep(timeout)
            return False
        now = time.monotonic()
        wait = self._last_attempt + self.reconnect_interval - now
        if wait > 0:
            time.sleep(min(wait, timeout))
            return False
        self._last_attempt = now
        try:
            self._ser = self._open()
        except DeviceError:
            time.sleep(timeout)
            return False
        self._reconnects += 1
        return True

    def _fail(self, err: BaseException) -> DeviceError:
        ser, self._ser = self._ser, None
        self._disconnects += 1
        self._last_attempt = time.monotonic()
        self._parser.flush()  # a frame cut by the loss counts as truncated
        if self._owns and ser is not None:
            try:
                ser.close()
            except Exception:  # noqa: BLE001 - the port is already gone
                pass
        return DeviceError(f"{self.port_name}: DAQ port lost: {err}")

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
        >>> from slipreflex.devices import wire
        >>> loop = serial.serial_for_url("loop://")
        >>> daq = SerialDaq(loop)
        >>> frame = wire.encode_frame(seq=9, adc=1)
        >>> _ = loop.write(frame[:5]); daq.read(0.0)
        []
        >>> _ = loop.write(frame[5:]); [s.seq for s in daq.read(0.0)]
        [9]
        """
        import serial

        if self._ser is None and not self._reopen(timeout):
            return []
        ser = self._ser
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
            raise self._fail(err) from None
        if not data:
            return []
        self.last_arrival = time.perf_counter()
        return [f.to_sample() for f in self._parser.feed(data)]

    def close(self) -> None:
        """Close the port if this reader opened it.

        Examples
        --------
        >>> d = SerialDaq("loop://"); d.close(); d.close()
        """
        ser, self._ser = self._ser, None
        if ser is not None and self._owns:
            ser.close()

    def __enter__(self) -> "SerialDaq":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
