"""docs/speed.md's table, measured now: every row's numbers come from the command in its last column.

Usage::

    python -m scripts.docs.speed_table                 # run every benchmark, print the table
    python -m scripts.docs.speed_table --write         # ... and put it between docs/speed.md's markers
    python -m scripts.docs.speed_table --write --reproduce-timing /tmp/repro/timing.json \
        --study-timing /tmp/s/timing.json

``python -m scripts.regenerate`` runs it with ``--write`` after its default reproduction and hands
it the timings of its default reproduction and study (``--reproduce-timing``, ``--study-timing``);
alone, it times its own. A
benchmark whose output no longer has the line a row reads is an error naming the benchmark and
the line, so the table never keeps an old number.
"""

from __future__ import annotations

import datetime
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "speed.md"
BEGIN, END = "<!-- speed table begins -->", "<!-- speed table ends -->"
PY = "python"    # how the table writes the interpreter in its commands


class Missing(Exception):
    """A benchmark's output lacks a line a row reads."""


def find(pattern: str, text: str, where: str) -> tuple[str, ...]:
    """The groups of the first match of ``pattern`` (multi-line) in ``text``; Missing names ``where``."""
    m = re.search(pattern, text, flags=re.M)
    if not m:
        raise Missing(f"{where}: no line matching {pattern!r} in its output")
    return m.groups()


def timed(argv: list[str]) -> dict[str, float]:
    """Run ``argv`` (from the repository root): wall and CPU seconds of it and its children, load before."""
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(argv, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise Missing(f"{' '.join(argv)} failed (exit {done.returncode}): {done.stderr.strip()[-300:]}")
    return {"wall_s": wall, "user_s": after.ru_utime - before.ru_utime, "sys_s": after.ru_stime - before.ru_stime,
            "load": load}


# --- what each row reads from its benchmark's output ---------------------------------------------

def chain_step(out: str) -> str:
    us = [find(rf"^SlipReflex\.step \({m}\): median ([\d.]+) us", out, "bench_chain")[0]
          for m in ("dath", "authors-gui", "dath-event")]
    return " / ".join(us) + " us"


def chain_batch(out: str) -> str:
    med, best = find(r"^run_chain .*: median ([\d.]+) M samples/s \(best ([\d.]+)\)", out, "bench_chain")
    return f"{med} M samples/s median (best {best})"


def sosfilt(out: str) -> str:
    return find(r"^scipy\.signal\.sosfilt alone.*: median ([\d.]+) M samples/s", out, "bench_chain")[0] + \
        " M samples/s"


def baselines(out: str) -> str:
    stream = [find(rf"^{m} streaming object \.step: median (\d+) k frames/s", out, "bench_baselines")[0]
              for m in ("NMSD", "SWT-SD")]
    compiled = [find(rf"^{m} compiled step in an @njit loop: median ([\d.]+) M", out, "bench_baselines")[0]
                for m in ("NMSD", "SWT-SD")]
    return (f"{' / '.join(stream)} k frames/s median; the compiled step in an `@njit` loop (as the compiled "
            f"closed loop calls it): {' / '.join(compiled)} M frames/s")


def sim(out: str) -> str:
    def cpu(label: str) -> str:
        return find(rf"^\s*{re.escape(label)}.*?(\d+) per CPU-s", out, "bench_sim")[0]
    return (f"open-loop pour {cpu('physics + sensors (open loop')}, held pour {cpu('held through the pour')}; "
            f"with a 260 Hz tactile stream {cpu('... plus a 260 Hz')} / {cpu('held, plus a 260 Hz')} "
            "sim-s per CPU-s")


def kernel_steps(out: str) -> str:
    ns = [find(rf"^{re.escape(label)}:\s+([\d.]+) ns", out, "bench_kernel_steps")[0]
          for label in ("held grasp at rest", "held pour, contacts stuck (5 s in)",
                        "held pour, cuff creeping (20 s in)", "tactile frame")]
    return f"{ns[0]} / {ns[1]} / {ns[2]} ns per step (held at rest / pour, stuck / pour, creeping); {ns[3]} ns " \
           "per tactile frame"


def closed_loop(out: str) -> str:
    names = ("dath", "fixed", "nmsd", "swt")
    rate = {(m, e): find(rf"^{m}\s+{e}\s+[\d.]+\s+(\d+) \(\s*\d+\)\s+(\d+) \(\s*\d+\)\s+([\d.]+)x", out,
                         "bench_closed_loop")
            for m in names for e in ("drop", "pour")}
    held = [find(rf"^held pour{what}: open loop .*? fixed\s+(\d+) adaptive\s+(\d+) \(([\d.]+)x, pairs [\d.-]+\) "
                 rf"sim-s per CPU-s; closed by a compiled reflex that never commands fixed\s+(\d+) adaptive\s+(\d+) "
                 rf"\(([\d.]+)x, pairs ([\d.]+)-([\d.]+)\)",
                 out, "bench_closed_loop")
            for what in ("", ", 260 Hz tactile", ", 380 Hz tactile")]

    def cells(e: str) -> str:
        return " / ".join(f"{rate[m, e][1]} ({rate[m, e][2]}x)" for m in names)
    h, t260, t380 = held
    return (f"adaptive kernel (ratio to the fixed-step reference in the same run): pour {cells('pour')}; drop "
            f"{cells('drop')}, median of 3 pairs. The held pour closed by a compiled reflex that never commands: "
            f"{h[4]} ({h[5]}x, {h[6]}-{h[7]}x over the pairs; fixed {h[3]}), with a 260 Hz tactile stream {t260[4]} "
            f"({t260[5]}x), 380 Hz {t380[4]} ({t380[5]}x); open loop {h[1]} ({h[2]}x), median of 15 pairs. Sim-s per "
            "CPU-s; a ratio is the median of the pairs' ratios, the two kernels run back to back")


def interrupt(out: str) -> str:
    got = {how: re.findall(rf"^{how}\s+stopped in ([\d.]+) s, exit 130", out, flags=re.M)
           for how in ("ctrl-c", "sigterm")}
    if not got["ctrl-c"] or not got["sigterm"]:
        raise Missing("bench_interrupt: a run did not stop with exit 130 and its finished trials written")
    return f"Ctrl-C {' / '.join(got['ctrl-c'])} s, SIGTERM {' / '.join(got['sigterm'])} s"


def runtime(out: str) -> str:
    p50, p99, top = find(r"^RESULT latency_p50_ms=([\d.]+) latency_p99_ms=([\d.]+) latency_max_ms=([\d.]+)", out,
                         "bench_runtime")
    n = find(r"^latency sample read->command: .*\(n=(\d+)\)", out, "bench_runtime")[0]
    return f"{p50} / {p99} / {top} ms over {n} commands"


def runtime_live(out: str) -> str:
    p99 = find(r"^RESULT latency_p50_ms=[\d.]+ latency_p99_ms=([\d.]+)", out, "bench_runtime --live")[0]
    sent = find(r"^live view: (\d+) messages published, (\d+) dropped", out, "bench_runtime --live")
    return f"p99 {p99} ms with a subscribed client ({sent[0]} messages published, {sent[1]} dropped)"


_FW = ("DAQ alone, MPU6050 on the bus", "DAQ + reflex chain (ATmega328P)", "standalone reflex + hand (ATmega2560)")


def firmware_cpu(out: str) -> str:
    runs = [find(rf"^\[{re.escape(label)}\].*\n\s+CPU per 3 ms period: mean \d+ cycles = ([\d.]+) % of \d+; "
                 r"worst period \d+ cycles = ([\d.]+) %", out, "firmware_budget") for label in _FW]
    return (f"{' % / '.join(r[0] for r in runs)} % (worst {' / '.join(r[1] for r in runs)} %) "
            "per 3 ms period of 48,000 cycles")


def firmware_size(out: str) -> str:
    sizes = [find(rf"^{name} size: flash (\d+) of \d+ bytes .*?RAM (\d+) of", out, "firmware_budget")
             for name in ("firmware", "daq-reflex", "hand2560")]
    return ", ".join(f"{flash} / {ram} B" for flash, ram in sizes)


def hand_latency(out: str) -> str:
    block = out.split("[standalone reflex + hand (ATmega2560)]", 1)[-1]
    cycles, ms = find(r"first byte on UART1: max (\d+) cycles \(([\d.]+) ms\)", block, "firmware_budget")
    return f"{cycles} cycles = {ms} ms (the worst packet)"


def _duration(s: float) -> str:
    return f"{s:.0f} s" if s < 120 else f"{int(s // 60)} min {s % 60:.0f} s"


def whole_run(what: str, timing: dict[str, float]) -> str:
    """A whole command's cost: wall at the load it met, CPU (user + system), the least wall on 2 free cores."""
    cpu = timing["user_s"] + timing["sys_s"]
    return (f"{what}: {_duration(timing['wall_s'])} wall at load average {timing['load']:.1f}, {cpu:.0f} CPU s "
            f"({timing['user_s']:.0f} user + {timing['sys_s']:.0f} system), so at least {_duration(cpu / 2)} on "
            "2 free cores")


#: (what, target, the command as the table shows it, the benchmark's arguments, reader). Rows that share a
#: command share one run of it.
ROWS: list[tuple[str, str, str, list[str], Callable[[str], str]]] = [
    ("`SlipReflex.step` (DATH / authors-gui / dath-event), median per sample", "<= 2 us",
     "bench_chain.py", [], chain_step),
    ("`run_chain` batch (filter + encode + windows + MPI), one core", ">= 50 M/s", "bench_chain.py", [], chain_batch),
    ("`scipy.signal.sosfilt` alone on the same array, for scale", "", "bench_chain.py", [], sosfilt),
    ("NMSD / SWT-SD streaming `.step` per 4 x 4 frame, one core", "", "bench_baselines.py", [], baselines),
    ("simulator, physics + sensors, one core", ">= 1000", "bench_sim.py", ["--quick"], sim),
    ("simulator, one physics step", "", "bench_kernel_steps.py", [], kernel_steps),
    ("simulator, one closed-loop trial (compiled loop), DATH / fixed / NMSD / SWT-SD",
     ">= 4x the fixed step on the held pour", "bench_closed_loop.py",
     ["--methods", "dath,fixed,nmsd,swt", "--repeat", "3"],
     closed_loop),
    ("`slipreflex reproduce` stopping after Ctrl-C / SIGTERM, signal to exit with the finished trials written",
     "<= 2 s", "bench_interrupt.py", [], interrupt),
    ("real-time loop over virtual devices, 333 Hz, 60 s: p50 / p99 / max", "p99 <= 1 ms", "bench_runtime.py",
     [], runtime),
    ("the loop with the live view (`--live`), 30 s", "p99 <= 1 ms", "bench_runtime.py",
     ["--duration", "30", "--live"], runtime_live),
    ("firmware CPU: DAQ / DAQ + reflex / ATmega2560 standalone", "<= 5 % / <= 15 %", "firmware_budget.py",
     ["--seconds", "10"], firmware_cpu),
    ("firmware size, flash / static RAM: DAQ, DAQ + reflex, ATmega2560", "", "firmware_budget.py",
     ["--seconds", "10"], firmware_size),
    ("board hand-packet latency (window-completing ADC sample to first UART1 byte)", "< 1 ms",
     "firmware_budget.py", ["--seconds", "10"], hand_latency),
]


def reproduce_row(timing: dict[str, float]) -> tuple[str, str, str, str]:
    """The default reproduction's row, from its timing."""
    from slipreflex.reproduce.experiments import ReproduceConfig

    return ("`slipreflex reproduce`, the default grid, 2 cores",
            whole_run(f"{len(ReproduceConfig().cells())} trials, start-up to report", timing), "<= 30 s",
            "`time slipreflex reproduce --jobs 2 --out /tmp/r --no-progress`")


def study_row(timing: dict[str, float]) -> tuple[str, str, str, str]:
    """The default study's row, from its timing (the study extra must be installed)."""
    from slipreflex.study import DEFAULT_PLANTS, DEFAULT_TRIALS, StudyConfig

    per_plant = StudyConfig(plants=DEFAULT_PLANTS, trials=DEFAULT_TRIALS).trials_per_plant
    return ("`slipreflex study`, default, 2 cores",
            whole_run(f"{DEFAULT_PLANTS} plants x {per_plant} trials, calibration and scans included", timing),
            "<= 5 min on 2 cores", "`time slipreflex study --out /tmp/s` (a fresh directory)")


REPRODUCE = [sys.executable, "-m", "slipreflex", "reproduce", "--jobs", "2", "--no-progress", "--out"]
STUDY = [sys.executable, "-m", "slipreflex", "study", "--out"]


def measure(timing: dict[str, float] | None, log=print,
            study_timing: dict[str, float] | None = None) -> list[tuple[str, str, str, str]]:
    """Every row, measured now (the reproduction and the study timed here unless their timings are given)."""
    outputs: dict[tuple[str, ...], str] = {}
    rows = []
    for what, target, script, args, read in ROWS:
        key = (script, *args)
        if key not in outputs:
            log(f"speed_table: {PY} benchmarks/{' '.join(key)}")
            done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / script), *args], cwd=ROOT,
                                  capture_output=True, text=True, timeout=3600)
            if done.returncode != 0:
                raise Missing(f"benchmarks/{script} failed (exit {done.returncode}): {done.stderr.strip()[-300:]}")
            outputs[key] = done.stdout
        shown = " ".join([f"{PY} benchmarks/{script}", *(a if a else '""' for a in args)])
        rows.append((what, read(outputs[key]), target, f"`{shown}`"))
    if timing is None:
        with tempfile.TemporaryDirectory() as out:
            log("speed_table: timing the default reproduction")
            timing = timed([*REPRODUCE, out])
    rows.insert(7, reproduce_row(timing))
    if study_timing is None:
        with tempfile.TemporaryDirectory() as out:
            log("speed_table: timing the default study")
            study_timing = timed([*STUDY, str(Path(out) / "study")])
    rows.append(study_row(study_timing))
    rows.append(("set-up and every test on a fresh Debian 12 (debootstrap, python3 only), network included",
                 "not measured here: it needs root and debootstrap", "",
                 "`sudo bash scripts/dev/fresh_debian_check.sh`"))
    return rows


def markdown(rows: list[tuple[str, str, str, str]], machine: str) -> str:
    """The table and the line that says when and where it was measured."""
    lines = [f"Measured on {datetime.date.today().isoformat()} by `python -m scripts.regenerate` on {machine} "
             "(shared with other jobs: the load average says how busy it was).", "",
             "| what | measured | target | command |", "|---|---|---|---|"]
    lines += [f"| {' | '.join(r)} |" for r in rows]
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    from benchmarks.machine import describe

    from scripts.docs.splice_report import write_marked

    timing, study_timing = (json.loads(Path(argv[argv.index(o) + 1]).read_text()) if o in argv else None
                            for o in ("--reproduce-timing", "--study-timing"))
    machine = describe()
    try:
        table = markdown(measure(timing, study_timing=study_timing), machine)
    except Missing as err:
        print(f"speed_table: {err}", file=sys.stderr)
        return 2
    print(table)
    return write_marked("speed_table", DOC, BEGIN, END, table) if "--write" in argv else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
