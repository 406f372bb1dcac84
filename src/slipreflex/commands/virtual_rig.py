"""``slipreflex virtual-rig``: the simulated rig behind a virtual DAQ port and a virtual hand port.

Prints the two device paths and the grasp position, then runs in real time
until ``q``, Ctrl-C, SIGTERM or ``--duration``. A drop or a pour is triggered
by a key (``d`` / ``p`` then Enter), a signal (SIGUSR1 / SIGUSR2) or a
schedule (``--schedule "drop@2.0,pour@5.0"``, seconds after ``slipreflex run`` connects,
or after the rig's start with ``--schedule-from start``); each is announced as it starts.
At exit the summary gives the fall's time (if the bottle fell) on the rig's clock, and the
slide capped at the grip's fall-out travel.

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
import os
import select
import signal
import sys
import threading
import time
from pathlib import Path

from ..core.errors import ParameterError
from ..core.validation import within
from ..files.paths import output_dir
from ..methods import applicable
from ..rig.devices.simrig import SimRig
from ..rig.devices.virtual import VirtualDevices, parse_schedule
from ..rig.hands import get_hand, hand_names
from ..rig.runtime import realtime_priority
from ._live import add_live_arguments, check_live_arguments, close_taps, open_taps
from .nir import add_graph_option, apply_graph_option
from .reproduce import own_objects

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
    p.add_argument("--schedule", default="",
                   help='perturbations, e.g. "drop@2.0,pour@5.0" (s after --schedule-from)')
    p.add_argument("--schedule-from", choices=("connect", "start"), default="connect",
                   help="the schedule counts from when 'slipreflex run' connects (its first hand packet; "
                        "the default) or from the rig's start")
    p.add_argument("--link-dir", default=None,
                   help="also create DIR/daq and DIR/hand symlinks to the ports (stable paths; DIR is created; "
                        "existing DIR/daq or DIR/hand is an error, and only the links made are removed at exit)")
    p.add_argument("--duration", type=float, default=None, help="exit after this many seconds")

    p.add_argument("--hand-type", default="ilimb", choices=hand_names(),
                   help="the hand behind the hand port (default ilimb; ability: the Ability Hand's UART, "
                        "with its fingertip touch sensors fed from the simulated tactile arrays)")
    p.add_argument("--method", default=None,
                   help="the method 'run' will use: checked against what this rig supplies (the slip "
                        "sensor; tactile frames with --hand-type ability) and put in the printed run line")
    add_graph_option(p)
    add_live_arguments(p, lsl=False)
    p.add_argument("--realtime", action="store_true",
                   help="run the rig's real-time thread under SCHED_FIFO (it stands in for hardware "
                        "that a busy PC cannot slow; Linux, needs privileges)")


def _objects(args: argparse.Namespace):
    """The bottle and the drop / pour to use, by name, from the paper's or ``--objects``."""
    from ..sim import BOTTLES, load_objects  # deferred: heavy (numba kernels)
    from ..sim.calibration import check_grasp  # deferred: heavy (numba kernels)

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


def _announce(dev, grasp, args: argparse.Namespace, hand, method, schedule) -> None:
    """The lines a user needs first: the ports, p0, the grasp, the run line, keys, the schedule."""
    print(f"daq: {dev.daq_path}", flush=True)
    print(f"hand: {dev.hand_path}", flush=True)
    print(f"p0: {grasp.p0_text()}", flush=True)
    print(f"grasp: bottle {args.bottle}, {grasp.force_n:.2f} N per contact, "
          f"{'stable' if grasp.stable else 'NOT stable'}", flush=True)
    tactile = method is not None and method.input_kind == "tactile"
    line = "slipreflex run" + ("" if tactile else f" --daq {dev.daq_path}") + f" --hand {dev.hand_path}"
    if hand.name != "ilimb":
        line += f" --hand-type {hand.name}"
    if method is not None:
        line += f" --method {method.name}" + (" --tactile-threshold T" if tactile else "")
        line += f" --nir-graph {args.nir_graph}" if args.nir_graph is not None else ""
    print(f"run: {line} --p0 {grasp.p0_text()}", flush=True)
    print("keys: d+Enter drop, p+Enter pour, q+Enter quit; SIGUSR1 drop, SIGUSR2 pour", flush=True)
    if schedule:
        when = "after 'run' connects" if args.schedule_from == "connect" else "after now"
        print("schedule: " + ", ".join(f"{k} {t:g} s" for k, t in schedule) + f" {when}", flush=True)
    if args.realtime:

        print(f"rig: {realtime_priority()}", flush=True)  # the rig's thread inherits it


def _serve(dev, args: argparse.Namespace, stop: threading.Event, pending: list[str]) -> None:
    """Run until q, a signal, --duration or the rig's end; keys and signals start perturbations."""
    t0 = time.monotonic()
    stdin_open = sys.stdin is not None and not sys.stdin.closed
    while not stop.is_set():
        if args.duration is not None and time.monotonic() - t0 >= args.duration:
            break
        while pending:
            dev.trigger(pending.pop(0), "signal")
        if not dev.running:
            break
        if not stdin_open:
            stop.wait(0.1)
            continue
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
                dev.trigger("drop" if key == "d" else "pour", "key")


def _check_arguments(args: argparse.Namespace) -> None:
    """Bounded --duration and --grasp-force; a --link-dir whose daq/hand names are free (before the grasp)."""

    if args.duration is not None:
        within("duration_s", args.duration, "--duration")
    if args.grasp_force is not None:
        within("grasp_force_n", args.grasp_force, "--grasp-force")
    if args.link_dir is not None:
        link_dir = output_dir(args.link_dir, "--link-dir")      # before the grasp: a bad DIR costs one line
        for name in ("daq", "hand"):
            if os.path.lexists(link_dir / name):
                raise ParameterError(f"--link-dir {args.link_dir}: {name} exists; the rig makes its links "
                                     f"new and removes only those (move it or choose another --link-dir)")


def run(args: argparse.Namespace) -> int:
    """Grasp, open the ports, run in real time, print a summary at exit."""
    schedule = parse_schedule(args.schedule)
    _check_arguments(args)
    check_live_arguments(args)
    hand = get_hand(args.hand_type)
    apply_graph_option(args)
    method = None
    if args.method is not None:
        method = applicable(args.method, {"slip", "tactile"} if hand.tactile else {"slip"},
                            f"the virtual rig with the {hand.label}")
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

    def announce(text: str) -> None:
        print(text, flush=True)

    taps = open_taps(args, ("/rig/truth",))

    def publish_truth(_rig: object) -> None:  # the rig's thread: one /rig/truth per advance
        msg = rig.truth()
        for tap in taps:
            tap.put("/rig/truth", msg, time.time_ns())

    try:
        dev = VirtualDevices(rig, link_dir=args.link_dir, schedule=schedule, schedule_from=args.schedule_from,
                             on_event=announce, on_advance=publish_truth if taps else None,
                             hand_type=hand.name)
    except BaseException:
        close_taps(taps)
        raise
    try:
        _announce(dev, grasp, args, hand, method, schedule)
        dev.start()
        _serve(dev, args, stop, pending)
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        try:
            dev.stop()
        finally:
            close_taps(taps)
    print(f"stopped after {dev.elapsed:.1f} s: {dev.frames_written} frames sent, "
          f"{dev.hand_packets} hand packets applied "
          f"({(dev.emulator or dev.hand_parser).rejected} rejected), "
          f"perturbations {[(k, round(t, 2)) for k, t in dev.triggered]}", flush=True)
    print(rig.status(), flush=True)
    return 0

