"""The CSV formats of slipreflex, defined once; every reader and writer uses them.

Input (what ``slipreflex detect`` reads and ``slipreflex export`` writes): a
header row with ``t`` (seconds) and ``x`` (slip-sensor volts), extra columns
ignored; or a single column of volts (with or without a header) and a sampling
rate given by the caller.

Outputs of ``slipreflex detect``: per sample ``t, x, threshold, event`` (x is the
filtered signal, threshold the one in force) and per window ``t_end, v, command``.

Examples
--------
>>> import tempfile, pathlib
>>> p = pathlib.Path(tempfile.mkdtemp()) / "rec.csv"
>>> write_columns(p, {"t": [0.0, 0.003], "x": [0.41, 0.42]})
>>> t, x = read_slip_csv(p)
>>> x.tolist()
[0.41, 0.42]
"""

from __future__ import annotations

import csv
import math
import os
from array import array
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import DataError
from ..core.validation import LIMITS
from .paths import new_file

__all__ = ["INPUT_COLUMNS", "SAMPLE_COLUMNS", "WINDOW_COLUMNS", "read_slip_csv", "write_columns",
           "read_preamble", "PREAMBLE_PREFIX", "Recording", "read_recording", "irregular_steps",
           "JITTER_TOLERANCE", "cell_float", "cell_bool", "finite_cell"]

#: A time step further than this fraction from the median step is a gap or jitter
#: (the chain assumes uniform sampling; a missing 3 ms sample is a 100 % step).
JITTER_TOLERANCE: float = 0.1

#: Lines before the column header that start with this are ``# key: value`` facts about the
#: file (``slipreflex export`` writes the run's p0 and chain parameters there; docs/runtime.md).
PREAMBLE_PREFIX: str = "#"

INPUT_COLUMNS: tuple[str, str] = ("t", "x")
SAMPLE_COLUMNS: tuple[str, ...] = ("t", "x", "threshold", "event")
WINDOW_COLUMNS: tuple[str, ...] = ("t_end", "v", "command")


def finite_cell(path: Path, line: int, column: str, cell: str) -> float:
    """One CSV cell as a finite float, or a ``DataError`` naming the file, line and column.

    The one check every CSV reader of the package applies to a numeric cell.

    Examples
    --------
    >>> from pathlib import Path
    >>> finite_cell(Path("a.csv"), 3, "x", "0.25")
    0.25
    >>> finite_cell(Path("a.csv"), 3, "x", "nan")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.DataError: a.csv, line 3: column 'x' is not finite: 'nan'
    """
    try:
        value = float(cell)
    except ValueError:
        raise DataError(f"{path}, line {line}: column '{column}' is not a number: {cell!r}") from None
    if not math.isfinite(value):
        raise DataError(f"{path}, line {line}: column '{column}' is not finite: {cell!r}")
    return value


@dataclass(frozen=True)
class Recording:
    """A slip-sensor recording read from a CSV file.

    Attributes
    ----------
    path : pathlib.Path
        The file.
    t, x : numpy.ndarray
        Times (s, strictly increasing) and volts.
    lines : numpy.ndarray
        The file's line number (1-based) of each sample, for messages.
    has_time : bool
        True if ``t`` came from a ``t`` column, False if from a given rate.
    preamble : dict of str to str
        The ``# key: value`` lines before the header (:func:`read_preamble`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "rec.csv"
    >>> _ = p.write_text("# p0: 147\\nt,x\\n0.0,0.41\\n0.003,0.42\\n")
    >>> rec = read_recording(p)
    >>> rec.lines.tolist(), rec.preamble, rec.has_time
    ([3, 4], {'p0': '147'}, True)
    """

    path: Path
    t: np.ndarray
    x: np.ndarray
    lines: np.ndarray
    has_time: bool
    preamble: dict[str, str] = field(default_factory=dict)

    def step_rate(self) -> float:
        """The sampling rate implied by the median time step (Hz).

        Examples
        --------
        >>> import numpy as np
        >>> rec = Recording(None, np.array([0.0, 0.001, 0.002]), np.zeros(3), np.arange(3), True)
        >>> round(rec.step_rate(), 6)
        1000.0
        """
        if self.t.size < 2:
            raise DataError(f"{self.path}: one sample gives no sampling rate; pass --fs")
        return float(1.0 / np.median(np.diff(self.t)))


def irregular_steps(t: np.ndarray, tolerance: float = JITTER_TOLERANCE) -> np.ndarray:
    """Indices ``k`` where ``t[k] - t[k-1]`` is more than ``tolerance`` from the median step.

    Parameters
    ----------
    t : numpy.ndarray
        Strictly increasing times.
    tolerance : float
        Allowed deviation, as a fraction of the median step.

    Returns
    -------
    numpy.ndarray of int
        Sample indices (into ``t``) that end an irregular step: gaps and jitter.

    Examples
    --------
    >>> irregular_steps(np.array([0.0, 0.003, 0.006, 0.012, 0.015, 0.0181])).tolist()
    [3]
    """
    t = np.asarray(t, dtype=float)
    if t.size < 3:
        return np.zeros(0, dtype=int)
    dt = np.diff(t)
    med = np.median(dt)
    return np.flatnonzero(np.abs(dt - med) > tolerance * med) + 1


def read_slip_csv(path: str | os.PathLike, fs: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Read a slip-sensor recording's times and volts (:func:`read_recording` has the rest).

    Parameters
    ----------
    path : path-like
        CSV file with a header naming ``t`` and ``x``, or a single column of volts.
    fs : float, optional
        Sampling rate (Hz) for a single-column file (times are k / fs). With a
        ``t`` column it is not needed.

    Returns
    -------
    t, x : numpy.ndarray
        Times (s, strictly increasing) and volts.

    Raises
    ------
    DataError
        Unreadable, empty, missing column, non-numeric or non-finite cell, or
        time not increasing; the message names the file and the line.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "one.csv"
    >>> _ = p.write_text("x\\n0.4\\n0.5\\n")
    >>> read_slip_csv(p, fs=100.0)[0].tolist()
    [0.0, 0.01]
    """
    rec = read_recording(path, fs=fs)
    return rec.t, rec.x


def read_recording(path: str | os.PathLike, fs: float | None = None) -> Recording:
    """Read a slip-sensor recording with its line numbers and preamble.

    Parameters
    ----------
    path : path-like
        CSV file with a header naming ``t`` and ``x``, or a single column of volts,
        after optional ``# key: value`` preamble lines.
    fs : float, optional
        Sampling rate (Hz) for a single-column file; ignored with a ``t`` column
        (the caller compares it with :meth:`Recording.step_rate`).

    Returns
    -------
    Recording

    Raises
    ------
    DataError
        As :func:`read_slip_csv`.

    Examples
    --------
    >>> read_recording("examples/slip_example.csv").x.size > 0
    True
    """


    path = Path(path)
    cap = int(LIMITS["csv_samples"].hi)
    preamble: dict[str, str] = {}
    header: list[str] | None = None
    first_line = 0
    has_header = False
    it: int | None = None
    ix = 0
    width = 0
    t, x, lines = array("d"), array("d"), array("q")
    for line_no, line in _lines(path):
        if header is None and not (t or x) and line.lstrip().startswith(PREAMBLE_PREFIX):
            if not lines and header is None:
                _preamble_line(path, line_no, line, preamble)
            continue
        try:
            row = [c.strip() for c in next(csv.reader([line]), [])]
        except csv.Error as err:  # a cell over the csv module's field limit, a stray NUL...
            raise DataError(f"{path}, line {line_no}: not a CSV row ({err})") from None
        if not any(row) or row[0].startswith(PREAMBLE_PREFIX):
            continue
        if header is None:
            header, first_line = row, line_no
            has_header = any(_is_text(c) for c in header)
            if has_header and "x" in header and "t" in header:
                it, ix = header.index("t"), header.index("x")
            elif len(header) == 1:
                ix = 0
            else:
                missing = [c for c in INPUT_COLUMNS if c not in header] if has_header else list(INPUT_COLUMNS)
                raise DataError(f"{path}, line {first_line}: missing column(s) {', '.join(missing)} "
                                f"(need a header with t and x, or a single column of volts)")
            if it is None and fs is None:
                raise DataError(f"{path}: single-column file needs a sampling rate (--fs)")
            width = len(header)
            if has_header:
                continue
        if len(row) < width:
            raise DataError(f"{path}, line {line_no}: expected {width} cells, got {len(row)}")
        if len(x) >= cap:
            raise DataError(f"{path}: more than {cap} samples, the most a recording may have "
                            f"(docs/runtime.md, Limits)")
        x.append(finite_cell(path, line_no, header[ix] if has_header else "x", row[ix]))
        if it is not None:
            tk = finite_cell(path, line_no, "t", row[it])
            if t and tk <= t[-1]:
                raise DataError(f"{path}, line {line_no}: time not increasing ({tk!r} after {t[-1]!r})")
            t.append(tk)
        lines.append(line_no)
    if header is None:
        raise DataError(f"{path}: file is empty")
    if not x:
        raise DataError(f"{path}: no samples after the header")
    xs = np.frombuffer(x, dtype=float).copy()
    ts = np.frombuffer(t, dtype=float).copy() if it is not None else np.arange(xs.size) / float(fs or 1.0)
    return Recording(path, ts, xs, np.frombuffer(lines, dtype=np.int64).astype(int), it is not None, preamble)


def _lines(path: Path):
    """``(line number, text)`` of a CSV, streamed: a line over ``LIMITS["csv_line_bytes"]``, a NUL
    byte or bytes that are not UTF-8 are one :class:`DataError` (a binary file, /dev/zero)."""

    limit = int(LIMITS["csv_line_bytes"].hi)
    line_no = 0
    try:
        # utf-8-sig: a byte order mark (as spreadsheet programs write) is read, not taken for a column name
        with path.open(newline="", encoding="utf-8-sig") as fh:
            while True:
                line = fh.readline(limit + 1)
                if not line:
                    return
                line_no += 1
                if len(line) > limit:
                    raise DataError(f"{path}, line {line_no}: longer than {limit} characters (not a CSV of "
                                    f"samples?)")
                if "\x00" in line:
                    raise DataError(f"{path}, line {line_no}: a NUL byte (a binary file?)")
                yield line_no, line
    except UnicodeDecodeError as err:
        raise DataError(f"{path}, line {line_no + 1}: not UTF-8 text (byte 0x{err.object[err.start]:02x})") from None
    except OSError as err:
        raise DataError(f"{path}: cannot read: {err.strerror or err}") from None


def _preamble_line(path: Path, line_no: int, line: str, out: dict[str, str]) -> None:
    key, sep, value = line.lstrip()[len(PREAMBLE_PREFIX):].partition(":")
    if not sep or not key.strip():
        raise DataError(f"{path}, line {line_no}: expected '# key: value', got {line.strip()!r}")
    out[key.strip()] = value.strip()


def _is_text(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return True
    return False


def read_preamble(path: str | os.PathLike) -> dict[str, str]:
    """The ``# key: value`` lines at the top of a CSV, as a dict (empty if none).

    Parameters
    ----------
    path : path-like

    Returns
    -------
    dict of str to str
        Keys and values stripped; values as written (JSON where the writer put JSON).

    Raises
    ------
    DataError
        Unreadable file, or a preamble line without ``key: value``; the
        message names the file and line.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "h.csv"
    >>> write_columns(p, {"t": [0.0], "x": [0.4]}, preamble={"p0": '{"middle": 147.0}'})
    >>> read_preamble(p)
    {'p0': '{"middle": 147.0}'}
    """
    path = Path(path)
    out: dict[str, str] = {}
    for line_no, line in _lines(path):
        if not line.lstrip().startswith(PREAMBLE_PREFIX):
            break
        _preamble_line(path, line_no, line, out)
    return out


def write_columns(path: str | os.PathLike, columns: Mapping[str, Sequence | np.ndarray], *,
                  preamble: Mapping[str, str] | None = None, replace: bool = True) -> None:
    """Write equal-length columns to a CSV atomically.

    The file appears under its name only once it is complete (written to a
    temporary file in the same folder, then renamed), so an interrupted write
    never leaves a file that looks complete.

    Parameters
    ----------
    path : path-like
        Destination.
    columns : mapping of str to sequence
        Column name to values; all the same length.
    preamble : mapping of str to str, optional
        Written first as ``# key: value`` lines (one line each; see :func:`read_preamble`).
    replace : bool
        Replace an earlier file of that name (a regular file only; a symlink is replaced,
        never followed); False refuses any existing name (:class:`FileExistsError`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "w.csv"
    >>> write_columns(p, {"v": [1, 2], "command": [10.0, 20.0]})
    >>> p.read_text().splitlines()
    ['v,command', '1,10.0', '2,20.0']
    """
    path = Path(path)
    names = list(columns)
    cols = [np.asarray(columns[n]) for n in names]
    if len({c.shape[0] for c in cols}) > 1:
        raise ValueError(f"columns of {path} differ in length: {[c.shape[0] for c in cols]}")

    with new_file(path, "w", replace=replace) as fh:
        for key, value in (preamble or {}).items():
            if "\n" in f"{key}{value}" or ":" in key:
                raise ValueError(f"preamble of {path}: key {key!r} or its value spans lines or has ':'")
            fh.write(f"{PREAMBLE_PREFIX} {key}: {value}\n")
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(names)
        w.writerows(zip(*(c.tolist() for c in cols)))


def cell_float(x: object, *, lenient: bool = False) -> float:
    """A results-table cell as a float: None and a blank cell (how NaN is written) are NaN.

    Parameters
    ----------
    x : object
        A cell as read from a CSV (str) or as a run produced it (number, None).
    lenient : bool
        True: a cell that is not a number is NaN too (for judging a table someone
        else wrote); False (default): it raises ``ValueError``.

    Returns
    -------
    float

    Examples
    --------
    >>> cell_float("12.5"), cell_float(""), cell_float(None)
    (12.5, nan, nan)
    >>> cell_float("n/a", lenient=True)
    nan
    """
    if x is None or (isinstance(x, str) and not x.strip()):
        return float("nan")
    try:
        return float(x)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        if lenient:
            return float("nan")
        raise


def cell_bool(x: object) -> bool:
    """A results-table cell as a truth value: "true"/"1" (any case) are True, NaN is False.

    Examples
    --------
    >>> cell_bool("True"), cell_bool("0"), cell_bool(1), cell_bool(float("nan"))
    (True, False, True, False)
    """
    if isinstance(x, str):
        return x.strip().lower() in ("true", "1")
    return bool(x) and not (isinstance(x, float) and math.isnan(x))
