"""The loop's states as a state machine: every transition of the table is taken by the real loop,
nothing but CLOSE and STOP reaches the hand while a reflex runs, and docs/runtime.md shows the table."""

from __future__ import annotations

import collections
from pathlib import Path

import pytest

from slipreflex.core.errors import DeviceError
from slipreflex.core.interfaces import DaqSample
from slipreflex.rig import loop_states, runtime
from slipreflex.rig.loop_states import REGIONS, TRANSITIONS, LoopStates, states_markdown

POLL, WATCHDOG, PERIOD = 0.01, 0.1, 0.003


class _Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


class _Script:
    """A DAQ in simulated time: each read is one entry ``(seconds it takes, [(age, volts), ...])``;
    a read of ``None`` seconds waits its whole timeout. The board's clock is the PC's, so a sample's
    age when it is processed is the age it was given."""

    def __init__(self, clock):
        self.clock, self.entries, self.seq = clock, [], 0

    def quiet(self, seconds):
        self.entries += [(None, [])] * round(seconds / POLL)

    def fresh(self, seconds, commands=None):
        commands = commands or {}
        self.entries += [(PERIOD, [(0.0, commands.get(k, 0.0))]) for k in range(round(seconds / PERIOD))]

    def frozen(self, seconds, commands=None):
        """The loop stuck for ``seconds``: then the whole backlog at once, the oldest first."""
        commands, n = commands or {}, round(seconds / PERIOD)
        self.entries.append((seconds, [((n - k) * PERIOD, commands.get(k, 0.0)) for k in range(n + 1)]))

    def read(self, timeout):
        dt, batch = self.entries.pop(0) if self.entries else (None, [])
        self.clock.t += timeout if dt is None else dt
        out = []
        for age, volts in batch:
            self.seq += 1
            out.append(DaqSample(self.seq, self.clock.t - age, volts, None, 0))
        return out

    def close(self):
        pass


class _Hand:
    """Logs every command the loop tries (sent or failed); its port and its holds fail in windows."""

    def __init__(self, clock):
        self.clock, self.log, self.running = clock, [], False
        self.port_down: list[tuple[float, float]] = []
        self.hold_down: list[tuple[float, float]] = []

    def _failing(self, windows):
        return any(a <= self.clock.t < b for a, b in windows)

    def set_positions(self, targets):
        self.log.append(("POSITION", self.running))

    def close_fingers(self, fingers, speed):
        self.log.append(("CLOSE", self.running))
        if self._failing(self.port_down):
            raise DeviceError("hand port lost")

    def hold(self, fingers):
        self.log.append(("STOP", self.running))
        if self._failing(self.hold_down):
            raise DeviceError("hand port busy")

    def positions(self):
        return {}

    def reflex_running(self, running):
        self.running = running


class _Echo:
    """Commands what the sample says (0 V: no command), so the script decides every rise."""

    name, input_kind, fs, command = "echo", "slip", 1 / PERIOD, 100.0
    last_event, last_filtered, last_threshold, last_count = False, 0.0, None, None

    def step(self, volts, position=None):
        return volts if volts > 0 else None

    def reset(self):
        pass


def _walk(monkeypatch):
    """One run through every transition; returns the run, the hand and (transition, hand log length)."""
    clock = _Clock()
    src, hand = _Script(clock), _Hand(clock)
    taken = []

    class Recorded(LoopStates):
        def take(self, region, event):
            t = super().take(region, event)
            taken.append((t, len(hand.log)))
            return t

    monkeypatch.setattr(runtime, "LoopStates", Recorded)
    src.quiet(1.05)                                   # silent: the watchdog, then the first-second warning
    src.fresh(0.3, {10: 150.0})                       # samples again; the first rise, sent
    src.frozen(0.3, {5: 200.0})                       # a backlog: stale, a rise while stale, fresh again
    src.fresh(0.3)
    src.frozen(0.3)                                   # stale and fresh again, nothing owed
    t_port = 1.05 + 0.3 + 0.3 + 0.3 + 0.3
    src.fresh(0.5, {30: 250.0})                       # the CLOSE fails on the port; retried until it is back
    hand.port_down.append((t_port + 0.05, t_port + 0.25))
    t_hold = t_port + 0.5
    src.fresh(0.2, {5: 300.0})                        # a closing whose ending STOP fails ...
    src.quiet(0.5)                                    # ... and the watchdog's holds fail too, for a while
    hand.hold_down.append((t_hold + 0.05, t_hold + 0.5))
    src.fresh(0.1)
    duration = t_hold + 0.2 + 0.5 + 0.1
    res = runtime.run_loop(src, hand, _Echo(), duration=duration, watchdog=WATCHDOG, poll=POLL, clock=clock,
                           guard=False)
    return res, hand, taken


def test_the_loop_takes_every_transition_and_sends_only_close_and_stop_while_a_reflex_runs(monkeypatch):
    res, hand, taken = _walk(monkeypatch)
    missed = [f"{t.source} --{t.event}--> {t.target}" for t in TRANSITIONS if t not in {t for t, _ in taken}]
    assert not missed, f"transitions never taken: {missed}"
    during = [cmd for cmd, running in hand.log if running]
    assert during and set(during) <= {"CLOSE", "STOP"}
    assert "POSITION" not in {cmd for cmd, _ in hand.log}
    assert {"CLOSE", "STOP"} <= set(during)
    for t, at in taken:  # a transition that sends STOP: the very next command the hand gets is it
        if t.sends == "STOP":
            assert hand.log[at][0] == "STOP", f"{t.event}: next command {hand.log[at]}"
    # every fault of the table's kinds came from a transition of the table, one each
    kinds = {t.fault for t in TRANSITIONS if t.fault}
    assert collections.Counter(t.fault for t, _ in taken if t.fault) == \
        collections.Counter(f.kind for f in res.faults if f.kind in kinds)


def test_every_state_is_reachable_and_every_region_starts_in_its_first_state():
    reached = {t.target for t in TRANSITIONS} | {next(iter(region)) for region in REGIONS}
    assert reached == {s for region in REGIONS for s in region}
    assert all(t.source in loop_states.SENT_WHILE and t.target in loop_states.SENT_WHILE for t in TRANSITIONS)
    assert len({(t.source, t.event) for t in TRANSITIONS}) == len(TRANSITIONS)


def test_a_transition_the_table_does_not_list_is_refused():
    s = LoopStates()
    with pytest.raises(RuntimeError, match="allow no 'a fresh sample'"):
        s.take(loop_states.Age, "a fresh sample")
    assert s[loop_states.Age] is loop_states.Age.FRESH


def test_docs_runtime_shows_the_table_the_loop_runs():
    text = (Path(__file__).resolve().parents[2] / "docs" / "runtime.md").read_text(encoding="utf-8")
    begin, end = "<!-- loop states table begins -->\n", "\n<!-- loop states table ends -->"
    assert begin in text and end in text
    assert text.split(begin, 1)[1].split(end, 1)[0].strip() == states_markdown()
