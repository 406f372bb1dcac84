"""SerialDaq: the wire parser behind a port; garbage, truncation, bit flips, gaps, port loss."""

from __future__ import annotations

import random
import time

import pytest
import serial

from slipreflex.core import hardware as hw
from slipreflex.core.errors import DeviceError
from slipreflex.rig.devices import wire
from slipreflex.rig.devices.daq import DaqStats, SerialDaq
from slipreflex.rig.devices.virtual import PtyPort


def _frames(seqs, adc=300):
    return [wire.encode_frame(seq=s, adc=adc + (s % 7), accel=(0, 0, 16384) if s % 4 == 0 else None,
                              flow_pulses=s // 10) for s in seqs]


def _read_all(daq, deadline_s=2.0, want=None):
    out = []
    deadline = time.monotonic() + deadline_s
    while time.monotonic() < deadline:
        got = daq.read(0.01)
        out += got
        if want is not None and len(out) >= want:
            break
        if want is None and not got:
            break
    return out


def test_clean_stream_decodes_to_samples():
    loop = serial.serial_for_url("loop://")
    daq = SerialDaq(loop)
    loop.write(b"".join(_frames(range(10))))
    got = _read_all(daq, want=10)
    assert [s.seq for s in got] == list(range(10))
    assert got[4].accel_g == (0.0, 0.0, 1.0) and got[5].accel_g is None
    assert got[3].slip_volts == pytest.approx((300 + 3) * hw.ADC_LSB)
    assert got[9].t == pytest.approx(9 * hw.DAQ_PERIOD_S)
    assert daq.stats == DaqStats(wire.ParserStats(bytes_fed=10 * wire.FRAME_LEN, frames=10))
    daq.close()
    loop.close()


def test_garbage_truncation_bitflips_and_seq_jump_are_survived_and_counted():
    rng = random.Random(3)
    frames = _frames(range(100))
    stream = bytearray(b"\x00\xa5\x5a\xff garbage")
    for k, f in enumerate(frames):
        if k == 20:
            stream += f[:9]  # truncated frame (this sample is lost)
            continue
        if k == 40:
            f = bytearray(f)
            f[7] ^= 0x10  # bit flip: CRC failure
            f = bytes(f)
        if k == 60:
            stream += bytes(rng.randrange(256) for _ in range(13))
        stream += f
    stream += b"".join(_frames([500, 501]))  # sequence jump
    loop = serial.serial_for_url("loop://")
    daq = SerialDaq(loop)
    got = []
    i = 0
    while i < len(stream):
        n = rng.randint(1, 60)
        loop.write(bytes(stream[i:i + n]))
        i += n
        got += daq.read(0.0)
    got += _read_all(daq)
    seqs = [s.seq for s in got]
    assert seqs == [s for s in range(100) if s not in (20, 40)] + [500, 501]
    st = daq.stats
    assert st.truncated >= 1 and st.crc_errors >= 1
    assert st.seq_gaps == 3  # 19->21, 39->41, 99->500
    assert st.frames_lost == 2 + 400
    assert st.garbage_bytes > 0 and st.resyncs >= 3
    # Times stay monotonic across the jump (the parser unwraps the index).
    ts = [s.t for s in got]
    assert all(b > a for a, b in zip(ts, ts[1:]))
    daq.close()
    loop.close()


def test_read_never_blocks_longer_than_its_timeout_on_silence():
    loop = serial.serial_for_url("loop://")
    daq = SerialDaq(loop)
    assert daq.read(0.0) == []
    assert daq.read(0.02) == []
    daq.close()
    loop.close()


def test_daq_port_that_disappears_and_comes_back(tmp_path):
    port = PtyPort(link=str(tmp_path / "daq"))
    daq = SerialDaq(port.path, reconnect_interval=0.0)
    try:
        port.write(b"".join(_frames(range(5))))
        assert [s.seq for s in _read_all(daq, want=5)] == list(range(5))
        port.unplug()
        with pytest.raises(DeviceError, match="DAQ port lost"):
            deadline = time.monotonic() + 2.0
            while time.monotonic() < deadline:
                daq.read(0.01)
        assert not daq.connected
        assert daq.read(0.01) == []  # still gone: no error, no samples
        port.replug()
        deadline = time.monotonic() + 2.0
        got = []
        while time.monotonic() < deadline and not got:
            port.write(b"".join(_frames([0, 1])))  # a restarted board counts from 0
            got = daq.read(0.01)
        assert got and got[0].seq in (0, 1)
        st = daq.stats
        assert st.disconnects == 1 and st.reconnects == 1
    finally:
        daq.close()
        port.close()


def test_open_failure_names_the_port(tmp_path):
    with pytest.raises(DeviceError, match="missing"):
        SerialDaq(str(tmp_path / "missing"))


def test_a_port_in_use_is_refused_with_a_clear_error():
    from slipreflex.rig.devices.ilimb import ILimb

    port = PtyPort()
    first = SerialDaq(port.path)
    try:
        with pytest.raises(DeviceError, match="exclusively lock"):
            SerialDaq(port.path)
        with pytest.raises(DeviceError, match="i-Limb"):
            ILimb(port.path)  # e.g. --daq and --hand swapped onto the same device
    finally:
        first.close()
        port.close()
