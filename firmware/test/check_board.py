"""Check the reflex a board ran under simavr against its Python twin, and its hand packets.

    python3 firmware/test/check_board.py OUTDIR [--fixed] [--p0 N]

Reads a harness capture (firmware/test/harness.c) of a firmware built with the reflex
on board (daq-reflex.elf, or hand2560.elf run with --mcu atmega2560), decodes its
version-2 frames with slipreflex.rig.devices.wire and runs slipreflex.methods.board on the ADC
counts the harness injected, with the parameters that firmware was built with
(BoardParams.firmware). It checks that

- every frame carries the twin's filtered sample (Q16), spike, fault, window flag,
  window count and command for its sample: bit-exact, on every sample;
- (with uart1.bin, the standalone build) the bytes on UART1 are valid i-Limb packets
  (slipreflex.rig.devices.ilimb.PacketParser), each a CLOSE at full PWM or a STOP for
  thumb, index and middle, never an OPEN or a POSITION; the first is the STOP every
  start sends, before the first sample; the packets are exactly those the grip-only
  rule predicts from the twin (slipreflex.methods.board.board_hand: CLOSE when a rise owes
  closing time, STOP when it is up or a fault starts), at the same samples; every
  frame flagged HAND matches one packet; each packet's first byte leaves within 1 ms
  (16,000 cycles) of the start of its sample's conversion; and every closing with no
  fault lasts, from CLOSE's first byte to STOP's, g / 625 s rounded up to whole
  samples (within 400 cycles of jitter).

Exit status 0 when every check passes.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from slipreflex.methods import board
from slipreflex.core import hardware
from slipreflex.rig.devices import ilimb, wire

#: Latency bound from the completing sample's conversion start to the packet's first byte.
LATENCY_LIMIT_CYCLES = hardware.F_CPU // 1000
#: CPU cycles per 3 ms sample.
PERIOD_CYCLES = round(hardware.F_CPU * hardware.DAQ_PERIOD_S)
#: How much two packets' latencies may differ (conversion-start jitter, interrupt order).
CLOSING_JITTER_CYCLES = 400


@dataclass
class BoardReport:
    """What :func:`check` found; ``errors`` is empty when the capture passes."""

    samples: int = 0
    windows: int = 0
    spikes: int = 0
    faults: int = 0
    packets: list[tuple[int, str]] = field(default_factory=list)   # (sample, "CLOSE"/"STOP")
    latencies: list[int] = field(default_factory=list)            # cycles per packet
    closings: list[tuple[int, int, float]] = field(default_factory=list)  # (g, cycles, g/625 s)
    hand_commands: list[list[int]] = field(default_factory=list)  # command codes of every packet
    events: np.ndarray | None = None
    counts: np.ndarray | None = None
    commands: np.ndarray | None = None
    errors: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.errors

    def summary(self) -> str:
        lines = [f"{self.samples} samples, {self.windows} windows, {self.spikes} spikes, "
                 f"{self.faults} faulty readings: board and twin compared on every sample"]
        if self.latencies:
            lat = np.array(self.latencies)
            n_close = sum(c == "CLOSE" for _, c in self.packets)
            lines.append(f"{len(self.packets)} hand packets after the start's STOP: {n_close} CLOSE, "
                         f"{len(self.packets) - n_close} STOP; none OPEN or POSITION")
            lines.append(f"sample -> first hand byte: max {lat.max()} cycles "
                         f"({lat.max() / hardware.F_CPU * 1e3:.3f} ms), mean {lat.mean():.0f} cycles")
        if self.closings:
            over = np.array([(got - exact) / hardware.F_CPU * 1e3 for _, got, exact in self.closings])
            lines.append(f"{len(self.closings)} closings without a fault: CLOSE -> STOP lasted g / 625 s "
                         f"+ {over.min():.3f} .. {over.max():.3f} ms")
        lines += [f"ERROR: {e}" for e in self.errors] or ["OK"]
        return "\n".join(lines)


def _adc_events(outdir: Path) -> tuple[np.ndarray, np.ndarray]:
    t, v = [], []
    for line in (outdir / "events.txt").read_text().splitlines():
        if line.startswith("A "):
            f = line.split(" ")
            t.append(int(f[1]))
            v.append(int(f[2]))
    return np.array(t, dtype=np.int64), np.array(v, dtype=np.int64)


def board_outputs(frames: list[wire.Frame]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-sample events and per-window counts and commands, as the board sent them."""
    events = np.array([f.reflex.spike for f in frames], dtype=bool)
    wins = [f.reflex for f in frames if f.reflex.window]
    return (events, np.array([r.v for r in wins], dtype=np.int64),
            np.array([r.command for r in wins], dtype=np.int64))


def _compare(frames: list[wire.Frame], res: board.BoardResult, err: list[str]) -> None:
    n = res.params.n
    for name, got, want in (
            ("filtered sample", [f.reflex.x for f in frames], res.filtered.tolist()),
            ("spike", [f.reflex.spike for f in frames], res.events.tolist()),
            ("fault", [f.reflex.fault for f in frames], res.faults.tolist()),
            ("window flag", [f.reflex.window for f in frames],
             [(k + 1) % n == 0 for k in range(len(frames))])):
        bad = [k for k, (g, w) in enumerate(zip(got, want)) if g != w]
        if bad:
            err.append(f"{len(bad)} samples where the board's {name} differs from the twin's "
                       f"(first: sample {bad[0]}: board {got[bad[0]]}, twin {want[bad[0]]})")
    _, counts, commands = board_outputs(frames)
    for name, got, want in (("window count", counts, res.counts), ("command", commands, res.commands)):
        bad = np.flatnonzero(got != want[:got.size])
        if bad.size or got.size != want.size:
            k = int(bad[0]) if bad.size else min(got.size, want.size)
            err.append(f"the board's {name} differs from the twin's (first: window {k})")
    # The command in force is carried by every frame, not only at window ends.
    p = res.params
    z = (np.arange(len(frames)) + 1) // n - 1
    running = np.where(z >= 0, np.r_[res.commands, 0][z], min(max(p.p0, p.lo), p.hi))
    got = np.array([f.reflex.command for f in frames])
    if np.any(got != running):
        err.append("a frame carries a command other than the one in force")


def expected_packets(res: board.BoardResult) -> list[tuple[int, hardware.HandCommand]]:
    """(sample, CLOSE or STOP) of every hand packet the firmware sends for this run;
    sample -1 is the STOP every start sends (slipreflex.methods.board.board_hand)."""
    return board.board_hand(res).packets


def _packet_kind(pkt) -> hardware.HandCommand | None:
    """CLOSE or STOP if ``pkt`` is one for exactly thumb, index and middle with the board's
    value (full PWM, or 0), else None."""
    fingers = tuple(c.finger for c in pkt)
    kinds = {c.command for c in pkt}
    vals = {c.value for c in pkt}
    if fingers != tuple(hardware.TRIPOD) or len(kinds) != 1:
        return None
    kind = kinds.pop()
    if kind == hardware.HandCommand.CLOSE and vals == {board.HAND_PWM}:
        return hardware.HandCommand.CLOSE
    if kind == hardware.HandCommand.STOP and vals == {0}:
        return hardware.HandCommand.STOP
    return None


def _check_hand(outdir: Path, frames, res, adc_t, rep: BoardReport) -> None:
    err = rep.errors
    data = (outdir / "uart1.bin").read_bytes()
    cycles = np.fromfile(outdir / "uart1_cycles.bin", dtype="<u8")
    parser = ilimb.PacketParser()
    packets = parser.feed(data)
    size = 3 + 4 * len(hardware.TRIPOD)
    rep.hand_commands = [sorted({int(c.command) for c in pkt}) for pkt in packets]
    # The last packet may still be in flight when the run ends.
    if parser.rejected or parser.skipped_bytes or not 0 <= len(data) - len(packets) * size < size:
        err.append(f"UART1: {len(data)} bytes are not {len(packets)} whole i-Limb packets "
                   f"({parser.rejected} rejected, {parser.skipped_bytes} skipped)")
        return
    kinds = []
    for i, pkt in enumerate(packets):
        if any(c.command in (hardware.HandCommand.OPEN, hardware.HandCommand.POSITION) for c in pkt):
            err.append(f"hand packet {i} is an OPEN or a POSITION, which the board must never send: {pkt}")
            return
        kind = _packet_kind(pkt)
        if kind is None:
            err.append(f"hand packet {i} is not one CLOSE at PWM {board.HAND_PWM} or one STOP for "
                       f"thumb, index and middle: {pkt}")
            return
        kinds.append(kind)
    trace = board.board_hand(res)
    want = [(k, c) for k, c in trace.packets if k < len(frames)]
    if not kinds or kinds[0] != hardware.HandCommand.STOP or cycles[0] >= adc_t[0]:
        err.append("the board did not send STOP before its first sample")
        return
    if [c for _, c in want] != kinds[:len(want)] or len(kinds) > len(want) + 1:
        err.append(f"hand packets {[c.name for c in kinds[:10]]} are not those the twin predicts "
                   f"{[c.name for _, c in want[:10]]}")
    flagged = [k for k, f in enumerate(frames) if f.reflex.hand]
    if flagged != [k for k, _ in want[1:]]:
        err.append(f"frames flagged HAND {flagged[:10]} are not the samples the twin sends a packet at "
                   f"{[k for k, _ in want[1:11]]}")
    rep.packets = [(k, c.name) for k, c in want[1:]]
    first = []                                    # first byte's cycle of packets 1..
    for j, (k, _) in enumerate(want[1:len(kinds)], start=1):
        first.append(int(cycles[j * size]))
        rep.latencies.append(first[-1] - int(adc_t[k]))
    if rep.latencies and max(rep.latencies) >= LATENCY_LIMIT_CYCLES:
        err.append(f"hand packet latency {max(rep.latencies)} cycles is not under 1 ms")
    if any(lat <= 0 for lat in rep.latencies):
        err.append("a hand packet left before its sample was taken")
    # Each closing with nothing owed before it and no fault until its STOP: the time from
    # CLOSE's first byte to STOP's, against its grip's g / 625 s, in CPU cycles.
    pk = want[1:1 + len(first)]
    for j in range(len(pk) - 1):
        (c, kc), (s, ks) = pk[j], pk[j + 1]
        if kc != hardware.HandCommand.CLOSE or ks != hardware.HandCommand.STOP:
            continue
        if (c > 0 and trace.left[c - 1] != 0) or res.faults[c:s + 1].any():
            continue
        g = int(trace.rises[c:s].sum())
        exact = g / hardware.FINGER_SPEED_UNITS_S * hardware.F_CPU
        rep.closings.append((g, first[j + 1] - first[j], exact))
    for g, got, exact in rep.closings:
        if not exact - CLOSING_JITTER_CYCLES <= got < exact + PERIOD_CYCLES + CLOSING_JITTER_CYCLES:
            err.append(f"a closing for {g} units lasted {got} cycles, not g / 625 s = {exact:.0f} "
                       f"cycles rounded up to whole samples")
            break


def check(outdir: str | Path, *, dath: bool = True, p0: int = 0) -> BoardReport:
    """Check one harness output directory of a board-reflex firmware; see the module doc."""
    out = Path(outdir)
    rep = BoardReport()
    parser = wire.FrameParser()
    frames = parser.feed((out / "uart.bin").read_bytes())
    adc_t, adc_v = _adc_events(out)
    if not frames or any(f.reflex is None for f in frames):
        rep.errors.append("no version-2 frames: is this a firmware with the reflex on board?")
        return rep
    if frames[0].seq != 0 or parser.stats.seq_gaps or len(adc_v) < len(frames):
        rep.errors.append("frames are not the consecutive samples 0.. of the injected readings")
        return rep
    if any(f.adc != a for f, a in zip(frames, adc_v)):
        rep.errors.append("a frame does not carry its injected ADC reading")
    res = board.run_board_chain(adc_v[:len(frames)], board.BoardParams.firmware(dath=dath, p0=p0))
    rep.samples, rep.windows = len(frames), int(res.counts.size)
    rep.events, rep.counts, rep.commands = board_outputs(frames)
    rep.spikes, rep.faults = int(res.events.sum()), int(res.faults.sum())
    _compare(frames, res, rep.errors)
    if (out / "uart1.bin").exists():
        _check_hand(out, frames, res, adc_t, rep)
    return rep


def main(argv: list[str] | None = None) -> int:
    """Command line: check a directory, print the report, exit 0 if it passes."""
    args = sys.argv[1:] if argv is None else argv
    if not args or args[0].startswith("-"):
        print(__doc__.splitlines()[2].strip(), file=sys.stderr)
        return 2
    p0 = int(args[args.index("--p0") + 1]) if "--p0" in args else 0
    rep = check(args[0], dath="--fixed" not in args, p0=p0)
    print(rep.summary())
    return 0 if rep.ok else 1


if __name__ == "__main__":
    sys.exit(main())
