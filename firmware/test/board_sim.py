"""Run the firmware's on-board reflex under simavr on a CSV of ADC counts.

    python3 firmware/test/board_sim.py ADC.csv OUT [--dath] [--p0 N] [--mega]

ADC.csv has a header with a column ``adc`` (one 10-bit count per sample, 0..1023).
The script builds the firmware with the reflex on board for these options (make -C
firmware REFLEX_DATH=... REFLEX_P0=..., into firmware/build/sim-<options>/), runs it in
firmware/build/.../harness at 16 MHz with those counts injected at the ADC, one per
3 ms conversion, decodes the board's version-2 frames and writes what the board
produced:

    OUT.samples.csv   sample, event          (one row per sample)
    OUT.windows.csv   window, v, command     (one row per complete window)

(OUT may end in .csv; the suffix is dropped.) ``slipreflex detect --board ADC.csv
--out OUT2`` writes the same two files from the Python twin, so ``diff`` shows any
disagreement. --dath selects the DATH encoder (default: fixed threshold, as in the
issue's runner); --p0 the MPI's start (REFLEX_P0); --mega runs the standalone ATmega2560
build and also writes OUT.hand.csv (sample, cycles, command: every i-Limb packet it
sent on UART1 after the STOP every start sends, CLOSE or STOP, with the CPU cycles
from its sample's conversion start to the packet's first byte). The board's outputs are also checked against the twin
(firmware/test/check_board.py); exit status 1 if they differ.
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
from pathlib import Path

FIRMWARE = Path(__file__).resolve().parents[1]


def _load(name: str):
    spec = importlib.util.spec_from_file_location(f"slipreflex_fw_{name}", FIRMWARE / "test" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def slip_like(seed: int, k: int):
    """Counts like the slip sensor's: a level, quiet stretches, slips (fast texture),
    a disconnected sensor (near 0 V, 120 ms at k/3) and a stuck converter (identical
    readings, 3.3 s at 2k/3). Deterministic for a seed; the tests and
    benchmarks/firmware_budget.py run the standalone firmware on it.

    Examples
    --------
    >>> a = slip_like(1, 3000)
    >>> a.size, int(a[1000]), bool((a[2000:3000] == a[1999]).all())
    (3000, 2, True)
    """
    import numpy as np

    rng = np.random.default_rng(seed)
    x = 300 + np.cumsum(rng.normal(0, 0.3, k))
    for start in range(400, k - 200, 900):          # slips: texture at 30-60 Hz
        n = int(rng.integers(80, 200))
        x[start:start + n] += rng.uniform(3, 12) * np.sin(np.arange(n) * rng.uniform(0.6, 1.2))
    adc = np.clip(np.round(x + rng.normal(0, 0.6, k)), 0, 1023).astype(int)
    adc[k // 3:k // 3 + 40] = 2                       # sensor unplugged for 120 ms
    adc[2 * k // 3:2 * k // 3 + 1100] = adc[2 * k // 3 - 1]   # stuck for 3.3 s
    return adc


def build(dath: bool, p0: int, build_root: Path = FIRMWARE / "build") -> Path:
    """Build (or reuse) the firmware variant and the harness; return the build directory."""
    out = build_root / f"sim-dath{int(dath)}-p0{p0}"
    targets = [f"{out}/daq-reflex.elf", f"{out}/hand2560.elf", f"{out}/harness"]
    proc = subprocess.run(["make", "-C", str(FIRMWARE), f"BUILD={out}", f"REFLEX_DATH={int(dath)}",
                           f"REFLEX_P0={p0}", *targets], capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"board_sim: building the firmware failed:\n{proc.stdout}{proc.stderr}")
    return out


def simulate(adc, *, dath: bool, p0: int, mega: bool = False, workdir: Path | None = None):
    """Run the board on ``adc``; return (capture directory, check_board report)."""
    from slipreflex.core import hardware

    check_board = _load("check_board")
    bdir = build(dath, p0)
    work = Path(workdir) if workdir is not None else Path(tempfile.mkdtemp(prefix="board_sim."))
    work.mkdir(parents=True, exist_ok=True)
    (work / "adc.txt").write_text("\n".join(str(int(a)) for a in adc) + "\n")
    seconds = (len(adc) + 2) * hardware.DAQ_PERIOD_S
    elf = "hand2560.elf" if mega else "daq-reflex.elf"
    cmd = [str(bdir / "harness"), str(bdir / elf), str(work), f"{seconds:.6f}",
           "--adc", str(work / "adc.txt")] + (["--mcu", "atmega2560"] if mega else [])
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"board_sim: the simulation failed:\n{proc.stdout}{proc.stderr}")
    # The harness repeats the last count after the file ends; keep the file's samples.
    rep = check_board.check(work, dath=dath, p0=p0)
    return work, rep


def main(argv: list[str] | None = None) -> int:
    """Command line; see the module docstring."""
    from slipreflex.methods import board
    from slipreflex.core.errors import SlipreflexError

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("adc_csv", type=Path, help="CSV with a column adc (counts 0..1023)")
    ap.add_argument("out", type=Path, help="output prefix: OUT.samples.csv, OUT.windows.csv")
    ap.add_argument("--dath", action="store_true", help="DATH encoder (default: fixed threshold)")
    ap.add_argument("--p0", type=int, default=0, help="initial finger position (default 0)")
    ap.add_argument("--mega", action="store_true",
                    help="run the standalone ATmega2560 build and write OUT.hand.csv")
    args = ap.parse_args(argv)
    try:
        adc = board.read_adc_csv(args.adc_csv)
    except SlipreflexError as err:
        print(f"board_sim: {err}", file=sys.stderr)
        return 2
    if not -32768 <= args.p0 <= 32767:
        print(f"board_sim: --p0 must be in -32768..32767, got {args.p0}", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="board_sim.") as tmp:
        work, rep = simulate(adc, dath=args.dath, p0=args.p0, mega=args.mega, workdir=Path(tmp))
        k = len(adc)
        if rep.events is None or rep.samples < k:
            print(f"board_sim: the board sent {rep.samples} of {k} samples", file=sys.stderr)
            return 1
        nwin = k // board.BoardParams.firmware().n
        prefix = args.out.with_suffix("") if args.out.suffix == ".csv" else args.out
        paths = board.write_board_outputs(prefix, rep.events[:k], rep.counts[:nwin], rep.commands[:nwin])
        if args.mega:
            from slipreflex.files.csvfiles import write_columns

            hand = [(s, c, p) for (s, p), c in zip(rep.packets, rep.latencies) if s < k]
            paths += (Path(f"{prefix}.hand.csv"),)
            write_columns(paths[-1], {"sample": [h[0] for h in hand], "cycles": [h[1] for h in hand],
                                      "command": [h[2] for h in hand]})
    print(f"{args.adc_csv}: {k} samples through the board under simavr "
          f"({'DATH' if args.dath else 'fixed'}, p0 {args.p0}{', ATmega2560' if args.mega else ''})")
    print("  " + rep.summary().replace("\n", "\n  "))
    print(f"  wrote {', '.join(str(p) for p in paths)}")
    return 0 if rep.ok else 1


if __name__ == "__main__":
    sys.exit(main())
