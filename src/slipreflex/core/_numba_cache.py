"""Where numba caches the compiled kernels, decided before any kernel module is imported.

numba caches a kernel beside its source (``__pycache__``) or, when that folder is not
writable (a system-wide install), in ``~/.cache/numba``. Where neither is writable (a
read-only install run by a user without a home, a locked-down container) numba would stop
every command at import. This module then points numba at a private folder of the
temporary directory (``slipreflex-numba-UID``, mode 0700, owned by this user) with a
warning; if even that cannot be had, caching is switched off (:data:`CACHE` False; the
kernels compile in every process) with a warning. ``NUMBA_CACHE_DIR`` set by the user is
always left alone. Whoever can write the cache folder can change the code the kernels run
(docs/runtime.md, "Files").

numba stamps a cached kernel with its own source file only, but a kernel compiles into
itself the code it calls and the constants it reads, from whatever file they come.
:func:`stamped_cache` lets a module declare those files: its kernels' cache is then stamped
with the contents of the module, of every file it declares and of what those declare in
turn (:func:`source_stamp`), so an edit in any of them recompiles instead of running a
stale kernel.

Examples
--------
>>> isinstance(CACHE, bool)
True
"""

from __future__ import annotations

import hashlib
import os
import stat
import sys
import tempfile
from pathlib import Path

__all__ = ["CACHE", "choose_cache", "KERNEL_PACKAGES", "stamped_cache", "source_stamp"]

#: Sub-packages holding ``@njit(cache=...)`` kernels (their ``__pycache__`` is numba's first choice).
KERNEL_PACKAGES: tuple[str, ...] = ("sim", "chain", "baselines")


def _writable(folder: Path) -> bool:
    """True if a file can be created in ``folder`` (or in the nearest existing parent, where
    numba would create it)."""
    probe = folder
    while not probe.exists():
        if probe.parent == probe:
            return False
        probe = probe.parent
    if not probe.is_dir():
        return False
    try:
        with tempfile.TemporaryFile(dir=probe):
            return True
    except OSError:
        return False


def _private_folder(base: Path) -> Path | None:
    """``base/slipreflex-numba-UID``: created 0700, or reused only if it is this user's own folder."""
    folder = base / f"slipreflex-numba-{os.getuid()}"
    try:
        folder.mkdir(mode=0o700, exist_ok=True)
        st = os.lstat(folder)
    except OSError:
        return None
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.getuid() or st.st_mode & 0o022:
        return None   # a symlink, someone else's folder, or writable by others: not trusted
    return folder if _writable(folder) else None


def choose_cache(package: Path, user_cache: Path, temp: Path) -> tuple[str | None, bool, str]:
    """Decide numba's cache: ``(NUMBA_CACHE_DIR to set or None, caching on, warning or "")``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> choose_cache(pathlib.Path(tempfile.mkdtemp()), pathlib.Path("/proc/x"), pathlib.Path("/proc"))
    (None, True, '')
    >>> d, on, warning = choose_cache(pathlib.Path("/proc/1"), pathlib.Path("/proc/x"),
    ...                               pathlib.Path(tempfile.mkdtemp()))
    >>> on, "slipreflex-numba-" in d, warning.startswith("numba's cache")
    (True, True, True)
    >>> choose_cache(pathlib.Path("/proc/1"), pathlib.Path("/proc/x"), pathlib.Path("/proc/y"))[1]
    False
    """
    if all(_writable(package / sub / "__pycache__") for sub in KERNEL_PACKAGES) or _writable(user_cache):
        return None, True, ""
    where = f"neither {package} nor {user_cache} is writable"
    folder = _private_folder(temp)
    if folder is not None:
        return str(folder), True, f"numba's cache: {where}; the compiled kernels are cached in {folder}"
    return None, False, (f"numba's cache: {where}, nor a private folder in {temp}; the kernels compile "
                         f"in every process (set NUMBA_CACHE_DIR to a writable folder)")


def _decide() -> bool:
    if os.environ.get("NUMBA_CACHE_DIR"):
        return True
    user = Path(os.environ.get("XDG_CACHE_HOME") or Path("~/.cache").expanduser()) / "numba"
    folder, on, warning = choose_cache(Path(__file__).resolve().parent, user, Path(tempfile.gettempdir()))
    if folder is not None:
        os.environ["NUMBA_CACHE_DIR"] = folder
        if "numba" in sys.modules:          # numba read its configuration already
            from numba.core import config  # deferred: heavy (numba)

            config.CACHE_DIR = folder  # pyright: ignore[reportAttributeAccessIssue]
    if warning:
        print(f"slipreflex: warning: {warning}", file=sys.stderr)
    return on


#: Whether the kernels are cached on disk (False only when no writable folder could be found).
CACHE: bool = _decide()


#: module file -> the files whose code or constants its kernels compile in (:func:`stamped_cache`)
_INLINES: dict[str, tuple[str, ...]] = {}


def _key(path: str) -> str:
    return os.path.abspath(path)


def stamped_files(module_file: str) -> list[str]:
    """``module_file`` and every file it declares, theirs in turn (each once, depth first).

    Examples
    --------
    >>> stamped_files("/nowhere/undeclared.py")
    ['/nowhere/undeclared.py']
    """
    seen: list[str] = []
    todo = [_key(module_file)]
    while todo:
        path = todo.pop()
        if path not in seen:
            seen.append(path)
            todo.extend(reversed(_INLINES.get(path, ())))
    return seen


def source_stamp(module_file: str) -> str:
    """SHA-256 over the contents of :func:`stamped_files` of ``module_file``: the stamp its kernels' cache carries.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> a, b = (pathlib.Path(tempfile.mkdtemp()) / name for name in ("a.py", "b.py"))
    >>> _ = a.write_text("x = 1"), b.write_text("y = 2")
    >>> _INLINES[str(a)] = (str(b),)
    >>> before = source_stamp(str(a))
    >>> _ = b.write_text("y = 3")
    >>> source_stamp(str(a)) == before
    False
    >>> del _INLINES[str(a)]
    """
    h = hashlib.sha256()
    for path in stamped_files(module_file):
        with open(path, "rb") as fh:
            h.update(hashlib.sha256(fh.read()).digest())
    return h.hexdigest()


class _Stamped:
    """Mixed into numba's locators (their order kept): a declared module's kernels are stamped with
    :func:`source_stamp`; every other function is left to the next locator."""

    _module_file = ""

    def get_source_stamp(self):
        return source_stamp(self._module_file)

    @classmethod
    def from_function(cls, py_func, py_file):
        if _key(py_file) not in _INLINES:
            return None
        self = super().from_function(py_func, py_file)  # pyright: ignore[reportAttributeAccessIssue] (numba's locator, mixed in)
        if self is not None:
            self._module_file = _key(py_file)
        return self


def _install() -> bool:
    """Put the stamped locators first in numba's list; False where numba keeps no such list (another version)."""
    from numba.core import caching  # deferred: heavy (numba)

    locators = getattr(getattr(caching, "CacheImpl", None), "_locator_classes", None)
    if not isinstance(locators, list):
        return False
    if not any(issubclass(c, _Stamped) for c in locators):
        locators[:0] = [type(f"_Stamped{base.__name__}", (_Stamped, base), {})
                        for base in (caching.UserProvidedCacheLocator, caching.InTreeCacheLocator,
                                     caching.UserWideCacheLocator)]
    return True


def stamped_cache(module_file: str, *inlines: str) -> bool:
    """Declare that the kernels of ``module_file`` compile in the code or constants of the files ``inlines``;
    return the ``cache=`` flag for them.

    Call it at the module's top, before its first ``@njit``: numba picks a kernel's cache
    locator when it decorates it. A file in ``inlines`` that declares files of its own brings
    them in too, so a module names only what it imports. Where numba has changed how it
    finds its locators, the flag is False: no cache rather than a stale one.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> a, b = (pathlib.Path(tempfile.mkdtemp()) / name for name in ("a.py", "b.py"))
    >>> stamped_cache(str(a), str(b)) == CACHE
    True
    >>> stamped_files(str(a)) == [str(a), str(b)]
    True
    >>> del _INLINES[str(a)]
    """
    _INLINES[_key(module_file)] = tuple(_key(p) for p in inlines)
    return CACHE and _install()
