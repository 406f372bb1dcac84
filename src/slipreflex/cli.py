"""The ``slipreflex`` console script: parse, call, print.

Subcommands live in :mod:`slipreflex.commands`, one module each, discovered at
run time. A :class:`~slipreflex.core.errors.SlipreflexError` becomes a one-line
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
import os
import pkgutil
import sys
from collections.abc import Sequence

from . import __version__, commands
from .commands._lists import list_hint
from .core.errors import ParameterError, SlipreflexError
from .core.registry import PLUGIN_ENV, load_plugin_file

__all__ = ["main", "build_parser"]


def _command_modules() -> list:
    mods = [importlib.import_module(f"{commands.__name__}.{info.name}")
            for info in pkgutil.iter_modules(commands.__path__) if not info.name.startswith("_")]
    return sorted((m for m in mods if hasattr(m, "NAME")), key=lambda m: (getattr(m, "ORDER", 99), m.NAME))


def _load_plugins(argv: list[str]) -> list[str]:
    """Load every ``--plugin FILE`` of ``argv`` (before the parser is built: its choices list the plugins'
    names) and name them in :data:`~slipreflex.core.registry.PLUGIN_ENV` for worker processes; returns the rest."""
    rest, files = [], []
    it = iter(argv)
    for arg in it:
        if arg == "--":
            rest += [arg, *it]
        elif arg == "--plugin":
            file = next(it, None)
            if file is None:
                raise ParameterError("--plugin: give a FILE.py")
            files.append(file)
        elif arg.startswith("--plugin="):
            files.append(arg.partition("=")[2])
        else:
            rest.append(arg)
    for file in files:
        load_plugin_file(file)
    if files:
        known = [f for f in os.environ.get(PLUGIN_ENV, "").split(os.pathsep) if f]
        os.environ[PLUGIN_ENV] = os.pathsep.join(known + [os.path.abspath(f) for f in files])
    return rest


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
    parser.add_argument("--plugin", action="append", metavar="FILE.py",
                        help="load a Python file that registers hands, experiments, methods or load kinds "
                             "(repeatable; allowed anywhere on the line, before or after the command; "
                             f"also {PLUGIN_ENV}=FILE{os.pathsep}FILE)")
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
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        argv = _load_plugins(argv)
    except SlipreflexError as err:
        print(f"slipreflex: error: {err}", file=sys.stderr)
        return 2
    parser = build_parser()
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
