"""Where a study's plants run: a Dask scheduler checked before use, or a local cluster of worker processes.

``slipreflex study --scheduler ADDRESS`` runs on a cluster a user started (``dask scheduler`` and
``dask worker`` on each machine); without it, a :class:`dask.distributed.LocalCluster` of ``--workers``
processes on this machine. A scheduler address is probed first (:func:`probe_scheduler`), so a wrong
address, a foreign server or a silent one ends the study in one line before any work.

Examples
--------
>>> SCHEDULER_TIMEOUT_S > 0
True
"""

from __future__ import annotations

import logging
import os
import signal
import socket
import struct
import threading
import time
from typing import Any

from ..core.errors import ParameterError

__all__ = ["SCHEDULER_TIMEOUT_S", "probe_scheduler"]


#: Seconds a ``--scheduler`` has to answer as a Dask scheduler (its handshake) before the study
#: gives up with one line.
SCHEDULER_TIMEOUT_S: float = 10.0
#: The largest first handshake a Dask scheduler sends (bytes); anything claiming more is not one.
_HANDSHAKE_MAX = 1 << 20


def probe_scheduler(address: str, timeout: float | None = None) -> None:
    """Check that ``address`` answers as a Dask scheduler, within ``timeout`` seconds.

    A Dask scheduler sends its handshake as soon as a client connects: a little-endian
    8-byte length, then that many bytes starting with a small frame count. Anything else
    (an SSH banner, an HTTP server waiting for a request, a closed port) is refused here in
    one line, before Dask's own client would wait for minutes or try to allocate what a
    foreign banner's first bytes claim. The whole first message is read within ``timeout``
    (a server that sends a Dask-looking header and then nothing is refused too). A ``tls://``
    address needs Dask's TLS configuration (``distributed.comm.tls``: a CA file, or the
    client's certificate and key); without one it is refused here, and with one it is left to
    Dask's client.

    Raises
    ------
    ParameterError
        ``--scheduler ADDRESS: ...``, naming what was wrong.

    Examples
    --------
    >>> probe_scheduler("tcp://127.0.0.1:1", timeout=1)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: --scheduler tcp://127.0.0.1:1: cannot connect (...)
    """

    timeout = SCHEDULER_TIMEOUT_S if timeout is None else timeout
    where = f"--scheduler {address}"
    scheme, _, rest = address.rpartition("://")
    if scheme == "tls":
        _require_tls_config(where)
        return
    if scheme not in ("", "tcp"):
        return
    host, sep, port = rest.rpartition(":")
    if not sep or not port.isdigit() or not host:
        raise ParameterError(f"{where}: expected tcp://HOST:PORT")
    host = host.strip("[]")
    deadline = time.monotonic() + timeout

    def read_exact(sock: Any, n: int) -> bytes:
        buf = b""
        while len(buf) < n:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError
            sock.settimeout(left)
            got = sock.recv(n - len(buf))
            if not got:
                raise ConnectionError("closed the connection")
            buf += got
        return buf

    try:
        with socket.create_connection((host, int(port)), timeout=timeout) as sock:
            try:
                size = struct.unpack("<Q", read_exact(sock, 8))[0]
                if not 16 <= size <= _HANDSHAKE_MAX:
                    raise ValueError
                frames = struct.unpack("<Q", read_exact(sock, 8))[0]
                if not 1 <= frames <= 64:
                    raise ValueError
                read_exact(sock, size - 8)  # the rest of the handshake, within the same deadline
            except TimeoutError:
                raise ParameterError(f"{where}: no Dask handshake within {timeout:g} s (not a Dask "
                                     f"scheduler?)") from None
            except (ValueError, ConnectionError):
                raise ParameterError(f"{where}: answers, but not as a Dask scheduler") from None
    except OSError as err:
        raise ParameterError(f"{where}: cannot connect ({err.strerror or err})") from None


def _require_tls_config(where: str) -> None:
    """A one-line error unless Dask's configuration gives the client something to speak TLS with."""
    import dask.config  # deferred: optional extra (study: dask)

    tls = dask.config.get("distributed.comm.tls", default={}) or {}
    client = tls.get("client") or {}
    if not (tls.get("ca-file") or client.get("cert")):
        raise ParameterError(f"{where}: tls:// needs Dask's TLS configuration (distributed.comm.tls.ca-file, "
                             f"client.cert and client.key, e.g. in ~/.config/dask/distributed.yaml); none is set")


def _client(workers: int | None, scheduler: str | None, dashboard: str | None = None):

    import dask.config  # deferred: optional extra (study: dask)
    from dask.distributed import Client, LocalCluster  # deferred: optional extra (study: dask)

    if scheduler:
        probe_scheduler(scheduler)
        try:
            return Client(scheduler, timeout=f"{SCHEDULER_TIMEOUT_S:g}s"), None, scheduler
        except (OSError, ValueError, TimeoutError) as err:   # unreachable, timed out, or not an address
            raise ParameterError(f"--scheduler {scheduler}: cannot connect: {err}") from None
    n = int(workers or os.cpu_count() or 1)
    # The workers start with SIGINT ignored (an ignored signal stays ignored in the spawned
    # interpreter): a Ctrl-C reaches the whole process group, and only this process acts on it.
    # Here SIGINT is blocked meanwhile (Linux keeps a blocked signal pending even while it is
    # ignored), so a Ctrl-C during the start is acted on as soon as the cluster is up.
    main = _main_thread()
    if main:
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    # Dask's statistical profiler samples each worker's stack every 10 ms, for the dashboard's profile
    # page: without a dashboard nobody reads it, and a plant's Python-heavy work paid for it (about a
    # tenth of a plant's CPU, docs/speed.md)
    profile = {"distributed.worker.profile.enabled": dashboard is not None}
    try:
        # Without a dashboard the scheduler still serves its health page: on a free local port, not on
        # 8787, which two studies at once would both try (the second with a warning and a leaked socket)
        quiet_page = {} if dashboard is not None else {"dashboard": False, "dashboard_address": "127.0.0.1:0"}
        with dask.config.set(profile):
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                                   dashboard_address=dashboard,  # type: ignore[arg-type]  # None: no dashboard
                                   scheduler_kwargs=quiet_page,
                                   # the workers' own logs are Dask's business: what fails in a plant is recorded in
                                   # its part, what fails in a worker reaches the client as an exception; and on a
                                   # loaded machine a stopped study's workers log the scheduler's close as errors
                                   silence_logs=logging.CRITICAL)
    finally:
        if main:
            signal.signal(signal.SIGINT, old)
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    return Client(cluster), cluster, f"LocalCluster({n})"


def _main_thread() -> bool:

    return threading.current_thread() is threading.main_thread()
