"""``--live`` and ``--lsl``, shared by ``run``, ``virtual-rig`` and ``replay``.

Examples
--------
>>> import argparse
>>> p = argparse.ArgumentParser(); add_live_arguments(p)
>>> args = p.parse_args(["--live", "9000"]); args.live, args.lsl
('9000', None)
"""

from __future__ import annotations

import argparse
import ipaddress
import sys
from collections.abc import Iterable
from typing import Any

from ..core.errors import ParameterError
from ..core.hardware import DAQ_FS
from ..core.taps import close_all
from ..rig.live import DEFAULT_PORT, LiveView, parse_address, require_foxglove
from ..rig.lsl import LslOutlets, require_pylsl

__all__ = ["add_live_arguments", "check_live_arguments", "open_taps", "close_taps", "is_loopback"]


def add_live_arguments(p: argparse.ArgumentParser, *, lsl: bool = True) -> None:
    """Add ``--live [HOST:]PORT`` (and ``--lsl [NAME]``)."""

    g = p.add_argument_group("watching a run live")
    g.add_argument("--live", metavar="[HOST:]PORT", nargs="?", const=str(DEFAULT_PORT), default=None,
                   help=f"serve the run to Foxglove over WebSocket (needs slipreflex[live]); host "
                        f"127.0.0.1 unless given, port {DEFAULT_PORT} when left out; open "
                        f"foxglove/slipreflex.json as the layout (docs/runtime.md)")
    if lsl:
        g.add_argument("--lsl", metavar="NAME", nargs="?", const="slipreflex", default=None,
                       help="publish Lab Streaming Layer outlets NAME-samples and NAME-markers "
                            "(default name slipreflex; needs slipreflex[lsl]) for LabRecorder")


def check_live_arguments(args: argparse.Namespace) -> None:
    """Check ``--live`` / ``--lsl`` and their packages before any work starts."""

    if getattr(args, "live", None) is not None:
        host, _ = parse_address(args.live)
        require_foxglove()
        if not is_loopback(host):
            print(f"slipreflex: warning: --live {args.live} serves the run, unauthenticated, to every host that "
                  f"can reach {host}; keep it on 127.0.0.1 unless the network is yours", file=sys.stderr,
                  flush=True)
    if getattr(args, "lsl", None) is not None:

        if not args.lsl.strip():

            raise ParameterError("--lsl: the stream name is empty")
        require_pylsl()


def is_loopback(host: str) -> bool:
    """Whether ``host`` is this machine only (``localhost``, 127.0.0.0/8, ``::1``).

    Examples
    --------
    >>> is_loopback("127.0.0.1"), is_loopback("localhost"), is_loopback("0.0.0.0"), is_loopback("::")
    (True, True, False, False)
    """
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:  # a host name: it may resolve to anything
        return False


def open_taps(args: argparse.Namespace, topics: Iterable[str], *, lsl_source: str = "",
              fs: float | None = None, taxels: int = 0) -> list[Any]:
    """Start the taps the options ask for and say where they are; the caller closes them."""
    taps: list[Any] = []
    try:
        if getattr(args, "live", None) is not None:

            view = LiveView(args.live, topics)
            taps.append(view.start())
            print(f"live view: {view.url} (Foxglove: Open connection -> Foxglove WebSocket)", flush=True)
        if getattr(args, "lsl", None) is not None:

            outlets = LslOutlets(args.lsl, source_id=f"{args.lsl}@{lsl_source}" if lsl_source else None,
                                 fs=fs or DAQ_FS, taxels=taxels)
            taps.append(outlets.start())
            print(f"lsl: outlets {outlets.names[0]} and {outlets.names[1]}", flush=True)
    except BaseException:
        close_taps(taps)
        raise
    return taps


def close_taps(taps: Iterable[Any]) -> None:
    """Close the taps; a tap that dropped messages or failed is a warning on stderr."""

    for note in close_all(taps):
        print(f"slipreflex: warning: {note}", file=sys.stderr, flush=True)
