"""The machine line every benchmark prints first: CPU model, cores, Python, load average."""

from __future__ import annotations

import os
import platform


def describe() -> str:
    """``"AMD EPYC, 2 cores, Python 3.11.7, load 0.42"`` (the model as /proc/cpuinfo names it)."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next(line.split(":", 1)[1].strip() for line in fh if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, load {load:.2f}"
