"""Output paths checked before any work starts.

A command that will write files checks its output location first, so a typo in
``--out`` costs one line and exit status 2, not a finished run that dies at the end
(or a traceback from deep inside the run).

Examples
--------
>>> import tempfile, pathlib
>>> d = output_dir(pathlib.Path(tempfile.mkdtemp()) / "new" / "dir", "--out")
>>> d.is_dir()
True
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from .errors import ParameterError

__all__ = ["output_dir"]


def output_dir(path: str | os.PathLike, option: str = "--out") -> Path:
    """Make sure ``path`` is a directory this process can write files into.

    A missing directory is created (with its parents). Writability is proven by
    creating and removing a temporary file, which also holds for root on a
    read-only file system, where permission bits say nothing.

    Parameters
    ----------
    path : str or os.PathLike
        The directory.
    option : str
        The option or field that named it, for the error message.

    Returns
    -------
    pathlib.Path
        ``path``, now an existing, writable directory.

    Raises
    ------
    ParameterError
        ``path`` is a file, cannot be created, or cannot be written into; the
        message names the option and the path.

    Examples
    --------
    >>> output_dir("README.md", "--out")
    Traceback (most recent call last):
    ...
    slipreflex.errors.ParameterError: --out README.md: is a file, not a directory
    >>> output_dir("/proc/nope", "--link-dir")
    Traceback (most recent call last):
    ...
    slipreflex.errors.ParameterError: --link-dir /proc/nope: cannot create the directory (No such file or directory)
    """
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise ParameterError(f"{option} {path}: is a file, not a directory")
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ParameterError(f"{option} {path}: cannot create the directory ({err.strerror})") from None
    try:
        with tempfile.NamedTemporaryFile(dir=p, prefix=".write-test-"):
            pass
    except OSError as err:
        raise ParameterError(f"{option} {path}: cannot write into the directory ({err.strerror})") from None
    return p
