"""``slipreflex run``: the reflex in real time on the DAQ and the i-Limb (real or virtual).

Examples
--------
>>> from slipreflex.cli import main
>>> main(["run", "--daq", "/dev/ttyACM0", "--hand", "/dev/ttyUSB0", "--p0", "220"])  # doctest: +SKIP
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import math
import signal
import sys
import threading
from pathlib import Path
from typing import Any

from .. import __version__
from ..core.errors import ParameterError
from ..core.hardware import DAQ_FS, FINGER_MAX, FINGER_MIN, SLIP_FINGER, TRIPOD, Finger
from ..core.validation import within
from ..files.paths import unique_name
from ..files.recording import METADATA_NAME, PART_SUFFIX, PLANNED_SAMPLES, Recorder, RecordingError
from ..methods import DATH, FIXED, MethodContext, applicable, make
from ..methods.board import BoardParams, BoardSource, CheckedBoardReflex
from ..methods.chain import ReflexParams, SlipReflex
from ..methods.chain.params import PRESETS
from ..rig.devices.daq import SerialDaq
from ..rig.hands import get_hand, hand_names, open_hand
from ..rig.live import RUN_TOPICS
from ..rig.runtime import (
    WATCHDOG_MAX_S,
    WATCHDOG_MIN_S,
    WATCHDOG_S,
    drop_capabilities,
    print_fault,
    realtime_priority,
    run_loop,
    start_positions,
)
from ._live import add_live_arguments, check_live_arguments, close_taps, open_taps
from .nir import add_graph_option, apply_graph_option

NAME = "run"
HELP = "run the slip reflex in real time: read the DAQ (or the hand's touch sensors), drive the hand, record to MCAP"
ORDER = 30


#: Where a registered method other than fixed and dath starts its command (its own frame's open end).
REFLEX_FRAME_P0: float = float(FINGER_MIN)


def add_chain_arguments(p: argparse.ArgumentParser) -> None:
    """Chain options shared by ``run`` (defaults: the paper's)."""

    d = ReflexParams()
    g = p.add_argument_group("reflex chain")
    g.add_argument("--method", default=DATH,
                   help="a registered method: fixed or dath (default; the options below apply), a "
                        "variant of the chain on the slip sensor (dath-event, dath-floor, dath-leak, "
                        "authors-gui, ...), or a tactile method (nmsd, swt) reading the touch sensors "
                        "of a hand that has them (--hand-type ability) with --tactile-threshold")
    add_graph_option(g)
    g.add_argument("--tactile-threshold", type=float, default=None,
                   help="a tactile method's threshold, in its unit (N/s for nmsd, N for swt), as "
                        "calibrated at rest")

    g.add_argument("--preset", choices=sorted(PRESETS), default=None,
                   help="a named chain instead of the options below (the presets of 'detect'): "
                        "authors-gui is the authors' rig code (the middle finger gets the command + 20), "
                        "dath-event DATH with the event-driven MPI (docs/method.md); only --fs may be "
                        "given with it")
    g.add_argument("--fs", type=float, default=DAQ_FS,
                   help=f"sampling rate the chain assumes, Hz (the DAQ's {DAQ_FS:.2f})")
    g.add_argument("--cutoff", type=float, default=d.cutoff, help=f"low-pass cutoff, Hz ({d.cutoff:g})")
    g.add_argument("--no-filter", action="store_true", help="input is already filtered")
    g.add_argument("--threshold", type=float, default=d.threshold, help=f"theta0 in V ({d.threshold:g})")
    g.add_argument("--dath-samples", type=int, default=d.dath_samples, help=f"DATH duration D ({d.dath_samples})")
    g.add_argument("--dath-floor", type=float, default=d.dath_floor, help=f"DATH floor in V ({d.dath_floor:g})")
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
    """Build the ReflexParams the options describe for fixed or dath (a ``--preset`` with any other
    chain option is an error naming it, rather than one of them being silently ignored).

    ``p0`` is the MPI's bookkeeping only (the hand gets the command's rises as closing time,
    :mod:`slipreflex.core.grip`), so the command's ceiling is ``p0`` plus one whole finger travel:
    whatever ``p0`` says, the reflex can add the same grip (the hand's end stop ends it)."""

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
    slipreflex.core.errors.ParameterError: --p0 'thumb=148,thumb=14,index=147,middle=147': finger thumb is given twice
    """

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


def method_spec(args: argparse.Namespace):
    """``--method`` checked against what ``--daq`` and ``--hand-type`` supply (one-line errors)."""

    hand = get_hand(args.hand_type)
    supplies = {"slip"} if args.daq else set()
    if hand.tactile:
        supplies.add("tactile")
    where = " and ".join(([f"--daq {args.daq}"] if args.daq else ["no --daq"])
                         + [f"the {hand.label}" + ("'s touch sensors" if hand.tactile else "")])
    spec = applicable(args.method, supplies, where)
    chain_given = [o for o, k in _PRESET_REPLACES.items() if getattr(args, k) != getattr(_chain_defaults(), k)]
    if spec.name not in (FIXED, DATH):
        if args.preset or chain_given or args.no_filter:
            what = f"--preset {args.preset}" if args.preset else (chain_given or ["--no-filter"])[0]
            raise ParameterError(f"--method {spec.name} is a registered method with its own parameters; "
                                 f"{what} applies to fixed and dath only")
        if args.board_reflex:
            raise ParameterError(f"--method {spec.name} cannot be used with --board-reflex (fixed or dath)")
    if spec.input_kind == "tactile":
        thr = args.tactile_threshold
        if thr is None or not (math.isfinite(thr) and thr > 0):
            raise ParameterError(f"--method {spec.name} needs --tactile-threshold > 0 ({spec.threshold_unit}, "
                                 f"calibrated at rest), got {thr}")
    elif args.tactile_threshold is not None:
        raise ParameterError(f"--tactile-threshold is for a tactile method; --method {spec.name} reads the "
                             f"slip sensor")
    return spec, hand


def _chain_defaults():

    return ReflexParams()


def build_reflex(args: argparse.Namespace, p0: dict[Finger, float]) -> tuple[Any, dict[str, str]]:
    """The reflex ``--method`` names and what the recording's metadata says about it."""

    spec, hand = method_spec(args)
    start = p0[SLIP_FINGER]
    if spec.name in (FIXED, DATH):
        params = chain_params(args, start)
        reflex: Any = SlipReflex.from_params(params)
        if args.preset:
            reflex.name = args.preset
        return reflex, {"reflex_params": json.dumps(params.to_dict())}
    # Every other method runs in its own frame, started at the open end of the finger range: its
    # command then has a whole finger travel of room below its own ceiling (a board method's is an
    # absolute 500), whatever --p0 says. The loop maps the measured positions into that frame and
    # sends only the command's rises, so the grip is the same for every --p0 (docs/runtime.md).
    if spec.input_kind == "slip":
        reflex = make(spec.name, p0=REFLEX_FRAME_P0)
    else:
        reflex = make(spec.name, p0=REFLEX_FRAME_P0, shape=hand.tactile_shape,
                      context=MethodContext(thresholds={spec.name: args.tactile_threshold}))
    params = getattr(reflex, "params", None)
    if isinstance(params, ReflexParams):
        return reflex, {"reflex_params": json.dumps(params.to_dict())}
    return reflex, {"method_params": repr(params)}


def check_arguments(args: argparse.Namespace) -> dict[Finger, float]:
    """Check every option of ``run`` (before any port is opened); return the per-finger p0."""

    if args.duration is not None:
        within("duration_s", args.duration, "--duration")
    within("fs_hz", args.fs, "--fs")
    if not (WATCHDOG_MIN_S <= args.watchdog <= WATCHDOG_MAX_S):
        raise ParameterError(f"--watchdog must be in {WATCHDOG_MIN_S:g}..{WATCHDOG_MAX_S:g} s "
                             f"(a hold needs a bounded wait), got {args.watchdog}")
    p0 = parse_p0(args.p0)
    apply_graph_option(args)
    build_reflex(args, p0)  # validates the method and every chain option
    if getattr(args, "board_reflex", False):
        _check_board_arguments(args)
    check_live_arguments(args)
    return p0


def _check_board_arguments(args: argparse.Namespace) -> None:
    """``--board-reflex`` runs the chain the board was built with: only --method may change."""

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

    p.add_argument("--daq", default=None,
                   help="DAQ serial port (e.g. /dev/ttyACM0, or a virtual-rig path); needed by a method "
                        "that reads the slip sensor")
    p.add_argument("--hand", required=True,
                   help="the hand's serial port (i-Limb control unit e.g. /dev/ttyUSB0; Ability Hand UART)")
    p.add_argument("--hand-type", default="ilimb", choices=hand_names(),
                   help="which hand is on --hand (slipreflex.rig.hands; default ilimb); ability: the PSYONIC "
                        "Ability Hand, whose index fingertip's touch sensors a tactile method reads")
    p.add_argument("--p0", required=True,
                   help="position (0..500) at which each tripod finger holds the object, as the grasp "
                        "routine left it: thumb=148,index=148,middle=148 (virtual-rig prints this line for "
                        "its default bottle), "
                        "or one value for all three (each finger once). Bookkeeping only: the loop "
                        "starts with STOP (fingers stay where they are), the MPI starts from the "
                        "middle finger's p0, and the hand only ever gets the command's rises as "
                        "closing time (no OPEN, no position; docs/runtime.md)")
    p.add_argument("--record", type=Path, default=None,
                   help="new MCAP file to record to, never an existing one (default: run-YYYYmmdd-HHMMSS.mcap "
                        "here, -2, -3... when taken); written as NAME.part and named NAME when the run ends")
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
    add_live_arguments(p)


def _p0_text(p0: dict[Finger, float]) -> str:
    return ",".join(f"{f.name.lower()}={v:g}" for f, v in p0.items())


def _open_run_taps(args: argparse.Namespace, reflex: Any, tactile: bool) -> list[Any]:
    """``--live`` / ``--lsl`` for this run: the topics its reflex and source give."""

    topics = RUN_TOPICS + (("/board/state",) if args.board_reflex else ())
    if tactile:
        topics = ("/tactile/frames",) + tuple(t for t in topics if not t.startswith("/daq/"))
    return open_taps(args, topics, lsl_source=args.daq or args.hand, fs=getattr(reflex, "fs", None),
                     taxels=math.prod(getattr(reflex.params, "shape", ())) if tactile else 0)


def _recorder(path: Path | None, meta: dict):
    """A new recording: ``path`` (never an existing file), or a free ``run-YYYYmmdd-HHMMSS[-N].mcap`` here."""

    if path is not None:
        return Recorder(path, metadata={METADATA_NAME: meta})
    stem = f"run-{datetime.datetime.now():%Y%m%d-%H%M%S}"
    for _ in range(100):      # two runs started in the same second get -2, -3...
        try:
            return Recorder(unique_name(".", stem, ".mcap", also=(PART_SUFFIX,)),
                            metadata={METADATA_NAME: meta})
        except RecordingError as err:
            if "exists" not in str(err):
                raise
    raise ParameterError(f"no free recording name {stem}-N.mcap here; give --record")


def _metadata(args: argparse.Namespace, reflex: Any, p0: dict[Finger, float],
              board_meta: dict[str, str]) -> dict[str, str]:
    """The run's facts for the recording's metadata."""

    fs = float(getattr(reflex, "fs", DAQ_FS))
    meta = {"version": __version__, "reflex": reflex.name, "hand_type": args.hand_type,
            "fingers": json.dumps([f.name.lower() for f in TRIPOD]),
            "p0": json.dumps({f.name.lower(): v for f, v in p0.items()}),
            "daq": str(args.daq), "hand": args.hand, "watchdog_s": repr(args.watchdog),
            "started": datetime.datetime.now(datetime.UTC).isoformat(), "rate_hz": repr(fs),
            **board_meta}
    if args.duration is not None:   # a reader of a file cut short then knows what it misses
        meta[PLANNED_SAMPLES] = str(round(args.duration * fs))
    return meta


def run(args: argparse.Namespace) -> int:
    """Open the devices and the recording, run the loop, print the summary."""
    p0 = check_arguments(args)  # everything, before a port opens or a byte is sent
    reflex: Any
    reflex, board_meta = build_reflex(args, p0)
    tactile = getattr(reflex, "input_kind", "slip") == "tactile"
    if args.board_reflex:

        bparams = BoardParams.firmware(dath=args.method == DATH, p0=args.board_p0)
        reflex = CheckedBoardReflex(bparams)
        board_meta = {**board_meta, "board_params": json.dumps(bparams.to_dict())}
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
        recorder = _recorder(args.record, _metadata(args, reflex, p0, board_meta))  # before the ports open
    taps: list[Any] = []
    old = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    started = False
    try:
        taps = _open_run_taps(args, reflex, tactile)
        with contextlib.ExitStack() as devices:
            hand = devices.enter_context(open_hand(args.hand_type, args.hand,
                                                   **({"fs": reflex.fs} if tactile else {})))
            daq = None if tactile else devices.enter_context(SerialDaq(args.daq))
            started = True
            print(f"running {reflex.name} reflex: "
                  + (f"touch sensors of the {args.hand_type} hand" if tactile else f"daq {args.daq}")
                  + f", hand {args.hand_type} on {args.hand}, p0 " + _p0_text(p0)
                  + (f", recording {recorder.path}" if recorder else "") + " (Ctrl-C stops)", flush=True)
            source: Any = hand if tactile else daq
            if args.board_reflex:

                source = BoardSource(daq, reflex)
            # run_loop starts with STOP: the fingers stay where the grasp left them
            res = run_loop(source, hand, reflex, p0=p0, recorder=recorder, duration=args.duration,
                           watchdog=args.watchdog, stop=stop, on_fault=print_fault, taps=taps)
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        close_taps(taps)
        if recorder is not None:
            if started:
                recorder.close()
            else:  # the ports did not open: remove the recording this run created, nothing else
                recorder.discard()
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
    if res.error:  # the method failed: the fingers were held, the summary and recording are written
        print(f"slipreflex run: error: {res.error}", file=sys.stderr)
        return 2
    return 0
