"""The one list syntax of every command: names separated by commas (``--bottles TR,DK,TX``).

Examples
--------
>>> names_list("TR, DK,TX")
('TR', 'DK', 'TX')
>>> list_hint(["calibrate", "--bottles", "TR", "DK"], ["DK"])
'--bottles takes one comma-separated list: --bottles TR,DK (not space-separated names)'
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["LIST_OPTIONS", "names_list", "list_hint"]

#: The options that take a list of names, in every command that has them.
LIST_OPTIONS: tuple[str, ...] = ("--bottles", "--methods", "--experiments")


def names_list(text: str) -> tuple[str, ...]:
    """A comma-separated list of names (blanks around a name dropped).

    Examples
    --------
    >>> names_list("nmsd,")
    ('nmsd',)
    """
    return tuple(x.strip() for x in str(text).split(",") if x.strip())


def list_hint(argv: Sequence[str], extra: Sequence[str]) -> str | None:
    """The line naming the comma form when ``extra`` (left over by argparse) follows a list option.

    ``argv`` is the command line without the program name; None when the leftover
    words are not names given space-separated after a list option.

    Examples
    --------
    >>> list_hint(["reproduce", "--trials", "2", "x"], ["x"]) is None
    True
    """
    argv = list(argv)
    if not extra or extra[0] not in argv:
        return None
    i = argv.index(extra[0])
    j = i - 1
    while j >= 0 and not argv[j].startswith("-"):
        j -= 1
    if j < 0 or argv[j] not in LIST_OPTIONS:
        return None
    stop = next((k for k, w in enumerate(argv[j + 1:]) if w.startswith("-")), len(argv) - j - 1)
    words = argv[j + 1:j + 1 + stop]
    return (f"{argv[j]} takes one comma-separated list: {argv[j]} {','.join(names_list(','.join(words)))} "
            "(not space-separated names)")
