"""Latency of the real-time loop over the virtual devices (333 Hz DAQ, i-Limb port).

Starts ``slipreflex virtual-rig`` in its own process (the simulated rig behind
two pseudo-terminals, as a real DAQ board and control unit would be), then runs
exactly what ``slipreflex run`` runs - SerialDaq -> SlipReflex -> ILimb, with
the MCAP recording on - for ``--duration`` seconds and prints the latency from
a sample's arrival (its bytes read from the DAQ port) to its command written
to the hand port: p50, p99 and max, plus the DAQ counters.

Usage::

    python benchmarks/bench_runtime.py              # 60 s
    python benchmarks/bench_runtime.py --duration 10 --no-record
    python benchmarks/bench_runtime.py --hogs 2 --realtime   # two CPU hogs; loop and rig SCHED_FIFO
    python benchmarks/bench_runtime.py --duration 30 --live  # with the Foxglove live view and a client

With ``--live`` the loop publishes every message on a Foxglove WebSocket server
(``run --live``) and a client in another process subscribes to every channel and
reads everything, as Foxglove would.

Both latencies are printed: from reading the sample's bytes (the loop's work)
and from the frame's own arrival as its board time places it (what a backlog
adds). With ``--realtime`` the virtual rig, which stands in for hardware that
no CPU hog can slow, runs under SCHED_FIFO too.

Target: p99 <= 1 ms; with ``--realtime`` also under two CPU hogs.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time


def start_rig(link_dir: str, schedule: str, seed: int,
              realtime: bool = False) -> tuple[subprocess.Popen, dict[str, str]]:
    """Start the virtual rig and return it with the facts it prints (daq, hand, p0)."""
    cmd = [sys.executable, "-m", "slipreflex", "virtual-rig", "--link-dir", link_dir,
           "--seed", str(seed)] + (["--realtime"] if realtime else [])
    if schedule:
        cmd += ["--schedule", schedule]
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    info: dict[str, str] = {}
    deadline = time.monotonic() + 120
    while not {"daq", "hand", "p0"} <= set(info) and time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            raise SystemExit(f"virtual-rig exited early (status {proc.wait()})")
        key, sep, value = line.partition(":")
        if sep:
            info[key.strip()] = value.strip()
    return proc, info


def live_client(url: str, seconds: float) -> int:
    """A Foxglove WebSocket client that subscribes to every channel and reads until closed."""
    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect

    from slipreflex.rig.live import WS_SUBPROTOCOLS

    n, channels = 0, {}
    with connect(url, subprotocols=list(WS_SUBPROTOCOLS)) as ws:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            try:
                msg = ws.recv(timeout=1.0)
            except TimeoutError:
                continue
            except ConnectionClosed:
                break
            if isinstance(msg, str):
                m = json.loads(msg)
                if m["op"] == "advertise":
                    new = [c["id"] for c in m["channels"] if c["id"] not in channels]
                    channels.update({c["id"]: c["topic"] for c in m["channels"]})
                    ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                        {"id": cid, "channelId": cid} for cid in new]}))
            else:
                n += 1
    print(f"live client: {n} messages on {len(channels)} channels", flush=True)
    return 0


def _stop(rig: subprocess.Popen, hogs: list[subprocess.Popen]) -> None:
    """End the CPU hogs and the virtual rig (asked to quit first, killed after 10 s)."""
    for hog in hogs:
        hog.kill()
        hog.wait()
    try:
        rig.stdin.write("q\n")
        rig.stdin.flush()
    except OSError:
        pass
    try:
        rig.wait(timeout=10)
    except subprocess.TimeoutExpired:
        rig.kill()
        rig.wait()
    rig.stdin.close()
    rig.stdout.close()


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark; print the numbers."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=60.0, help="seconds of loop (default 60)")
    ap.add_argument("--no-record", action="store_true", help="run without the MCAP recording")
    ap.add_argument("--realtime", action="store_true",
                    help="run the loop under SCHED_FIFO (as 'slipreflex run --realtime')")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--hogs", type=int, default=0,
                    help="start this many CPU hogs (busy processes at normal priority) meanwhile")
    ap.add_argument("--live", action="store_true",
                    help="publish on a Foxglove live view with a subscribed client (as 'run --live')")
    ap.add_argument("--client", default=None, help=argparse.SUPPRESS)  # the live client's own process
    ap.add_argument("--schedule", default=None,
                    help="perturbations for the rig (default: a drop every 10 s, first at 5 s)")
    args = ap.parse_args(argv)
    if args.client:
        return live_client(args.client, args.duration + 30)

    from slipreflex.commands.run import parse_p0
    from slipreflex.core.hardware import SLIP_FINGER
    from slipreflex.files.recording import METADATA_NAME, Recorder
    from slipreflex.methods.chain import SlipReflex
    from slipreflex.rig.devices.daq import SerialDaq
    from slipreflex.rig.devices.ilimb import ILimb
    from slipreflex.rig.runtime import realtime_priority, run_loop

    schedule = args.schedule
    if schedule is None:
        schedule = ",".join(f"drop@{t:g}" for t in range(5, int(args.duration) + 5, 10))
    with tempfile.TemporaryDirectory() as tmp:
        rig, info = start_rig(tmp, schedule, args.seed, args.realtime)
        hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(args.hogs)]
        try:
            p0 = parse_p0(info["p0"])  # per finger, as `run --p0` takes it
            reflex = SlipReflex(dath=True, p0=p0[SLIP_FINGER])
            rec = None
            if not args.no_record:
                rec = Recorder(os.path.join(tmp, "bench.mcap"), metadata={METADATA_NAME: {
                    "reflex_params": json.dumps(reflex.params.to_dict())}})
            note = realtime_priority() if args.realtime else "normal priority"
            taps, client = [], None
            if args.live:
                from slipreflex.rig.live import RUN_TOPICS, LiveView

                taps = [LiveView(("127.0.0.1", 0), RUN_TOPICS).start()]
                client = subprocess.Popen([sys.executable, __file__, "--client", taps[0].url,
                                           "--duration", str(args.duration)])
                time.sleep(2.0)  # the client connects and subscribes before the loop starts
            with SerialDaq(info["daq"]) as daq, ILimb(info["hand"]) as hand:
                res = run_loop(daq, hand, reflex, p0=p0, recorder=rec, duration=args.duration, taps=taps)
            for tap in taps:
                tap.close()
                print(f"live view: {tap.published} messages published, {tap.dropped} dropped", flush=True)
            if client is not None:
                client.wait(timeout=30)
            if rec is not None:
                rec.close()
                size = os.path.getsize(rec.path)
        finally:
            _stop(rig, hogs)
    lat, frame = res.latency_ms(), res.latency_ms("frame")
    print(f"machine: {platform.machine()}, {os.cpu_count()} cpus, python {platform.python_version()}, "
          f"load average {os.getloadavg()[0]:.2f}")
    print(f"loop over virtual devices for {res.duration:.1f} s "
          f"({'recording to MCAP' if not args.no_record else 'no recording'}"
          f"{', live view with a client' if args.live else ''}), p0 {info['p0']}, "
          f"rig schedule {schedule or 'none'}; {note}; {args.hogs} CPU hogs")
    print(res.summary())
    if not args.no_record:
        print(f"recording: {size / 1e6:.1f} MB ({size / res.duration / 1e3:.0f} kB/s)")
    print(f"RESULT latency_p50_ms={lat['p50']:.3f} latency_p99_ms={lat['p99']:.3f} "
          f"latency_max_ms={lat['max']:.3f} frame_latency_p50_ms={frame['p50']:.3f} "
          f"frame_latency_p99_ms={frame['p99']:.3f} frame_latency_max_ms={frame['max']:.3f} "
          f"commands={res.commands_sent} samples={res.samples} "
          f"seq_gaps={res.daq_stats.get('seq_gaps', 0)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
