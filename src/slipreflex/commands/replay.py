"""``slipreflex replay``: re-run a recorded run's chain offline and check it reproduces the run.

Examples
--------
>>> from slipreflex.cli import main
>>> main(["replay", "run.mcap"])  # doctest: +SKIP
samples 19998
events: recorded 112, replayed 112 - identical
commands: recorded 1249, replayed 1249 - identical
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from ..core.errors import DataError, ParameterError
from ..core.hardware import SLIP_FINGER
from ..files.recording import METADATA_NAME, TOPICS, read_recording
from ..methods import MethodContext, applicable, make
from ..rig.replay import replay
from ._live import add_live_arguments, check_live_arguments, close_taps, open_taps

NAME = "replay"
HELP = "re-run the chain over a recording (MCAP) and compare with the recorded events and commands"
ORDER = 32


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex replay``."""

    add_recording_arguments(p, "replay a recording cut by a crash or with damaged chunks up to its first gap")
    add_live_arguments(p)
    p.add_argument("--method", default=None,
                   help="instead of checking the recorded chain, run this registered method over the "
                        "recorded input (a method that reads the slip sensor over /daq/samples, a tactile "
                        "one over /tactile/frames) and print what it would have done")
    p.add_argument("--threshold", type=float, default=None,
                   help="with a tactile --method: its threshold in its unit (N/s for nmsd, N for swt)")
    p.add_argument("--pace", type=float, default=1.0,
                   help="with --live/--lsl: play the recording at this many times real time "
                        "(1 = as recorded; 0 = as fast as possible)")


def run(args: argparse.Namespace) -> int:
    """Replay; exit 0 if identical, 1 if not, 2 for a partial recording without --allow-partial."""


    if not (math.isfinite(args.pace) and args.pace >= 0):
        raise ParameterError(f"--pace must be a number >= 0, got {args.pace}")
    check_live_arguments(args)
    rec = read_checked(args)
    if args.live is not None or args.lsl is not None:
        frames = rec.topic("/tactile/frames")
        taxels = sum(k.startswith("taxel_") for k in frames[0]) if frames else 0
        taps = open_taps(args, [t for t in rec.messages if rec.messages[t]],
                         lsl_source=str(args.recording), taxels=taxels)
        try:
            n = play(rec, taps, args.pace)
        finally:
            close_taps(taps)
        print(f"played {n} messages of {args.recording}", flush=True)
    if args.method is not None:
        return replay_method(rec, args.method, args.threshold)
    res = replay(rec)
    print(res.summary())
    return 0 if res.identical else 1


def replay_method(rec, name: str, threshold: float | None = None) -> int:
    """Run a registered method over a recording's input; print its spikes and commands."""



    supplies = {k for k, topic in (("slip", "/daq/samples"), ("tactile", "/tactile/frames")) if rec.topic(topic)}
    spec = applicable(name, supplies, f"{rec.path} (recorded: {', '.join(sorted(supplies)) or 'nothing'})")
    start = json.loads(rec.metadata.get("start", {}).get("p0", "{}") or "{}")
    p0 = float(start.get(SLIP_FINGER.name.lower(), 0.0))
    params = {}
    if spec.input_kind == "tactile":
        frames = rec.topic("/tactile/frames")
        n = len([k for k in frames[0] if k.startswith("taxel_")])
        x = [np.array([m[f"taxel_{k}"] for k in range(n)]) for m in frames]
        if threshold is None:
            raise DataError(f"--method {spec.name} needs --threshold (its unit: {spec.threshold_unit})")
        params = {"threshold": threshold, "shape": (n,)}
        positions = [None] * len(x)
    else:
        samples = rec.topic("/daq/samples")
        x = [m["slip_volts"] for m in samples]
        positions = [m.get("position") for m in samples]
        frames = samples
    reflex = make(spec.name, p0=p0, context=MethodContext(), **params)
    events = commands = 0
    last = None
    for m, v, pos in zip(frames, x, positions):
        cmd = reflex.step(v, pos)
        events += bool(reflex.last_event)
        if cmd is not None:
            commands += 1
            last = (m["t"], float(cmd))
    recorded = rec.metadata.get(METADATA_NAME, {}).get("reflex", "?")
    print(f"{rec.path}: {len(x)} recorded {'frames' if spec.input_kind == 'tactile' else 'samples'} "
          f"(recorded with {recorded}) through {spec.name}")
    print(f"{spec.name}: events {events}, commands {commands}"
          + (f", last command {last[1]:g} at t={last[0]:.3f} s" if last else ""))
    return 0


def play(rec, taps, pace: float = 1.0, *, sleep=None, clock=None) -> int:
    """Put a recording's messages into ``taps`` in log-time order, ``pace`` times real time
    (0: at once); returns how many. Log times are the recorded ones.

    Examples
    --------
    >>> from slipreflex.files.recording import Recording
    >>> rec = Recording("r.mcap", messages={"/chain/events": [{"seq": 1, "t": 0.0}]},
    ...                 log_times={"/chain/events": [5]})
    >>> class Tap:
    ...     def put(self, topic, msg, ns): print(topic, msg, ns)
    >>> play(rec, [Tap()], 0)
    /chain/events {'seq': 1, 't': 0.0} 5
    1
    """

    sleep = sleep or time.sleep
    clock = clock or time.monotonic

    rank = {t: k for k, t in enumerate(TOPICS)}
    # the loop's own order: by log time, then sample, then topic as it writes them
    order = sorted(((ns, msg.get("seq", math.inf), rank.get(topic, len(rank)), topic, msg)
                    for topic, msgs in rec.messages.items()
                    for ns, msg in zip(rec.log_times.get(topic, []), msgs)), key=lambda x: x[:3])
    if not order:
        return 0
    ns0, start = order[0][0], clock()
    for ns, _, _, topic, msg in order:
        if pace > 0:
            wait = start + (ns - ns0) * 1e-9 / pace - clock()
            if wait > 0:
                sleep(wait)
        for tap in taps:
            tap.put(topic, msg, ns)
    return len(order)


def add_recording_arguments(p: argparse.ArgumentParser, partial_help: str) -> None:
    """The recording to read and ``--allow-partial`` (what the command does with a partial one)."""
    p.add_argument("recording", type=Path, help="MCAP file written by 'slipreflex run'")
    p.add_argument("--allow-partial", action="store_true",
                   help=f"{partial_help} (without it, such a recording is an error naming every gap)")


def read_checked(args: argparse.Namespace):
    """The recording ``args.recording``, partial ones refused unless ``args.allow_partial``."""

    rec = read_recording(args.recording)
    check_partial(rec, args.allow_partial)
    return rec


def check_partial(rec, allow: bool) -> None:
    """A recording with gaps is an error naming them, or with ``allow`` a warning on stderr."""


    gaps = rec.gaps()
    if gaps and not allow:
        raise DataError(f"{gaps} (--allow-partial uses what was read)")
    if gaps:
        print(f"slipreflex: warning: {gaps}", file=sys.stderr, flush=True)
