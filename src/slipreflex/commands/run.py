"""``slipreflex run``: the reflex in real time on the DAQ and the i-Limb (real or virtual).

Examples
--------
>>> from slipreflex.cli import main
>>> main(["run", "--daq", "/dev/ttyACM0", "--hand", "/dev/ttyUSB0", "--p0", "220"])  # doctest: +SKIP
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import signal
import sys
import threading
from pathlib import Path
from typing import Any

from .. import __version__
from ..errors import ParameterError
from ..hardware import DAQ_FS, FINGER_MAX, FINGER_MIN, SLIP_FINGER, TRIPOD, Finger
from ..methods import DATH, FIXED
from ..runtime import WATCHDOG_MAX_S, WATCHDOG_MIN_S, WATCHDOG_S

NAME = "run"
HELP = "run the slip reflex in real time: read the DAQ port, drive the i-Limb port, record to MCAP"
ORDER = 30


def add_chain_arguments(p: argparse.ArgumentParser) -> None:
    """Chain options shared by ``run`` (defaults: the paper's)."""
    from ..chain import ReflexParams

    d = ReflexParams()
    g = p.add_argument_group("reflex chain")
    g.add_argument("--method", choices=(FIXED, DATH), default=DATH,
                   help="fixed threshold or Dynamic Adaptive Threshold (default: dath)")
    g.add_argument("--preset", choices=("authors-gui", "dath-event"), default=None,
                   help="a named chain instead of the options below: authors-gui is the authors' rig "
                        "code (the middle finger gets the command + 20), dath-event DATH with the "
                        "event-driven MPI (docs/method.md); only --fs may be given with it")
    g.add_argument("--fs", type=float, default=DAQ_FS,
                   help=f"sampling rate the chain assumes, Hz (the DAQ's {DAQ_FS:.2f})")
    g.add_argument("--cutoff", type=float, default=d.cutoff, help=f"low-pass cutoff, Hz ({d.cutoff:g})")
    g.add_argument("--no-filter", action="store_true", help="input is already filtered")
    g.add_argument("--threshold", type=float, default=d.threshold, help=f"theta0 in V ({d.threshold:g})")
    g.add_argument("--dath-samples", type=int, default=d.dath_samples, help=f"DATH duration D ({d.dath_samples})")
    g.add_argument("--dath-floor", type=float, default=d.dath_floor, help="DATH floor in V (0)")
    g.add_argument("--n", type=int, default=d.n, help=f"samples per window ({d.n})")
    g.add_argument("--kp", type=float, default=d.kp, help=f"proportional gain ({d.kp:g})")
    g.add_argument("--ki", type=float, default=d.ki, help=f"integral gain ({d.ki:g})")
    g.add_argument("--reset-after", type=int, default=d.reset_after,
                   help=f"zero windows before P0 resets ({d.reset_after})")


#: chain options a preset replaces: option -> its argparse dest (a ReflexParams field)
_PRESET_REPLACES = {"--cutoff": "cutoff", "--threshold": "threshold", "--dath-samples": "dath_samples",
                    "--dath-floor": "dath_floor", "--n": "n", "--kp": "kp", "--ki": "ki",
                    "--reset-after": "reset_after"}


def chain_params(args: argparse.Namespace, p0: float):
    """Build the ReflexParams the options describe (a ``--preset`` with any other chain option
    is an error naming it, rather than one of them being silently ignored).

    ``p0`` is the MPI's bookkeeping only (the hand gets the command's rises as closing time,
    :mod:`slipreflex.grip`), so the command's ceiling is ``p0`` plus one whole finger travel:
    whatever ``p0`` says, the reflex can add the same grip (the hand's end stop ends it)."""
    from ..chain import ReflexParams

    hi = p0 + (FINGER_MAX - FINGER_MIN)
    if getattr(args, "preset", None):
        d = ReflexParams()
        given = [o for o, k in _PRESET_REPLACES.items() if getattr(args, k) != getattr(d, k)]
        given += ["--method fixed"] * (args.method != DATH) + ["--no-filter"] * args.no_filter
        if given:
            raise ParameterError(f"--preset {args.preset} sets the whole chain; {given[0]} cannot be "
                                 f"combined with it")
        return ReflexParams.preset(args.preset, fs=args.fs, p0=p0, hi=hi)
    return ReflexParams(fs=args.fs, cutoff=args.cutoff, filter=not args.no_filter,
                        threshold=args.threshold, dath=args.method == DATH,
                        dath_samples=args.dath_samples, dath_floor=args.dath_floor, n=args.n,
                        p0=p0, kp=args.kp, ki=args.ki, reset_after=args.reset_after, hi=hi)


def parse_p0(text: str) -> dict[Finger, float]:
    """Parse ``--p0``: ``thumb=149,index=147,middle=147``, ``149,147,147`` (tripod order) or ``147``.

    Examples
    --------
    >>> {f.name: v for f, v in parse_p0("thumb=149, index=147, middle=147").items()}
    {'THUMB': 149.0, 'INDEX': 147.0, 'MIDDLE': 147.0}
    >>> parse_p0("147")[Finger.THUMB]
    147.0
    >>> parse_p0("thumb=148,thumb=14,index=147,middle=147")
    Traceback (most recent call last):
    ...
    slipreflex.errors.ParameterError: --p0 'thumb=148,thumb=14,index=147,middle=147': finger thumb is given twice
    """
    from ..runtime import start_positions

    items = [x.strip() for x in str(text).split(",") if x.strip()]
    if not items:
        raise ParameterError("--p0: empty (give thumb=..,index=..,middle=.. or one position)")
    names = [x.split("=", 1)[0].strip().lower() for x in items if "=" in x]
    twice = next((k for i, k in enumerate(names) if k in names[:i]), None)
    if twice is not None:
        raise ParameterError(f"--p0 {text!r}: finger {twice} is given twice")
    try:
        if all("=" in x for x in items):
            given: Any = {k.strip(): float(v) for k, v in (x.split("=", 1) for x in items)}
        elif len(items) == 1:
            given = float(items[0])
        elif len(items) == len(TRIPOD):
            given = {f: float(v) for f, v in zip(TRIPOD, items)}
        else:
            raise ParameterError(f"--p0 {text!r}: give one position, {len(TRIPOD)} (thumb,index,middle) "
                                 f"or finger=position items")
    except ValueError:
        raise ParameterError(f"--p0 {text!r}: positions must be numbers in 0..{FINGER_MAX}") from None
    return start_positions(given, TRIPOD, where="--p0")


def check_arguments(args: argparse.Namespace) -> dict[Finger, float]:
    """Check every option of ``run`` (before any port is opened); return the per-finger p0."""
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise ParameterError(f"--duration must be a number of seconds > 0, got {args.duration}")
    if not (WATCHDOG_MIN_S <= args.watchdog <= WATCHDOG_MAX_S):
        raise ParameterError(f"--watchdog must be in {WATCHDOG_MIN_S:g}..{WATCHDOG_MAX_S:g} s "
                             f"(a hold needs a bounded wait), got {args.watchdog}")
    p0 = parse_p0(args.p0)
    chain_params(args, p0[SLIP_FINGER])  # validates every chain option
    if getattr(args, "board_reflex", False):
        _check_board_arguments(args)
    return p0


def _check_board_arguments(args: argparse.Namespace) -> None:
    """``--board-reflex`` runs the chain the board was built with: only --method may change."""
    from ..chain import ReflexParams

    if args.preset:
        raise ParameterError(f"--preset {args.preset} cannot be used with --board-reflex: the board "
                             f"runs the paper's chain it was built with (docs/firmware.md)")
    d = ReflexParams()
    fixed = {"fs": DAQ_FS, "cutoff": d.cutoff, "no_filter": False, "threshold": d.threshold,
             "dath_samples": d.dath_samples, "dath_floor": d.dath_floor, "n": d.n, "kp": d.kp,
             "ki": d.ki, "reset_after": d.reset_after}
    for name, value in fixed.items():
        if getattr(args, name) != value:
            raise ParameterError(f"--{name.replace('_', '-')} cannot be changed with --board-reflex: "
                                 f"the board runs the chain it was built with (docs/firmware.md)")
    if not (isinstance(args.board_p0, int) and 0 <= args.board_p0 <= FINGER_MAX):
        raise ParameterError(f"--board-p0 must be a whole position in 0..{FINGER_MAX}, got {args.board_p0}")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex run``."""
    p.add_argument("--daq", required=True, help="DAQ serial port (e.g. /dev/ttyACM0, or a virtual-rig path)")
    p.add_argument("--hand", required=True, help="i-Limb control unit serial port (e.g. /dev/ttyUSB0)")
    p.add_argument("--p0", required=True,
                   help="position (0..500) at which each tripod finger holds the object, as the grasp "
                        "routine left it: thumb=149,index=147,middle=147 (virtual-rig prints this), "
                        "or one value for all three (each finger once). Bookkeeping only: the loop "
                        "starts with STOP (fingers stay where they are), the MPI starts from the "
                        "middle finger's p0, and the hand only ever gets the command's rises as "
                        "closing time (no OPEN, no position; docs/runtime.md)")
    p.add_argument("--record", type=Path, default=None,
                   help="MCAP file to record to (default: run-YYYYmmdd-HHMMSS.mcap here)")
    p.add_argument("--no-record", action="store_true", help="do not record")
    p.add_argument("--duration", type=float, default=None, help="stop after this many seconds")
    p.add_argument("--watchdog", type=float, default=WATCHDOG_S,
                   help=f"seconds without a valid sample before the fingers hold "
                        f"({WATCHDOG_MIN_S:g}..{WATCHDOG_MAX_S:g}; {WATCHDOG_S:g})")
    p.add_argument("--realtime", action="store_true",
                   help="ask for SCHED_FIFO real-time scheduling (Linux; needs CAP_SYS_NICE or an "
                        "rtprio limit, not root: docs/runtime.md)")
    p.add_argument("--board-reflex", action="store_true",
                   help="the DAQ board runs the reflex itself (firmware daq-reflex or hand2560): record "
                        "what it does and check its output on every sample against its Python twin; a "
                        "difference is a recorded fault (board-mismatch). The hand gets the twin's commands")
    p.add_argument("--board-p0", type=int, default=0,
                   help="with --board-reflex: the REFLEX_P0 the board was built with (default 0)")
    add_chain_arguments(p)


def run(args: argparse.Namespace) -> int:
    """Open the devices and the recording, run the loop, print the summary."""
    from ..chain import SlipReflex
    from ..devices.daq import SerialDaq
    from ..devices.ilimb import ILimb
    from ..recording import METADATA_NAME, Recorder
    from ..runtime import drop_capabilities, print_fault, realtime_priority, run_loop

    p0 = check_arguments(args)  # everything, before a port opens or a byte is sent
    params = chain_params(args, p0[SLIP_FINGER])
    reflex: Any = SlipReflex.from_params(params)
    if args.preset:
        reflex.name = args.preset
    board_meta: dict[str, str] = {}
    if args.board_reflex:
        from ..board import BoardParams, CheckedBoardReflex

        bparams = BoardParams.firmware(dath=args.method == DATH, p0=args.board_p0)
        reflex = CheckedBoardReflex(bparams)
        board_meta = {"board_params": json.dumps(bparams.to_dict())}
    if args.realtime:
        print(realtime_priority(), flush=True)
    dropped = drop_capabilities()  # the loop keeps nothing it does not need (docs/runtime.md)
    if dropped and (args.realtime or not dropped.startswith("root:")):
        print(dropped, flush=True)
    stop = threading.Event()

    def on_signal(signum: int, _frame: object) -> None:
        if stop.is_set() and signum == signal.SIGINT:
            raise KeyboardInterrupt  # a second Ctrl-C: stop now
        stop.set()  # the loop ends within one poll and everything is closed in order

    recorder = None
    if not args.no_record:
        path = args.record or Path(f"run-{datetime.datetime.now():%Y%m%d-%H%M%S}.mcap")
        meta = {"version": __version__, "reflex": reflex.name,
                "reflex_params": json.dumps(params.to_dict()),
                "fingers": json.dumps([f.name.lower() for f in TRIPOD]),
                "p0": json.dumps({f.name.lower(): v for f, v in p0.items()}),
                "daq": args.daq, "hand": args.hand, "watchdog_s": repr(args.watchdog),
                "started": datetime.datetime.now(datetime.UTC).isoformat(), **board_meta}
        recorder = Recorder(path, metadata={METADATA_NAME: meta})  # fails before the ports open
    old = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    started = False
    try:
        with SerialDaq(args.daq) as daq, ILimb(args.hand) as hand:
            started = True
            print(f"running {reflex.name} reflex: daq {args.daq}, hand {args.hand}, p0 "
                  + ",".join(f"{f.name.lower()}={v:g}" for f, v in p0.items())
                  + (f", recording {recorder.path}" if recorder else "") + " (Ctrl-C stops)",
                  flush=True)
            source: Any = daq
            if args.board_reflex:
                from ..board import BoardSource

                source = BoardSource(daq, reflex)
            # run_loop starts with STOP: the fingers stay where the grasp left them
            res = run_loop(source, hand, reflex, p0=p0, recorder=recorder, duration=args.duration,
                           watchdog=args.watchdog, stop=stop, on_fault=print_fault)
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        if recorder is not None:
            recorder.close()
            if not started:  # the ports did not open: leave no empty recording behind
                Path(recorder.path).unlink(missing_ok=True)
    if stop.is_set():
        print("stopped by signal", flush=True)
    print(res.summary(), flush=True)
    if args.board_reflex:
        print(f"board check: {reflex.checked} samples compared with the Python twin, "
              f"{reflex.mismatches} differed", flush=True)
    if recorder is not None:
        print(f"recorded to {recorder.path}" + (" (incomplete)" if res.recording_error else ""))
    if res.recording_error:
        print(f"slipreflex run: warning: {res.recording_error}", file=sys.stderr)
    return 0
