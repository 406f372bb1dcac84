"""The safety cases of the real-rig path, measured one at a time on whichever slipreflex is imported.

Each case is a function; ``python benchmarks/safety_cases.py CASE [ARGS]`` prints one line. To compare
with an earlier commit, export its ``src`` and put it first on the path:

    git archive COMMIT src | tar -x -C /tmp/before
    PYTHONPATH=/tmp/before/src python benchmarks/safety_cases.py grip nmsd 500
    python benchmarks/safety_cases.py grip nmsd 500

Cases: grip METHOD P0, plugin {1e9,start-1e6,offset-1e7,nan}, raises, lost_port, ability_silence, bomb,
resync, fifo, csv_bom, csv_cell, tls, scheduler, live, detect_out, calibrate_fig, manifest_fail, lock.
Several start subprocesses of ``python -m slipreflex`` and take seconds to minutes.
"""
import argparse
import io
import math
import os
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import zlib
from contextlib import redirect_stderr
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the tests' harnesses
import slipreflex.core.grip as _G  # noqa: E402

if not hasattr(_G, "TRAVEL"):  # the tests' helpers import it; the old tree has no such name
    _G.TRAVEL = 500.0


def grip(method, p0):
    import test_one_grip_rule as g
    thr = g._threshold(method) if g.methods.get(method).input_kind == "tactile" else None
    res, log = g._drop(method, p0, thr)
    kinds = sorted({f.kind for f in res.faults})
    return f"grip {res.grip_added.get('middle', 0.0):.1f}, closes {res.closes}, faults {','.join(kinds) or 'none'}"


def plugin(kind):
    import test_one_grip_rule as g
    from slipreflex.core.hardware import Finger
    p = {"1e9": g._Plugin(1e9), "start-1e6": g._Plugin(600.0, start=-1e6),
         "offset-1e7": g._Plugin(149.0, offsets={Finger.MIDDLE: 1e7}), "nan": g._Plugin(math.nan)}[kind]
    res = g._plugin_run(p)
    kinds = sorted({f.kind for f in res.faults})
    mx = max(res.grip_added.values()) if res.grip_added else 0.0
    return f"max grip {mx:.0f} units in 1 s, faults {','.join(kinds) or 'none'}"


def raises():
    import test_one_grip_rule as g

    class Broken(g._Plugin):
        steps = 0

        def step(self, volts, position=None):
            self.steps += 1
            if self.steps > 40:
                raise ZeroDivisionError("boom")
            return self.out
    hand = g._LogHand()
    try:
        res = g._plugin_run(Broken(150.0), hand=hand)
    except ZeroDivisionError:
        return f"traceback (ZeroDivisionError), no summary; last hand command {hand.log[-1][0] if hand.log else '-'}"
    return f"faults {[f.kind for f in res.faults]}, summary written, last hand command {hand.log[-1][0]}"


def lost_port():
    import test_one_line_faults as t
    src = t._Still()
    res = t.run_loop(src, t._PortLostAfterClose(), t._Step(), p0=148, duration=0.5, watchdog=0.5,
                     clock=lambda: src.now, guard=False)
    line = [ln for ln in res.summary().splitlines() if ln.startswith("grip added")][0]
    return f"faults {sorted({f.kind for f in res.faults})}; '{line}'"


def ability_silence():
    from slipreflex.core.hardware import FINGER_SPEED_UNITS_S, Finger
    from slipreflex.rig.devices.simrig import SimRig
    from slipreflex.rig.devices.virtual import VirtualDevices
    from slipreflex.rig.hands import open_hand
    rig = SimRig("TR", seed=3)
    rig.grasp()
    with tempfile.TemporaryDirectory() as d, VirtualDevices(rig, hand_type="ability", link_dir=d) as dev:
        times = []
        feed = dev.emulator.feed
        dev.emulator.feed = lambda data: (times.append(time.perf_counter()), feed(data))[1]
        with open_hand("ability", dev.hand_path) as hand:
            start = hand.positions()[Finger.MIDDLE]
            t0 = time.perf_counter()
            time.sleep(1.2)
            hand.close_fingers([Finger.MIDDLE], FINGER_SPEED_UNITS_S)
            time.sleep(0.15)
            hand.hold([Finger.MIDDLE])
            time.sleep(0.1)
            live = hand.positions()[Finger.MIDDLE]
            true = dev.rig.rig.hand.positions()[Finger.MIDDLE]
            hand.reflex_running(True)
            try:
                hand.set_positions({})
                empty = "written"
            except Exception as e:  # noqa
                empty = "refused"
        ts = [t for t in times if t >= t0]
        gap = max(np.diff([t0] + ts)) if ts else float("nan")
        timeouts = getattr(dev.emulator, "api_timeouts", "n/a")
    return (f"longest silence {gap * 1e3:.0f} ms in 1.2 s idle (API timeout 300 ms; twin's count {timeouts}); "
            f"positions() {live:.0f} vs hand {true:.0f} (start {start:.0f}); set_positions({{}}) in a reflex: {empty}")


def _string(b):
    return struct.pack("<I", len(b)) + b


def _mcap(chunks):
    from slipreflex.files.recording import reader
    header = _string(b"") + _string(b"bomb")
    return reader._MAGIC + bytes([1]) + struct.pack("<Q", len(header)) + header + b"".join(chunks)


def bomb():
    import lz4.frame
    zeros = bytes(64 << 20)
    payload = lz4.frame.compress(zeros)
    body = (struct.pack("<QQQI", 0, 0, len(zeros), zlib.crc32(zeros)) + _string(b"lz4")
            + struct.pack("<Q", len(payload)) + payload)
    chunk = bytes([6]) + struct.pack("<Q", len(body)) + body
    d = tempfile.mkdtemp()
    p = os.path.join(d, "bomb.mcap")
    Path(p).write_bytes(_mcap([chunk] * 16))
    r = subprocess.run([sys.executable, "-c", f"""
import resource, sys
from slipreflex.cli import main
rc = main(['replay', {p!r}])
print('RC', rc, 'RSS_MB', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024)
"""], capture_output=True, text=True, timeout=300)
    out = r.stdout.strip().splitlines()[-1] if r.stdout.strip() else ""
    err = r.stderr.strip().splitlines()
    last = err[-1][:90] if err else ""
    return f"{os.path.getsize(p) // 1024} kB lz4 file (1 GiB inside): {out}; stderr lines {len(err)}: {last}"


def resync():
    n = 4 << 20
    filler = bytearray(n)
    for q in range(0, n - 128, 16):
        filler[q] = 0x06
        filler[q + 1:q + 9] = struct.pack("<Q", n - q - 64)
    d = tempfile.mkdtemp()
    p = os.path.join(d, "resync.mcap")
    Path(p).write_bytes(_mcap([bytes([0x7F]) + struct.pack("<Q", 1) + b"x", bytes(filler)]))
    t0 = time.perf_counter()
    try:
        code = f"from slipreflex.files.recording import read_recording; read_recording({p!r})"
        subprocess.run([sys.executable, "-c", code], timeout=120, capture_output=True)
        return f"4 MB crafted file read in {time.perf_counter() - t0:.1f} s"
    except subprocess.TimeoutExpired:
        return "4 MB crafted file: still reading after 120 s (killed)"


def fifo():
    d = tempfile.mkdtemp()
    p = os.path.join(d, "x.mcap")
    os.mkfifo(p)
    try:
        r = subprocess.run([sys.executable, "-m", "slipreflex", "replay", p], timeout=20, capture_output=True,
                           text=True)
        return f"rc {r.returncode}: {r.stderr.strip()[:90]}"
    except subprocess.TimeoutExpired:
        return "blocks (killed after 20 s)"


def _cli(argv, timeout=120):
    r = subprocess.run([sys.executable, "-m", "slipreflex", *argv], timeout=timeout, capture_output=True, text=True)
    err = r.stderr.strip().splitlines()
    return r, f"rc {r.returncode}, stderr {len(err)} line(s){': ' + err[-1][:100] if err else ''}"


def csv_bom():
    d = tempfile.mkdtemp()
    p = os.path.join(d, "bom.csv")
    Path(p).write_bytes("\ufefft,x\n".encode() + "".join(f"{k * 0.003:.3f},0.4\n" for k in range(64)).encode())
    return _cli(["detect", p, "--out", os.path.join(d, "o")])[1]


def csv_cell():
    d = tempfile.mkdtemp()
    p = os.path.join(d, "cell.csv")
    Path(p).write_text("t,x\n0,0.4\n0.003,\"" + "9" * 200_000 + "\"\n")
    return _cli(["detect", p, "--out", os.path.join(d, "o")])[1]


def tls():
    d = tempfile.mkdtemp()
    t0 = time.perf_counter()
    try:
        r, s = _cli(["study", "--scheduler", "tls://127.0.0.1:9", "--out", os.path.join(d, "s"), "--plants", "2",
                     "--no-progress"], timeout=90)
    except subprocess.TimeoutExpired:
        return "still running after 90 s (killed)"
    return f"{s} ({time.perf_counter() - t0:.0f} s)"


def scheduler():
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(4)
    conns = []

    def serve():
        while True:
            try:
                c, _ = srv.accept()
            except OSError:
                return
            c.sendall(struct.pack("<QQ", 100, 1))
            conns.append(c)
    threading.Thread(target=serve, daemon=True).start()
    d = tempfile.mkdtemp()
    out = os.path.join(d, "s")
    t0 = time.perf_counter()
    try:
        r, s = _cli(["study", "--scheduler", f"tcp://127.0.0.1:{srv.getsockname()[1]}", "--out", out, "--plants", "2",
                     "--no-progress"], timeout=120)
        res = f"{s} after {time.perf_counter() - t0:.0f} s"
    except subprocess.TimeoutExpired:
        res = "silent for 120 s (killed)"
    left = sorted(os.listdir(out)) if os.path.isdir(out) else []
    return f"{res}; left in --out: {left or 'nothing'}"


def live():
    from slipreflex.commands import _live
    _live.require_foxglove = lambda *a: None
    buf = io.StringIO()
    with redirect_stderr(buf):
        _live.check_live_arguments(argparse.Namespace(live="0.0.0.0:8765", lsl=None))
    return "warning: " + (buf.getvalue().strip()[:80] or "none")


def detect_out():
    d = Path(tempfile.mkdtemp())
    src = d / "slip.csv"
    src.write_text("t,x\n" + "".join(f"{k * 0.003:.3f},0.4\n" for k in range(64)))
    (d / "res.samples.csv").write_text("user's own")
    victim = d / "victim.txt"
    victim.write_text("mine")
    (d / "res.windows.csv").symlink_to(victim)
    r, s = _cli(["detect", str(src), "--out", str(d / "res")])
    own = (d / "res.samples.csv").read_text() == "user's own"
    return (f"{s}; user's res.samples.csv {'kept' if own else 'REPLACED'}, "
            f"file behind the link {'kept' if victim.read_text() == 'mine' else 'OVERWRITTEN'}")


def calibrate_fig():
    d = Path(tempfile.mkdtemp())
    victim = d / "outside.txt"
    victim.write_text("mine")
    (d / "cal.png").symlink_to(victim)
    r, s = _cli(["calibrate", "--bottles", "TX", "--figure", str(d / "cal.png")], timeout=300)
    return f"{s}; file behind the link {'kept' if victim.read_text() == 'mine' else 'OVERWRITTEN with PNG data'}"


def manifest_fail():
    from slipreflex.files import paths
    from slipreflex.files.paths import MANIFEST, OutputSet
    d = Path(tempfile.mkdtemp())

    def put(text):
        out = OutputSet(d, "demo")
        st = out.stage()
        for n in ("a.csv", "b.csv"):
            (st / n).write_text(text)
        return out, st
    out, st = put("old")
    out.commit(st)
    out, st = put("new")
    real = paths.new_file

    def nospace(path, *a, **kw):
        if Path(path).name == MANIFEST:
            raise OSError(28, "No space left on device")
        return real(path, *a, **kw)
    paths.new_file = nospace
    try:
        out.commit(st)
    except OSError:
        pass
    left = sorted(p.name for p in d.iterdir() if not p.name.startswith("."))
    return f"after a failed manifest write: {left or 'nothing'} " + \
           (f"({(d / 'a.csv').read_text()})" if (d / "a.csv").exists() else "(both sets deleted)")


def lock():
    from slipreflex.files.paths import OutputSet
    if not hasattr(OutputSet, "claim"):
        return "no lock: two commits into one folder interleave"
    import multiprocessing

    import test_output_sets as t
    ctx = multiprocessing.get_context("fork")
    ready, done = ctx.Event(), ctx.Event()
    p = ctx.Process(target=t._hold_lock, args=(Path(tempfile.mkdtemp()), ready, done))
    d = Path(tempfile.mkdtemp())
    p = ctx.Process(target=t._hold_lock, args=(d, ready, done))
    p.start()
    ready.wait(20)
    try:
        OutputSet(d, "demo").claim()
        res = "second claim accepted"
    except Exception as e:  # noqa
        res = f"second process refused: {str(e)[:70]}"
    done.set()
    p.join()
    return res


if __name__ == "__main__":
    name, *a = sys.argv[1:]
    try:
        print(globals()[name](*[int(x) if x.isdigit() else x for x in a]))
    except Exception as e:  # noqa
        print(f"EXCEPTION {type(e).__name__}: {str(e)[:150]}")
