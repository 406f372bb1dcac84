"""``slipreflex detect``: run the reflex chain over a recorded CSV.

Examples
--------
>>> from slipreflex.cli import main
>>> main(["detect", "examples/slip_example.csv"])  # doctest: +SKIP
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..chain import ReflexParams, run_chain
from ..csvfiles import read_slip_csv, write_columns
from ..errors import DataError

NAME = "detect"
HELP = "run the slip-detection chain over a CSV recording of slip-sensor samples"
ORDER = 10

_DEFAULTS = ReflexParams()


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex detect``, one per chain parameter."""
    p.add_argument("recording", type=Path, help="CSV with columns t (s) and x (V), or one column of volts")
    p.add_argument("--method", choices=("fixed", "dath"), default="dath",
                   help="fixed threshold or Dynamic Adaptive Threshold (default: dath)")
    p.add_argument("--fs", type=float, default=None,
                   help="sampling rate in Hz (required for a single-column file; default: from t)")
    p.add_argument("--cutoff", type=float, default=_DEFAULTS.cutoff, help="low-pass cutoff, Hz (default 10)")
    p.add_argument("--no-filter", action="store_true", help="input is already filtered")
    p.add_argument("--threshold", type=float, default=_DEFAULTS.threshold, help="theta0 in V (default 0.008)")
    p.add_argument("--dath-samples", type=int, default=_DEFAULTS.dath_samples, help="DATH duration D (16)")
    p.add_argument("--dath-floor", type=float, default=_DEFAULTS.dath_floor, help="DATH floor in V (0)")
    p.add_argument("--x0", type=float, default=None,
                   help="initial reference; default the first sample, 0 is the paper's literal start")
    p.add_argument("--n", type=int, default=_DEFAULTS.n, help="samples per window (16)")
    p.add_argument("--p0", type=float, default=_DEFAULTS.p0, help="initial finger position P0 (0)")
    p.add_argument("--kp", type=float, default=_DEFAULTS.kp, help="proportional gain (5)")
    p.add_argument("--ki", type=float, default=_DEFAULTS.ki, help="integral gain (5)")
    p.add_argument("--reset-after", type=int, default=_DEFAULTS.reset_after, help="zero windows to reset (10)")
    p.add_argument("--lo", type=float, default=_DEFAULTS.lo, help="lowest command (0)")
    p.add_argument("--hi", type=float, default=_DEFAULTS.hi, help="highest command (500)")
    p.add_argument("--board", action="store_true",
                   help="the recording is ADC counts (a column adc): run the board's fixed-point chain "
                        "(slipreflex.board, as the firmware is built, with --method and --p0 only) and "
                        "write sample,event and window,v,command as firmware/test/board_sim.py does")
    p.add_argument("--out", type=Path, default=None,
                   help="output prefix (default: next to the recording, NAME.samples.csv and NAME.windows.csv)")


def _sampling_rate(t: np.ndarray, given: float | None, path: Path) -> float:
    if given is not None:
        return given
    if t.size < 2:
        raise DataError(f"{path}: one sample gives no sampling rate; pass --fs")
    return float(1.0 / np.median(np.diff(t)))


def run(args: argparse.Namespace) -> int:
    """Run the chain and write the two CSVs; print a summary."""
    if args.board:
        return _run_board(args)
    t, raw = read_slip_csv(args.recording, fs=args.fs)
    params = ReflexParams(
        fs=_sampling_rate(t, args.fs, args.recording), cutoff=args.cutoff, filter=not args.no_filter,
        threshold=args.threshold, dath=args.method == "dath", dath_samples=args.dath_samples,
        x0=args.x0, dath_floor=args.dath_floor, n=args.n, p0=args.p0, kp=args.kp, ki=args.ki,
        reset_after=args.reset_after, lo=args.lo, hi=args.hi)
    res = run_chain(raw, params)
    prefix = args.out if args.out is not None else args.recording.with_suffix("")
    prefix.parent.mkdir(parents=True, exist_ok=True)
    samples_path = Path(f"{prefix}.samples.csv")
    windows_path = Path(f"{prefix}.windows.csv")
    write_columns(samples_path, res.sample_columns(t))
    write_columns(windows_path, res.window_columns(t))
    final = f"{res.commands[-1]:g}" if res.commands.size else "none (shorter than one window)"
    print(f"{args.recording}: {raw.size} samples at {params.fs:.2f} Hz, method {params.name}")
    print(f"  events: {int(res.events.sum())}")
    print(f"  windows with slip: {int((res.counts > 0).sum())} of {res.counts.size}")
    print(f"  final command: {final}")
    print(f"  wrote {samples_path} and {windows_path}")
    return 0


def _run_board(args: argparse.Namespace) -> int:
    """``detect --board``: the Python twin of the firmware over a CSV of ADC counts."""
    from ..board import BoardParams, read_adc_csv, run_board_chain, write_board_outputs
    from ..errors import ParameterError

    if args.p0 != int(args.p0):
        raise ParameterError(f"--p0 must be a whole position with --board, got {args.p0!r}")
    adc = read_adc_csv(args.recording)
    res = run_board_chain(adc, BoardParams.firmware(dath=args.method == "dath", p0=int(args.p0)))
    prefix = args.out if args.out is not None else args.recording.with_suffix("")
    prefix.parent.mkdir(parents=True, exist_ok=True)
    paths = write_board_outputs(prefix, res.events, res.counts, res.commands)
    print(f"{args.recording}: {adc.size} ADC counts through the board's chain, method {args.method}")
    print(f"  events: {int(res.events.sum())}, faulty readings: {int(res.faults.sum())}")
    print(f"  wrote {paths[0]} and {paths[1]}")
    return 0
