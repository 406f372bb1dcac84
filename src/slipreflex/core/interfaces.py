"""The small protocols everything else is built on.

A *sample source* yields DAQ samples, a *hand* takes finger positions and
reports them, and a *reflex* maps input samples to finger commands. The
simulated rig, the serial drivers and the replay of a recording all implement
these; the runtime loop and the experiment runner depend only on them. This
module imports nothing from the rest of the package except constants.

Examples
--------
>>> from slipreflex.core.interfaces import DaqSample
>>> s = DaqSample(seq=0, t=0.0, slip_volts=0.42, accel_g=(0.0, 0.0, 1.0), flow_pulses=0)
>>> s.slip_volts
0.42
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np

from .hardware import FINGER_MAX, TACTILE_SHAPE, Finger

__all__ = ["DaqSample", "SampleSource", "TactileSample", "TactileSource", "Hand", "Reflex", "CompiledReflex",
           "InputKind", "GraspResult", "Rig", "RunRecorder", "Member", "CONTRACTS", "optional", "missing",
           "contract_markdown"]

#: What a reflex reads: the slip sensor (one float per sample) or the 4 x 4
#: tactile array (one ``(4, 4)`` float array of newtons per sample).
InputKind = Literal["slip", "tactile"]


@dataclass(frozen=True, slots=True)
class DaqSample:
    """One sample period of the DAQ board, decoded.

    Parameters
    ----------
    seq : int
        Sequence number as sent by the board (wraps as the wire format says).
    t : float
        Sample time in seconds on the board's clock (``seq`` times the period,
        unwrapped by the reader).
    slip_volts : float
        Slip-sensor voltage (V).
    accel_g : tuple of float or None
        Accelerometer x, y, z in g, or None when no fresh IMU reading came
        with this sample.
    flow_pulses : int
        Cumulative YF-S201 pulse count.

    Examples
    --------
    >>> DaqSample(seq=1, t=0.003, slip_volts=3.33, accel_g=None, flow_pulses=7).flow_pulses
    7
    """

    seq: int
    t: float
    slip_volts: float
    accel_g: tuple[float, float, float] | None
    flow_pulses: int


@runtime_checkable
class SampleSource(Protocol):
    """Anything that yields DAQ samples: a serial DAQ, the simulated rig, a recording.

    ``read(timeout)`` returns the samples that arrived since the last call
    (possibly none after ``timeout`` seconds); it never blocks longer than
    ``timeout``. Optional members (``last_arrival``, ``stats``, ``drop_buffered()``,
    ``port_name``) are declared with their defaults in :data:`CONTRACTS`.

    Examples
    --------
    >>> class Two:
    ...     def read(self, timeout): return []
    ...     def close(self): pass
    >>> isinstance(Two(), SampleSource)
    True
    """

    def read(self, timeout: float) -> list[DaqSample]: ...

    def close(self) -> None: ...


@dataclass(frozen=True, slots=True)
class TactileSample:
    """One tactile frame, as a :class:`TactileSource` delivers it.

    Parameters
    ----------
    seq : int
        Frame number (consecutive from the source's start).
    t : float
        Seconds on the source's clock (for a hand that stamps nothing: when the frame arrived).
    frame : numpy.ndarray
        Forces (N) in the source's ``shape``: ``(4, 4)`` for the paper's array, ``(6,)`` for
        one fingertip of the Ability Hand.

    Examples
    --------
    >>> TactileSample(0, 0.0, np.zeros(6)).frame.shape
    (6,)
    """

    seq: int
    t: float
    frame: np.ndarray


@runtime_checkable
class TactileSource(Protocol):
    """Anything that yields tactile frames: a hand's touch sensors, a DAQ with a tactile array.

    ``read_frames(timeout)`` returns the frames that arrived since the last call
    (possibly none after ``timeout`` seconds) and never blocks longer; ``shape`` is the
    shape of every frame and ``fs`` the rate (Hz) at which they come. A tactile method
    (``input_kind == "tactile"``) reads one.

    Examples
    --------
    >>> class Still:
    ...     shape, fs = (6,), 260.0
    ...     def read_frames(self, timeout): return []
    ...     def close(self): pass
    >>> isinstance(Still(), TactileSource)
    True
    """

    shape: tuple[int, ...]
    fs: float

    def read_frames(self, timeout: float) -> list[TactileSample]: ...

    def close(self) -> None: ...


@runtime_checkable
class Hand(Protocol):
    """A hand: what a grasp routine and a reflex may tell it, and what it reports.

    Positions are in i-Limb units (0 open .. 500 closed). Four methods:

    - ``set_positions(targets)`` sends position targets for the named fingers
      (grasp routines, before a reflex runs; a reflex never uses it);
    - ``close_fingers(fingers, speed)`` starts closing the fingers at ``speed``
      units/s, until ``hold``;
    - ``hold(fingers)`` stops them where they are (never opens);
    - ``positions()`` returns the measured position of every finger the hand
      measures, and an empty dict for a hand that reports none (the i-Limb).

    A reflex adds grip only through ``close_fingers`` then ``hold``
    (:mod:`slipreflex.core.grip`); where ``positions`` reports a finger, the loops
    use it as the reflex's measured position and its start.

    Optional members (:data:`CONTRACTS` declares them with their defaults; the loop
    reads them through :func:`optional`): ``reflex_running(bool)`` (the driver's guard:
    no position frame while a reflex runs), ``stalled()`` (the fingers the hand reports
    stalled: a fault, and grip sent to them is not counted as added) and ``close()``.

    Examples
    --------
    >>> class Still:
    ...     def set_positions(self, targets): pass
    ...     def close_fingers(self, fingers, speed): pass
    ...     def hold(self, fingers): pass
    ...     def positions(self): return {}
    >>> isinstance(Still(), Hand)
    True
    """

    def set_positions(self, targets: Mapping[Finger, float]) -> None: ...

    def close_fingers(self, fingers: Iterable[Finger], speed: float) -> None: ...

    def hold(self, fingers: Iterable[Finger]) -> None: ...

    def positions(self) -> dict[Finger, float]: ...


@runtime_checkable
class Reflex(Protocol):
    """Maps input samples to finger commands, one sample at a time.

    Attributes
    ----------
    name : str
        Method name used by the trial runner (a name of :mod:`slipreflex.methods`).
    input_kind : {"slip", "tactile"}
        Which stream ``step`` expects.
    fs : float
        The rate (Hz) at which ``step`` must be called.
    last_event : bool
        Diagnostics of the last ``step`` (what the runtime records and replay
        compares): the step detected something (a spike of the chain, a
        detection of NMSD, the start of an SWT-SD ON period).
    last_filtered : float
        The filtered input the method looked at (NaN where the method has no
        scalar filtered signal, or the sample was skipped).
    last_threshold : float or None
        The detection threshold in force (None if the method has none).
    last_count : int or None
        The window's spike count when the step completed a window, else None.

    ``step(sample, position=None)`` takes one sample (a float for "slip", a
    frame array for "tactile") and the hand's measured slip-finger position if
    known; it returns a new target position for the grasping fingers, or None
    when the command does not change. A non-finite sample is skipped (None) or
    refused with :class:`~slipreflex.core.errors.DataError`; it never becomes a
    command. ``reset()`` restores the initial state bit for bit.
    :func:`slipreflex.testing.check_reflex` checks all of this.

    Examples
    --------
    >>> class Never:
    ...     name, input_kind, fs = "never", "slip", 333.33
    ...     last_event, last_filtered, last_threshold, last_count = False, float("nan"), None, None
    ...     def step(self, sample, position=None): return None
    ...     def reset(self): pass
    >>> isinstance(Never(), Reflex)
    True
    """

    # Read-only to a caller: an implementation may keep each as a plain attribute or a property.
    @property
    def name(self) -> str: ...
    @property
    def input_kind(self) -> InputKind: ...
    @property
    def fs(self) -> float: ...
    @property
    def last_event(self) -> bool: ...
    @property
    def last_filtered(self) -> float: ...
    @property
    def last_threshold(self) -> float | None: ...
    @property
    def last_count(self) -> int | None: ...

    def step(self, sample: Any, /, position: float | None = None) -> float | None: ...

    def reset(self) -> None: ...


@runtime_checkable
class CompiledReflex(Protocol):
    """A reflex whose ``step`` is also a numba function over its live state (optional).

    ``compiled()`` returns ``(step, S, P)``: ``step`` a numba ``@njit`` function,
    ``S`` the reflex's own state vector (float64, C-contiguous, the very array its
    :meth:`Reflex.step` updates, not a copy) and ``P`` its parameter vector (float64,
    read only). ``step(S, P, sample, position)`` does exactly what
    ``reflex.step(sample, position)`` does and returns the new command, or NaN for
    none; ``position`` is the measured slip-finger position (NaN if unknown).
    ``sample`` is, for ``input_kind == "slip"``, the raw volts (float64); for
    ``"tactile"``, the frame's taxels as a 1-D C-contiguous float64 array (the
    frame flattened in C order). The compiled closed loop
    (:func:`slipreflex.sim.run_closed_loop`) calls it from its own numba code, so
    after the loop ``reflex.step`` continues from where the loop left ``S``; the
    reflex must keep no other state that ``step`` changes. A reflex without
    ``compiled`` runs in the Python loop.

    Examples
    --------
    >>> from slipreflex.methods.chain import SlipReflex
    >>> r = SlipReflex(dath=True)
    >>> isinstance(r, CompiledReflex)
    True
    >>> step, S, P = r.compiled()
    >>> S is r.compiled()[1]
    True
    """

    def compiled(self) -> tuple[Any, np.ndarray, np.ndarray]: ...


@dataclass(frozen=True)
class GraspResult:
    """Outcome of a grasp routine: the one type every home returns.

    The simulated rig's routine (:meth:`slipreflex.sim.Rig.grasp`), the
    hardware's step-and-read routine (:func:`slipreflex.rig.devices.ilimb.tripod_grasp`)
    and the virtual rig (:class:`slipreflex.rig.devices.simrig.SimRig`) all return it;
    a field a routine cannot know keeps its default.

    Parameters
    ----------
    position : float
        Measured (or, on hardware, commanded) slip-finger position when the
        routine finished: the reflex's ``p0``.
    force_n : float
        Contact force (N): the normal force per contact after settling in
        simulation, the tactile reading when closing stopped on hardware.
    positions : dict of Finger to float
        Every tripod finger's position (the per-finger ``p0``; the thumb often
        stops at another position than the index and middle).
    contact : bool
        The target force was reached (False: the hand closed fully).
    stable : bool or None
        The object hangs still in the fingers after its support is removed
        (None where the routine cannot tell, as on hardware).
    steps : int
        Position increments sent (step-and-read routines; 0 otherwise).
    t, t_contact, t_release : float
        When the routine finished, when the target force was first read and
        when the support was removed (s, rig time; NaN where unknown).

    Examples
    --------
    >>> from slipreflex.core.hardware import Finger
    >>> g = GraspResult(147.0, 0.83, {Finger.THUMB: 149.0, Finger.MIDDLE: 147.0})
    >>> g.contact, g.stable, g.p0_text()
    (True, None, 'thumb=149,middle=147')
    """

    position: float
    force_n: float
    positions: dict = field(default_factory=dict)
    contact: bool = True
    stable: bool | None = None
    steps: int = 0
    t: float = float("nan")
    t_contact: float = float("nan")
    t_release: float = float("nan")

    def p0_text(self) -> str:
        """The positions as ``run --p0`` takes them: ``thumb=149,index=147,middle=147``.

        Examples
        --------
        >>> from slipreflex.core.hardware import Finger
        >>> GraspResult(147.0, 0.8, {Finger.INDEX: 147.0}).p0_text()
        'index=147'
        """
        return ",".join(f"{f.name.lower()}={v:g}" for f, v in self.positions.items())


@runtime_checkable
class Rig(Protocol):
    """A simulated rig as the virtual devices and the closed-loop runner see it.

    ``t`` is the rig's time (s); ``advance_to(t)`` advances it and returns the
    DAQ samples produced; ``hand`` is its :class:`Hand` (the simulated one also
    takes ``command(kind, fingers, value, at=)``); ``grasp(force)`` runs the
    grasp routine and ``perturb(what, at)`` schedules a load change.
    :class:`slipreflex.sim.Rig` implements it.

    Examples
    --------
    >>> class Still:
    ...     t, hand = 0.0, None
    ...     def advance_to(self, t): return []
    ...     def grasp(self, force=0.8): return GraspResult(0.0, force)
    ...     def perturb(self, what, at=None): pass
    >>> isinstance(Still(), Rig)
    True
    """

    t: float
    hand: Any

    def advance_to(self, t: float) -> list[DaqSample]: ...

    def grasp(self, force: float = ...) -> GraspResult: ...

    def perturb(self, what: Any, at: float | None = None) -> None: ...


@runtime_checkable
class RunRecorder(Protocol):
    """What the real-time loop writes its recording through (:class:`slipreflex.files.recording.Recorder`).

    ``write(topic, message, ns)`` records one message and returns False once the
    recording has failed (``error`` then says why, and the loop goes on unrecorded);
    ``maybe_flush()`` flushes at most every so often; ``add_metadata(name, fields)``
    adds a metadata record (the start, the run's summary).

    Examples
    --------
    >>> class Nowhere:
    ...     error = None
    ...     def write(self, topic, message, ns): return True
    ...     def maybe_flush(self): pass
    ...     def add_metadata(self, name, fields): pass
    >>> isinstance(Nowhere(), RunRecorder)
    True
    """

    error: Any

    def write(self, topic: str, message: dict[str, Any], ns: int) -> bool: ...

    def maybe_flush(self) -> None: ...

    def add_metadata(self, name: str, fields: dict[str, str]) -> None: ...


@dataclass(frozen=True)
class Member:
    """One member of a protocol as its users read it: required, or optional with its default.

    Parameters
    ----------
    name : str
        The attribute; a dotted name (``params.p0``) is a field of an optional attribute.
    required : bool
        Every implementation has it (the loop refuses, before anything is sent, an object
        without the required members it uses).
    default : object
        What an optional member is taken to be where an implementation has none.
    kind : {"method", "value"}
        Called, or read.
    doc : str
        What it is and what the loop does with it.

    Examples
    --------
    >>> [m.name for m in CONTRACTS[Hand] if not m.required]
    ['reflex_running', 'stalled', 'close']
    """

    name: str
    required: bool
    default: Any = None
    kind: Literal["method", "value"] = "method"
    doc: str = ""


def _required(name: str, doc: str, kind: Literal["method", "value"] = "method") -> Member:
    return Member(name, True, None, kind, doc)


#: Every member the real-time loop, the conformance checkers and the registries use of each
#: protocol: the required ones, and the optional ones with the default an implementation
#: without them gets (:func:`optional` reads those; nothing else probes).
CONTRACTS: dict[type, tuple[Member, ...]] = {
    SampleSource: (
        _required("read", "`read(timeout)`: the samples that arrived since the last call; never blocks longer"),
        _required("close", "`close()`: releases the port"),
        Member("last_arrival", False, math.nan, "value",
               "clock time (`perf_counter`) at which the last read's bytes arrived; without it the loop "
               "takes its own clock when `read` returns"),
        Member("stats", False, None, "value",
               "the source's counters, an object with `to_dict()` (`crc_errors`, `frames_lost`, "
               "`resets`, ...): recorded on `/stats`, returned as `RunResult.daq_stats`, increases become "
               "fault events, a counted reset re-anchors the board clock"),
        Member("drop_buffered", False, None, "method",
               "`drop_buffered() -> int`: drops the frames buffered during the set-up, called once just "
               "before the clock starts; without it nothing is dropped"),
        Member("port_name", False, "the DAQ port", "value", "how messages name the port"),
    ),
    TactileSource: (
        _required("read_frames", "`read_frames(timeout)`: the frames that arrived since the last call"),
        _required("close", "`close()`: releases the port"),
        _required("shape", "the shape of every frame", "value"),
        _required("fs", "the rate (Hz) at which frames come", "value"),
        Member("last_arrival", False, math.nan, "value", "as a sample source's"),
        Member("drop_buffered", False, None, "method",
               "as a sample source's (a source that reads on its own thread queues frames during the set-up)"),
        Member("port_name", False, "the tactile source", "value", "how messages name the port"),
    ),
    Hand: (
        _required("set_positions", "`set_positions(targets)`: grasp routines only, never while a reflex runs"),
        _required("close_fingers", "`close_fingers(fingers, speed)`: CLOSE, until `hold`"),
        _required("hold", "`hold(fingers)`: STOP where they are; never opens"),
        _required("positions", "`positions()`: measured positions; `{}` for a hand that reports none"),
        Member("reflex_running", False, None, "method",
               "`reflex_running(bool)`: the driver's own guard, switched on for the run and off after it "
               "(the i-Limb then refuses anything that could open a finger); without it the loop's rule "
               "(CLOSE and STOP only) is the only guard"),
        Member("stalled", False, None, "method",
               "`stalled()`: the fingers the hand reports stalled; each is a `finger-stalled` fault and grip "
               "sent to it is not counted; without it no finger is ever stalled"),
        Member("close", False, None, "method",
               "`close()`: releases the port; a registered hand's driver (`HandSpec.open`) has it"),
    ),
    Reflex: (
        *(_required(n, f"see `Reflex.{n}`", "value") for n in
          ("name", "input_kind", "fs", "last_event", "last_filtered", "last_threshold", "last_count")),
        _required("step", "`step(sample, position=None)`: the new command or None"),
        _required("reset", "`reset()`: the initial state, bit for bit"),
        Member("command", False, None, "value",
               "the command before the first step: where the rises the loop sends as grip are counted from"),
        Member("params.p0", False, None, "value", "the start command where there is no `command`"),
        Member("params.hi", False, float(FINGER_MAX), "value",
               "the command's ceiling: from there on it adds no grip (`mpi-saturated`)"),
        Member("params.shape", False, TACTILE_SHAPE, "value", "a tactile reflex's frame shape"),
        Member("finger_offsets", False, None, "value",
               "`{finger: units}` added to the command for that finger (preset `authors-gui`: middle + 20)"),
        Member("last_board", False, None, "value",
               "a board twin's own output for the last sample (recorded on `/board/state`)"),
        Member("last_mismatch", False, None, "value",
               "why the board and its twin disagreed on the last sample (a `board-mismatch` fault)"),
        Member("compiled", False, None, "method",
               "`compiled() -> (step, S, P)` (`CompiledReflex`): the compiled closed loop runs it"),
    ),
    RunRecorder: (
        _required("write", "`write(topic, message, ns) -> bool`"),
        _required("error", "why the recording failed, or None", "value"),
        _required("maybe_flush", "`maybe_flush()`"),
        _required("add_metadata", "`add_metadata(name, fields)`: the start and the run's summary"),
        Member("path", False, "recording", "value", "how messages name the recording"),
    ),
}

_OPTIONAL: dict[type, dict[str, Member]] = {
    protocol: {m.name: m for m in members if not m.required} for protocol, members in CONTRACTS.items()}
_ABSENT = object()


def optional(obj: Any, protocol: type, name: str) -> Any:
    """An optional member of ``obj`` as ``protocol`` declares it: its value, or the declared default.

    The one way the loop reads what an implementation may lack; a name the protocol does not
    declare optional is a programming error (:class:`KeyError`), never a silent default.

    Examples
    --------
    >>> class Still:
    ...     def read(self, timeout): return []
    ...     def close(self): pass
    >>> optional(Still(), SampleSource, "port_name")
    'the DAQ port'
    >>> optional(Still(), SampleSource, "colour")
    Traceback (most recent call last):
    ...
    KeyError: "SampleSource declares no optional member 'colour'"
    """
    member = _OPTIONAL[protocol].get(name)
    if member is None:
        raise KeyError(f"{protocol.__name__} declares no optional member {name!r}")
    if "." not in name:
        return getattr(obj, name, member.default)
    value = obj
    for part in name.split("."):
        value = getattr(value, part, _ABSENT)
        if value is _ABSENT:
            return member.default
    return value


def missing(obj: Any, protocol: type, names: Iterable[str] | None = None) -> list[str]:
    """The required members of ``protocol`` (or of ``names`` among them) that ``obj`` lacks.

    A method counts as present when it is callable.

    Examples
    --------
    >>> class Mute:
    ...     def hold(self, fingers): pass
    >>> missing(Mute(), Hand, ("close_fingers", "hold", "positions"))
    ['close_fingers', 'positions']
    """
    members = [m for m in CONTRACTS[protocol] if m.required]
    if names is not None:
        wanted = tuple(names)
        unknown = set(wanted) - {m.name for m in members}
        if unknown:
            raise KeyError(f"{protocol.__name__} requires no {', '.join(sorted(unknown))}")
        members = [m for m in members if m.name in wanted]
    out = []
    for m in members:
        value = getattr(obj, m.name, _ABSENT)
        if value is _ABSENT or (m.kind == "method" and not callable(value)):
            out.append(m.name)
    return out


def contract_markdown() -> str:
    """The contracts as the table docs/runtime.md shows (a test keeps the two the same).

    Examples
    --------
    >>> contract_markdown().splitlines()[0]
    '| protocol | member | required | default | what |'
    """
    rows = ["| protocol | member | required | default | what |", "| --- | --- | --- | --- | --- |"]
    for protocol, members in CONTRACTS.items():
        for m in members:
            default = "" if m.required else f"`{m.default!r}`"
            rows.append(f"| `{protocol.__name__}` | `{m.name}` | {'yes' if m.required else 'no'} | {default} "
                        f"| {m.doc} |")
    return "\n".join(rows)
