"""Closed-loop runs of a reflex on the simulated rig, and their result object.

:func:`run_closed_loop` feeds a :class:`slipreflex.core.interfaces.Reflex` the
input its ``input_kind`` asks for (slip-sensor volts at the DAQ's 333.33 Hz,
or ``(4, 4)`` index-finger tactile frames at the reflex's own ``fs``), passes
the measured middle-finger position with every sample, and sends every rise of
the returned command to the tripod fingers (thumb, index, middle) as closing
time, the grip-only rule of :mod:`slipreflex.core.grip` that the real-rig loop
applies too: a rise of ``g`` units is a CLOSE at the hand's closing speed
(full PWM: ``HandParams.speed_units_s``, the documented
:data:`~slipreflex.core.hardware.FINGER_SPEED_UNITS_S` on the nominal plant) and a
STOP ``g / speed`` seconds later, a rise while the fingers still close extends
the closing. The commands are sent at the time of the sample that produced them and
reach the fingers after the hand's latency; the physics is advanced in
stretches that never pass a time a pending command could still change, so
the result is the same as stepping sample by sample.

A reflex with a compiled step (:class:`slipreflex.core.interfaces.CompiledReflex`:
every method on the paper's chain, NMSD, SWT-SD) runs this same loop inside
one numba function (:mod:`slipreflex.sim.closed`), 2 to 4 times faster and
with the same bits; ``run_closed_loop(..., compiled=False)`` forces the Python
loop, which every other reflex runs.

No finger ever gets OPEN or a position from a reflex, so none can open, whatever
the reflex's start: each closes from wherever it holds (the grasp stops each
finger at its own position). A reflex's declared ``finger_offsets`` close that
finger's group ``offset`` units more at the first command
(:func:`grip_groups`). The closing in progress is the hand's
(:attr:`SimHand.closing_until <slipreflex.sim.rig.SimHand>`), so a loop that
continues a run extends it rather than cutting it short.

:class:`SimTrace` holds every stream of the run as arrays.

Examples
--------
>>> from slipreflex.sim import Rig, run_closed_loop
>>> class Never:
...     name, input_kind, fs = "never", "slip", 333.0
...     def step(self, sample, position=None): return None
...     def reset(self): pass
>>> rig = Rig("TR", seed=1); _ = rig.grasp()
>>> tr = run_closed_loop(rig, Never(), 0.5)
>>> tr.t.size, tr.fallen
(167, False)
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core import hardware as hw
from ..core.errors import ParameterError
from ..core.grip import Grip, finger_groups, span
from ..core.hardware import Finger, HandCommand
from ..core.interfaces import Reflex
from ..files.paths import new_file
from .closed import compilable, run_compiled, stretch_end
from .objects import Drop, Pour
from .rig import DaqBlock, Rig, SlipEvent

__all__ = ["SimTrace", "run_closed_loop", "TRACE_COLUMNS", "reflex_log"]

#: Columns of :meth:`SimTrace.to_frame` / :meth:`SimTrace.write_csv` (DAQ-rate streams), with units.
TRACE_COLUMNS: dict[str, str] = {
    "t": "s", "volts": "V", "accel_x": "g", "accel_y": "g", "accel_z": "g", "accel_fresh": "bool",
    "flow_pulses": "count", "thumb": "units", "index": "units", "middle": "units", "command": "units",
    "displacement": "m", "velocity": "m/s", "slip": "m", "stuck": "bool", "fallen": "bool",
    "normal_force": "N", "load_mass": "kg", "accel_true": "m/s^2",
}


@dataclass
class SimTrace:
    """Everything a closed-loop (or open-loop) run produced.

    Attributes
    ----------
    daq : DaqBlock
        Slip-sensor volts, accelerometer (g), flow pulses at 333.33 Hz, with
        the truth at the same instants (displacement, velocity, slip, stuck,
        fallen, normal force, load mass, finger positions).
    cmd_t, cmd_value : ndarray
        Commands the reflex returned: time of the sample that produced each,
        and the target position.
    tactile_t, tactile : ndarray
        Index-finger tactile frames (times, ``(n, 4, 4)`` N) if the reflex
        read them or ``tactile_fs`` asked for them (else empty).
    onsets : ndarray
        Truth: times of every stick -> slip transition in the run.
    slip_events : list of SlipEvent
        Truth: sliding episodes (see :meth:`Rig.slip_events`).
    fallen : bool
        The bottle slid out of the grasp.
    fall_time : float or None
    perturbations : list of (float, Drop | Pour)
        Every perturbation scheduled on the rig, with its time.
    method : str
        The reflex's name.
    t_start, t_end : float
        The run's time span (s).

    Examples
    --------
    >>> from slipreflex.sim import Rig, simulate_open_loop
    >>> tr = simulate_open_loop(Rig("TR"), 0.1)
    >>> sorted(tr.to_frame())[:3]
    ['accel_fresh', 'accel_true', 'accel_x']
    """

    daq: DaqBlock
    cmd_t: np.ndarray
    cmd_value: np.ndarray
    tactile_t: np.ndarray
    tactile: np.ndarray
    onsets: np.ndarray
    slip_events: list[SlipEvent]
    fallen: bool
    fall_time: float | None
    perturbations: list[tuple[float, Drop | Pour]]
    method: str
    t_start: float
    t_end: float
    extra: dict = field(default_factory=dict)

    # convenient aliases of the DAQ streams
    @property
    def t(self) -> np.ndarray:
        """DAQ sample times (s).

        Examples
        --------
        >>> from slipreflex.sim import Rig, simulate_open_loop
        >>> simulate_open_loop(Rig("TR"), 0.03).t.size   # 0, 3, ..., 30 ms
        11
        """
        return self.daq.t

    @property
    def volts(self) -> np.ndarray:
        """Slip-sensor volts.

        Examples
        --------
        >>> from slipreflex.sim import Rig, simulate_open_loop
        >>> float(simulate_open_loop(Rig("TR"), 0.03).volts[0]) > 4
        True
        """
        return self.daq.volts

    @property
    def accel(self) -> np.ndarray:
        """Accelerometer readings (g), shape (n, 3).

        Examples
        --------
        >>> from slipreflex.sim import Rig, simulate_open_loop
        >>> simulate_open_loop(Rig("TR"), 0.03).accel.shape
        (11, 3)
        """
        return self.daq.accel

    @property
    def command(self) -> np.ndarray:
        """The last command at or before each DAQ sample (NaN before the first).

        Examples
        --------
        >>> from slipreflex.sim import Rig, simulate_open_loop
        >>> bool(np.isnan(simulate_open_loop(Rig("TR"), 0.03).command).all())
        True
        """
        out = np.full(self.daq.t.size, np.nan)
        if self.cmd_t.size:
            idx = np.searchsorted(self.cmd_t, self.daq.t + 1e-12, side="right") - 1
            ok = idx >= 0
            out[ok] = self.cmd_value[idx[ok]]
        return out

    @property
    def water_ml(self) -> np.ndarray:
        """Water volume estimated from the flow pulses (ml), as the paper's Fig. 15A.

        Examples
        --------
        >>> from slipreflex.sim import Rig, simulate_open_loop
        >>> float(simulate_open_loop(Rig("TR"), 0.03).water_ml.max())
        0.0
        """
        return self.daq.flow_pulses / hw.FLOW_PULSES_PER_LITRE * 1000.0

    def to_frame(self) -> dict[str, np.ndarray]:
        """The DAQ-rate streams as a dict of equal-length 1-D arrays (see :data:`TRACE_COLUMNS`).

        Examples
        --------
        >>> from slipreflex.sim import Rig, simulate_open_loop
        >>> f = simulate_open_loop(Rig("TR"), 0.03).to_frame()
        >>> len({v.size for v in f.values()})
        1
        """
        d = self.daq
        return {
            "t": d.t, "volts": d.volts, "accel_x": d.accel[:, 0], "accel_y": d.accel[:, 1],
            "accel_z": d.accel[:, 2], "accel_fresh": d.accel_fresh, "flow_pulses": d.flow_pulses,
            "thumb": d.fingers[:, 0], "index": d.fingers[:, 1], "middle": d.fingers[:, 2],
            "command": self.command, "displacement": d.displacement, "velocity": d.velocity, "slip": d.slip,
            "stuck": d.stuck, "fallen": d.fallen, "normal_force": d.normal_force, "load_mass": d.load_mass,
            "accel_true": d.accel_true,
        }

    def write_csv(self, path: str | Path) -> Path:
        """Write :meth:`to_frame` as CSV (header row of column names).

        Examples
        --------
        >>> import tempfile, pathlib
        >>> from slipreflex.sim import Rig, simulate_open_loop
        >>> p = simulate_open_loop(Rig("TR"), 0.03).write_csv(pathlib.Path(tempfile.mkdtemp()) / "a.csv")
        >>> p.read_text().splitlines()[0].split(",")[:3]
        ['t', 'volts', 'accel_x']
        """

        path = Path(path)
        frame = self.to_frame()
        cols = list(frame)
        with new_file(path, "w", replace=True) as fh:
            w = csv.writer(fh)
            w.writerow(cols)
            arrs = [np.asarray(frame[c]) for c in cols]
            for i in range(self.daq.t.size):
                w.writerow([_fmt(a[i]) for a in arrs])
        return path


def _fmt(v: object) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "1" if v else "0"
    if isinstance(v, (np.integer, int)):
        return str(int(v))
    f = float(v)  # type: ignore[arg-type]
    return "" if math.isnan(f) else repr(f)


def _trace(rig: Rig, t0: float, method: str, cmd_t: Sequence[float] | np.ndarray, cmd_v: Sequence[float] | np.ndarray,
           tac_t: np.ndarray, tac: np.ndarray) -> SimTrace:
    d = rig.daq_history(since=t0)
    ons = rig.onsets
    ev = [e for e in rig.slip_events() if e.onset >= t0 - 1e-12 or e.end is None or e.end >= t0]
    return SimTrace(daq=d, cmd_t=np.asarray(cmd_t, dtype=float), cmd_value=np.asarray(cmd_v, dtype=float),
                    tactile_t=tac_t, tactile=tac, onsets=ons[ons >= t0 - 1e-12], slip_events=ev,
                    fallen=rig.fallen, fall_time=rig.fall_time, perturbations=list(rig.perturbations),
                    method=method, t_start=t0, t_end=rig.t)


def simulate_open_loop(rig: Rig, duration: float, *, tactile_fs: float | None = None) -> SimTrace:
    """Advance the rig without a reflex and return the trace of that stretch.

    Parameters
    ----------
    rig : Rig
    duration : float
        Seconds to simulate.
    tactile_fs : float, optional
        Also record index-finger tactile frames at this rate.

    Returns
    -------
    SimTrace

    Examples
    --------
    >>> from slipreflex.sim import Rig, Pour
    >>> rig = Rig("TR", seed=2); _ = rig.grasp(); rig.perturb(Pour(), at=rig.t)
    >>> simulate_open_loop(rig, 40.0).fallen
    True
    """
    if not (math.isfinite(duration) and duration >= 0):
        raise ParameterError(f"duration must be >= 0, got {duration!r}")
    if not rig.history:
        raise ParameterError("simulate_open_loop needs a Rig made with history=True")
    t0 = rig.t
    s = rig.tactile_sampler(tactile_fs, keep=True) if tactile_fs else None
    rig.advance_block(t0 + duration)
    tac_t, tac = s.history if s else (np.zeros(0), np.zeros((0,) + hw.TACTILE_SHAPE))
    if s:
        s.close()
    return _trace(rig, t0, "open-loop", [], [], tac_t, tac)


def grip_groups(fingers: tuple[Finger, ...], offsets) -> list[tuple[tuple[Finger, ...], float]]:
    """How the rises of a command go to ``fingers``: ``(fingers, offset)`` pairs.

    Fingers with the same declared offset (``finger_offsets``; 0 for the others)
    close together (:func:`slipreflex.core.grip.finger_groups`); the Python loop and the
    compiled one both split a command this way.

    Examples
    --------
    >>> from slipreflex.core.hardware import TRIPOD
    >>> grip_groups(TRIPOD, {Finger.MIDDLE: 20.0})
    [((<Finger.THUMB: 0>, <Finger.INDEX: 1>), 0.0), ((<Finger.MIDDLE: 2>,), 20.0)]
    """
    return finger_groups(fingers, offsets)


def grip_start(rig: Rig, reflex: Reflex) -> float:
    """The command level from which a reflex's rises count: its own ``command`` when it
    has a finite one (its bookkeeping), else the middle finger's measured position.

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> from slipreflex.methods.chain import SlipReflex
    >>> grip_start(Rig("TR"), SlipReflex(p0=500.0)), grip_start(Rig("TR"), object())
    (500.0, 0.0)
    """
    c = getattr(reflex, "command", None)
    if isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c):
        return float(c)
    return float(rig.hand.positions()[Finger.MIDDLE])


def _grip_sender(hand, groups: list[tuple[tuple[Finger, ...], float]], start: float):
    """A ``send(c, at)`` that turns each rise of ``c`` into CLOSE and STOP commands (the grip rule)."""
    grip = Grip(start, [f for g, _ in groups for f in g], {f: off for g, off in groups for f in g})
    assert grip.groups == groups   # both from slipreflex.core.grip.finger_groups
    # the simulated hand's own closing speed is its documented rate (625 units/s on the nominal
    # plant, hardware.FINGER_SPEED_UNITS_S): a rise of g units closes its fingers g units
    speed = float(getattr(getattr(hand, "params", None), "speed_units_s", hw.FINGER_SPEED_UNITS_S))

    def send(value, at):
        if not math.isfinite(value):   # checked before any finger gets it, as the compiled loop does
            raise ParameterError(f"hand command value must be finite, got {value!r}")
        for (fingers, _), g in zip(groups, grip.rise(value)):
            if g > 0.0:
                until = max((hand.closing_until.get(f, -math.inf) for f in fingers), default=-math.inf)
                begin, end = span(at, until, g, speed)
                hand.command(HandCommand.CLOSE, fingers, float(hw.PWM_MAX), at=begin)
                hand.command(HandCommand.STOP, fingers, 0.0, at=end)
                for f in fingers:
                    hand.closing_until[f] = end
    return send


def run_closed_loop(rig: Rig, reflex: Reflex, duration: float, *,
                    fingers: Sequence[Finger] = hw.TRIPOD, tactile_fs: float | None = None,
                    compiled: bool = True) -> SimTrace:
    """Run ``reflex`` on ``rig`` for ``duration`` seconds from the rig's current time.

    Parameters
    ----------
    rig : Rig
        Usually after :meth:`Rig.grasp` and with perturbations scheduled.
    reflex : Reflex
        ``input_kind == "slip"``: called once per DAQ sample with the slip
        volts; ``"tactile"``: called at ``reflex.fs`` with index-finger
        frames. ``position`` is the measured middle-finger position.
    duration : float
        Seconds to run.
    fingers : sequence of Finger
        Fingers that close when the command rises (default: the tripod;
        :func:`grip_groups`).
    tactile_fs : float, optional
        For a slip reflex, also record tactile frames at this rate.
    compiled : bool
        Run the whole loop in one compiled function (:mod:`slipreflex.sim.closed`)
        when the reflex has a compiled step
        (:class:`~slipreflex.core.interfaces.CompiledReflex`), the fingers are tripod
        fingers and no command for another finger is queued; the result is the
        same, bit for bit, as the Python loop's, which ``compiled=False`` forces
        (and which runs every other reflex).

    Returns
    -------
    SimTrace

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> class Squeeze:
    ...     name, input_kind, fs = "squeeze", "tactile", 260.0
    ...     def step(self, frame, position=None): return position + 1 if frame.sum() < 2 else None
    ...     def reset(self): pass
    >>> rig = Rig("TR"); _ = rig.grasp()
    >>> tr = run_closed_loop(rig, Squeeze(), 0.5)
    >>> bool(tr.daq.normal_force[-1] > 1.9)
    True
    """
    if not (math.isfinite(duration) and duration >= 0):
        raise ParameterError(f"duration must be >= 0, got {duration!r}")
    if not rig.history:
        raise ParameterError("run_closed_loop needs a Rig made with history=True")
    kind = getattr(reflex, "input_kind", None)
    if kind not in ("slip", "tactile"):
        raise ParameterError(f"reflex.input_kind must be 'slip' or 'tactile', got {kind!r}")
    if not isinstance(compiled, bool):
        raise ParameterError(f"compiled must be True or False, got {compiled!r}")
    fingers = tuple(Finger(f) for f in fingers)
    offsets = getattr(reflex, "finger_offsets", None) if kind == "slip" else None
    groups = grip_groups(fingers, offsets)
    start = grip_start(rig, reflex)
    t0 = rig.t
    t_end = t0 + duration
    fs = float(reflex.fs) if kind == "tactile" else tactile_fs
    tac_s = rig.tactile_sampler(float(fs), Finger.INDEX, keep=True) if fs else None
    record: list = []
    try:

        if compiled and compilable(rig, reflex, fingers):
            reflex_sampler = tac_s if kind == "tactile" else None
            cmd_t, cmd_v = run_compiled(rig, reflex, t_end, groups, reflex_sampler, start, record=record)
            if reflex_sampler is not None:
                reflex_sampler.read()     # the loop consumed them
        elif kind == "slip":
            cmd_t, cmd_v = _python_slip(rig, reflex, t_end, _grip_sender(rig.hand, groups, start), record)
        else:
            assert tac_s is not None
            cmd_t, cmd_v = _python_tactile(rig, reflex, t_end, _grip_sender(rig.hand, groups, start), tac_s,
                                           record)
        if rig.t < t_end - _EPS:
            rig.advance_block(t_end)
    finally:
        if tac_s is not None:
            tac_s.close()
    tac_t, tac = tac_s.history if tac_s is not None else (np.zeros(0), np.zeros((0,) + hw.TACTILE_SHAPE))
    trace = _trace(rig, t0, getattr(reflex, "name", type(reflex).__name__), cmd_t, cmd_v, tac_t, tac)
    if record:
        names, rows = record[0]
        trace.extra["reflex"] = {"t": rows[:, 0].copy(), **{n: rows[:, j + 1].copy() for j, n in enumerate(names)}}
    return trace


def reflex_log(trace: SimTrace) -> dict[str, np.ndarray] | None:
    """What the loop's reflex computed, input by input, as the loop recorded it (None: nothing recorded).

    A reflex with ``probe_slots`` (name -> slot of its state vector, e.g. the chain's
    filtered sample, spike, threshold in force and window count) has those slots
    recorded after every input it took, with the input's time under ``"t"``: the
    spikes a figure draws are the ones the controller saw.

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> from slipreflex.methods.chain import SlipReflex
    >>> rig = Rig("TR"); g = rig.grasp()
    >>> log = reflex_log(run_closed_loop(rig, SlipReflex(p0=g.position), 0.1))
    >>> sorted(log)[:3], log["t"].size
    (['acc', 'command', 'count'], 33)
    """
    return trace.extra.get("reflex")


def _probe(reflex: Reflex, record: list | None):
    """(names, state vector, slots) of the reflex's recorded state, or None."""
    slots = dict(getattr(reflex, "probe_slots", {}) or {}) if record is not None else {}
    compiled = getattr(reflex, "compiled", None)
    if not slots or compiled is None:
        return None
    return tuple(slots), compiled()[1], np.array(list(slots.values()), dtype=np.int64)


_EPS = 1e-12


def _python_slip(rig: Rig, reflex: Reflex, t_end: float, send, record: list | None = None):
    """The Python loop for a slip reflex: one ``reflex.step`` per DAQ sample."""
    cmd_t: list[float] = []
    cmd_v: list[float] = []
    probe = _probe(reflex, record)
    rows: list = []
    step = reflex.step
    dt = rig.physics.dt
    lat = rig.hand.latency
    while rig.next_daq_time <= t_end + _EPS:
        horizon = min(t_end, max(rig.t + dt, float(stretch_end(rig.next_daq_index, 0.0, lat, hw.DAQ_PERIOD_S))))
        if math.ceil(horizon / dt - 1e-9) <= rig.step_index:
            break   # no step left before t_end (a zero-length run from t = 0)
        times, volts_a, mids_a = rig.advance_slip(horizon)
        for v, pos, ts_k in zip(volts_a.tolist(), np.rint(mids_a).tolist(), times.tolist()):
            c = step(v, position=pos)
            if probe is not None:
                rows.append([ts_k, *probe[1][probe[2]].tolist()])
            if c is not None:
                send(float(c), ts_k)
                cmd_t.append(ts_k)
                cmd_v.append(float(c))
        if rig.t >= t_end - _EPS and rig.next_daq_time > t_end + _EPS:
            break
    _keep(record, probe, rows)
    return cmd_t, cmd_v


def _keep(record: list | None, probe, rows: list) -> None:
    if probe is not None and record is not None:
        record.append((probe[0], np.asarray(rows, dtype=float).reshape(len(rows), len(probe[0]) + 1)))


def _python_tactile(rig: Rig, reflex: Reflex, t_end: float, send, tac_s, record: list | None = None):
    """The Python loop for a tactile reflex: one ``reflex.step`` per frame of ``tac_s``."""
    cmd_t: list[float] = []
    cmd_v: list[float] = []
    probe = _probe(reflex, record)
    rows: list = []
    step = reflex.step
    lat = rig.hand.latency
    while tac_s.next_time <= t_end + _EPS:
        horizon = min(t_end, max(rig.t + rig.physics.dt, float(stretch_end(tac_s.next_index, tac_s.fs, lat,
                                                                           hw.DAQ_PERIOD_S))))
        if math.ceil(horizon / rig.physics.dt - 1e-9) <= rig.step_index:
            break
        rig.advance_slip(horizon)
        tt, frames = tac_s.read()
        # measured middle position at each frame time: the latest DAQ-rate value
        for k in range(tt.size):
            ts_k = float(tt[k])
            pos = float(round(rig.finger_position_at(ts_k, Finger.MIDDLE)))
            c = step(frames[k], position=pos)
            if probe is not None:
                rows.append([ts_k, *probe[1][probe[2]].tolist()])
            if c is not None:
                send(float(c), ts_k)
                cmd_t.append(ts_k)
                cmd_v.append(float(c))
        if rig.t >= t_end - _EPS and tac_s.next_time > t_end + _EPS:
            break
    _keep(record, probe, rows)
    return cmd_t, cmd_v
