"""How long `slipreflex reproduce` takes to stop after Ctrl-C or SIGTERM, printed, not asserted.

Starts the default reproduction, waits for its first progress line (10 % of the
trials), sends the signal (SIGINT to the process group as a terminal's Ctrl-C does,
or SIGTERM to the parent as `kill` does) and measures the time until the process has
exited with the finished trials written.

Usage::

    python benchmarks/bench_interrupt.py [--jobs N] [--repeat R]
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time


def stop_time(how: str, jobs: int) -> tuple[float, int, str]:
    """Seconds from the signal to the exit, the exit status and the partial note."""
    with tempfile.TemporaryDirectory() as out:
        cmd = [sys.executable, "-m", "slipreflex", "reproduce", "--out", out, "--jobs", str(jobs)]
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                                start_new_session=True)
        for line in proc.stderr:
            if line.startswith("trials:"):
                break
        t0 = time.monotonic()
        if how == "ctrl-c":
            os.killpg(proc.pid, signal.SIGINT)
        else:
            proc.send_signal(signal.SIGTERM)
        err = proc.communicate()[1]
        note = next((ln for ln in err.splitlines() if "interrupted after" in ln), "no partial note")
        return time.monotonic() - t0, proc.returncode, note


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--repeat", type=int, default=2, help="runs per signal (default 2)")
    args = ap.parse_args()
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}; jobs={args.jobs}")
    for how in ("ctrl-c", "sigterm"):
        for _ in range(args.repeat):
            s, code, note = stop_time(how, args.jobs)
            print(f"{how:8s} stopped in {s:.2f} s, exit {code}: {note.split(': ', 1)[-1]}")


if __name__ == "__main__":
    main()
