"""The i-Limb port's write: a packet that went out whole is never a write timeout (pyserial
issue #281, seen as a flaky "Write timeout" of test_virtual under load); a port that stopped
draining still times out."""

from __future__ import annotations

import os
import select
import time

import pytest

from slipreflex.core.errors import DeviceError
from slipreflex.core.hardware import Finger
from slipreflex.rig.devices.ilimb import ILimb, PacketParser
from slipreflex.rig.devices.virtual import PtyPort


def test_a_packet_written_whole_is_sent_even_if_the_thread_lost_the_cpu_after_it(monkeypatch):
    port = PtyPort()
    hand = ILimb(port.path, write_timeout=0.01)
    fd = hand._port.serial.fd
    real_write = os.write

    def descheduled(f, data):
        n = real_write(f, data)
        if f == fd:
            time.sleep(0.03)  # the writing thread loses the CPU for 30 ms just after the write
        return n

    monkeypatch.setattr(os, "write", descheduled)
    try:
        hand.set_positions({Finger.MIDDLE: 150})
        assert hand.write_failures == 0 and hand.connected and hand.packets_sent == 1
        assert select.select([port.master], [], [], 5.0)[0]  # awaits the pty's transfer
        packets = PacketParser().feed(port.read())
        assert [(c.finger, c.value) for p in packets for c in p] == [(Finger.MIDDLE, 150)]
    finally:
        monkeypatch.undo()
        hand.close()
        port.close()


def test_a_hand_port_that_stopped_draining_still_times_out():
    port = PtyPort()  # nobody reads the master: the pty's buffer fills
    hand = ILimb(port.path, write_timeout=0.01)
    try:
        with pytest.raises(DeviceError, match=r"write failed: Write timeout \(\d+ of 15 bytes not written\)"):
            for _ in range(100_000):
                hand.set_positions({Finger.THUMB: 100, Finger.INDEX: 100, Finger.MIDDLE: 100})
        assert hand.write_failures == 1 and not hand.connected
    finally:
        hand.close()
        port.close()
