"""CPU, flash and RAM budget of every firmware build, measured under simavr.

Builds the firmware (firmware/Makefile) into a temporary directory, prints the flash
and RAM use of each build (the DAQ, the DAQ with the reflex on board, the standalone
ATmega2560 reflex), runs each for --seconds of simulated time with the simulated slip
sensor (a new pseudo-random count at every conversion: the chain sees spikes, windows
and faults all the time), flow sensor and MPU6050 (the DAQ once more with no IMU on
the bus), checks the capture (firmware/test/check_capture.py, and for the reflex
builds firmware/test/check_board.py against the Python twin) and prints the CPU cycles
the firmware spends awake per 3 ms sample period, as a share of the 48,000 cycles
available at 16 MHz (the budget: DAQ alone <= 5 %, DAQ + chain <= 15 %). Awake
means not in the SLEEP instruction: every interrupt handler, the framing, the CRC and
the chain. For the DAQ and the DAQ + chain it also prints where those cycles go, per
function (the harness attributes every instruction's cycles to its address; avr-nm
maps addresses to functions), and for the ATmega2560 the time from the conversion of
the sample at which a hand packet (CLOSE or STOP) is due to its first byte on UART1,
and how much longer than g / 625 s each closing (CLOSE to STOP) lasted.
Simulated time, so the numbers do not depend on the host machine.

Run: python benchmarks/firmware_budget.py [--seconds S]
"""

from __future__ import annotations

import argparse
import importlib.util
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIRMWARE = ROOT / "firmware"


def _load(name: str):
    path = FIRMWARE / "test" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"slipreflex_fw_{name}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


#: Interrupt vector numbers of the handlers the firmware defines, per MCU.
VECTORS = {
    "atmega328p": {"__vector_1": "ISR INT0 (flow pulse)", "__vector_11": "ISR TIMER1_COMPA (tick)",
                   "__vector_19": "ISR USART_UDRE (one byte out)",
                   "__vector_21": "ISR ADC (sample: frame, CRC, chain)",
                   "__vector_24": "ISR TWI (MPU6050 bus)"},
    "atmega2560": {"__vector_5": "ISR INT4 (flow pulse)", "__vector_17": "ISR TIMER1_COMPA (tick)",
                   "__vector_26": "ISR USART0_UDRE (one byte out)",
                   "__vector_29": "ISR ADC (sample: frame, CRC, chain)",
                   "__vector_39": "ISR TWI (MPU6050 bus)", "__vector_37": "ISR USART1_UDRE (hand)"},
}

#: Stands for the file of slip-like counts in a run's harness options.
SLIP_FILE = "{slip}"
#: Seed and length of that input.
SLIP_SEED, SLIP_SAMPLES = 4, 6000

#: (label, ELF, MCU, harness options, profile?, reflex on board?)
RUNS = [
    ("DAQ alone, MPU6050 on the bus", "daq.elf", "atmega328p", [], True, False),
    ("DAQ alone, no IMU on the bus", "daq.elf", "atmega328p", ["--no-imu"], False, False),
    ("DAQ + reflex chain (ATmega328P)", "daq-reflex.elf", "atmega328p", [], True, True),
    ("standalone reflex + hand (ATmega2560)", "hand2560.elf", "atmega2560", ["--mcu", "atmega2560"],
     False, True),
    # The same on slip-like counts (board_sim.slip_like(4, 6000): slips, a 120 ms unplugged
    # sensor, a 3.3 s stuck converter): closings with no fault in them, to time.
    ("standalone reflex + hand, slip-like input", "hand2560.elf", "atmega2560",
     ["--mcu", "atmega2560", "--adc", SLIP_FILE], False, True),
]


def _profile(elf: Path, profile: Path, periods: float, mcu: str) -> list[tuple[str, float]]:
    """Awake cycles per period for each function of the firmware, largest first."""
    nm = subprocess.run(["avr-nm", "-n", "-S", str(elf)], capture_output=True, text=True,
                        check=True).stdout
    funcs = []
    for line in nm.splitlines():
        parts = line.split()
        if len(parts) == 4 and parts[2] in "tTwW":
            funcs.append((int(parts[0], 16), int(parts[1], 16), parts[3]))
    per: dict[str, float] = {}
    for line in profile.read_text().splitlines():
        pc, cycles = map(int, line.split())
        name = next((VECTORS[mcu].get(n, n) for a, size, n in funcs if a <= pc < a + size),
                    "vector table, interrupt entry")
        per[name] = per.get(name, 0.0) + cycles / periods
    return sorted(per.items(), key=lambda kv: -kv[1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=30.0, help="simulated seconds per run")
    args = ap.parse_args()
    check, check_board = _load("check_capture"), _load("check_board")
    with tempfile.TemporaryDirectory() as tmp:
        build = Path(tmp) / "build"
        proc = subprocess.run(["make", "-C", str(FIRMWARE), f"BUILD={build}"],
                              capture_output=True, text=True)
        if proc.returncode != 0:
            print(proc.stdout + proc.stderr, file=sys.stderr)
            return 1
        for line in re.findall(r"^\S+ size: .*$", proc.stdout, flags=re.M):
            print(line)
        slip = Path(tmp) / "slip.txt"
        slip.write_text("\n".join(map(str, _load("board_sim").slip_like(SLIP_SEED, SLIP_SAMPLES))))
        status = 0
        for i, (label, elf, mcu, extra, profile, reflex) in enumerate(RUNS):
            out = Path(tmp) / f"run{i}"
            out.mkdir(parents=True)
            seconds = args.seconds if SLIP_FILE not in extra else SLIP_SAMPLES * 0.003 + 0.01
            extra = [str(slip) if e == SLIP_FILE else e for e in extra]
            run = subprocess.run([str(build / "harness"), str(build / elf), str(out),
                                  str(seconds), *(["--profile"] if profile else []), *extra],
                                 capture_output=True, text=True)
            if run.returncode != 0:
                print(run.stdout + run.stderr, file=sys.stderr)
                return 1
            rep = check.check(out, imu="--no-imu" not in extra)
            errors = list(rep.errors)
            brep = check_board.check(out) if reflex else None
            if brep is not None:
                errors += brep.errors
            print(f"\n[{label}] {elf}, {seconds:g} s simulated, {rep.frames} frames, "
                  f"checks {'passed' if not errors else 'FAILED'}")
            print(f"  CPU per 3 ms period: mean {rep.busy_mean_cycles:.0f} cycles = "
                  f"{100 * rep.busy_share:.2f} % of {check.PERIOD_CYCLES:.0f}; "
                  f"worst period {rep.busy_max_cycles:.0f} cycles = "
                  f"{100 * rep.busy_max_cycles / check.PERIOD_CYCLES:.2f} %")
            print(f"  sample period {rep.period_uart_cycles / 16e3:.6f} ms from UART timestamps, "
                  f"conversion-start jitter +-{rep.period_adc_jitter_cycles / 16:.1f} us")
            if brep is not None:
                print(f"  chain: {brep.spikes} spikes, {brep.windows} windows, {brep.faults} faulty "
                      f"readings, every frame equal to the Python twin's")
                if brep.latencies:
                    lat = brep.latencies
                    n_close = sum(c == "CLOSE" for _, c in brep.packets)
                    print(f"  hand packets: {len(lat)} ({n_close} CLOSE, {len(lat) - n_close} STOP, "
                          f"none OPEN or POSITION); conversion start of their sample -> first byte "
                          f"on UART1: max {max(lat)} cycles ({max(lat) / 16e3:.3f} ms), mean "
                          f"{sum(lat) / len(lat):.0f} cycles")
                if brep.closings:
                    over = [(got - exact) / 16e3 for _, got, exact in brep.closings]
                    print(f"  closings without a fault: {len(over)}; CLOSE -> STOP minus g / 625 s: "
                          f"{min(over):+.3f} .. {max(over):+.3f} ms (rounded up to whole 3 ms samples)")
            for e in errors:
                print(f"  ERROR: {e}")
            if profile:
                periods = seconds / 0.003
                print("  where the cycles go (per period):")
                for name, cycles in _profile(build / elf, out / "profile.txt", periods, mcu):
                    if cycles >= 1:
                        print(f"    {cycles:7.0f}  {name}")
            status |= bool(errors)
        return int(status)


if __name__ == "__main__":
    sys.exit(main())
