"""The i-Limb protocol and driver: encoding, validation, parsing, reconnection, grasp."""

from __future__ import annotations

import random
import time

import pytest
import serial

from slipreflex.core import hardware as hw
from slipreflex.core.errors import DeviceError, ParameterError
from slipreflex.core.hardware import Finger, HandCommand
from slipreflex.rig.devices.ilimb import FingerCommand, GraspResult, ILimb, PacketParser, encode_packet, tripod_grasp
from slipreflex.rig.devices.virtual import PtyPort


def test_packet_layout_follows_spec():
    pkt = encode_packet([FingerCommand(Finger.THUMB, HandCommand.POSITION, 300),
                         FingerCommand(Finger.INDEX, HandCommand.CLOSE, 297)])
    assert pkt[0] == hw.ILIMB_START and pkt[-1] == hw.ILIMB_END
    assert pkt[1] == 8 == len(pkt) - 3
    assert list(pkt[2:6]) == [0, 3, 300 >> 8, 300 & 0xFF]
    assert list(pkt[6:10]) == [1, 1, 297 >> 8, 297 & 0xFF]


@pytest.mark.parametrize("finger,command,value", [
    (7, 3, 0), (-1, 3, 0), (1, 4, 0), (1, 3, hw.FINGER_MAX + 1), (1, 3, -1),
    (Finger.THUMB_ROTATOR, 3, hw.THUMB_ROTATOR_MAX + 1), (1, 1, hw.PWM_MAX + 1), (1, 2, -5),
    (1, 0, 1), (Finger.WRIST, 3, 10), (1, 3, 1.5), (1, 3, float("nan")), (1, 3, True), (1, 3, "5"),
])
def test_invalid_commands_are_rejected(finger, command, value):
    with pytest.raises(ParameterError, match="i-Limb"):
        FingerCommand(finger, command, value)


def test_valid_extremes_are_accepted():
    assert FingerCommand(Finger.THUMB_ROTATOR, 3, hw.THUMB_ROTATOR_MAX).value == 750
    assert FingerCommand(Finger.LITTLE, 3, hw.FINGER_MAX).value == 500
    assert FingerCommand(Finger.WRIST, 2, hw.PWM_MAX).value == 297
    assert FingerCommand(1, 3, 250.0).value == 250


def test_packet_level_validation():
    with pytest.raises(ParameterError, match="at least one"):
        encode_packet([])
    with pytest.raises(ParameterError, match="twice"):
        encode_packet([FingerCommand(1, 3, 1), FingerCommand(1, 3, 2)])


def test_nothing_is_sent_for_an_out_of_range_target():
    loop = serial.serial_for_url("loop://", timeout=0)
    hand = ILimb(loop)
    with pytest.raises(ParameterError, match="MIDDLE"):
        hand.set_positions({Finger.INDEX: 100, Finger.MIDDLE: 600})
    with pytest.raises(ParameterError, match="unknown finger"):
        hand.set_positions({9: 100})
    assert loop.read(100) == b""
    assert hand.positions() == {}  # a rejected command does not change the grip
    hand.set_positions({Finger.MIDDLE: 499.5})
    assert PacketParser().feed(loop.read(100))[0][0].value == 500
    loop.close()


def test_parser_roundtrip_with_garbage_truncation_and_bit_flips():
    rng = random.Random(1)
    sent = []
    stream = bytearray()
    for k in range(300):
        fingers = rng.sample(list(Finger), rng.randint(1, 7))
        cmds = tuple(FingerCommand(f, HandCommand.POSITION, rng.randint(0, 500))
                     if f != Finger.WRIST else FingerCommand(f, HandCommand.STOP, 0) for f in fingers)
        pkt = encode_packet(cmds)
        sent.append(cmds)
        stream += pkt
        if k % 10 == 3:
            stream += bytes(rng.randrange(256) for _ in range(rng.randint(1, 9)))  # garbage
    p = PacketParser()
    got = []
    i = 0
    while i < len(stream):  # arbitrary cuts
        n = rng.randint(1, 40)
        got += p.feed(bytes(stream[i:i + n]))
        i += n
    assert got == sent  # garbage between packets never loses or invents a packet
    assert p.skipped_bytes > 0

    # A truncated packet followed by a good one: the good one survives.
    good = encode_packet([FingerCommand(2, 3, 123)])
    q = PacketParser()
    assert q.feed(good[:4] + good) == [(FingerCommand(2, 3, 123),)]

    # Bit flips: the parser never raises and only returns valid commands.
    flipped = bytearray(stream)
    for _ in range(200):
        flipped[rng.randrange(len(flipped))] ^= 1 << rng.randrange(8)
    r = PacketParser()
    out = r.feed(bytes(flipped))
    assert all(isinstance(c, FingerCommand) for pkt in out for c in pkt)
    assert r.rejected > 0 and len(out) < len(sent)


def _packets(port, n, timeout=10.0):
    """The next ``n`` packets from the pty, awaiting each one (the tty layer passes bytes on
    asynchronously: one read right after the write may find only part of them)."""
    import select

    parser, out = PacketParser(), []
    deadline = time.monotonic() + timeout
    while len(out) < n:
        left = deadline - time.monotonic()
        assert left > 0, f"got {len(out)} of {n} packets"
        if select.select([port.master], [], [], left)[0]:
            out += parser.feed(port.read())
    return out


def test_hand_port_that_disappears_and_comes_back(tmp_path):
    port = PtyPort(link=str(tmp_path / "hand"))
    hand = ILimb(port.path, reconnect_interval=0.0)
    try:
        hand.set_positions({f: 200 for f in hw.TRIPOD})
        assert len(_packets(port, 1)) == 1
        port.unplug()
        with pytest.raises(DeviceError, match="hand"):
            hand.set_positions({f: 210 for f in hw.TRIPOD})
        assert not hand.connected
        with pytest.raises(DeviceError, match="not connected"):
            hand.set_positions({f: 215 for f in hw.TRIPOD})
        port.replug()
        hand.set_positions({Finger.MIDDLE: 220})
        packets = _packets(port, 2)
        # First the whole grip is restored (latest targets), then the new command.
        assert [{c.finger: c.value for c in p} for p in packets] == [
            {Finger.THUMB: 215, Finger.INDEX: 215, Finger.MIDDLE: 220}, {Finger.MIDDLE: 220}]
        assert hand.reconnects == 1 and hand.write_failures == 1
    finally:
        hand.close()
        port.close()


def test_open_failure_names_the_port(tmp_path):
    with pytest.raises(DeviceError, match="nope"):
        ILimb(str(tmp_path / "nope"))


def test_hold_sends_stop_not_open():
    loop = serial.serial_for_url("loop://", timeout=0)
    ILimb(loop).hold()
    (pkt,) = PacketParser().feed(loop.read(100))
    assert {c.command for c in pkt} == {HandCommand.STOP}
    assert {c.finger for c in pkt} == set(hw.TRIPOD)
    loop.close()


class _ToyHand:
    """Fingers that reach their target after one settle; contact from position 180 on."""

    def __init__(self):
        self.targets = {}
        self.pos = 0.0

    def set_positions(self, targets):
        assert set(targets) == set(hw.TRIPOD)
        self.targets.update(targets)

    def settle(self):
        self.pos = max(self.targets.values())

    def force(self):
        return max(0.0, (self.pos - 180.0) * 0.05)


def test_tripod_grasp_stops_at_contact_force():
    h = _ToyHand()
    res = tripod_grasp(h, h.force, settle=h.settle, step=4.0)
    assert isinstance(res, GraspResult) and res.contact
    assert res.force_n >= hw.CONTACT_FORCE_N
    assert h.force() >= hw.CONTACT_FORCE_N and (res.position - 4.0 - 180.0) * 0.05 < hw.CONTACT_FORCE_N
    nothing = tripod_grasp(_ToyHand(), lambda: 0.0, step=100.0)
    assert not nothing.contact and nothing.position == hw.FINGER_MAX
    with pytest.raises(ParameterError):
        tripod_grasp(h, h.force, step=0.0)

