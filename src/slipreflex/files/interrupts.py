"""Ctrl-C and SIGTERM that keep the finished work.

A long job run in worker processes stops like this: the workers ignore SIGINT (so a
Ctrl-C, which reaches the whole process group, does not print a traceback per worker),
the parent turns SIGTERM into the same :class:`KeyboardInterrupt` as Ctrl-C, cancels the
queued work, gives the running items a short grace to finish, ends the workers that are
still busy, and raises :class:`Interrupted` carrying what was finished.

Examples
--------
>>> import signal
>>> with sigterm_interrupts():
...     signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL
True
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor, wait
from typing import Any

__all__ = ["Interrupted", "sigterm_interrupts", "signals_ignored", "worker_signals", "stop_pool",
           "GRACE_S"]

#: How long running items may take to finish after an interrupt before their workers
#: are ended (s); with the cancelling and the writing this keeps a stop under two seconds.
GRACE_S: float = 0.5


class Interrupted(KeyboardInterrupt):
    """A job stopped by Ctrl-C or SIGTERM; ``partial`` holds what it finished.

    A :class:`KeyboardInterrupt`, so code that does not know it stops as before.

    Parameters
    ----------
    partial : object
        The job's result over the finished items (for ``run_reproduce`` a
        ``ReproduceResult`` whose ``trials_finished < trials_planned``).
    message : str
        For example ``"interrupted after 87 of 240 trials"``.

    Examples
    --------
    >>> err = Interrupted([1, 2], "interrupted after 2 of 5 trials")
    >>> isinstance(err, KeyboardInterrupt), err.partial, str(err)
    (True, [1, 2], 'interrupted after 2 of 5 trials')
    """

    def __init__(self, partial: Any, message: str) -> None:
        super().__init__(message)
        self.partial = partial


def _raise_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt(f"signal {signal.Signals(signum).name}")


@contextlib.contextmanager
def sigterm_interrupts() -> Iterator[None]:
    """Inside the block SIGTERM raises :class:`KeyboardInterrupt`, as Ctrl-C does.

    Outside the main thread (where handlers cannot be set) it does nothing.

    Examples
    --------
    >>> with sigterm_interrupts():
    ...     pass
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGTERM, _raise_interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


@contextlib.contextmanager
def signals_ignored() -> Iterator[None]:
    """Ignore SIGINT and SIGTERM inside the block: saving finished work is not interrupted.

    Examples
    --------
    >>> with signals_ignored():
    ...     signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    True
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = {s: signal.signal(s, signal.SIG_IGN) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def worker_signals() -> None:
    """Worker initializer: the parent handles Ctrl-C; a worker just gets ended.

    SIGINT is ignored, and SIGTERM is reset to its default (a forked worker inherits
    the parent's :func:`sigterm_interrupts` handler, which would print a traceback
    when the parent ends the worker).

    Examples
    --------
    >>> old = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    >>> worker_signals()
    >>> signal.getsignal(signal.SIGINT) is signal.SIG_IGN, signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
    (True, True)
    >>> for s, h in old.items(): _ = signal.signal(s, h)
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def stop_pool(ex: ProcessPoolExecutor, futures: list[Future], collect: Callable[[Future], None],
              grace_s: float = GRACE_S) -> None:
    """Cancel queued futures, let running ones finish for ``grace_s``, end the rest.

    ``collect`` is called with every future that finished successfully during the
    grace (the caller ignores ones it has already collected).

    Examples
    --------
    >>> from concurrent.futures import ProcessPoolExecutor
    >>> ex = ProcessPoolExecutor(1)
    >>> fs = [ex.submit(abs, -k) for k in range(3)]
    >>> got = []
    >>> stop_pool(ex, fs, lambda f: got.append(f.result()))
    >>> set(got) <= {0, 1, 2}
    True
    """
    with signals_ignored():
        for f in futures:
            f.cancel()
        running = [f for f in futures if not f.cancelled()]
        wait(running, timeout=grace_s)
        for f in running:
            if f.done() and not f.cancelled() and f.exception() is None:
                collect(f)
        busy = not all(f.done() for f in running)
        procs = list((getattr(ex, "_processes", None) or {}).values())
        ex.shutdown(wait=False, cancel_futures=True)
        if busy:
            # A trial cannot be told to stop: its worker is ended (the executor has no
            # public way to do it; _processes is stable since Python 3.2).
            for proc in procs:
                proc.terminate()
            for proc in procs:
                proc.join(timeout=grace_s)
