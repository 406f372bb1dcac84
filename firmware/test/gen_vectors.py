"""Regenerate tests/data/wire/vectors.txt (the committed file is what tests read).

Run from the repository root:  python3 firmware/test/gen_vectors.py > tests/data/wire/vectors.txt

The Python tests check the committed file against slipreflex.rig.devices.wire; the C
host test (firmware/test/test_vectors.c) checks it against the firmware's own
encoder and an independent CRC, so a change on either side shows up as a failure.
"""

from __future__ import annotations

import sys

from slipreflex.rig.devices import wire

HEADER = """\
# Wire-protocol test vectors of the slipreflex DAQ board (docs/wire-protocol.md).
# Read by tests/test_wire.py (Python) and firmware/test/test_vectors.c (C).
# One record per line, fields separated by single spaces; '#' starts a comment line.
#
# F <name> <hex> <seq> <flags> <adc> <ax> <ay> <az> <flow>
#     One good frame and its decoded fields (decimal).
# R <name> <hex> <seq> <flags> <adc> <ax> <ay> <az> <flow> <bits> <v> <command> <x>
#     One good version-2 frame (board running the reflex) and its decoded fields.
# B <name> <hex> <reason>
#     Bytes that decode_frame() must reject; reason is one of
#     truncated (not the 20 or 28 bytes the version byte asks for), sync, crc,
#     version, adc.
# S <name> <hex> <frames> <crc_errors> <truncated> <invalid> <garbage_bytes> <resyncs> <seq_gaps> <frames_lost> <seqs>
#     A byte stream fed to FrameParser.feed() in one piece, then flush(); the
#     expected counters and the seq of every good frame, comma-separated
#     ('-' when none). <hex> is '-' for an empty stream.
"""


def flip(raw: bytes, index: int, mask: int = 0x01) -> bytes:
    b = bytearray(raw)
    b[index] ^= mask
    return bytes(b)


def forged(version: int = wire.VERSION, adc: int = 0, seq: int = 0) -> bytes:
    """A frame with a correct CRC but content a good board never sends."""
    body = bytes([version]) + seq.to_bytes(2, "little") + b"\x00" + adc.to_bytes(2, "little") \
        + bytes(10)
    return wire.SYNC + body + wire.crc16(body).to_bytes(2, "big")


def main(out=sys.stdout) -> None:
    enc = wire.encode_frame
    p = out.write
    p(HEADER)
    good = [
        ("zero", dict(seq=0, adc=0)),
        ("basic", dict(seq=1, adc=512)),
        ("accel_1g_z", dict(seq=2, adc=100, accel=(0, 0, 16384), flow_pulses=1)),
        ("accel_extremes", dict(seq=3, adc=1023, accel=(-32768, 32767, -1), flow_pulses=450)),
        ("seq_max", dict(seq=65535, adc=77, accel=(1, -2, 3), flow_pulses=123456)),
        ("flow_max", dict(seq=4660, adc=682, flow_pulses=2**32 - 1)),
        ("imu_error", dict(seq=9, adc=68, flags=wire.FLAG_IMU_ERROR)),
        ("overrun", dict(seq=10, adc=1, accel=(100, 200, 300), flags=wire.FLAG_OVERRUN)),
        ("sync_in_payload", dict(seq=0x5AA5, adc=0x1A5, accel=(0x5AA5, 0x5AA5, -23131),
                                 flow_pulses=0x5AA55AA5)),
    ]
    frames = {}
    for name, kw in good:
        raw = enc(**kw)
        frames[name] = raw
        f = wire.decode_frame(raw)
        p(f"F {name} {raw.hex()} {f.seq} {f.flags} {f.adc} {f.accel[0]} {f.accel[1]} "
          f"{f.accel[2]} {f.flow_pulses}\n")
    RF = wire.ReflexFields
    good2 = [
        ("reflex_quiet", dict(seq=0, adc=300), RF(0, 0, 0, 300 << 16)),
        ("reflex_spike_window", dict(seq=47, adc=305, accel=(10, -20, 16384), flow_pulses=3),
         RF(wire.REFLEX_SPIKE | wire.REFLEX_WINDOW, 3, 40, 19988480)),
        ("reflex_hand", dict(seq=65535, adc=1023, flow_pulses=2**32 - 1),
         RF(wire.REFLEX_SPIKE | wire.REFLEX_WINDOW | wire.REFLEX_HAND, 16, 500, 67043328)),
        ("reflex_fault_negative", dict(seq=9, adc=0, flags=wire.FLAG_IMU_ERROR),
         RF(wire.REFLEX_FAULT, 0, -32768, -2**31)),
    ]
    for name, kw, r in good2:
        raw = enc(**kw, reflex=r)
        frames[name] = raw
        f = wire.decode_frame(raw)
        p(f"R {name} {raw.hex()} {f.seq} {f.flags} {f.adc} {f.accel[0]} {f.accel[1]} "
          f"{f.accel[2]} {f.flow_pulses} {f.reflex.bits} {f.reflex.v} {f.reflex.command} "
          f"{f.reflex.x}\n")
    b = frames["accel_1g_z"]
    b2 = frames["reflex_spike_window"]
    bad = [
        ("empty", b"", "truncated"),
        ("sync_only", b[:2], "truncated"),
        ("cut_19", b[:19], "truncated"),
        ("too_long", b + b"\x00", "truncated"),
        ("bad_sync0", flip(b, 0), "sync"),
        ("bad_sync1", flip(b, 1, 0x80), "sync"),
        ("crc_low_bit", flip(b, 19), "crc"),
        ("crc_high_bit", flip(b, 18, 0x80), "crc"),
        ("payload_bit", flip(b, 7, 0x10), "crc"),
        ("seq_bit", flip(b, 3), "crc"),
        ("version_3", forged(version=3), "version"),
        ("adc_1024", forged(adc=1024), "adc"),
        ("v2_cut_20", b2[:20], "truncated"),
        ("v2_cut_27", b2[:27], "truncated"),
        ("v2_crc_low_bit", flip(b2, 27), "crc"),
        ("v2_command_bit", flip(b2, 20, 0x02), "crc"),
        ("v2_as_v1", b2[:2] + b"\x01" + b2[3:], "truncated"),
    ]
    for name, raw, reason in bad:
        p(f"B {name} {raw.hex() or '-'} {reason}\n")

    def seqs(*ss: int) -> list[bytes]:
        return [enc(seq=s, adc=s % 1024, accel=(s % 4096, -(s % 4096), 16384) if s % 2 else None,
                    flow_pulses=s // 3) for s in ss]

    a0, a1, a2, a3 = seqs(100, 101, 102, 103)
    w = seqs(65534, 65535, 0, 1)
    sp = [enc(seq=0x5AA5 + k, adc=0x1A5, accel=(0x5AA5, 0x5AA5, 0x5AA5),
              flow_pulses=0x5AA55AA5) for k in range(3)]
    streams = [
        ("empty", b""),
        ("one", a0),
        ("clean", a0 + a1 + a2),
        ("leading_garbage", b"\x00\xff\xa5\x13" + a0 + a1),
        ("lone_sync_bytes", b"\xa5\xa5\x5a\x5a" + a0),
        ("garbage_only", bytes(range(0, 250, 7))),
        ("trailing_garbage", a0 + a1 + b"\x42\x42\x42"),
        ("bad_crc_middle", a0 + flip(a1, 19) + a2),
        ("bad_payload_middle", a0 + flip(a1, 9, 0x40) + a2),
        ("bad_sync_middle", a0 + flip(a1, 0) + a2),
        ("truncated_middle", a0 + a1[:9] + a2),
        ("truncated_before_last", a0 + a1[:19] + a2),
        ("truncated_sync_only", a0 + a1[:2] + a2),
        ("truncated_end", a0 + a1[:12]),
        ("truncated_end_sync_only", a0 + a1[:2]),
        ("lone_a5_end", a0 + b"\xa5"),
        ("wraparound", b"".join(w)),
        ("gap", a0 + a3),
        ("gap_across_wrap", w[1] + seqs(3)[0]),
        ("duplicate", a0 + a0),
        ("restart", a2 + seqs(0)[0]),
        ("late", a0 + a2 + a1 + a3),
        ("sync_in_payload", b"".join(sp)),
        ("sync_in_payload_bad_crc", sp[0] + flip(sp[1], 18) + sp[2]),
        ("sync_in_payload_truncated", sp[0] + sp[1][:10] + sp[2]),
        ("invalid_version", a0 + forged(version=3, seq=101) + a2),
        ("invalid_adc", a0 + forged(adc=2000, seq=101) + a2),
        ("doubled_sync", b"\xa5\x5a" + a0),
        ("v2_clean", b"".join(enc(seq=k, adc=300 + k, reflex=RF(k % 2, 0, k, (300 + k) << 16))
                              for k in range(3))),
        ("v1_then_v2", a0 + enc(seq=101, adc=5, reflex=RF(0, 0, 7, 5 << 16)) + a2),
        ("v2_bad_crc_middle", a0 + flip(enc(seq=101, adc=5, reflex=RF(0, 0, 7, 5 << 16)), 25)
         + a2),
        ("v2_truncated_middle", a0 + enc(seq=101, adc=5, reflex=RF(0, 0, 7, 5 << 16))[:22] + a2),
        ("v2_truncated_end", a0 + enc(seq=101, adc=5, reflex=RF(0, 0, 7, 5 << 16))[:27]),
    ]
    for name, data in streams:
        parser = wire.FrameParser()
        got = parser.feed(data) + parser.flush()
        s = parser.stats
        assert s.bytes_fed == sum(wire.FRAME_LEN_REFLEX if f.reflex else wire.FRAME_LEN
                                  for f in got) + s.garbage_bytes + s.dropped_bytes + s.pending
        seq_list = ",".join(str(f.seq) for f in got) or "-"
        p(f"S {name} {data.hex() or '-'} {s.frames} {s.crc_errors} {s.truncated} {s.invalid} "
          f"{s.garbage_bytes} {s.resyncs} {s.seq_gaps} {s.frames_lost} {seq_list}\n")


if __name__ == "__main__":
    main()
