"""CPU, flash and RAM budget of the DAQ firmware, measured under simavr.

Builds the firmware (firmware/Makefile) into a temporary directory, prints its flash
and RAM use, runs it for --seconds of simulated time with the simulated slip sensor,
flow sensor and MPU6050 (and once more with no IMU on the bus), checks the capture
(firmware/test/check_capture.py) and prints the CPU cycles the firmware spends awake
per 3 ms sample period, as a share of the 48,000 cycles available at 16 MHz. Awake
means not in the SLEEP instruction: interrupt handlers plus the main loop's framing
and CRC. With the IMU, it also prints where those cycles go, per function (the harness
attributes every instruction's cycles to its address; avr-nm maps addresses to
functions). Simulated time, so the numbers do not depend on the host machine.

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


def _checker():
    path = FIRMWARE / "test" / "check_capture.py"
    spec = importlib.util.spec_from_file_location("slipreflex_fw_check_capture", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


#: ATmega328P interrupt vector numbers of the handlers the firmware defines.
VECTORS = {"__vector_1": "ISR INT0 (flow pulse)", "__vector_11": "ISR TIMER1_COMPA (tick)",
           "__vector_19": "ISR USART_UDRE (one byte out)", "__vector_21": "ISR ADC (snapshot)",
           "__vector_24": "ISR TWI (MPU6050 bus)"}


def _profile(elf: Path, profile: Path, periods: float) -> list[tuple[str, float]]:
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
        name = next((VECTORS.get(n, n) for a, size, n in funcs if a <= pc < a + size),
                    "vector table, interrupt entry")
        per[name] = per.get(name, 0.0) + cycles / periods
    return sorted(per.items(), key=lambda kv: -kv[1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=30.0, help="simulated seconds per run")
    args = ap.parse_args()
    check = _checker()
    with tempfile.TemporaryDirectory() as tmp:
        build = Path(tmp) / "build"
        proc = subprocess.run(["make", "-C", str(FIRMWARE), f"BUILD={build}"],
                              capture_output=True, text=True)
        if proc.returncode != 0:
            print(proc.stdout + proc.stderr, file=sys.stderr)
            return 1
        size = re.search(r"firmware size: .*", proc.stdout)
        print(size[0] if size else "firmware size: (not reported)")
        status = 0
        for label, extra in (("MPU6050 on the bus", []), ("no IMU on the bus", ["--no-imu"])):
            out = Path(tmp) / label.replace(" ", "_")
            out.mkdir()
            run = subprocess.run([str(build / "harness"), str(build / "daq.elf"), str(out),
                                  str(args.seconds), "--profile", *extra],
                                 capture_output=True, text=True)
            if run.returncode != 0:
                print(run.stdout + run.stderr, file=sys.stderr)
                return 1
            rep = check.check(out, imu=not extra)
            print(f"\n[{label}] {args.seconds:g} s simulated, {rep.frames} frames, "
                  f"checks {'passed' if rep.ok else 'FAILED'}")
            print(f"  CPU per 3 ms period: mean {rep.busy_mean_cycles:.0f} cycles = "
                  f"{100 * rep.busy_share:.2f} % of {check.PERIOD_CYCLES:.0f}; "
                  f"worst period {rep.busy_max_cycles:.0f} cycles = "
                  f"{100 * rep.busy_max_cycles / check.PERIOD_CYCLES:.2f} %")
            print(f"  sample period {rep.period_uart_cycles / 16e3:.6f} ms from UART timestamps, "
                  f"conversion-start jitter +-{rep.period_adc_jitter_cycles / 16:.1f} us")
            for e in rep.errors:
                print(f"  ERROR: {e}")
            if not extra:
                periods = args.seconds / 0.003
                print("  where the cycles go (per period):")
                for name, cycles in _profile(build / "daq.elf", out / "profile.txt", periods):
                    if cycles >= 1:
                        print(f"    {cycles:7.0f}  {name}")
            status |= not rep.ok
        return int(status)


if __name__ == "__main__":
    sys.exit(main())
