"""The loop's side of the recorder and the live taps: every message the loop writes, never raising.

Examples
--------
>>> from slipreflex.core.interfaces import TactileSample
>>> tactile_message(TactileSample(0, 0.0, np.ones(2)))["total"]
2.0
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..core.interfaces import RunRecorder, TactileSample, optional
from .loop_results import SampleRecord

__all__ = ["tactile_message"]


def _json_float(x: Any) -> float | None:
    """JSON-safe float: NaN/inf/None -> None."""
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


class _Sink:
    """The loop's side of the recorder: never raises; its failure is reported once."""

    def __init__(self, recorder: Any, t0: float, on_fail: Callable[[str], None],
                 taps: Sequence[Any] = ()) -> None:
        self.recorder = recorder
        self.ok = recorder is not None
        self.taps = tuple(taps)
        self.t0 = t0
        self.wall0 = time.time_ns()
        self.on_fail = on_fail
        self.error: str | None = None

    def write(self, topic: str, msg: dict[str, Any], t: float) -> None:
        ns = self.wall0 + int((t - self.t0) * 1e9)
        if self.ok and not self.recorder.write(topic, msg, ns):
            self.check()
        for tap in self.taps:
            tap.put(topic, msg, ns)

    def check(self) -> None:
        if self.ok and self.recorder.error is not None:
            self.ok = False
            self.error = f"{optional(self.recorder, RunRecorder, 'path')}: {self.recorder.error}"
            self.on_fail(self.error)

    def samples(self, records: list[SampleRecord], finger_names: list[str], last_flow: int | None) -> int | None:
        if not (self.ok or self.taps):
            return last_flow
        for r in records:
            s, arr = r.sample, r.arrival
            if isinstance(s, TactileSample):  # a tactile source's frame, flat
                self.write("/tactile/frames", tactile_message(s, r.position), arr)
                self._chain(r, finger_names)
                continue
            self.write("/daq/samples", {"seq": s.seq, "t": s.t, "slip_volts": s.slip_volts,
                                        "flow_pulses": s.flow_pulses, "arrival": arr - self.t0,
                                        "position": _json_float(r.position)}, arr)
            if s.accel_g is not None:
                ax, ay, az = s.accel_g
                self.write("/daq/imu", {"seq": s.seq, "t": s.t, "ax": ax, "ay": ay, "az": az}, arr)
            if s.flow_pulses != last_flow:
                self.write("/daq/flow", {"seq": s.seq, "t": s.t, "pulses": s.flow_pulses}, arr)
            last_flow = s.flow_pulses
            self._chain(r, finger_names)
        return last_flow

    def _chain(self, r: SampleRecord, finger_names: list[str]) -> None:
        """What the reflex did with one sample or frame: state, spikes, windows, commands."""
        s, arr = r.sample, r.arrival
        self.write("/chain/state", {"seq": s.seq, "t": s.t, "filtered": _json_float(r.filtered),
                                    "threshold": _json_float(r.threshold) or 0.0, "event": r.event}, arr)
        if r.event:
            self.write("/chain/events", {"seq": s.seq, "t": s.t}, arr)
        if r.count is not None:
            self.write("/chain/windows", {"seq": s.seq, "t": s.t, "count": int(r.count)}, arr)
        if r.board is not None:
            self.write("/board/state", {"seq": s.seq, "t": s.t, **r.board}, arr)
        if r.command is not None:
            grip = {f.name.lower(): _json_float(v) for f, v in (r.grip or {}).items()}
            self.write("/hand/commands", {"seq": s.seq, "t": s.t, "target": float(r.command),
                                          "fingers": finger_names, "targets": {}, "grip": grip,
                                          "sent": r.sent, "note": r.note, "latency": r.latency,
                                          "frame_latency": r.frame_latency}, arr)
            self.write("/hand/grip", {"seq": s.seq, "t": s.t, "sent": r.sent, **grip}, arr)


def tactile_message(s: Any, position: float | None = None) -> dict[str, Any]:
    """A tactile frame as its ``/tactile/frames`` message: flat fields, one per taxel.

    Examples
    --------
    >>> from slipreflex.core.interfaces import TactileSample
    >>> m = tactile_message(TactileSample(3, 0.5, np.array([[0.25, 0.5], [0.0, 1.0]])))
    >>> m["total"], m["peak"], m["taxel_3"], m["position"]
    (1.75, 1.0, 1.0, None)
    """
    flat = np.asarray(s.frame, dtype=np.float64).reshape(-1)
    return {"seq": s.seq, "t": s.t, "total": float(flat.sum()), "peak": float(flat.max(initial=0.0)),
            "position": _json_float(position), **{f"taxel_{k}": float(v) for k, v in enumerate(flat)}}
