"""Subcommands of the ``slipreflex`` console script, one module each.

Each module defines ``NAME`` (the subcommand), ``HELP`` (one line), ``ORDER``
(position in ``--help``), ``add_arguments(parser)`` and ``run(args) -> int``.
The console script discovers them, so adding a command never touches cli.py.
"""
