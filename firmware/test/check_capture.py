"""Check a capture of the DAQ firmware running under simavr (firmware/test/harness.c).

    python3 firmware/test/check_capture.py OUTDIR [--no-imu]

Reads OUTDIR/uart.bin, uart_cycles.bin and events.txt, decodes the UART bytes with
slipreflex.rig.devices.wire.FrameParser and checks that

- the stream is clean: no CRC error, truncated or invalid frame, no garbage byte, no
  sequence gap, seq starting at 0, no OVERRUN flag;
- the ADC count injected at conversion k comes back in frame k;
- the sample period, measured from the UART byte timestamps (first byte of every frame,
  least-squares slope over the run) and from the ADC conversion starts, is 3.000 ms
  within 0.01 % in simulated time (48,000 cycles at 16 MHz);
- each frame's cumulative flow count lies between the pulses before its conversion
  started and the pulses before its first byte left;
- every accelerometer reading the simulated MPU6050 latched arrives, in order, exactly
  once, flagged fresh, after it was latched (and with --no-imu: none, IMU_ERROR set);
- the firmware woke the MPU6050 and configured +-2 g and the 94 Hz filter.

It also measures the CPU time the firmware spends per sample period (cycles not asleep,
between consecutive conversion starts). Exit status 0 when every check passes.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from slipreflex.core import hardware
from slipreflex.rig.devices import wire

#: CPU cycles in one sample period at 16 MHz.
PERIOD_CYCLES = hardware.F_CPU * hardware.DAQ_PERIOD_S
#: Allowed relative error of the mean sample period.
PERIOD_TOL = 1e-4
#: MPU6050 configuration the firmware must write (register: value).
IMU_CONFIG = {0x6B: 0x01, 0x1C: 0x00, 0x1A: 0x02}
#: Frames at start-up that may lack a fresh reading (3 configuration writes, 1 read lag).
IMU_STARTUP_FRAMES = 5


@dataclass
class Report:
    """What :func:`check` found; ``errors`` is empty when the capture passes."""

    frames: int = 0
    seconds: float = 0.0
    period_uart_cycles: float = float("nan")
    period_adc_cycles: float = float("nan")
    period_adc_jitter_cycles: float = float("nan")
    busy_mean_cycles: float = float("nan")
    busy_max_cycles: float = float("nan")
    fresh_frames: int = 0
    flow_pulses: int = 0
    stats: wire.ParserStats | None = None
    errors: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.errors

    @property
    def busy_share(self) -> float:
        return self.busy_mean_cycles / PERIOD_CYCLES

    def summary(self) -> str:
        lines = [
            f"frames {self.frames} over {self.seconds:.3f} s simulated",
            f"sample period (UART, fit) {self.period_uart_cycles:.3f} cycles = "
            f"{self.period_uart_cycles / hardware.F_CPU * 1e3:.6f} ms "
            f"(error {1e6 * (self.period_uart_cycles / PERIOD_CYCLES - 1):+.1f} ppm)",
            f"sample period (ADC starts) {self.period_adc_cycles:.3f} cycles, "
            f"jitter +-{self.period_adc_jitter_cycles:.0f} cycles",
            f"firmware CPU per period: mean {self.busy_mean_cycles:.0f} cycles "
            f"({100 * self.busy_share:.2f} % of {PERIOD_CYCLES:.0f}), "
            f"max {self.busy_max_cycles:.0f} cycles",
            f"fresh accel readings {self.fresh_frames}, flow pulses {self.flow_pulses}",
            f"parser: {self.stats}",
        ]
        lines += [f"ERROR: {e}" for e in self.errors] or ["OK"]
        return "\n".join(lines)


def _slope(y: np.ndarray) -> float:
    x = np.arange(len(y), dtype=float)
    return float(np.polyfit(x, y.astype(float) - float(y[0]), 1)[0])


def check(outdir: str | Path, imu: bool = True) -> Report:
    """Check one harness output directory; see the module docstring."""
    out = Path(outdir)
    rep = Report()
    err = rep.errors
    data = (out / "uart.bin").read_bytes()
    cycles = np.fromfile(out / "uart_cycles.bin", dtype="<u8")
    if len(cycles) != len(data):
        err.append(f"{len(data)} UART bytes but {len(cycles)} timestamps")
        return rep
    adc_t, adc_v, adc_busy, pulses, latched, writes, end = [], [], [], [], [], {}, 0
    for lineno, line in enumerate((out / "events.txt").read_text().splitlines(), 1):
        kind, *f = line.split(" ")
        if kind == "A":
            adc_t.append(int(f[0])); adc_v.append(int(f[1])); adc_busy.append(int(f[2]))
        elif kind == "P":
            pulses.append(int(f[0]))
        elif kind == "I":
            latched.append((int(f[0]), (int(f[1]), int(f[2]), int(f[3]))))
        elif kind == "W":
            writes[int(f[1])] = int(f[2])
        elif kind == "X":
            end = int(f[0])
        elif kind == "E":
            err.append(f"harness event: {line}")
        else:
            err.append(f"events.txt line {lineno}: unknown event {line!r}")
    rep.seconds = end / hardware.F_CPU

    # Framing: every byte belongs to a good frame (a last frame may still be in flight).
    parser = wire.FrameParser()
    frames = parser.feed(data)
    rep.stats = s = parser.stats
    rep.frames = len(frames)
    for name in ("crc_errors", "truncated", "invalid", "garbage_bytes", "seq_gaps"):
        if getattr(s, name):
            err.append(f"{getattr(s, name)} {name.replace('_', ' ')}")
    # Frames of a board running the reflex are longer (version 2); all have one length.
    size = wire.FRAME_LEN_REFLEX if frames and frames[0].reflex is not None else wire.FRAME_LEN
    if len({f.reflex is None for f in frames}) > 1:
        err.append("version-1 and version-2 frames mixed in one capture")
    if s.pending >= size:
        err.append(f"{s.pending} bytes left undecoded")
    if len(frames) < 100:
        err.append(f"only {len(frames)} frames")
        return rep
    if frames[0].seq != 0:
        err.append(f"first frame has seq {frames[0].seq}, expected 0 after reset")
    idx = np.array([f.index for f in frames])
    if np.any(np.diff(idx) != 1):
        err.append("frame indices are not consecutive")
    if any(f.overrun for f in frames):
        err.append(f"{sum(f.overrun for f in frames)} frames flagged OVERRUN")

    # Timing: the first byte of frame k (frames are back to back from byte 0, as there
    # is no garbage and no gap) and conversion start k.
    t_first = cycles[np.arange(len(frames)) * size]
    rep.period_uart_cycles = _slope(t_first)
    adc_t = np.array(adc_t, dtype=np.int64)
    if len(adc_t) < len(frames):
        err.append(f"{len(frames)} frames but only {len(adc_t)} conversions")
        return rep
    d = np.diff(adc_t)
    rep.period_adc_cycles = _slope(adc_t)
    rep.period_adc_jitter_cycles = float(np.max(np.abs(d - PERIOD_CYCLES)))
    for name, value in (("UART", rep.period_uart_cycles), ("ADC", rep.period_adc_cycles)):
        if abs(value / PERIOD_CYCLES - 1) > PERIOD_TOL:
            err.append(f"sample period from {name} timestamps {value:.3f} cycles "
                       f"({value / hardware.F_CPU * 1e3:.6f} ms) is not 3.000 ms within 0.01 %")
    if np.any(t_first <= adc_t[: len(frames)]):
        err.append("a frame left before its conversion started")

    # Values: ADC counts come back in order.
    got_adc = np.array([f.adc for f in frames])
    want_adc = np.array(adc_v[: len(frames)])
    bad = np.flatnonzero(got_adc != want_adc)
    if len(bad):
        k = int(bad[0])
        err.append(f"{len(bad)} frames carry the wrong ADC count (first: frame {k} has "
                   f"{got_adc[k]}, injected {want_adc[k]})")

    # Flow pulses: cumulative count consistent with the edges' times.
    pulses_a = np.array(pulses, dtype=np.int64)
    flow = np.array([f.flow_pulses for f in frames], dtype=np.int64)
    lo = np.searchsorted(pulses_a, adc_t[: len(frames)], side="left")
    hi = np.searchsorted(pulses_a, t_first, side="left")
    bad = np.flatnonzero((flow < lo) | (flow > hi))
    if len(bad):
        k = int(bad[0])
        err.append(f"{len(bad)} frames carry an impossible flow count (first: frame {k} "
                   f"has {flow[k]}, expected {lo[k]}..{hi[k]})")
    if len(pulses_a) < 10:
        err.append("the harness generated fewer than 10 flow pulses")
    rep.flow_pulses = int(flow[-1])

    # Accelerometer.
    fresh = [(i, f) for i, f in enumerate(frames) if f.accel_fresh]
    rep.fresh_frames = len(fresh)
    if imu:
        for reg, value in IMU_CONFIG.items():
            if writes.get(reg) != value:
                err.append(f"MPU6050 register 0x{reg:02X} is {writes.get(reg)}, "
                           f"expected 0x{value:02X}")
        if any(f.imu_error for f in frames):
            err.append(f"{sum(f.imu_error for f in frames)} frames flagged IMU_ERROR")
        stale = [i for i, f in enumerate(frames) if i >= IMU_STARTUP_FRAMES and not f.accel_fresh]
        if stale:
            err.append(f"{len(stale)} frames after start-up without a fresh accel reading "
                       f"(first: frame {stale[0]})")
        if [f.accel for _, f in fresh] != [v for _, v in latched[: len(fresh)]]:
            err.append("accelerometer readings do not come back in order, exactly once")
        elif len(latched) - len(fresh) > 2:
            err.append(f"{len(latched) - len(fresh)} accelerometer readings never sent")
        else:
            # Documented timing: frame k carries the reading latched during period k - 1
            # (started by tick k - 1, completed after the ADC snapshot of tick k - 1).
            wrong = [i for (i, _), (tl, _) in zip(fresh, latched)
                     if i == 0 or not adc_t[i - 1] <= tl < adc_t[i]]
            if wrong:
                err.append(f"frame {wrong[0]} carries an accel reading not latched during "
                           f"the previous period")
    else:
        if fresh:
            err.append(f"{len(fresh)} fresh accel readings with no IMU on the bus")
        noerr = [i for i, f in enumerate(frames) if not f.imu_error]
        if noerr:
            err.append(f"{len(noerr)} frames without IMU_ERROR while no IMU answers")

    # CPU budget: busy cycles between consecutive conversion starts.
    busy = np.diff(np.array(adc_busy, dtype=np.int64))[IMU_STARTUP_FRAMES:]
    rep.busy_mean_cycles = float(busy.mean())
    rep.busy_max_cycles = float(busy.max())
    if rep.busy_max_cycles >= PERIOD_CYCLES:
        err.append("a sample period used all CPU cycles")
    return rep


def main(argv: list[str] | None = None) -> int:
    """Command line: check a directory, print the report, exit 0 if it passes."""
    args = sys.argv[1:] if argv is None else argv
    if not args or args[0].startswith("-"):
        print(__doc__.splitlines()[2].strip(), file=sys.stderr)
        return 2
    rep = check(args[0], imu="--no-imu" not in args)
    print(rep.summary())
    return 0 if rep.ok else 1


if __name__ == "__main__":
    sys.exit(main())
