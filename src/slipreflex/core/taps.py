"""Taps: a run's messages handed, off the loop's thread, to whoever watches it live.

The real-time loop (:func:`slipreflex.rig.runtime.run_loop`) builds one message per topic
of :data:`slipreflex.files.recording.TOPICS` for its recording. A :class:`Tap` gets the same
messages: :meth:`Tap.put` only appends to a queue (it never blocks, never raises and
never does I/O), and the tap's own thread takes them from there and publishes them
(the Foxglove live view, :mod:`slipreflex.rig.live`; Lab Streaming Layer outlets,
:mod:`slipreflex.rig.lsl`). A tap that cannot keep up drops messages (counted in
:attr:`Tap.dropped`), never the loop's time. Between two messages the tap's thread
gives the interpreter lock back, so the loop waits at most one message's work for it.

Examples
--------
>>> class Printer(Tap):
...     def handle(self, topic, msg, log_time_ns): print(topic, msg["count"], log_time_ns)
>>> with Printer("demo") as tap:
...     tap.put("/chain/windows", {"seq": 7, "t": 0.021, "count": 2}, 21)
/chain/windows 2 21
"""

from __future__ import annotations

import collections
import threading
import time
from collections.abc import Iterable, Mapping
from typing import Any

from .errors import ParameterError

__all__ = ["Tap", "put_all", "close_all"]


class Tap:
    """A queue and a thread that publishes what the loop puts in it.

    Subclasses implement :meth:`handle` (and, if they hold resources, :meth:`shutdown`).

    Parameters
    ----------
    name : str
        Thread name and what messages name it.
    capacity : int
        Messages the queue holds before new ones are dropped (at 333 Hz a run puts
        about 2,000 messages per second).
    poll : float
        Seconds the thread sleeps when the queue is empty.

    Attributes
    ----------
    dropped : int
        Messages dropped because the queue was full.
    published : int
        Messages handled.
    error : BaseException or None
        What stopped the thread, if :meth:`handle` raised (later messages are dropped).

    Examples
    --------
    >>> class Count(Tap):
    ...     n = 0
    ...     def handle(self, topic, msg, log_time_ns): self.n += 1
    >>> tap = Count("count", capacity=2)
    >>> for k in range(3):
    ...     tap.put("/faults", {}, k)      # not started: the third does not fit
    >>> tap.dropped
    1
    >>> _ = tap.start(); tap.close(); tap.n, tap.published
    (2, 2)
    """

    def __init__(self, name: str, *, capacity: int = 1 << 16, poll: float = 0.005) -> None:
        if not (isinstance(capacity, int) and capacity > 0):
            raise ParameterError(f"{name}: capacity must be a whole number > 0, got {capacity!r}")
        if not 0 < poll <= 1:
            raise ParameterError(f"{name}: poll must be in (0, 1] s, got {poll!r}")
        self.name = name
        self.capacity = capacity
        self.poll = poll
        self.dropped = 0
        self.published = 0
        self.error: BaseException | None = None
        self._queue: collections.deque[tuple[str, Mapping[str, Any], int]] = collections.deque()
        self._closing = threading.Event()
        self._thread: threading.Thread | None = None
        self._shut = False

    # -- the loop's side -----------------------------------------------------------------
    def put(self, topic: str, msg: Mapping[str, Any], log_time_ns: int) -> None:
        """Queue one message (the loop's thread; O(1), no I/O, never raises).

        Parameters
        ----------
        topic : str
            A topic of :data:`slipreflex.files.recording.TOPICS`.
        msg : mapping
            The message, as recorded; not changed afterwards by the caller.
        log_time_ns : int
            Its log time (ns, wall clock), as recorded.
        """
        if len(self._queue) >= self.capacity:
            self.dropped += 1
            return
        self._queue.append((topic, msg, log_time_ns))

    # -- the tap's side ------------------------------------------------------------------
    def handle(self, topic: str, msg: Mapping[str, Any], log_time_ns: int) -> None:
        """Publish one message (the tap's thread). Subclasses implement it."""
        raise NotImplementedError

    def shutdown(self) -> None:
        """Release what the tap holds, after the last message (the closing thread)."""

    def start(self) -> Tap:
        """Start the thread (idempotent); returns self."""
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name=f"slipreflex-{self.name}", daemon=True)
            self._thread.start()
        return self

    def _run(self) -> None:
        q = self._queue
        while True:
            closing = self._closing.is_set()
            while q:
                topic, msg, ns = q.popleft()
                if self.error is None:
                    try:
                        self.handle(topic, msg, ns)
                        self.published += 1
                    except Exception as err:  # noqa: BLE001 - a viewer's failure never reaches the loop
                        self.error = err
                else:
                    self.dropped += 1
                time.sleep(0)  # give the interpreter lock back: the loop never waits for a batch
            if closing:
                return
            self._closing.wait(self.poll)

    def flush(self, timeout: float = 5.0) -> bool:
        """Wait until the queue is empty (True) or ``timeout`` seconds passed (False)."""
        deadline = time.monotonic() + timeout
        while self._queue and time.monotonic() < deadline:
            time.sleep(self.poll)
        return not self._queue

    def close(self) -> None:
        """Publish what is queued, stop the thread, then :meth:`shutdown` (idempotent)."""
        self._closing.set()
        if self._thread is not None:
            self._thread.join(timeout=10.0)
        elif self._queue:
            self._run()
        self._queue.clear()
        if not self._shut:
            self._shut = True
            self.shutdown()

    def __enter__(self) -> Tap:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()


def put_all(taps: Iterable[Tap], topic: str, msg: Mapping[str, Any], log_time_ns: int) -> None:
    """:meth:`Tap.put` on each tap.

    Examples
    --------
    >>> put_all((), "/faults", {}, 0)
    """
    for tap in taps:
        tap.put(topic, msg, log_time_ns)


def close_all(taps: Iterable[Tap]) -> list[str]:
    """Close every tap; one line per tap that dropped messages or failed (for the user).

    Examples
    --------
    >>> close_all(())
    []
    """
    notes = []
    for tap in taps:
        tap.close()
        if tap.error is not None:
            notes.append(f"{tap.name}: stopped publishing: {tap.error}")
        if tap.dropped:
            notes.append(f"{tap.name}: {tap.dropped} messages dropped (the publisher fell behind)")
    return notes
