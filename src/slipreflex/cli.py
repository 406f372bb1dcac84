"""The ``slipreflex`` console script: parse, call, print.

Subcommands live in :mod:`slipreflex.commands`, one module each, discovered at
run time. A :class:`~slipreflex.errors.SlipreflexError` becomes a one-line
message on stderr and exit status 2, never a traceback.

Examples
--------
>>> from slipreflex.cli import main
>>> main(["--version"])  # doctest: +SKIP
slipreflex 0.1.0
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
from collections.abc import Sequence

from . import __version__, commands
from .commands._lists import list_hint
from .errors import SlipreflexError

__all__ = ["main", "build_parser"]


def _command_modules() -> list:
    mods = [importlib.import_module(f"{commands.__name__}.{info.name}")
            for info in pkgutil.iter_modules(commands.__path__) if not info.name.startswith("_")]
    return sorted((m for m in mods if hasattr(m, "NAME")), key=lambda m: (getattr(m, "ORDER", 99), m.NAME))


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser with every discovered subcommand.

    Returns
    -------
    argparse.ArgumentParser

    Examples
    --------
    >>> "detect" in build_parser().format_help()
    True
    """
    parser = argparse.ArgumentParser(
        prog="slipreflex",
        description="Event-based slip detection and reflex-like grip control (paper method + tools).")
    parser.add_argument("--version", action="version", version=f"slipreflex {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for mod in _command_modules():
        p = sub.add_parser(mod.NAME, help=mod.HELP, description=mod.HELP)
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the console script; returns the exit status.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0 on success, 2 on a user error (bad file, bad parameter, bad port).

    Examples
    --------
    >>> main([])  # doctest: +SKIP
    usage: slipreflex ...
    """
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    args, extra = parser.parse_known_args(argv)
    if extra:

        hint = list_hint(argv, extra)
        if hint is None:
            parser.parse_args(argv)     # argparse's own message and exit status 2
        print(f"slipreflex {args.command}: error: {hint}", file=sys.stderr)
        return 2
    if not getattr(args, "_run", None):
        parser.print_help()
        return 2
    try:
        return int(args._run(args) or 0)
    except SlipreflexError as err:
        print(f"slipreflex {args.command}: error: {err}", file=sys.stderr)
        return 2
    except OSError as err:      # the machine, not the code (disk full, file gone): one line
        where = f"{err.filename}: " if err.filename else ""
        print(f"slipreflex {args.command}: error: {where}{err.strerror or err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
