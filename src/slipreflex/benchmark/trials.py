"""Recorded trials: the format in which real (or any) labelled slip data comes in.

One CSV file per trial, one folder per data set (docs/benchmark.md, "Bring your own data"):

* optional ``# key: value`` lines first (:func:`slipreflex.files.csvfiles.read_preamble`);
* a header row naming the columns: ``t`` (seconds, strictly increasing), ``slip``
  (0/1, the ground truth per sample), and every other column is one channel;
* ``# layout: RxC``, ``RxCxV`` or ``AxRxCxV`` says that the channels, in column order,
  fill ``A`` arrays of ``R`` x ``C`` taxels with ``V`` components each (row-major, the
  last dimension fastest); ``# components: x,y,z`` names the components (default
  ``c1..cV``) and ``# normal: z`` the one that is the normal force (default the last).
  Without a layout every channel is its own.
* ``# trial-label: slip`` or ``no-slip`` (instead of a ``slip`` column): the trial slips or
  not, with no onset (a data set of slip and touch trials); such a set is scored as
  classification. Files without the line keep the per-sample ``slip`` column.

Examples
--------
>>> import tempfile, pathlib
>>> p = pathlib.Path(tempfile.mkdtemp()) / "trial.csv"
>>> rows = "".join(f"{k / 10},{k},{2 * k},{int(k >= 6)}\\n" for k in range(8))
>>> _ = p.write_text("# layout: 1x2\\nt,a,b,slip\\n" + rows)
>>> tr = read_trial(p)
>>> tr.name, tr.layout.shape, tr.onset_t, tr.normal_frames().shape
('trial', (1, 1, 2, 1), 0.6, (8, 1, 2))
"""

from __future__ import annotations

import csv
import itertools
import os
import re
import stat
from array import array
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import DataError
from ..core.validation import LIMITS
from ..files.csvfiles import finite_cell, read_preamble

__all__ = ["Layout", "RecordedTrial", "read_trial", "read_folder", "TIME_COLUMN", "SLIP_COLUMN",
           "MIN_SAMPLES", "TRIAL_LABEL", "TRIAL_LABELS"]

TIME_COLUMN, SLIP_COLUMN = "t", "slip"
#: The preamble key of a trial-level label (a trial that slips or does not, no onset), and its values.
TRIAL_LABEL: str = "trial-label"
TRIAL_LABELS: dict[str, bool] = {"slip": True, "no-slip": False}
#: Fewest samples a trial may have (a threshold needs a stretch before the onset).
MIN_SAMPLES: int = 8

_DIMS = re.compile(r"^\s*\d+(\s*[x×]\s*\d+){1,3}\s*$")


@dataclass(frozen=True)
class Layout:
    """How a trial's channels form tactile arrays.

    Parameters
    ----------
    arrays, rows, cols, values : int
        ``A`` arrays of ``rows`` x ``cols`` taxels, ``values`` components per taxel.
    components : tuple of str
        Names of the components (``values`` of them).
    normal : int
        Index of the normal-force component.

    Examples
    --------
    >>> lay = Layout.parse("2x4x4x3", components="x,y,z", normal="z", channels=96, where="f.csv")
    >>> lay.shape, lay.normal, lay.taxels
    ((2, 4, 4, 3), 2, 32)
    """

    arrays: int
    rows: int
    cols: int
    values: int
    components: tuple[str, ...]
    normal: int

    @property
    def shape(self) -> tuple[int, int, int, int]:
        """``(arrays, rows, cols, values)``."""
        return (self.arrays, self.rows, self.cols, self.values)

    @property
    def taxels(self) -> int:
        """Taxels over all arrays."""
        return self.arrays * self.rows * self.cols

    @classmethod
    def parse(cls, text: str, *, components: str | None, normal: str | None, channels: int,
              where: str) -> Layout:
        """Read ``# layout`` (with ``# components`` and ``# normal``) and check it against the columns.

        Raises
        ------
        DataError
            A malformed layout, components that do not match it, an unknown normal
            component, or a layout whose size is not the number of channel columns.

        Examples
        --------
        >>> Layout.parse("4x4x3", components=None, normal=None, channels=47, where="f.csv")
        Traceback (most recent call last):
        ...
        slipreflex.core.errors.DataError: f.csv: layout 4x4x3 needs 48 channel columns, the file has 47
        """
        if not _DIMS.match(text):
            raise DataError(f"{where}: layout {text!r} is not RxC, RxCxV or AxRxCxV (positive integers)")
        dims = [int(d) for d in re.split(r"[x×]", text.replace(" ", ""))]
        if min(dims) < 1:
            raise DataError(f"{where}: layout {text!r} has a zero dimension")
        a, r, c, v = {2: lambda d: (1, *d, 1), 3: lambda d: (1, *d), 4: tuple}[len(dims)](dims)
        if a * r * c * v != channels:
            raise DataError(f"{where}: layout {text} needs {a * r * c * v} channel columns, "
                            f"the file has {channels}")
        names = tuple(s.strip() for s in components.split(",")) if components else \
            tuple(f"c{i + 1}" for i in range(v))
        if len(names) != v or not all(names):
            raise DataError(f"{where}: components {components!r} name {len(names)} components, "
                            f"layout {text} has {v} per taxel")
        if normal is None:
            k = v - 1
        elif normal.strip() in names:
            k = names.index(normal.strip())
        else:
            raise DataError(f"{where}: normal component {normal!r} is not one of the components "
                            f"({', '.join(names)})")
        return cls(a, r, c, v, names, k)


@dataclass(frozen=True)
class RecordedTrial:
    """One labelled trial read from its CSV file.

    Attributes
    ----------
    name : str
        The file's stem.
    path : pathlib.Path
    t : numpy.ndarray, shape (K,)
        Times (s), strictly increasing.
    channels : numpy.ndarray, shape (K, C)
        Channel values, in column order.
    channel_names : tuple of str
    slip : numpy.ndarray of int8, shape (K,)
        The ground truth per sample (1: slipping).
    layout : Layout or None
        The arrays the channels form, or None (every channel its own).
    preamble : dict of str to str
        The ``# key: value`` lines.
    trial_label : bool or None
        The ``# trial-label`` (True: slips), or None for a per-sample label.

    Examples
    --------
    >>> tr = RecordedTrial("x", Path("x.csv"), np.array([0.0, 0.5, 1.0]), np.zeros((3, 1)), ("a",),
    ...                    np.array([0, 0, 0], dtype=np.int8), None)
    >>> tr.fs, tr.onset_t, tr.duration
    (2.0, None, 1.0)
    """

    name: str
    path: Path
    t: np.ndarray
    channels: np.ndarray
    channel_names: tuple[str, ...]
    slip: np.ndarray
    layout: Layout | None
    preamble: dict[str, str] = field(default_factory=dict)
    trial_label: bool | None = None

    @property
    def fs(self) -> float:
        """Mean sampling rate (Hz): samples - 1 over the time span."""
        return float((len(self.t) - 1) / (self.t[-1] - self.t[0]))

    @property
    def duration(self) -> float:
        """Time span (s)."""
        return float(self.t[-1] - self.t[0])

    @property
    def slips(self) -> bool:
        """The trial has a labelled slip."""
        return bool(self.slip.any())

    @property
    def positive(self) -> bool:
        """The trial slips: its trial label, or a labelled slip sample."""
        return self.slips if self.trial_label is None else self.trial_label

    @property
    def onset_t(self) -> float | None:
        """Time of the first labelled slip sample, or None for a control."""
        on = np.flatnonzero(self.slip)
        return float(self.t[on[0]]) if on.size else None

    def normal_frames(self) -> np.ndarray:
        """The normal component of every taxel, arrays stacked: shape ``(K, A * rows, cols)``.

        Raises
        ------
        DataError
            When the trial has no layout.

        Examples
        --------
        >>> lay = Layout(2, 1, 2, 2, ("s", "n"), 1)
        >>> tr = RecordedTrial("x", Path("x.csv"), np.arange(2.0), np.arange(16.0).reshape(2, 8), tuple("abcdefgh"),
        ...                    np.zeros(2, np.int8), lay)
        >>> tr.normal_frames()[0].tolist()
        [[1.0, 3.0], [5.0, 7.0]]
        """
        lay = self.layout
        if lay is None:
            raise DataError(f"{self.path}: no '# layout' line: the channels form no tactile array")
        arr = self.channels.reshape(len(self.t), *lay.shape)[..., lay.normal]
        return arr.reshape(len(self.t), lay.arrays * lay.rows, lay.cols)

    def components(self, k: int) -> np.ndarray:
        """Component ``k`` of every taxel, shape ``(K, A, rows, cols)`` (needs a layout).

        Examples
        --------
        >>> lay = Layout(1, 1, 2, 2, ("s", "n"), 1)
        >>> tr = RecordedTrial("x", Path("x.csv"), np.arange(2.0), np.arange(8.0).reshape(2, 4), tuple("abcd"),
        ...                    np.zeros(2, np.int8), lay)
        >>> tr.components(0)[1].tolist()
        [[[4.0, 6.0]]]
        """
        if self.layout is None:
            raise DataError(f"{self.path}: no '# layout' line: the channels form no tactile array")
        return self.channels.reshape(len(self.t), *self.layout.shape)[..., k]


def read_trial(path: str | os.PathLike) -> RecordedTrial:
    """Read and check one trial file (see the module docstring for the format).

    The file is read as a stream under the limits of every CSV input (``LIMITS`` in
    :mod:`slipreflex.core.validation`, docs/runtime.md "Limits"): at most ``csv_samples`` rows,
    lines of at most ``csv_line_bytes``, a file of at most ``text_file_bytes``; a FIFO, a
    device or a folder named like a trial is refused before it is opened.

    Raises
    ------
    DataError
        One line naming the file (and line) for: a missing ``t`` or ``slip`` column, no
        channel column, a repeated column name, a cell that is not a finite number, a
        ``slip`` value other than 0/1, a time that does not increase, fewer than
        :data:`MIN_SAMPLES` samples, a layout that does not match the columns, a
        ``# trial-label`` other than slip/no-slip or beside a ``slip`` column, a file over a limit.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "bad.csv"
    >>> _ = p.write_text("time,x,slip\\n0,1,0\\n")
    >>> read_trial(p)
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.DataError: ...bad.csv: no 't' column (time in seconds); the columns are time, x, slip
    """
    path = Path(path)
    _check_regular(path)
    pre = read_preamble(path)
    trial_label = _trial_label(path, pre)
    head_line, head, cells, row_lines = _read_rows(path)
    if len(set(head)) != len(head):
        dup = sorted({h for h in head if head.count(h) > 1})
        raise DataError(f"{path}, line {head_line}: column {dup[0]!r} appears more than once")
    needed = ((TIME_COLUMN, "time in seconds"),) + (() if trial_label is not None else
                                                    ((SLIP_COLUMN, "0/1 ground truth per sample"),))
    for col, what in needed:
        if col not in head:
            raise DataError(f"{path}: no '{col}' column ({what}); the columns are {', '.join(head)}")
    if trial_label is not None and SLIP_COLUMN in head:
        raise DataError(f"{path}: both a '# {TRIAL_LABEL}' line and a '{SLIP_COLUMN}' column; give one")
    names = tuple(h for h in head if h not in (TIME_COLUMN, SLIP_COLUMN))
    if not names:
        raise DataError(f"{path}: no channel column besides 't' and 'slip'")
    if len(row_lines) < MIN_SAMPLES:
        raise DataError(f"{path}: {len(row_lines)} samples; a trial needs at least {MIN_SAMPLES}")
    data = np.frombuffer(cells, dtype=float).reshape(len(row_lines), len(head)).copy()
    t = data[:, head.index(TIME_COLUMN)]
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise DataError(f"{path}, line {row_lines[k]}: time does not increase (t = {t[k]:g} s after {t[k - 1]:g} s)")
    slip = data[:, head.index(SLIP_COLUMN)] if trial_label is None else np.zeros(len(t))
    odd = np.flatnonzero((slip != 0) & (slip != 1))
    if odd.size:
        k = int(odd[0])
        raise DataError(f"{path}, line {row_lines[k]}: slip must be 0 or 1, got {slip[k]:g}")
    idx = [head.index(n) for n in names]
    layout = None
    if "layout" in pre:
        layout = Layout.parse(pre["layout"], components=pre.get("components"), normal=pre.get("normal"),
                              channels=len(names), where=str(path))
    return RecordedTrial(path.stem, path, t, data[:, idx], names, slip.astype(np.int8), layout, pre, trial_label)


def _check_regular(path: Path) -> None:
    """Refuse what is not a regular file of at most ``text_file_bytes``, before opening it (a FIFO would block)."""
    try:
        st = path.stat()
    except FileNotFoundError:
        raise DataError(f"{path}: no such file") from None
    except OSError as err:
        raise DataError(f"{path}: cannot read: {err.strerror or err}") from None
    if not stat.S_ISREG(st.st_mode):
        raise DataError(f"{path}: not a regular file (a trial is a CSV file)")
    cap = int(LIMITS["text_file_bytes"].hi)
    if st.st_size > cap:
        raise DataError(f"{path}: {st.st_size} bytes, more than the {cap} a trial file may have "
                        "(docs/runtime.md, Limits)")


def _trial_label(path: Path, pre: dict[str, str]) -> bool | None:
    if TRIAL_LABEL not in pre:
        return None
    value = pre[TRIAL_LABEL].strip().lower()
    if value not in TRIAL_LABELS:
        raise DataError(f"{path}: '# {TRIAL_LABEL}: {pre[TRIAL_LABEL]}' must be one of {', '.join(TRIAL_LABELS)}")
    return TRIAL_LABELS[value]


def _read_rows(path: Path) -> tuple[int, list[str], array, list[int]]:
    """The header and every row's numbers, streamed under the CSV limits: (header line, header, cells, lines)."""
    cap_rows, cap_line = int(LIMITS["csv_samples"].hi), int(LIMITS["csv_line_bytes"].hi)
    head: list[str] | None = None
    head_line = 0
    cells: array = array("d")
    lines: list[int] = []
    try:
        with path.open(newline="", encoding="utf-8") as fh:
            for line_no in itertools.count(1):
                text = fh.readline(cap_line + 1)
                if not text:
                    break
                if len(text) > cap_line:
                    raise DataError(f"{path}, line {line_no}: longer than {cap_line} characters (docs/runtime.md, "
                                    "Limits)")
                row = next(csv.reader([text]), [])
                if not row or row[0].lstrip().startswith("#"):
                    continue
                if head is None:
                    head, head_line = [h.strip() for h in row], line_no
                    continue
                if len(row) != len(head):
                    raise DataError(f"{path}, line {line_no}: {len(row)} cells, the header has {len(head)}")
                if len(lines) >= cap_rows:
                    raise DataError(f"{path}: more than {cap_rows} samples, the most a trial may have "
                                    "(docs/runtime.md, Limits)")
                cells.extend(finite_cell(path, line_no, head[c], text) for c, text in enumerate(row))
                lines.append(line_no)
    except UnicodeDecodeError:
        raise DataError(f"{path}: not UTF-8 text") from None
    except OSError as err:
        raise DataError(f"{path}: cannot read: {getattr(err, 'strerror', None) or err}") from None
    if head is None:
        raise DataError(f"{path}: no header row")
    return head_line, head, cells, lines


def read_folder(folder: str | os.PathLike) -> list[RecordedTrial]:
    """Read every ``*.csv`` trial of a data-set folder, in name order, all checked before any is used.

    Raises
    ------
    DataError
        When the folder does not exist or holds no CSV file, more trials than ``LIMITS["trials"]``,
        any trial is malformed, or trial-level and per-sample labels are mixed.

    Examples
    --------
    >>> from slipreflex.benchmark import shipped_dataset
    >>> trials = read_folder(shipped_dataset())
    >>> len(trials), sum(tr.slips for tr in trials)
    (7, 3)
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise DataError(f"{folder}: no such folder (a data set is a folder of trial CSV files)")
    files = sorted(p for p in folder.glob("*.csv") if not p.name.startswith("."))
    if not files:
        raise DataError(f"{folder}: no *.csv trial files")
    cap = int(LIMITS["trials"].hi)
    if len(files) > cap:
        raise DataError(f"{folder}: {len(files)} trial files, more than the {cap} a data set may have "
                        "(docs/runtime.md, Limits)")
    trials = [read_trial(p) for p in files]
    kinds = {tr.trial_label is None for tr in trials}
    if len(kinds) > 1:
        odd = next(tr for tr in trials if tr.trial_label is not None)
        raise DataError(f"{odd.path}: a '# {TRIAL_LABEL}' trial in a folder of per-sample 'slip' labels; "
                        "a data set uses one kind of label")
    return trials
