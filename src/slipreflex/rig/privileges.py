"""The process's scheduling and capabilities for ``run --realtime``: SCHED_FIFO, then no capability kept.

Examples
--------
>>> isinstance(drop_capabilities(), str)
True
"""

from __future__ import annotations

import ctypes
import os
import sys

__all__ = ["realtime_priority", "drop_capabilities"]


def realtime_priority(priority: int = 50) -> str:
    """Ask the OS to run this process under SCHED_FIFO real-time scheduling.

    On Linux with an ``rtprio`` limit of at least ``priority`` or
    ``CAP_SYS_NICE`` (root works too, but is not needed: docs/runtime.md,
    "Privileges") the loop then preempts ordinary processes, which keeps its
    latency low on a busy machine. The loop blocks in ``select`` between
    samples, so it does not starve anything. Call :func:`drop_capabilities`
    afterwards: the policy stays, the capability is no longer needed.

    Parameters
    ----------
    priority : int
        SCHED_FIFO priority, 1..99.

    Returns
    -------
    str
        What happened, for the user (never raises).

    Examples
    --------
    >>> isinstance(realtime_priority.__doc__, str)
    True
    """
    if not hasattr(os, "sched_setscheduler"):
        return "real-time scheduling not available on this platform; running at normal priority"
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except (OSError, ValueError) as err:
        return f"could not get SCHED_FIFO ({err}); running at normal priority"
    return f"running under SCHED_FIFO priority {priority}"


#: Linux capability numbers named in messages (linux/capability.h).
_CAP_NAMES = {23: "CAP_SYS_NICE", 1: "CAP_DAC_OVERRIDE", 21: "CAP_SYS_ADMIN", 7: "CAP_SETUID"}


def _capabilities() -> tuple[int, int]:
    """The effective and permitted capability masks of this process (Linux; 0, 0 elsewhere)."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            fields = dict(line.split(":", 1) for line in fh if line.startswith("Cap"))
        return int(fields["CapEff"], 16), int(fields["CapPrm"], 16)
    except (OSError, KeyError, ValueError):
        return 0, 0


def drop_capabilities() -> str:
    """Give up every Linux capability this process holds; the scheduling policy already set stays.

    ``run --realtime`` started with ``CAP_SYS_NICE`` (an ambient capability, a
    file capability) needs it only for the one ``sched_setscheduler`` call; the
    serial ports need the ``dialout`` group, not a capability. So after
    :func:`realtime_priority` the effective, permitted and inheritable sets are
    cleared (``capset(2)``; the ambient set follows). A process running as root
    keeps its rights (dropping them could leave it unable to finish its
    recording in a user's folder); the message then says to use
    ``CAP_SYS_NICE`` or an ``rtprio`` limit instead.

    Returns
    -------
    str
        What happened, for the user, or ``""`` when nothing was held (never raises).

    Examples
    --------
    >>> isinstance(drop_capabilities.__doc__, str)
    True
    """
    if not sys.platform.startswith("linux"):
        return ""
    if os.geteuid() == 0:
        return ("root: not needed, its rights are kept; give the user CAP_SYS_NICE or an rtprio "
                "limit instead (docs/runtime.md, Privileges)")
    eff, prm = _capabilities()
    if not (eff or prm):
        return ""

    held = [name for bit, name in _CAP_NAMES.items() if (eff | prm) >> bit & 1]
    header = (ctypes.c_uint32 * 2)(0x20080522, 0)   # _LINUX_CAPABILITY_VERSION_3, this process
    data = (ctypes.c_uint32 * 6)()                  # effective, permitted, inheritable: none (2 words)
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.capset(header, data) != 0:
            return f"could not drop capabilities: {os.strerror(ctypes.get_errno())}"
    except (OSError, AttributeError) as err:
        return f"could not drop capabilities: {err}"
    eff, prm = _capabilities()
    if eff or prm:
        return f"could not drop capabilities (still held: {eff:#x})"
    return "gave up capabilities " + (", ".join(held) or "held") + " (the scheduling policy stays)"
