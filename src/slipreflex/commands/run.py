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
import signal
import sys
import threading
from pathlib import Path

from .. import __version__
from ..errors import ParameterError

NAME = "run"
HELP = "run the slip reflex in real time: read the DAQ port, drive the i-Limb port, record to MCAP"
ORDER = 30


def add_chain_arguments(p: argparse.ArgumentParser) -> None:
    """Chain options shared by ``run`` (defaults: the paper's)."""
    from ..chain import ReflexParams

    d = ReflexParams()
    g = p.add_argument_group("reflex chain")
    g.add_argument("--method", choices=("fixed", "dath"), default="dath",
                   help="fixed threshold or Dynamic Adaptive Threshold (default: dath)")
    g.add_argument("--fs", type=float, default=d.fs, help=f"sampling rate the chain assumes, Hz ({d.fs:g})")
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


def chain_params(args: argparse.Namespace, p0: float):
    """Build the ReflexParams the options describe."""
    from ..chain import ReflexParams

    return ReflexParams(fs=args.fs, cutoff=args.cutoff, filter=not args.no_filter,
                        threshold=args.threshold, dath=args.method == "dath",
                        dath_samples=args.dath_samples, dath_floor=args.dath_floor, n=args.n,
                        p0=p0, kp=args.kp, ki=args.ki, reset_after=args.reset_after)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex run``."""
    p.add_argument("--daq", required=True, help="DAQ serial port (e.g. /dev/ttyACM0, or a virtual-rig path)")
    p.add_argument("--hand", required=True, help="i-Limb control unit serial port (e.g. /dev/ttyUSB0)")
    p.add_argument("--p0", type=float, required=True,
                   help="position (0..500) at which the tripod holds the object; the loop first "
                        "commands the tripod there and the MPI starts from it (virtual-rig prints it)")
    p.add_argument("--record", type=Path, default=None,
                   help="MCAP file to record to (default: run-YYYYmmdd-HHMMSS.mcap here)")
    p.add_argument("--no-record", action="store_true", help="do not record")
    p.add_argument("--duration", type=float, default=None, help="stop after this many seconds")
    p.add_argument("--watchdog", type=float, default=0.1,
                   help="seconds without a valid sample before the fingers hold (0.1)")
    p.add_argument("--realtime", action="store_true",
                   help="ask for SCHED_FIFO real-time scheduling (Linux; needs privileges)")
    add_chain_arguments(p)


def run(args: argparse.Namespace) -> int:
    """Open the devices and the recording, run the loop, print the summary."""
    from ..chain import SlipReflex
    from ..devices.daq import SerialDaq
    from ..devices.ilimb import ILimb
    from ..hardware import TRIPOD
    from ..recording import METADATA_NAME, Recorder
    from ..runtime import print_fault, realtime_priority, run_loop

    if args.duration is not None and not args.duration > 0:
        raise ParameterError(f"--duration must be > 0, got {args.duration}")
    params = chain_params(args, args.p0)
    reflex = SlipReflex.from_params(params)
    if args.realtime:
        print(realtime_priority(), flush=True)
    stop = threading.Event()

    def on_signal(signum: int, _frame: object) -> None:
        if stop.is_set() and signum == signal.SIGINT:
            raise KeyboardInterrupt  # a second Ctrl-C: stop now
        stop.set()  # the loop ends within one poll and everything is closed in order

    old = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    recorder = None
    try:
        with SerialDaq(args.daq) as daq, ILimb(args.hand) as hand:
            if not args.no_record:
                path = args.record or Path(f"run-{datetime.datetime.now():%Y%m%d-%H%M%S}.mcap")
                meta = {"version": __version__, "reflex": reflex.name,
                        "reflex_params": json.dumps(params.to_dict()),
                        "fingers": json.dumps([f.name.lower() for f in TRIPOD]),
                        "daq": args.daq, "hand": args.hand, "watchdog_s": repr(args.watchdog),
                        "started": datetime.datetime.now(datetime.timezone.utc).isoformat()}
                recorder = Recorder(path, metadata={METADATA_NAME: meta})  # fails before the run
            hand.set_positions({f: args.p0 for f in TRIPOD})  # validated; holds the grasp
            print(f"running {reflex.name} reflex: daq {args.daq}, hand {args.hand}, p0 {args.p0:g}"
                  + (f", recording {recorder.path}" if recorder else "") + " (Ctrl-C stops)",
                  flush=True)
            res = run_loop(daq, hand, reflex, recorder=recorder, duration=args.duration,
                           watchdog=args.watchdog, stop=stop, on_fault=print_fault)
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        if recorder is not None:
            recorder.close()
    if stop.is_set():
        print("stopped by signal", flush=True)
    print(res.summary(), flush=True)
    if recorder is not None:
        print(f"recorded to {recorder.path}" + (" (incomplete)" if res.recording_error else ""))
    if res.recording_error:
        print(f"slipreflex run: warning: {res.recording_error}", file=sys.stderr)
    return 0
