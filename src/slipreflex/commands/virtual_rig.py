"""``slipreflex virtual-rig``: the simulated rig behind a virtual DAQ port and a virtual hand port.

Prints the two device paths and the grasp position, then runs in real time
until ``q``, Ctrl-C, SIGTERM or ``--duration``. A drop or a pour is triggered
by a key (``d`` / ``p`` then Enter), a signal (SIGUSR1 / SIGUSR2) or a
schedule (``--schedule "drop@2.0,pour@5.0"``, seconds after start).

Examples
--------
>>> from slipreflex.cli import main
>>> main(["virtual-rig", "--schedule", "drop@2.0", "--duration", "10"])  # doctest: +SKIP
daq: /dev/pts/5
hand: /dev/pts/6
p0: thumb=213,index=212,middle=212
"""

from __future__ import annotations

import argparse
import select
import signal
import sys
import threading
import time
from pathlib import Path

NAME = "virtual-rig"
HELP = "simulated rig behind two pseudo-terminals (DAQ and i-Limb) for 'slipreflex run'"
ORDER = 31


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex virtual-rig``."""
    p.add_argument("--bottle", default="TR",
                   help="bottle of the simulated rig (TX, TR, DK, or one of --objects; default TR)")
    p.add_argument("--objects", type=Path, default=None, metavar="FILE.toml",
                   help="your own bottles, surfaces, drops and pours (slipreflex.sim.load_objects)")
    p.add_argument("--drop", default=None, metavar="NAME", help="the drop of --objects that 'd' starts")
    p.add_argument("--pour", default=None, metavar="NAME", help="the pour of --objects that 'p' starts")
    p.add_argument("--grasp-force", type=float, default=None, metavar="N",
                   help="contact force at which the grasp stops closing, N (default: the paper's 0.8)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the simulation (0)")
    p.add_argument("--schedule", default="", help='perturbations, e.g. "drop@2.0,pour@5.0" (s after start)')
    p.add_argument("--link-dir", default=None,
                   help="also create DIR/daq and DIR/hand symlinks to the ports (stable paths; DIR is created)")
    p.add_argument("--duration", type=float, default=None, help="exit after this many seconds")
    p.add_argument("--realtime", action="store_true",
                   help="run the rig's real-time thread under SCHED_FIFO (it stands in for hardware "
                        "that a busy PC cannot slow; Linux, needs privileges)")


def _objects(args: argparse.Namespace):
    """The bottle and the drop / pour to use, by name, from the paper's or ``--objects``."""
    from ..errors import ParameterError
    from ..sim import BOTTLES, load_objects
    from ..sim.calibration import check_grasp
    from .reproduce import own_objects

    objs = load_objects(args.objects) if args.objects is not None else None
    table = {**BOTTLES, **(objs.bottles if objs is not None else {})}
    if args.bottle not in table:
        raise ParameterError(f"--bottle {args.bottle}: unknown (known: {', '.join(table)})")
    loads = {k[:-len("_object")]: v for k, v in own_objects(args).items() if k.endswith("_object")}
    if args.grasp_force is not None:
        check_grasp(table[args.bottle], args.grasp_force)
    else:
        check_grasp(table[args.bottle])
    return table[args.bottle], loads


def run(args: argparse.Namespace) -> int:
    """Grasp, open the ports, run in real time, print a summary at exit."""
    from ..devices.simrig import SimRig
    from ..devices.virtual import VirtualDevices, parse_schedule
    from ..paths import output_dir

    schedule = parse_schedule(args.schedule)
    if args.link_dir is not None:
        output_dir(args.link_dir, "--link-dir")      # before the grasp: a bad DIR costs one line
    bottle, loads = _objects(args)
    rig = SimRig(bottle=bottle, seed=args.seed, **loads)
    grasp = rig.grasp(args.grasp_force)
    stop = threading.Event()
    pending: list[str] = []

    def on_signal(signum: int, _frame: object) -> None:
        if signum in (signal.SIGINT, signal.SIGTERM):
            stop.set()
        else:
            pending.append("drop" if signum == signal.SIGUSR1 else "pour")

    old = {s: signal.signal(s, on_signal)
           for s in (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1, signal.SIGUSR2)}
    dev = VirtualDevices(rig, link_dir=args.link_dir, schedule=schedule)
    try:
        print(f"daq: {dev.daq_path}", flush=True)
        print(f"hand: {dev.hand_path}", flush=True)
        print(f"p0: {grasp.p0_text()}", flush=True)
        print(f"grasp: bottle {args.bottle}, {grasp.force_n:.2f} N per contact, "
              f"{'stable' if grasp.stable else 'NOT stable'}", flush=True)
        print(f"run: slipreflex run --daq {dev.daq_path} --hand {dev.hand_path} --p0 {grasp.p0_text()}",
              flush=True)
        print("keys: d+Enter drop, p+Enter pour, q+Enter quit; SIGUSR1 drop, SIGUSR2 pour", flush=True)
        if args.realtime:
            from ..runtime import realtime_priority

            print(f"rig: {realtime_priority()}", flush=True)  # the rig's thread inherits it
        dev.start()
        t0 = time.monotonic()
        stdin_open = sys.stdin is not None and not sys.stdin.closed
        while not stop.is_set():
            if args.duration is not None and time.monotonic() - t0 >= args.duration:
                break
            while pending:
                kind = pending.pop(0)
                dev.trigger(kind)
                print(f"{kind} at {dev.elapsed:.2f} s (signal)", flush=True)
            if not dev.running:
                break
            if stdin_open:
                try:
                    ready, _, _ = select.select([sys.stdin], [], [], 0.1)  # pyright: ignore[reportArgumentType]
                except (OSError, ValueError):
                    stdin_open = False
                    continue
                if ready and sys.stdin is not None:
                    line = sys.stdin.readline()
                    if not line:
                        stdin_open = False  # EOF: keep running on schedule and signals
                        continue
                    key = line.strip().lower()[:1]
                    if key == "q":
                        break
                    if key in ("d", "p"):
                        dev.trigger("drop" if key == "d" else "pour")
                        print(f"{'drop' if key == 'd' else 'pour'} at {dev.elapsed:.2f} s", flush=True)
            else:
                stop.wait(0.1)
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        dev.stop()
    print(f"stopped after {dev.elapsed:.1f} s: {dev.frames_written} frames sent, "
          f"{dev.hand_packets} hand packets applied ({dev.hand_parser.rejected} rejected), "
          f"perturbations {[(k, round(t, 2)) for k, t in dev.triggered]}", flush=True)
    print(rig.status(), flush=True)
    return 0

