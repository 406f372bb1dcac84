"""The board's chain on the host: the reflex behind the loop's protocol, its checked variant, the board as a source.

Re-exported by :mod:`slipreflex.methods.board`.

Examples
--------
>>> BoardReflex(BoardParams.from_chain()).name
'fixed-board'
"""

from __future__ import annotations

import csv
import math
from collections import deque
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ...core import hardware as hw
from ...core.errors import DataError
from ...files.csvfiles import write_columns
from .. import Detections, MethodContext
from .fixed import ADC_MAX, SIG_Q, BoardChain, BoardParams, adc_counts

if TYPE_CHECKING:
    from ...core.interfaces import InputKind

__all__ = [
    "BoardReflex", "board_detections", "read_adc_csv", "write_board_outputs", "CheckedBoardReflex", "BoardSource",
    "build_board_method", "board_method_detections"
]


class BoardReflex:
    """The board's chain behind the :class:`~slipreflex.core.interfaces.Reflex` protocol.

    Takes slip-sensor volts like the float :class:`~slipreflex.SlipReflex`,
    quantises them as the board's ADC does (:func:`adc_counts`) and runs
    :class:`BoardChain`; a measured position is rounded half up to a whole position.
    Named ``"dath-board"`` or ``"fixed-board"``.

    Parameters
    ----------
    params : BoardParams, optional
        Or keywords for :meth:`BoardParams.from_chain`.

    Examples
    --------
    >>> r = BoardReflex(dath=True, p0=100)
    >>> r.name, r.input_kind, round(r.fs, 2)
    ('dath-board', 'slip', 333.33)
    >>> [r.step(1.5) for _ in range(16)][-1]
    100.0
    """

    input_kind: InputKind = "slip"

    def __init__(self, params: BoardParams | None = None, *, fs: float = hw.DAQ_FS,
                 **kwargs) -> None:
        if params is not None and kwargs:
            raise TypeError("give either params or keyword parameters, not both")
        self.fs = float(fs)
        self.params = params if params is not None else BoardParams.from_chain(fs=fs, **kwargs)
        self.chain = BoardChain(self.params)

    @property
    def name(self) -> str:
        """``"dath-board"`` or ``"fixed-board"``."""
        return "dath-board" if self.params.dath else "fixed-board"

    def reset(self) -> None:
        """Restore the initial state."""
        self.chain.reset()

    @property
    def last_event(self) -> bool:
        """The last sample was a spike (the :class:`~slipreflex.core.interfaces.Reflex` diagnostics)."""
        return bool(self.chain.event)

    @property
    def last_filtered(self) -> float:
        """The filtered sample in volts (NaN on a fault sample)."""
        return math.nan if self.chain.fault else self.chain.x * hw.ADC_LSB / (1 << SIG_Q)

    @property
    def last_threshold(self) -> float:
        """The encoder threshold in force, in volts."""
        return self.chain.theta * hw.ADC_LSB / (1 << SIG_Q)

    @property
    def last_count(self) -> int | None:
        """The window's spike count if the last sample completed a window, else None."""
        return int(self.chain.v) if self.chain.window else None

    def step(self, sample: float, position: float | None = None) -> float | None:
        """One sample in volts; the new command when a window completes, else None."""
        pos = None if position is None else min(max(math.floor(float(position) + 0.5), -32768), 32767)
        volts = float(sample)
        # A NaN or inf reading is a fault, like a reading outside 0..1023 on the board.
        adc = adc_counts(volts) if math.isfinite(volts) else 0xFFFF
        if self.chain.step(adc, pos):
            return float(self.chain.command)
        return None


def board_detections(reflex: BoardReflex, volts) -> tuple[np.ndarray, np.ndarray]:
    """The filtered trace (volts) and spikes of a board reflex over a whole trial's volts.

    NaN or inf volts are faults, as in :meth:`BoardReflex.step`.

    Returns
    -------
    x : numpy.ndarray of float
        Filtered samples converted back to volts (Q16 counts x ADC_LSB / 2**16).
    events : numpy.ndarray of bool

    Examples
    --------
    >>> x, ev = board_detections(BoardReflex(), [1.0] * 4 + [1.2] * 8)
    >>> ev.nonzero()[0].tolist(), round(float(x[0]), 4)
    ([6, 7, 8, 9, 10, 11], 0.9961)
    """
    chain = BoardChain(reflex.params)
    v = np.asarray(volts, dtype=float)
    x = np.empty(v.size)
    events = np.zeros(v.size, dtype=bool)
    for i, volt in enumerate(v.tolist()):
        chain.step(adc_counts(volt) if math.isfinite(volt) else 0xFFFF)
        x[i], events[i] = chain.x * hw.ADC_LSB / (1 << SIG_Q), chain.event
    return x, events


def read_adc_csv(path) -> np.ndarray:
    """Read a CSV of ADC counts: a header with a column ``adc``, integers 0..1023.

    Other columns are ignored; ``#`` lines before the header are skipped.

    Raises
    ------
    DataError
        Unreadable file, no ``adc`` column, or a cell that is not a count; the
        message names the file and the line.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "adc.csv"
    >>> _ = p.write_text("adc\\n300\\n301\\n")
    >>> read_adc_csv(p).tolist()
    [300, 301]
    """

    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:  # a byte order mark is not a column name
            rows = [(i + 1, [c.strip() for c in row]) for i, row in enumerate(csv.reader(fh))
                    if any(c.strip() for c in row) and not row[0].lstrip().startswith("#")]
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise DataError(f"{path}: cannot read: {getattr(err, 'strerror', None) or err}") from None
    if not rows or "adc" not in rows[0][1]:
        raise DataError(f"{path}, line {rows[0][0] if rows else 1}: no column 'adc' "
                        "(need a header naming adc, one ADC count 0..1023 per row)")
    col = rows[0][1].index("adc")
    out = np.empty(len(rows) - 1, dtype=np.int64)
    for k, (line, row) in enumerate(rows[1:]):
        cell = row[col] if col < len(row) else ""
        if not cell.isdigit() or int(cell) > ADC_MAX:
            raise DataError(f"{path}, line {line}: column 'adc' is not a count 0..{ADC_MAX}: {cell!r}")
        out[k] = int(cell)
    return out


def write_board_outputs(prefix, events, counts, commands) -> tuple[Any, Any]:
    """Write PREFIX.samples.csv (``sample, event``) and PREFIX.windows.csv
    (``window, v, command``): the board's outputs, as the simavr runner and
    ``slipreflex detect --board`` write them.

    Returns
    -------
    (Path, Path)
        The two files written.

    Examples
    --------
    >>> from slipreflex.methods.board import run_board_chain
    >>> import tempfile, pathlib
    >>> prefix = pathlib.Path(tempfile.mkdtemp()) / "run"
    >>> res = run_board_chain([300] * 16)
    >>> s, w = write_board_outputs(prefix, res.events, res.counts, res.commands)
    >>> w.read_text().splitlines()
    ['window,v,command', '0,0,0']
    """


    events = np.asarray(events, dtype=np.int64)
    counts = np.asarray(counts, dtype=np.int64)
    samples_path, windows_path = Path(f"{prefix}.samples.csv"), Path(f"{prefix}.windows.csv")
    write_columns(samples_path, {"sample": np.arange(events.size), "event": events}, replace=False)
    write_columns(windows_path, {"window": np.arange(counts.size), "v": counts,
                                 "command": np.asarray(commands, dtype=np.int64)}, replace=False)
    return samples_path, windows_path


class CheckedBoardReflex(BoardReflex):
    """The twin of a board that runs the reflex itself, checking it on every sample.

    ``slipreflex run --board-reflex`` reads a board built with the reflex on board
    (version-2 frames: docs/wire-protocol.md) through a :class:`BoardSource`, which
    hands this reflex each sample's frame. :meth:`step` runs the twin on the sample and
    compares its filtered value, spike, fault flag, window, count and command with the
    board's. The command it returns is the twin's, equal to the board's while they agree.

    Attributes
    ----------
    last_board : dict or None
        The board's output for the last sample (``spike, window, fault, hand, v,
        command, x``) and ``match`` (whether the twin agreed).
    last_mismatch : str or None
        Set on the sample where board and twin start to disagree (one message per
        episode, naming the seq and the fields), else None.
    checked, mismatches : int
        Samples compared, and those that disagreed.

    Examples
    --------
    >>> from slipreflex.rig.devices import wire
    >>> twin = CheckedBoardReflex(BoardParams.firmware(p0=0))
    >>> good = wire.ReflexFields(0, 0, 0, 300 << 16)
    >>> twin.take_frames([wire.decode_frame(wire.encode_frame(seq=0, adc=300, reflex=good))])
    >>> twin.step(300 * hw.ADC_LSB), twin.last_mismatch, twin.last_board["match"]
    (None, None, True)
    >>> bad = wire.ReflexFields(wire.REFLEX_SPIKE, 0, 0, 300 << 16)
    >>> twin.take_frames([wire.decode_frame(wire.encode_frame(seq=1, adc=300, reflex=bad))])
    >>> _ = twin.step(300 * hw.ADC_LSB); twin.last_mismatch
    'seq 1: the board says spike=True, the twin spike=False'
    """

    def __init__(self, params: BoardParams | None = None, **kwargs) -> None:
        super().__init__(params, **kwargs)

        self._frames: Any = deque()
        self._reset_check()

    def _reset_check(self) -> None:
        self._frames.clear()
        self.last_board: dict[str, Any] | None = None
        self.last_mismatch: str | None = None
        self.checked = self.mismatches = 0
        self._bad = False

    def reset(self) -> None:
        """Restore the initial state and forget pending frames and counters."""
        super().reset()
        self._reset_check()

    def take_frames(self, frames) -> None:
        """Queue the board's frames of the samples :meth:`step` will get next, in order."""
        self._frames.extend(frames)

    def _disagreement(self, frame) -> str | None:
        if frame is None:
            return "a sample came without its board frame (read the board through BoardSource)"
        r = frame.reflex
        if r is None:
            return (f"seq {frame.seq}: a version-1 frame: this board does not run the reflex "
                    "(flash daq-reflex or hand2560, docs/firmware.md)")
        if self.checked == 0 and frame.seq != 0:
            return (f"the board was running before the host connected (first seq {frame.seq}, not 0): "
                    "its chain state is unknown; reset the board")
        c = self.chain
        pairs = (("x", r.x, c.x), ("spike", r.spike, c.event), ("fault", r.fault, c.fault),
                 ("window", r.window, c.window), ("v", r.v, c.v), ("command", r.command, c.command))
        diff = [f"{k}={b}" for k, b, t in pairs if b != t]
        if not diff:
            return None
        twin = [f"{k}={t}" for k, b, t in pairs if b != t]
        return f"seq {frame.seq}: the board says {', '.join(diff)}, the twin {', '.join(twin)}"

    def step(self, sample: float, position: float | None = None) -> float | None:
        """Run the twin on one sample and compare it with the board's frame for it."""
        frame = self._frames.popleft() if self._frames else None
        cmd = super().step(sample, position)
        problem = self._disagreement(frame)
        self.checked += 1
        self.mismatches += problem is not None
        self.last_mismatch = problem if problem is not None and not self._bad else None
        self._bad = problem is not None
        r = frame.reflex if frame is not None else None
        self.last_board = None if r is None else {
            "spike": r.spike, "window": r.window, "fault": r.fault, "hand": r.hand, "v": r.v,
            "command": r.command, "x": r.x, "match": problem is None}
        return cmd


class BoardSource:
    """A :class:`~slipreflex.rig.devices.daq.SerialDaq` that hands each sample's frame to a
    :class:`CheckedBoardReflex` (everything else is the reader's: stats, arrival times).

    Examples
    --------
    >>> import serial
    >>> from slipreflex.rig.devices import wire
    >>> from slipreflex.rig.devices.daq import SerialDaq
    >>> loop = serial.serial_for_url("loop://")
    >>> twin = CheckedBoardReflex(BoardParams.firmware())
    >>> src = BoardSource(SerialDaq(loop), twin)
    >>> _ = loop.write(wire.encode_frame(seq=0, adc=300, reflex=wire.ReflexFields(0, 0, 0, 300 << 16)))
    >>> [twin.step(s.slip_volts) for s in src.read(0.1)], twin.mismatches
    ([None], 0)
    >>> src.close(); loop.close()
    """

    def __init__(self, daq: Any, reflex: CheckedBoardReflex) -> None:
        self.daq, self.reflex = daq, reflex

    def read(self, timeout: float) -> list:
        """The reader's samples; their frames go to the reflex first."""
        samples = self.daq.read(timeout)
        if samples:
            self.reflex.take_frames(self.daq.last_frames)
        return samples

    def drop_buffered(self) -> int:
        """Drop nothing: the twin must see every frame from the board's seq 0 (``run_loop``
        calls this before its clock starts; the reader's own would bypass the twin)."""
        return 0

    def close(self) -> None:
        """Close the reader."""
        self.daq.close()

    def __getattr__(self, name: str) -> Any:
        return getattr(self.daq, name)


# --- the registry's board methods (slipreflex.methods names these by entry point) ------------

def build_board_method(dath: bool, p0: float, context: MethodContext, **params: Any) -> BoardReflex:
    """The registry's ``dath-board`` / ``fixed-board``: a :class:`BoardReflex` at the rounded ``p0``.

    Examples
    --------
    >>> build_board_method(True, 99.6, MethodContext()).params.p0
    100
    """
    return BoardReflex(**{"dath": dath, **params, "p0": int(np.floor(p0 + 0.5))})


def board_method_detections(reflex: BoardReflex, volts: np.ndarray) -> Detections:
    """What a trial figure draws for a board method: its Q16 low-pass and its spikes.

    Examples
    --------
    >>> board_method_detections(build_board_method(True, 100.0, MethodContext()), np.full(64, 0.4)).event_label
    'events (spikes)'
    """
    x, events = board_detections(reflex, volts)
    return Detections(x, "slip sensor on the board, Q16 low-pass (V)", events, "events (spikes)")
