"""The real-time loop's link and watchdog states, written down: the regions, their states, the
allowed transitions, and what the hand is sent in each.

The loop (:mod:`slipreflex.rig.runtime`) is in one state of every region at once (the regions are
independent: a silent DAQ and a failing hand port can coincide). It changes a region's state
only through :meth:`LoopStates.take`, which refuses a transition the table does not list, so
the table below is the whole of what can happen. Whatever the states, while a reflex runs the
hand is sent CLOSE (grip the reflex adds, as closing time) and STOP (the end of a closing, a
hold) and nothing else: no OPEN, no position (:mod:`slipreflex.core.grip`).

docs/runtime.md shows :func:`states_markdown`; a test keeps the two the same, and another
drives the loop through every transition.

Examples
--------
>>> s = LoopStates()
>>> s.silent, s[Arrival]
(False, <Arrival.RECEIVING: 'receiving'>)
>>> s.take(Arrival, "no valid sample for the watchdog time").sends
'STOP'
>>> s.silent
True
>>> s.take(Arrival, "no valid sample for the watchdog time")
Traceback (most recent call last):
...
RuntimeError: the loop's states allow no 'no valid sample for the watchdog time' in Arrival.SILENT
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

__all__ = ["Arrival", "Age", "HandPort", "HoldRetry", "StopRetry", "Rise", "FirstFrame", "REGIONS",
           "Transition", "TRANSITIONS", "SENT_WHILE", "LoopStates", "states_markdown"]


class Arrival(Enum):
    """Whether valid DAQ samples arrive (the no-data watchdog).

    Examples
    --------
    >>> Arrival.SILENT.value
    'silent'
    """

    RECEIVING = "receiving"
    SILENT = "silent"


class Age(Enum):
    """Whether the samples the reflex processes are fresh (the staleness check).

    Examples
    --------
    >>> Age.STALE_OWED.value
    'stale, grip owed'
    """

    FRESH = "fresh"
    STALE = "stale"
    STALE_OWED = "stale, grip owed"


class HandPort(Enum):
    """Whether the hand's port takes a CLOSE.

    Examples
    --------
    >>> HandPort.DOWN.value
    'down'
    """

    UP = "up"
    DOWN = "down"


class HoldRetry(Enum):
    """Whether the last hold (the watchdog's, the staleness check's) reached the hand.

    Examples
    --------
    >>> HoldRetry.FAILING.value
    'failing'
    """

    SENT = "sent"
    FAILING = "failing"


class StopRetry(Enum):
    """Whether the last STOP that ends a closing reached the hand.

    Examples
    --------
    >>> StopRetry.FAILING.value
    'failing'
    """

    SENT = "sent"
    FAILING = "failing"


class Rise(Enum):
    """Whether the reflex's command has risen above its start (a command note only).

    Examples
    --------
    >>> Rise.RISEN.value
    'risen'
    """

    AT_START = "at start"
    RISEN = "risen"


class FirstFrame(Enum):
    """Whether the missing first frame has been warned about.

    Examples
    --------
    >>> FirstFrame.WARNED.value
    'warned'
    """

    WAITING = "waiting"
    WARNED = "warned"


#: Every region, in the order the table lists them; the first member of each is its initial state.
REGIONS: tuple[type[Enum], ...] = (Arrival, Age, HandPort, HoldRetry, StopRetry, Rise, FirstFrame)


@dataclass(frozen=True)
class Transition:
    """One allowed change of state.

    Attributes
    ----------
    source, target : Enum
        The states of one region before and after.
    event : str
        What the loop saw.
    sends : str
        What the hand is sent on it: ``"STOP"``, a CLOSE of the grip owed (where some is, and
        the samples are fresh), or ``""`` (nothing).
    fault : str
        The fault kind the loop reports (``""``: none).

    Examples
    --------
    >>> TRANSITIONS[0].fault
    'watchdog'
    """

    source: Enum
    event: str
    target: Enum
    sends: str
    fault: str


_OWED = "CLOSE of the grip owed, if any"

#: The allowed transitions; :meth:`LoopStates.take` refuses any other.
TRANSITIONS: tuple[Transition, ...] = (
    Transition(Arrival.RECEIVING, "no valid sample for the watchdog time", Arrival.SILENT, "STOP", "watchdog"),
    Transition(Arrival.SILENT, "samples again", Arrival.RECEIVING, _OWED, "watchdog-clear"),
    Transition(Age.FRESH, "a sample older than the watchdog", Age.STALE, "STOP", "stale"),
    Transition(Age.STALE, "grip comes while stale", Age.STALE_OWED, "", ""),
    Transition(Age.STALE, "a fresh sample", Age.FRESH, "", "stale-clear"),
    Transition(Age.STALE_OWED, "a fresh sample", Age.FRESH, _OWED, "stale-clear"),
    Transition(HandPort.UP, "a CLOSE fails on the port", HandPort.DOWN, "", "hand-port"),
    Transition(HandPort.DOWN, "a CLOSE goes out", HandPort.UP, "", "hand-port-restored"),
    Transition(HoldRetry.SENT, "a hold fails", HoldRetry.FAILING, "", "hold-failed"),
    Transition(HoldRetry.FAILING, "a hold goes out", HoldRetry.SENT, "", ""),
    Transition(StopRetry.SENT, "the STOP ending a closing fails", StopRetry.FAILING, "", "stop-failed"),
    Transition(StopRetry.FAILING, "a STOP ending a closing goes out", StopRetry.SENT, "", ""),
    Transition(Rise.AT_START, "the command first rises", Rise.RISEN, "", ""),
    Transition(FirstFrame.WAITING, "no valid frame within a second of the start", FirstFrame.WARNED, "",
               "no-data"),
)

#: What the hand is sent while the loop is in each state (on top of the STOP that ends a
#: closing whose time is up, which goes out in every state).
SENT_WHILE: dict[Enum, str] = {
    Arrival.RECEIVING: "the reflex's grip: CLOSE, then STOP when its closing time is up",
    Arrival.SILENT: "STOP, re-sent every watchdog period; no CLOSE until samples return",
    Age.FRESH: "the reflex's grip as it comes",
    Age.STALE: "STOP, re-sent every watchdog period; the reflex's rises are held back",
    Age.STALE_OWED: "STOP, re-sent every watchdog period; the grip held back goes out (CLOSE) with the "
                    "first fresh sample",
    HandPort.UP: "CLOSE as the reflex's grip comes",
    HandPort.DOWN: "the grip owed, CLOSE retried every watchdog period while the samples are fresh",
    HoldRetry.SENT: "nothing more",
    HoldRetry.FAILING: "STOP retried every watchdog period while silent or stale",
    StopRetry.SENT: "nothing more",
    StopRetry.FAILING: "the STOP ending the closing, retried every iteration",
    Rise.AT_START: "nothing: the safe start's STOP holds the fingers",
    Rise.RISEN: "CLOSE for each later rise",
    FirstFrame.WAITING: "nothing: the safe start's STOP holds the fingers",
    FirstFrame.WARNED: "nothing: the safe start's STOP holds the fingers",
}

_TABLE: dict[tuple[Enum, str], Transition] = {(t.source, t.event): t for t in TRANSITIONS}


class LoopStates:
    """The loop's current state in every region; changed only by :meth:`take`.

    Examples
    --------
    >>> s = LoopStates()
    >>> _ = s.take(Age, "a sample older than the watchdog"); _ = s.take(Age, "grip comes while stale")
    >>> s.stale, s[Age]
    (True, <Age.STALE_OWED: 'stale, grip owed'>)
    """

    __slots__ = ("now",)

    def __init__(self) -> None:
        self.now: dict[type[Enum], Enum] = {region: next(iter(region)) for region in REGIONS}

    def __getitem__(self, region: type[Enum]) -> Enum:
        return self.now[region]

    def take(self, region: type[Enum], event: str) -> Transition:
        """Move ``region`` on ``event``, as the table allows; anything else is a bug in the loop."""
        transition = _TABLE.get((self.now[region], event))
        if transition is None:
            raise RuntimeError(f"the loop's states allow no {event!r} in {self.now[region]}")
        self.now[region] = transition.target
        return transition

    @property
    def silent(self) -> bool:
        """No valid sample for the watchdog time."""
        return self.now[Arrival] is Arrival.SILENT

    @property
    def stale(self) -> bool:
        """The last sample processed was older than the watchdog."""
        return self.now[Age] is not Age.FRESH

    @property
    def hand_up(self) -> bool:
        """The hand's port took the last CLOSE."""
        return self.now[HandPort] is HandPort.UP


def states_markdown() -> str:
    """The states and the transitions as docs/runtime.md shows them.

    Examples
    --------
    >>> states_markdown().splitlines()[0]
    '| region | state | what the hand is sent |'
    """
    rows = ["| region | state | what the hand is sent |", "| --- | --- | --- |"]
    rows += [f"| {type(s).__name__} | {s.name} | {SENT_WHILE[s]} |" for region in REGIONS for s in region]
    rows += ["", "| region | from | event | to | sent on it | fault |", "| --- | --- | --- | --- | --- | --- |"]
    rows += [f"| {type(t.source).__name__} | {t.source.name} | {t.event} | {t.target.name} | {t.sends or '-'} "
             f"| {t.fault and f'`{t.fault}`' or '-'} |" for t in TRANSITIONS]
    return "\n".join(rows)
