"""Device contracts declared, not probed: the loop reads nothing of a source, a hand or a reflex that
interfaces.CONTRACTS does not declare, reads the optional ones through one function, and the
conformance checkers hold the drivers to it."""

from __future__ import annotations

from pathlib import Path

import pytest
import serial

from slipreflex.core.errors import ParameterError
from slipreflex.core.hardware import Finger
from slipreflex.core.interfaces import (
    CONTRACTS,
    DaqSample,
    Hand,
    Reflex,
    SampleSource,
    contract_markdown,
    missing,
    optional,
)
from slipreflex.methods.chain import SlipReflex
from slipreflex.rig.devices import wire
from slipreflex.rig.devices.daq import SerialDaq
from slipreflex.rig.hands import open_hand
from slipreflex.rig.runtime import run_loop
from slipreflex.testing import ContractError, check_hand, check_reflex, check_source


class _Spy:
    """Passes every attribute through to ``target`` and notes its name."""

    def __init__(self, target, seen):
        object.__setattr__(self, "_target", target)
        object.__setattr__(self, "_seen", seen)

    def __getattr__(self, name):
        if name.startswith("__") or name in ("_target", "_seen"):
            raise AttributeError(name)
        self._seen.add(name)
        return getattr(self._target, name)


class _Counters:
    def to_dict(self):
        return {"crc_errors": 0, "resets": 0}


class _Source:
    """64 samples of a still surface, then nothing, in simulated time; every optional member."""

    port_name, stats, last_arrival = "spy-daq", _Counters(), float("nan")

    def __init__(self):
        self.left, self.now = [DaqSample(k, k * 0.003, 0.4, None, 0) for k in range(64)], 0.0

    def read(self, timeout):
        self.now += 0.024 if self.left else timeout
        out, self.left = self.left[:8], self.left[8:]
        return out

    def drop_buffered(self):
        return 0

    def close(self):
        pass


class _Hand:
    def __init__(self):
        self.running = []

    def set_positions(self, targets):
        raise AssertionError("the loop sent a position")

    def close_fingers(self, fingers, speed):
        pass

    def hold(self, fingers):
        pass

    def positions(self):
        return {}

    def reflex_running(self, on):
        self.running.append(on)

    def stalled(self):
        return frozenset()

    def close(self):
        pass


def _declared(protocol):
    return {m.name.split(".")[0] for m in CONTRACTS[protocol]}


def test_the_loop_reads_only_declared_members_of_the_source_the_hand_and_the_reflex():
    seen = {"source": set(), "hand": set(), "reflex": set()}
    src, hand = _Source(), _Hand()
    res = run_loop(_Spy(src, seen["source"]), _Spy(hand, seen["hand"]),
                   _Spy(SlipReflex(p0=200.0), seen["reflex"]), duration=0.5, clock=lambda: src.now, guard=False)
    assert res.samples == 64
    for who, protocol in (("source", SampleSource), ("hand", Hand), ("reflex", Reflex)):
        undeclared = seen[who] - _declared(protocol)
        assert not undeclared, f"the loop read undeclared members of the {who}: {sorted(undeclared)}"
    # the optional members are read where they exist: the guard switched on and off, stalls asked for
    assert hand.running == [True, False]
    assert {"reflex_running", "stalled"} <= seen["hand"]
    assert {"last_arrival", "stats", "drop_buffered"} <= seen["source"]


def test_an_optional_member_is_its_value_or_its_declared_default_and_nothing_else_is_read():
    assert optional(object(), SampleSource, "port_name") == "the DAQ port"
    assert optional(SlipReflex(p0=120.0), Reflex, "command") == 120.0
    assert optional(object(), Reflex, "params.hi") == 500.0
    assert optional(_Source(), SampleSource, "port_name") == "spy-daq"
    with pytest.raises(KeyError, match="declares no optional member 'read'"):
        optional(_Source(), SampleSource, "read")  # required: read directly, never defaulted
    with pytest.raises(KeyError):
        optional(_Hand(), Hand, "open_fingers")
    assert missing(object(), Hand) == ["set_positions", "close_fingers", "hold", "positions"]


def test_a_reflex_without_a_member_the_loop_reads_is_refused_before_anything_is_sent():
    class Nameless:
        input_kind = "slip"
        command = 100.0

        def step(self, x, position=None):
            return None

    hand = _Hand()
    hand.hold = lambda fingers: pytest.fail("a STOP went out")
    with pytest.raises(ParameterError, match="the reflex has no name, last_event, last_filtered"):
        run_loop(_Source(), hand, Nameless(), duration=0.1)


def test_docs_runtime_lists_the_contracts_the_loop_uses():
    text = (Path(__file__).resolve().parents[2] / "docs" / "runtime.md").read_text(encoding="utf-8")
    begin, end = "<!-- contracts table begins -->\n", "\n<!-- contracts table ends -->"
    assert begin in text and end in text
    assert text.split(begin, 1)[1].split(end, 1)[0].strip() == contract_markdown()


def test_the_drivers_keep_their_contracts():
    with open_hand("ilimb", serial.serial_for_url("loop://")) as hand:
        check_hand(hand)
    daq = SerialDaq(serial.serial_for_url("loop://"))
    try:
        daq._port.write(b"".join(wire.encode_sample(DaqSample(k, 0.0, 0.4, None, 0)) for k in range(3)))
        assert check_source(daq, timeout=0.05) >= 0
    finally:
        daq.close()
    check_reflex(SlipReflex(p0=100.0))


def test_the_checkers_name_a_broken_member():
    class Stalls(_Hand):
        def stalled(self):
            return ["the ring finger"]

    with pytest.raises(ContractError, match="stalled"):
        check_hand(Stalls())

    class NoStats(_Source):
        stats = object()

    with pytest.raises(ContractError, match="to_dict"):
        check_source(NoStats())

    class Offset(SlipReflex):
        finger_offsets = {Finger.MIDDLE: float("inf")}

    with pytest.raises(ContractError, match="finger_offsets"):
        check_reflex(Offset(p0=100.0))
