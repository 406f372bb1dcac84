"""``slipreflex detect``: run the reflex chain over a recorded CSV.

Examples
--------
>>> from slipreflex.cli import main
>>> main(["detect", "examples/slip_example.csv"])  # doctest: +SKIP
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from ..core.errors import DataError, ParameterError
from ..core.hardware import FINGER_MAX
from ..core.validation import number, within
from ..files.csvfiles import Recording, irregular_steps, read_recording, write_columns
from ..files.paths import output_dir, unique_prefix
from ..methods import DATH, FIXED, applicable, make
from ..methods.board import BoardParams, read_adc_csv, run_board_chain, write_board_outputs
from ..methods.chain import ReflexParams, run_chain
from ..methods.chain.params import PRESETS

NAME = "detect"
HELP = "run the slip-detection chain over a CSV recording of slip-sensor samples"
ORDER = 10

_DEFAULTS = ReflexParams()


_FIELDS = ("cutoff", "threshold", "dath_samples", "dath_floor", "x0", "n", "p0", "kp", "ki",
           "reset_after", "lo", "hi")
#: --fs and a t column may differ by this fraction (rounding of written times).
FS_TOLERANCE = 0.01


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex detect``, one per chain parameter.

    Options left out take the file's own values when its header has them (an export of
    a run: ``# reflex_params: {...}``, docs/runtime.md), else the paper's defaults.
    """
    d = _DEFAULTS
    p.add_argument("recording", type=Path, help="CSV with columns t (s) and x (V), or one column of volts")
    p.add_argument("--method", default=None,
                   help="a registered method that reads the slip sensor: fixed, dath, or a variant of the "
                        "chain (dath-event, dath-floor, dath-leak, authors-gui, ...; default: the file's, "
                        "else dath); other options still override its parameters")
    p.add_argument("--preset", choices=sorted(PRESETS), default=None,
                   help="start from a named chain instead of the file's or the paper's: authors-gui is "
                        "the authors' rig code, dath-event DATH with the event-driven MPI (docs/method.md); "
                        "other options still override it")
    p.add_argument("--fs", type=float, default=None,
                   help="sampling rate in Hz (required for a single-column file; with a t column it must agree)")
    p.add_argument("--cutoff", type=float, default=None, help=f"low-pass cutoff, Hz ({d.cutoff:g})")
    p.add_argument("--no-filter", action="store_true", help="input is already filtered")
    p.add_argument("--threshold", type=float, default=None, help=f"theta0 in V ({d.threshold:g})")
    p.add_argument("--dath-samples", type=int, default=None, help=f"DATH duration D in samples ({d.dath_samples})")
    p.add_argument("--dath-floor", type=float, default=None, help=f"DATH floor in V ({d.dath_floor:g})")
    p.add_argument("--x0", type=float, default=None,
                   help="initial reference; default the first sample, 0 is the paper's literal start")
    p.add_argument("--n", type=int, default=None, help=f"samples per window ({d.n})")
    p.add_argument("--p0", type=float, default=None, help=f"initial finger position P0 ({d.p0:g})")
    p.add_argument("--kp", type=float, default=None, help=f"proportional gain ({d.kp:g})")
    p.add_argument("--ki", type=float, default=None, help=f"integral gain ({d.ki:g})")
    p.add_argument("--reset-after", type=int, default=None, help=f"zero windows to reset ({d.reset_after})")
    p.add_argument("--lo", type=float, default=None, help=f"lowest command ({d.lo:g})")
    p.add_argument("--hi", type=float, default=None, help=f"highest command ({d.hi:g})")
    p.add_argument("--board", action="store_true",
                   help="the recording is ADC counts (a column adc): run the board's fixed-point chain "
                        "(slipreflex.methods.board, as the firmware is built, with --method and --p0 only) and "
                        "write sample,event and window,v,command as firmware/test/board_sim.py does")
    p.add_argument("--out", type=Path, default=None,
                   help="output prefix (default: out/detect/NAME, giving NAME.samples.csv and NAME.windows.csv)")


def _file_params(rec: Recording) -> ReflexParams | None:
    """The run's chain from an export's header, or None for a plain CSV."""
    text = rec.preamble.get("reflex_params")
    if text is None:
        return None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as err:
        raise DataError(f"{rec.path}: header line 'reflex_params' is not JSON ({err.msg})") from None
    try:
        return ReflexParams.from_dict(data)
    except (ParameterError, TypeError) as err:
        raise DataError(f"{rec.path}: header line 'reflex_params': {err}") from None


def _sampling_rate(rec: Recording, given: float | None, base: ReflexParams | None) -> float:
    if not rec.has_time:
        assert given is not None, "read_recording refuses a file with neither a t column nor --fs"
        return float(given)
    from_t = rec.step_rate()
    if given is not None and abs(given - from_t) > FS_TOLERANCE * from_t:
        raise ParameterError(f"--fs {given:g} disagrees with the t column of {rec.path} "
                             f"({from_t:.2f} Hz from its median step); leave out --fs or fix the file")
    if given is not None:
        return float(given)
    if base is not None and abs(base.fs - from_t) <= FS_TOLERANCE * from_t:
        return base.fs          # the run's exact rate, not the rounded times' estimate
    return from_t


#: What detect's input supplies, for the method check.
_INPUT = "detect's input (a CSV of slip-sensor volts)"


def method_chain(name: str | None) -> tuple[str | None, ReflexParams | None]:
    """``--method`` checked: its registered name, and the chain parameters of a chain variant
    (None for fixed and dath, whose options and header decide the rest).

    Examples
    --------
    >>> method_chain("DATH-event")[1].variants
    ('mpi_mode',)
    >>> method_chain("swt")                       # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: --method swt reads tactile frames, which detect's input ... does not ...
    """

    if name is None:
        return None, None
    spec = applicable(name, {"slip"}, _INPUT)
    if spec.name in (FIXED, DATH):
        return spec.name, None
    params = getattr(make(spec.name), "params", None)
    if not isinstance(params, ReflexParams):
        raise ParameterError(f"--method {spec.name} is not the chain with other parameters: give --board "
                             f"and a CSV of ADC counts for the board's chain")
    return spec.name, params


def chain_params(args: argparse.Namespace, rec: Recording) -> ReflexParams:
    """The chain to run: explicit options, else the method's or the file's header, else the defaults."""
    method, variant = method_chain(args.method)
    base = _file_params(rec)
    fs = _sampling_rate(rec, args.fs, base)
    preset = getattr(args, "preset", None)
    values = (ReflexParams.preset(preset, fs=fs) if preset else base or _DEFAULTS).to_dict()
    if variant is not None:
        values = {**variant.to_dict(), "p0": values["p0"]}
    values.update({k: getattr(args, k) for k in _FIELDS if getattr(args, k) is not None})
    if method in (FIXED, DATH):
        values["dath"] = method == DATH
    elif base is None and not preset and variant is None:
        values["dath"] = True
    if args.no_filter:
        values["filter"] = False
    values["fs"] = fs
    return ReflexParams.from_dict(values)


def _warn_irregular(rec: Recording) -> None:
    bad = irregular_steps(rec.t) if rec.has_time else []
    if len(bad):
        k = int(bad[0])
        med = float(np.median(np.diff(rec.t)))
        print(f"slipreflex detect: warning: {rec.path}, line {rec.lines[k]}: time step "
              f"{1e3 * (rec.t[k] - rec.t[k - 1]):.3g} ms where the median is {1e3 * med:.3g} ms "
              f"({len(bad)} such step(s)); the chain assumes uniform sampling", file=sys.stderr)


def _ms(samples: int, fs: float) -> str:
    return f"{samples} samples = {1e3 * samples / fs:.1f} ms"


def _saturation(res, t: np.ndarray, params: ReflexParams) -> str | None:
    """When the command reached the top of its range, and how many slip windows came after."""
    top = np.flatnonzero(res.commands >= params.hi)
    if not top.size:
        return None
    z = int(top[0])
    later = int((res.counts[z + 1:] > 0).sum())
    t_z = t[(z + 1) * params.n - 1]
    return (f"  saturated: the command reached {params.hi:g} (fully closed) at t = {t_z:.3f} s, window {z};"
            f" {later} later window(s) with slip could not raise it")


def run(args: argparse.Namespace) -> int:
    """Run the chain and write the two CSVs; print a summary."""

    if args.fs is not None:
        within("fs_hz", args.fs, "--fs")
    if args.board:
        if args.preset:
            raise ParameterError("--preset and --board: the board runs the paper's chain only")
        return _run_board(args)
    rec = read_recording(args.recording, fs=args.fs)
    params = chain_params(args, rec)
    prefix = _prefix(args)
    _warn_irregular(rec)
    res = run_chain(rec.x, params)
    prefix, note = _free_prefix(prefix)
    samples_path = Path(f"{prefix}.samples.csv")
    windows_path = Path(f"{prefix}.windows.csv")
    write_columns(samples_path, res.sample_columns(rec.t), replace=False)
    write_columns(windows_path, res.window_columns(rec.t), replace=False)
    final = f"{res.commands[-1]:g}" if res.commands.size else "none (shorter than one window)"
    source = " (chain and p0 from the file's header)" if "reflex_params" in rec.preamble else ""
    if args.preset:
        source = f" (preset {args.preset}: {', '.join(params.variants) or 'the paper chain'})"
    shown = method_chain(args.method)[0]
    shown = params.name if shown in (None, FIXED, DATH) else shown
    print(f"{args.recording}: {rec.x.size} samples at {params.fs:.2f} Hz, method {shown}{source}")
    print(f"  windows: {_ms(params.n, params.fs)}" + (f"; DATH: {_ms(params.dath_samples, params.fs)}"
                                                     if params.dath else ""))
    print(f"  events: {int(res.events.sum())}")
    print(f"  windows with slip: {int((res.counts > 0).sum())} of {res.counts.size}")
    print(f"  final command: {final} (p0 {params.p0:g})")
    saturated = _saturation(res, rec.t, params)
    if saturated:
        print(saturated)
    print(f"  wrote {samples_path} and {windows_path}{note}")
    return 0


_SUFFIXES = (".samples.csv", ".windows.csv")


def _free_prefix(prefix: Path) -> tuple[Path, str]:
    """The first prefix whose two files are both free (``NAME-2``...): detect writes new files, never
    over a file already there, nor through a symlink of that name; and a note saying so."""
    free = unique_prefix(prefix, _SUFFIXES)
    return free, "" if free == prefix else f" ({prefix.name}.* exist and are kept)"


def _prefix(args: argparse.Namespace) -> Path:
    """The output prefix, its folder checked before any work: out/detect/NAME by default."""
    prefix = args.out if args.out is not None else Path("out") / "detect" / args.recording.stem
    output_dir(prefix.parent, "--out")
    return prefix


def _run_board(args: argparse.Namespace) -> int:
    """``detect --board``: the Python twin of the firmware over a CSV of ADC counts."""
    p0 = number("--p0", 0.0 if args.p0 is None else args.p0, lo=0, hi=FINGER_MAX)
    method = applicable(args.method or DATH, {"slip"}, _INPUT).name
    method = {"dath-board": DATH, "fixed-board": FIXED}.get(method, method)
    if method not in (FIXED, DATH):
        raise ParameterError(f"--method {method} with --board: the board runs fixed or dath "
                             f"(dath-board, fixed-board) only")
    if p0 != int(p0):
        raise ParameterError(f"--p0 must be a whole position with --board, got {p0!r}")
    prefix = _prefix(args)
    adc = read_adc_csv(args.recording)
    res = run_board_chain(adc, BoardParams.firmware(dath=method == DATH, p0=int(p0)))
    prefix, note = _free_prefix(prefix)
    paths = write_board_outputs(prefix, res.events, res.counts, res.commands)
    print(f"{args.recording}: {adc.size} ADC counts through the board's chain, method {method}")
    print(f"  events: {int(res.events.sum())}, faulty readings: {int(res.faults.sum())}")
    print(f"  wrote {paths[0]} and {paths[1]}{note}")
    return 0
