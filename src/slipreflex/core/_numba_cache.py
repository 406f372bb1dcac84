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

Examples
--------
>>> isinstance(CACHE, bool)
True
"""

from __future__ import annotations

import os
import stat
import sys
import tempfile
from pathlib import Path

__all__ = ["CACHE", "choose_cache", "KERNEL_PACKAGES"]

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
