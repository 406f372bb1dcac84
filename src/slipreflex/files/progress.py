"""Progress of a long job: a live bar on a terminal, one plain line per tenth in a log.

A tqdm bar redraws itself with carriage returns, which a log file or a CI console
keeps as one enormous line. :class:`Progress` draws the bar only when its stream is a
terminal; anywhere else it prints one line at each 10 % (and at the end), each
with the time so far and an estimate of the time left.

Examples
--------
>>> import io
>>> log = io.StringIO()
>>> with Progress(20, desc="trials", unit="trial", file=log, clock=iter(range(100)).__next__) as p:
...     for _ in range(20):
...         p.update()
>>> print(log.getvalue(), end="")
trials: 2/20 (10 %), 1 s, about 9 s left
trials: 4/20 (20 %), 2 s, about 8 s left
trials: 6/20 (30 %), 3 s, about 7 s left
trials: 8/20 (40 %), 4 s, about 6 s left
trials: 10/20 (50 %), 5 s, about 5 s left
trials: 12/20 (60 %), 6 s, about 4 s left
trials: 14/20 (70 %), 7 s, about 3 s left
trials: 16/20 (80 %), 8 s, about 2 s left
trials: 18/20 (90 %), 9 s, about 1 s left
trials: 20/20 (100 %), 10 s
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import IO, Any

__all__ = ["Progress", "format_duration"]


def format_duration(seconds: float) -> str:
    """A duration for people: ``"42 s"``, ``"3.5 min"``, ``"2.1 h"``.

    Examples
    --------
    >>> [format_duration(s) for s in (0.4, 42, 210, 7560)]
    ['0.4 s', '42 s', '3.5 min', '2.1 h']
    """
    if seconds < 1:
        return f"{seconds:.1f} s"
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


class Progress:
    """Counts finished items of a job of known size and shows it.

    Parameters
    ----------
    total : int
        Items in the job.
    desc, unit : str
        What is counted (``"trials"``, ``"trial"``).
    file : file object, optional
        Where to write (default ``sys.stderr``).
    enabled : bool
        False shows nothing (``--no-progress``).
    tty : bool, optional
        Force the terminal (bar) or log (lines) form; default: ``file.isatty()``.
    clock : callable, optional
        Seconds now (default ``time.monotonic``); tests pass a fake one.

    Examples
    --------
    >>> import io
    >>> p = Progress(3, desc="trials", file=io.StringIO(), tty=False)
    >>> p.update(3); p.done
    3
    >>> p.close()
    """

    def __init__(self, total: int, *, desc: str = "", unit: str = "item", file: IO[str] | None = None,
                 enabled: bool = True, tty: bool | None = None,
                 clock: Callable[[], float] | None = None) -> None:
        self.total, self.desc, self.unit = int(total), desc, unit
        self.file = file if file is not None else sys.stderr
        self.done = 0
        self._clock = clock or time.monotonic
        self._t0 = self._clock()
        self._next_tenth = 1
        self._bar: Any = None
        self._enabled = bool(enabled) and self.total > 0
        if tty is None:
            isatty = getattr(self.file, "isatty", None)
            tty = bool(isatty and isatty())
        if self._enabled and tty:
            from tqdm import tqdm  # deferred: heavy (tqdm)
            self._bar = tqdm(total=self.total, file=self.file, desc=desc, unit=unit, dynamic_ncols=True)

    def update(self, n: int = 1) -> None:
        """Count ``n`` more finished items.

        Examples
        --------
        >>> import io
        >>> Progress(10, file=io.StringIO(), tty=False).update(2)
        """
        self.done += n
        if self._bar is not None:
            self._bar.update(n)
            return
        if not self._enabled:
            return
        while self._next_tenth <= 10 and self.done * 10 >= self._next_tenth * self.total:
            self._next_tenth += 1
            self._line()

    def _line(self) -> None:
        elapsed = self._clock() - self._t0
        text = (f"{self.desc}: {self.done}/{self.total} ({100 * self.done // self.total} %), "
                f"{format_duration(elapsed)}")
        if 0 < self.done < self.total:
            text += f", about {format_duration(elapsed * (self.total - self.done) / self.done)} left"
        print(text, file=self.file, flush=True)

    def close(self) -> None:
        """Finish the bar (a terminal) or do nothing (a log already has its lines).

        Examples
        --------
        >>> import io
        >>> Progress(1, file=io.StringIO(), tty=False).close()
        """
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
