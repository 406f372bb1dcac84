"""Replay: a recording's chain re-run offline over its recorded samples, compared with what it recorded.

A run recording stores the chain's parameters (or, for ``run --board-reflex``,
the board's) in its metadata; :func:`replay` rebuilds the chain (or the board's
Python twin, :class:`slipreflex.methods.board.BoardReflex`) from them, feeds it every
recorded sample and compares its events and commands with the recorded ones.
It sits above the recording format, which imports nothing of the chain or the
board.

Examples
--------
>>> from slipreflex.rig.replay import ReplayResult
>>> ReplayResult(1, [], [], [], [], True).identical
True
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any

from ..core.errors import DataError
from ..files.recording import METADATA_NAME, Recording, read_recording
from ..methods.board import BoardReflex, board_params_from_json
from ..methods.chain import ReflexParams, SlipReflex

__all__ = ["chain_params_of", "ReplayResult", "replay"]


def chain_params_of(rec: Recording):
    """The :class:`~slipreflex.methods.chain.ReflexParams` stored in a recording's metadata.

    Parameters
    ----------
    rec : Recording

    Returns
    -------
    ReflexParams

    Raises
    ------
    DataError
        The metadata is missing or malformed.

    Examples
    --------
    >>> import json
    >>> from slipreflex.methods.chain import ReflexParams
    >>> meta = {METADATA_NAME: {"reflex_params": json.dumps(ReflexParams(dath=True).to_dict())}}
    >>> chain_params_of(Recording("r.mcap", metadata=meta)).dath
    True
    """

    raw = rec.metadata.get(METADATA_NAME, {}).get("reflex_params")
    if raw is None and rec.bad_metadata:
        raise DataError(f"{rec.path}: damaged metadata: record(s) {', '.join(map(repr, rec.bad_metadata))} "
                        f"fail their checksum; the chain parameters cannot be trusted (nothing to replay)")
    if raw is None and not rec.complete:
        where = f"at byte {rec.cut_at}" if rec.cut_at is not None else "before its parameters"
        raise DataError(f"{rec.path}: cut short {where}, before the chain parameters were written "
                        f"(nothing to replay)")
    if raw is None:
        raise DataError(f"{rec.path}: no chain parameters in the metadata record {METADATA_NAME!r} "
                        f"(not a slipreflex run recording?)")
    try:
        return ReflexParams.from_dict(json.loads(raw))
    except (ValueError, TypeError) as err:
        raise DataError(f"{rec.path}: bad chain parameters in the metadata: {err}") from None


@dataclass
class ReplayResult:
    """Outcome of :func:`replay`: the recorded and the re-computed events and commands.

    Events are ``(seq, t)`` of the spiking samples; commands ``(seq, t, target)``.

    Attributes
    ----------
    samples : int
    recorded_events, replayed_events : list of tuple
    recorded_commands, replayed_commands : list of tuple
    complete : bool
        Whether the recording was complete (see :attr:`Recording.complete`) and undamaged.
    gaps : str
        What the recording misses (:meth:`Recording.gaps`), "" if nothing.
    board_events, board_commands : list of tuple or None
        For a ``run --board-reflex`` recording: the spikes and window commands the
        board itself sent (``/board/state``), which the replayed twin must match too.

    Examples
    --------
    >>> r = ReplayResult(3, [(1, 0.003)], [(1, 0.003)], [], [], True)
    >>> r.identical
    True
    """

    samples: int
    recorded_events: list[tuple]
    replayed_events: list[tuple]
    recorded_commands: list[tuple]
    replayed_commands: list[tuple]
    complete: bool
    gaps: str = ""
    board_events: list[tuple] | None = None
    board_commands: list[tuple] | None = None

    def _pairs(self) -> list[tuple[str, list, list]]:
        out = [("events", self.recorded_events, self.replayed_events),
               ("commands", self.recorded_commands, self.replayed_commands)]
        if self.board_events is not None:
            out += [("board events", self.board_events, self.replayed_events),
                    ("board commands", self.board_commands or [], self.replayed_commands)]
        return out

    @property
    def identical(self) -> bool:
        """True if replay reproduced the recorded events and commands exactly.

        For a recording cut short, the recorded lists must be a prefix of the
        replayed ones (the crash may have cut derived messages of the last
        samples).

        Examples
        --------
        >>> ReplayResult(1, [], [(0, 0.0)], [], [], complete=False).identical
        True
        """
        if self.complete:
            return all(a == b for _, a, b in self._pairs())
        return all(b[:len(a)] == a for _, a, b in self._pairs())

    def summary(self) -> str:
        """One line per stream: counts and whether they match.

        Examples
        --------
        >>> print(ReplayResult(1, [], [], [], [], True).summary())
        samples 1
        events: recorded 0, replayed 0 - identical
        commands: recorded 0, replayed 0 - identical
        """
        def line(name: str, a: list, b: list) -> str:
            same = a == b if self.complete else b[:len(a)] == a
            if same:
                verdict = "identical"
            else:
                k = next((i for i, (x, y) in enumerate(zip(a, b)) if x != y), min(len(a), len(b)))
                verdict = (f"DIFFERENT from #{k}: recorded {a[k] if k < len(a) else None}, "
                           f"replayed {b[k] if k < len(b) else None}")
            return f"{name}: recorded {len(a)}, replayed {len(b)} - {verdict}"
        return "\n".join([f"samples {self.samples}" + ("" if self.complete else
                                                      " (recording cut short or damaged: checked up to the first gap)")]
                         + [line(name, a, b) for name, a, b in self._pairs()])


def replay(path: str | os.PathLike | Recording) -> ReplayResult:
    """Re-run the recorded chain offline over the recorded samples.

    A fresh :class:`~slipreflex.methods.chain.SlipReflex` built from the parameters in
    the metadata gets every recorded sample, in order, with the slip-finger
    position the loop gave it; its events and commands are compared with
    the recorded ones. A ``run --board-reflex`` recording (metadata
    ``board_params``) replays its Python twin (:class:`slipreflex.methods.board.BoardReflex`)
    and compares it with the board's own recorded output too.

    Parameters
    ----------
    path : path-like or Recording

    Returns
    -------
    ReplayResult

    Raises
    ------
    DataError
        Not a slipreflex run recording.

    Examples
    --------
    >>> import io, json, tempfile, os
    >>> from slipreflex.methods.chain import ReflexParams
    >>> from slipreflex.files.recording import Recorder
    >>> path = os.path.join(tempfile.mkdtemp(), "r.mcap")
    >>> meta = {METADATA_NAME: {"reflex_params": json.dumps(ReflexParams(p0=100.0).to_dict())}}
    >>> with Recorder(path, metadata=meta) as rec:
    ...     for k in range(16):
    ...         _ = rec.write("/daq/samples", {"seq": k, "t": k * 0.003, "slip_volts": 0.4,
    ...                       "flow_pulses": 0, "arrival": 0.0, "position": None}, k)
    ...     _ = rec.write("/hand/commands", {"seq": 15, "t": 15 * 0.003, "target": 100.0,
    ...                   "fingers": ["middle"], "sent": True, "latency": 1e-4}, 16)
    >>> replay(path).identical
    True
    """

    rec = path if isinstance(path, Recording) else read_recording(path)
    board_params = rec.metadata.get(METADATA_NAME, {}).get("board_params")
    if board_params is not None:

        reflex: Any = BoardReflex(board_params_from_json(board_params, rec.path))
    else:
        reflex = SlipReflex.from_params(chain_params_of(rec))
    upto = rec.before_damage or {}
    samples = rec.topic("/daq/samples")[:upto.get("/daq/samples", 0)]  # exact up to the first damage
    if not samples:
        raise DataError(f"{rec.path}: no samples before {'the first damaged chunk' if rec.damaged else 'its end'}"
                        f": nothing to replay")
    events: list[tuple] = []
    commands: list[tuple] = []
    for s in samples:
        cmd = reflex.step(s["slip_volts"], s.get("position"))
        if reflex.last_event:
            events.append((s["seq"], s["t"]))
        if cmd is not None:
            commands.append((s["seq"], s["t"], float(cmd)))
    return ReplayResult(
        samples=len(samples),
        recorded_events=[(m["seq"], m["t"]) for m in rec.topic("/chain/events")[:upto.get("/chain/events", 0)]],
        replayed_events=events,
        recorded_commands=[(m["seq"], m["t"], float(m["target"]))
                           for m in rec.topic("/hand/commands")[:upto.get("/hand/commands", 0)]],
        replayed_commands=commands, complete=rec.complete and not rec.damaged, gaps=rec.gaps(),
        **(_board_outputs(rec, upto.get("/board/state", 0)) if board_params is not None else {}))


def _board_outputs(rec: Recording, upto: int) -> dict[str, list[tuple]]:
    board = rec.topic("/board/state")[:upto]
    return {"board_events": [(m["seq"], m["t"]) for m in board if m["spike"]],
            "board_commands": [(m["seq"], m["t"], float(m["command"])) for m in board if m["window"]]}
