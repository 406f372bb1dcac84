"""The file-safety helpers of every command: where outputs go, how they are created, how
user files are read.

* :func:`output_dir` checks an output location before any work starts, so a typo in
  ``--out`` costs one line and exit status 2, not a finished run that dies at the end.
* :func:`create_new`, :func:`new_file`, :func:`publish` and :func:`unique_name` create
  files new (exclusive create, no symlink followed), whole or absent (a temporary file in
  the same folder, named when complete): a command never overwrites or deletes what it did
  not create.
* :class:`OutputSet` replaces a command's set of outputs in a folder as one set.
* :func:`read_capped`, :func:`read_text` and :func:`read_toml` read a user's file with a
  size cap and one-line errors (a device, a binary or Latin-1 file, bad TOML).

Examples
--------
>>> import tempfile, pathlib
>>> d = output_dir(pathlib.Path(tempfile.mkdtemp()) / "new" / "dir", "--out")
>>> d.is_dir()
True
"""

from __future__ import annotations

import contextlib
import errno
import itertools
import json
import os
import shutil
import stat
import tempfile
import time
import tomllib
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import IO, Any

from ..core.errors import ParameterError
from ..core.validation import LIMITS
from .interrupts import signals_ignored

__all__ = ["output_dir", "create_new", "publish", "new_file", "unique_name", "unique_prefix", "OutputSet",
           "MANIFEST", "read_capped", "read_text", "read_toml", "MAX_TEXT_BYTES"]


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
    slipreflex.core.errors.ParameterError: --out README.md: is a file, not a directory
    >>> output_dir("/proc/nope", "--link-dir")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: --link-dir /proc/nope: cannot create the directory (No such file or ...
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


# --- files a command creates: never someone else's, whole or absent -------------------------

#: Flags of an exclusive create that follows no symlink (a name that exists, a dangling
#: symlink included, is refused).
_NEW = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)


def create_new(path: str | os.PathLike, mode: str = "wb") -> IO[Any]:
    """Open ``path`` for writing only if nothing, not even a symlink, has that name yet.

    Parameters
    ----------
    path : path-like
    mode : {"wb", "w"}

    Returns
    -------
    file object

    Raises
    ------
    FileExistsError
        Something already has the name (it is left as it was).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "new.bin"
    >>> with create_new(p) as fh:
    ...     _ = fh.write(b"x")
    >>> create_new(p)
    Traceback (most recent call last):
    ...
    FileExistsError: [Errno 17] File exists: ...
    """
    fd = os.open(path, _NEW, 0o666)
    try:
        return os.fdopen(fd, mode) if "b" in mode else os.fdopen(fd, mode, newline="", encoding="utf-8")
    except BaseException:
        os.close(fd)
        raise


def publish(tmp: str | os.PathLike, final: str | os.PathLike) -> None:
    """Give the complete file ``tmp`` the name ``final`` without replacing anything there.

    A hard link is made and ``tmp`` removed, so an existing ``final`` (a file, a symlink)
    is left alone and :class:`FileExistsError` raised (``tmp`` is then kept).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp()); _ = (d / "a.part").write_text("1")
    >>> publish(d / "a.part", d / "a"); sorted(p.name for p in d.iterdir())
    ['a']
    """
    try:
        os.link(tmp, final, follow_symlinks=False)
    except (PermissionError, NotImplementedError, OSError) as err:
        if isinstance(err, FileExistsError):
            raise
        if os.path.lexists(final):  # no hard links here (some file systems): check, then rename
            raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), os.fspath(final)) from None
        os.rename(tmp, final)
        return
    os.unlink(tmp)


@contextlib.contextmanager
def new_file(path: str | os.PathLike, mode: str = "w", *, replace: bool = False) -> Iterator[IO[Any]]:
    """Write a file that appears under its name only when complete.

    The data goes to a temporary file created new in the same folder; at the end of the
    block it gets the name (:func:`publish`; with ``replace`` an earlier file of that name
    is replaced, never followed if it is a symlink). On an error or Ctrl-C the temporary
    file is removed and nothing else changed.

    Parameters
    ----------
    path : path-like
    mode : {"w", "wb"}
    replace : bool
        Replace an existing file of that name (only for files the caller owns).

    Raises
    ------
    FileExistsError
        Without ``replace``, something has the name already.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "out.txt"
    >>> with new_file(p) as fh:
    ...     _ = fh.write("done")
    >>> p.read_text()
    'done'
    """
    path = Path(path)
    if not replace and os.path.lexists(path):
        raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), os.fspath(path))
    if replace and os.path.lexists(path) and not path.is_file():
        raise IsADirectoryError(errno.EISDIR, "exists and is not a regular file", os.fspath(path))
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
    try:
        os.fchmod(fd, 0o666 & ~_umask())   # mkstemp's 0600 would hide the output from the group
        with (os.fdopen(fd, mode) if "b" in mode else os.fdopen(fd, mode, newline="", encoding="utf-8")) as fh:
            yield fh
        if replace:
            os.replace(tmp, path)
        else:
            publish(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def unique_name(folder: str | os.PathLike, stem: str, suffix: str, *, also: Sequence[str] = ()) -> Path:
    """``folder/stem+suffix``, or ``stem-2``, ``stem-3``... : the first name free (``also`` are
    extra suffixes that must be free too, e.g. a ``.part`` beside the file).

    The caller still creates the file with :func:`create_new` (two processes may pick the
    same name; the second then gets :class:`FileExistsError` and asks again).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp()); _ = (d / "run.mcap").write_text("")
    >>> unique_name(d, "run", ".mcap").name
    'run-2.mcap'
    """
    folder = Path(folder)
    for k in itertools.count(1):
        name = folder / (f"{stem}{suffix}" if k == 1 else f"{stem}-{k}{suffix}")
        if not any(os.path.lexists(f"{name}{x}") for x in ("", *also)):
            return name
    raise AssertionError("unreachable")  # pragma: no cover


def unique_prefix(prefix: str | os.PathLike, suffixes: Sequence[str]) -> Path:
    """``prefix``, or ``prefix-2``, ``prefix-3``...: the first for which every ``prefix + suffix``
    is free (nothing, not even a dangling symlink, has the name). For a command's several files
    that belong together (``NAME.samples.csv`` and ``NAME.windows.csv``): never a mix of runs.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp()); _ = (d / "run.windows.csv").write_text("")
    >>> unique_prefix(d / "run", [".samples.csv", ".windows.csv"]).name
    'run-2'
    """
    prefix = Path(prefix)
    for k in itertools.count(1):
        name = prefix if k == 1 else prefix.with_name(f"{prefix.name}-{k}")
        if not any(os.path.lexists(f"{name}{x}") for x in suffixes):
            return name
    raise AssertionError("unreachable")  # pragma: no cover


#: Name of the file in which a command lists the outputs it wrote into a folder.
MANIFEST: str = ".slipreflex-outputs.json"


class OutputSet:
    """The files a command writes into a folder, replaced as one set.

    The command writes into a fresh hidden folder inside ``folder`` (:meth:`stage`); when
    everything is written, :meth:`commit` swaps the set in with Ctrl-C held off: the
    previous run's outputs (those the folder's manifest lists) are removed and the new
    ones renamed into place, so the folder never mixes two runs. A stopped write
    (:meth:`abort`, also on an error) leaves the previous set untouched. A name the
    command would write that exists but no manifest of this command lists (the user's
    own file) is refused before any work (:meth:`check`), and so is a manifest name that is
    not a regular file. Nothing is followed: the staged files are renamed into place, which
    replaces a name, never what a symlink of that name points to.

    One process at a time: :meth:`claim` takes the folder's lock (``flock`` on the folder) before any work
    and refuses, in one line, while another command holds it; :meth:`commit` takes it too
    (waiting for it) if the caller did not. When the swap fails half-way (no space for the
    manifest, no inodes left), it is rolled back: the new files are removed and the previous
    set put back as it was.

    Parameters
    ----------
    folder : path-like
        The output folder (created if missing).
    command : str
        The command that owns the set (``"reproduce"``), recorded in the manifest.
    option : str
        The option that named the folder, for messages.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = OutputSet(pathlib.Path(tempfile.mkdtemp()) / "o", "demo")
    >>> out.check(["a.csv"])
    >>> staged = out.stage(); _ = (staged / "a.csv").write_text("1")
    >>> out.commit(staged)
    ['a.csv']
    >>> sorted(p.name for p in out.folder.iterdir())
    ['.slipreflex-outputs.json', 'a.csv']
    """

    def __init__(self, folder: str | os.PathLike, command: str, option: str = "--out") -> None:
        self._lock_fd: int | None = None
        self.folder = output_dir(folder, option)
        self.command = command
        self.option = option
        manifest = self.folder / MANIFEST
        if os.path.lexists(manifest) and not (manifest.is_file() and not manifest.is_symlink()):
            raise ParameterError(f"{option} {self.folder}: {MANIFEST} is not a regular file; slipreflex keeps "
                                 f"its list of outputs there (move it or choose another {option})")

    def claim(self, wait: float = 0.0) -> None:
        """Take the folder's lock for this process (before any work); a no-op if held already.

        Raises
        ------
        ParameterError
            Another process holds it for longer than ``wait`` seconds.

        Examples
        --------
        >>> import tempfile
        >>> out = OutputSet(tempfile.mkdtemp(), "demo"); out.claim(); out.release()
        """
        import fcntl  # deferred: optional extra (POSIX only)

        if self._lock_fd is not None:
            return
        # the folder itself is the lock (flock on its descriptor): no lock file to leave behind
        fd = os.open(self.folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0) | getattr(os, "O_CLOEXEC", 0))
        deadline = time.monotonic() + wait
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() >= deadline:
                    os.close(fd)
                    raise ParameterError(f"{self.option} {self.folder}: another slipreflex command is writing "
                                         f"its outputs there; wait for it or choose another {self.option}") from None
                time.sleep(0.05)
        self._lock_fd = fd

    def __del__(self) -> None:  # a command that claimed and then failed still lets the folder go
        if getattr(self, "_lock_fd", None) is not None:
            self.release()

    def release(self) -> None:
        """Give the folder's lock back (closing the file releases it).

        Examples
        --------
        >>> import tempfile
        >>> OutputSet(tempfile.mkdtemp(), "demo").release()
        """
        if self._lock_fd is not None:
            os.close(self._lock_fd)
            self._lock_fd = None

    def owned(self) -> list[str]:
        """Names the previous run of this command wrote here (from the manifest; [] if none).

        Examples
        --------
        >>> import tempfile
        >>> OutputSet(tempfile.mkdtemp(), "demo").owned()
        []
        """
        try:
            doc = json.loads((self.folder / MANIFEST).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return []
        if not isinstance(doc, dict) or doc.get("command") != self.command:
            return []
        return [n for n in doc.get("files", []) if isinstance(n, str) and n and "/" not in n
                and n not in (".", "..")]

    def check(self, names: Iterable[str]) -> None:
        """Refuse (before any work) names that exist here and this command did not write.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> d = pathlib.Path(tempfile.mkdtemp()); _ = (d / "report.md").write_text("mine")
        >>> OutputSet(d, "demo").check(["report.md"])  # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        slipreflex.core.errors.ParameterError: --out ...: report.md exists and was not written by slipreflex demo; ...
        """
        owned = set(self.owned())
        for name in names:
            if os.path.lexists(self.folder / name) and name not in owned:
                raise ParameterError(f"{self.option} {self.folder}: {name} exists and was not written by "
                                     f"slipreflex {self.command}; move it or choose another {self.option}")

    def stage(self) -> Path:
        """A fresh, empty hidden folder inside ``folder`` to write this run's outputs into.

        Examples
        --------
        >>> import tempfile
        >>> OutputSet(tempfile.mkdtemp(), "demo").stage().name.startswith(".demo-new-")
        True
        """
        return Path(tempfile.mkdtemp(dir=self.folder, prefix=f".{self.command}-new-"))

    def abort(self, staged: str | os.PathLike) -> None:
        """Remove a staging folder (the previous outputs stay as they were).

        Examples
        --------
        >>> import tempfile
        >>> out = OutputSet(tempfile.mkdtemp(), "demo"); s = out.stage(); out.abort(s); s.exists()
        False
        """
        shutil.rmtree(staged, ignore_errors=True)

    def commit(self, staged: str | os.PathLike) -> list[str]:
        """Swap the staged outputs in for the previous run's; returns the names now in place.

        Examples
        --------
        >>> import tempfile
        >>> out = OutputSet(tempfile.mkdtemp(), "demo"); s = out.stage()
        >>> out.commit(s)
        []
        """

        staged = Path(staged)
        held = self._lock_fd is not None
        self.claim(wait=_COMMIT_WAIT_S)  # two commits into one folder never interleave
        try:
            names = sorted(p.name for p in staged.iterdir())
            self.check(names)  # a file the user put here meanwhile is still not ours to replace
            with signals_ignored():
                self._swap(staged, names)
        finally:
            if not held:
                self.release()
        return names

    def _swap(self, staged: Path, names: list[str]) -> None:
        """Previous set aside, manifest, new set in; on any failure the previous set comes back."""
        old = Path(tempfile.mkdtemp(dir=self.folder, prefix=f".{self.command}-old-"))
        moved: list[str] = []
        placed: list[str] = []
        manifest_old = old / MANIFEST
        had_manifest = os.path.lexists(self.folder / MANIFEST)
        try:
            if had_manifest:
                shutil.copy2(self.folder / MANIFEST, manifest_old, follow_symlinks=False)
            for name in self.owned():
                if os.path.lexists(self.folder / name):
                    os.rename(self.folder / name, old / name)
                    moved.append(name)
            with new_file(self.folder / MANIFEST, replace=True) as fh:
                json.dump({"command": self.command, "files": names}, fh, indent=1)
                fh.write("\n")
            for name in names:
                os.rename(staged / name, self.folder / name)
                placed.append(name)
        except BaseException:
            for name in placed:  # roll back: nothing of the new set stays...
                with contextlib.suppress(OSError):
                    os.rename(self.folder / name, staged / name)
            for name in moved:   # ...and the previous set is back under its names
                with contextlib.suppress(OSError):
                    os.rename(old / name, self.folder / name)
            with contextlib.suppress(OSError):
                if had_manifest:
                    os.replace(manifest_old, self.folder / MANIFEST)
                elif os.path.lexists(self.folder / MANIFEST):
                    os.unlink(self.folder / MANIFEST)
            raise
        finally:
            shutil.rmtree(old, ignore_errors=True)
            shutil.rmtree(staged, ignore_errors=True)


#: Seconds a commit waits for another process's commit into the same folder.
_COMMIT_WAIT_S = 30.0


# --- user input files: bounded reads, one-line errors ------------------------------------------

#: Largest text input (TOML, results CSV) a command reads, bytes (``LIMITS["text_file_bytes"]``,
#: docs/runtime.md "Limits").
MAX_TEXT_BYTES: int = int(LIMITS["text_file_bytes"].hi)


def _where(what: str, path: Any) -> str:
    return f"{what} {os.fspath(path)}" if what else os.fspath(path)


def read_capped(path: str | os.PathLike, what: str, limit: int = MAX_TEXT_BYTES, kind: str = "file") -> bytes:
    """The bytes of a user's file, refusing a non-regular file or one over ``limit`` bytes.

    Raises
    ------
    ParameterError
        Missing, a folder, a device (``/dev/zero``), unreadable or too large; one line
        naming ``what`` and the path.

    Examples
    --------
    >>> read_capped("/dev/zero", "--objects")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: --objects /dev/zero: not a regular file
    """
    p = os.fspath(path)
    try:
        # O_NONBLOCK: a FIFO must not block the open; it is refused below like every non-regular file
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise ParameterError(f"{_where(what, p)}: no such file") from None
    except OSError as err:
        raise ParameterError(f"{_where(what, p)}: cannot read: {err.strerror or err}") from None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):
        os.close(fd)
        raise ParameterError(f"{_where(what, p)}: " + (f"is a directory, not a {kind}" if stat.S_ISDIR(st.st_mode)
                                                       else "not a regular file"))
    with os.fdopen(fd, "rb") as fh:
        if st.st_size > limit:
            raise ParameterError(f"{_where(what, p)}: {st.st_size} bytes, more than the {limit} a command reads")
        try:
            data = fh.read(limit + 1)
        except OSError as err:
            raise ParameterError(f"{_where(what, p)}: cannot read: {err.strerror or err}") from None
    if len(data) > limit:
        raise ParameterError(f"{_where(what, p)}: more than the {limit} bytes a command reads")
    return data


def read_text(path: str | os.PathLike, what: str, limit: int = MAX_TEXT_BYTES, kind: str = "file") -> str:
    """A user's text file as UTF-8 (:func:`read_capped`; a binary or Latin-1 file is one line).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "l1.toml"; _ = p.write_bytes(b"a = '\\xe9'")
    >>> read_text(p, "--ranges")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: --ranges ...l1.toml: not UTF-8 text (byte 0xe9 at offset 5)...
    """
    data = read_capped(path, what, limit, kind)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ParameterError(f"{_where(what, path)}: not UTF-8 text (byte 0x{data[err.start]:02x} at "
                             f"offset {err.start}); save it as UTF-8") from None
    if "\x00" in text:
        raise ParameterError(f"{_where(what, path)}: a binary file (NUL byte at offset {text.index(chr(0))})")
    return text


def read_toml(path: str | os.PathLike, what: str) -> dict[str, Any]:
    """A user's TOML file as a dict; every failure is one :class:`ParameterError` line.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "o.toml"; _ = p.write_text("bottles = [")
    >>> read_toml(p, "--objects")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: --objects ...o.toml: invalid TOML: ...
    """

    text = read_text(path, what, kind="TOML file")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ParameterError(f"{_where(what, path)}: invalid TOML: {err}") from None
    except RecursionError:
        raise ParameterError(f"{_where(what, path)}: invalid TOML: nested too deeply") from None
