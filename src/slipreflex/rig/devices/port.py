"""One serial port that survives disappearing, shared by the DAQ reader and the i-Limb driver.

:class:`ReconnectingPort` wraps a pyserial port in the spirit of pyserial's
``SerialBase``: it opens a device path or URL with the settings given once,
turns every pyserial or OS error into a :class:`~slipreflex.core.errors.DeviceError`
naming the port, closes the port when it fails, and reopens it later (at most
every ``reconnect_interval`` seconds). A port object passed in already open
is used as it is and never closed or reopened (its owner keeps that right).

pyserial's ``open()`` discards whatever the kernel already received; on a
*re*-open that would throw away the frames that arrived while the port was
coming back, so device paths are reopened without that flush (the first open
keeps it: old bytes from before the run are not wanted).

Examples
--------
>>> port = ReconnectingPort("loop://", what="DAQ", baudrate=9600)
>>> _ = port.serial.write(b"hi"); port.serial.read(2)
b'hi'
>>> port.close(); port.connected
False
"""

from __future__ import annotations

import math
import os
import select
import time
from typing import Any

from ...core.errors import DeviceError

__all__ = ["ReconnectingPort"]


def _keep_input_class() -> type:
    """A pyserial Serial whose open() keeps the bytes the kernel already holds."""
    import serial  # deferred: heavy (serial)

    class KeepInputSerial(serial.Serial):  # type: ignore[misc, valid-type]
        _opening = False

        def open(self) -> None:
            self._opening = True
            try:
                super().open()
            finally:
                self._opening = False

        def _reset_input_buffer(self) -> None:
            if not self._opening:
                super()._reset_input_buffer()  # pyright: ignore[reportAttributeAccessIssue] (pyserial's, untyped)

    return KeepInputSerial


class ReconnectingPort:
    """A serial port that is closed when it fails and reopened on a later call.

    Parameters
    ----------
    port : str or serial.Serial
        Device path or pyserial URL (opened here), or an open port (used as is).
    what : str
        What is on the port ("DAQ", "i-Limb"), for messages.
    baudrate : int
    write_timeout : float, optional
        Seconds a write may block (pyserial's ``write_timeout``).
    reconnect_interval : float
        Minimum seconds between reopen attempts.

    Attributes
    ----------
    port_name : str
    serial : serial.Serial or None
        The open port, None while it is gone.
    disconnects, reconnects : int
        Failures that closed the port; successful reopens.

    Raises
    ------
    DeviceError
        The port cannot be opened at construction (the message names it).

    Examples
    --------
    >>> ReconnectingPort("/nonexistent/tty", what="DAQ", baudrate=115200)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.DeviceError: /nonexistent/tty: cannot open DAQ port: [Errno 2] could not open port ...
    """

    def __init__(self, port: Any, *, what: str, baudrate: int, write_timeout: float | None = None,
                 reconnect_interval: float = 0.2) -> None:
        self.what = what
        self.baudrate = baudrate
        self.write_timeout = write_timeout
        self.reconnect_interval = reconnect_interval
        self.owns = isinstance(port, str)
        self.port_name: str = port if isinstance(port, str) else str(getattr(port, "port", None) or port)
        self.disconnects = 0
        self.reconnects = 0
        self._last_attempt = -math.inf
        self.serial: Any = self._open(first=True) if self.owns else port

    def _open(self, first: bool = False) -> Any:
        import serial  # deferred: heavy (serial)

        name = self.port_name
        kw: dict[str, Any] = dict(baudrate=self.baudrate, timeout=0, write_timeout=self.write_timeout)
        try:
            if "://" in name:
                return serial.serial_for_url(name, **kw)
            cls = serial.Serial if first else _keep_input_class()
            return cls(name, exclusive=True, **kw)
        except (serial.SerialException, OSError, ValueError) as err:
            raise DeviceError(f"{name}: cannot open {self.what} port: {err}") from None

    @property
    def connected(self) -> bool:
        """True while the port is open.

        Examples
        --------
        >>> ReconnectingPort("loop://", what="DAQ", baudrate=9600).connected
        True
        """
        return self.serial is not None

    def ensure_open(self) -> bool:
        """Reopen a failed port if ``reconnect_interval`` has passed; True if the port is open.

        Examples
        --------
        >>> p = ReconnectingPort("loop://", what="DAQ", baudrate=9600, reconnect_interval=0.0)
        >>> _ = p.fail(OSError("gone")); p.ensure_open(), p.reconnects
        (True, 1)
        """
        if self.serial is not None:
            return True
        if not self.owns or time.monotonic() - self._last_attempt < self.reconnect_interval:
            return False
        self._last_attempt = time.monotonic()
        try:
            self.serial = self._open()
        except DeviceError:
            return False
        self.reconnects += 1
        return True

    def wait_before_retry(self) -> float:
        """Seconds until the next reopen attempt is allowed (0 if now).

        Examples
        --------
        >>> ReconnectingPort("loop://", what="DAQ", baudrate=9600).wait_before_retry()
        0.0
        """
        return max(0.0, self._last_attempt + self.reconnect_interval - time.monotonic())

    def fail(self, err: BaseException, doing: str = "lost") -> DeviceError:
        """Close the port after ``err``; return the error to raise (naming the port).

        Examples
        --------
        >>> p = ReconnectingPort("loop://", what="DAQ", baudrate=9600)
        >>> str(p.fail(OSError("EIO"))), p.connected, p.disconnects
        ('loop://: DAQ port lost: EIO', False, 1)
        """
        ser, self.serial = self.serial, None
        self.disconnects += 1
        self._last_attempt = time.monotonic()
        if ser is not None and self.owns:
            try:
                ser.close()
            except Exception:  # noqa: BLE001 - the port is already gone
                pass
        return DeviceError(f"{self.port_name}: {self.what} port {doing}: {err}")

    def write(self, data: bytes) -> None:
        """Write every byte of ``data``, waiting at most ``write_timeout`` for the port to drain.

        pyserial's POSIX ``write`` with a write timeout raises ``SerialTimeoutException``
        after a write that went out whole, whenever the timeout expired between its
        ``os.write`` and its check (pyserial issue #281): a thread descheduled for 10 ms on
        a loaded machine then reported a sent packet as a failed one. Here only bytes
        still unwritten at the deadline make a timeout. Ports without a file descriptor
        (``loop://``) and ports without a write timeout use pyserial's own ``write``.

        Raises
        ------
        serial.SerialTimeoutException
            Bytes left unwritten when ``write_timeout`` has passed.
        OSError, serial.SerialException
            From the port (the caller turns them into :meth:`fail`).

        Examples
        --------
        >>> p = ReconnectingPort("loop://", what="hand", baudrate=9600, write_timeout=0.01)
        >>> p.write(b"hi"); p.serial.read(2)
        b'hi'
        """

        import serial  # deferred: heavy (serial)

        ser = self.serial
        fd = getattr(ser, "fd", None)
        if not isinstance(fd, int) or not self.write_timeout:
            ser.write(data)
            return
        deadline = time.monotonic() + self.write_timeout
        left = memoryview(data)
        while left:
            try:
                left = left[os.write(fd, left):]
            except BlockingIOError:
                pass
            if left:
                wait = deadline - time.monotonic()
                if wait <= 0 or not select.select([], [fd], [], wait)[1]:
                    raise serial.SerialTimeoutException(
                        f"Write timeout ({len(left)} of {len(data)} bytes not written)")

    def close(self) -> None:
        """Close the port if it was opened here (idempotent); a port given open is only let go.

        Examples
        --------
        >>> p = ReconnectingPort("loop://", what="DAQ", baudrate=9600); p.close(); p.close()
        """
        ser, self.serial = self.serial, None
        if ser is not None and self.owns:
            ser.close()
