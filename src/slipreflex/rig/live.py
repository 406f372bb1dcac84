"""The live view: a run's messages on a Foxglove WebSocket server while it runs (``--live``).

:class:`LiveView` is a :class:`~slipreflex.core.taps.Tap`: the real-time loop puts every
message its recording gets (the same topics and schemas, :func:`slipreflex.files.recording.schema`)
and the tap's thread logs them on a `Foxglove SDK <https://docs.foxglove.dev/docs/sdk>`_
WebSocket server (the ``foxglove-sdk`` package, ``pip install 'slipreflex[live]'``), on
loopback by default. Open Foxglove, *Open connection* -> *Foxglove WebSocket*,
``ws://127.0.0.1:8765``, and import the layout ``foxglove/slipreflex.json`` of the
repository (built by ``scripts/dev/foxglove_layout.py``; docs/runtime.md, "Live view") for
plots of the signal, the spikes and the MPI command as in the paper's Fig. 10. The same
layout opens a recorded MCAP file.

Examples
--------
>>> parse_address("9000"), parse_address("0.0.0.0:8765")
(('127.0.0.1', 9000), ('0.0.0.0', 8765))
>>> view = LiveView(("127.0.0.1", 0), ["/chain/windows"])      # doctest: +SKIP
>>> view.start().put("/chain/windows", {"seq": 7, "t": 0.021, "count": 2}, 0)  # doctest: +SKIP
>>> view.close()                                                # doctest: +SKIP
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from typing import Any

from ..core.errors import DeviceError, ParameterError
from ..core.taps import Tap
from ..files.recording import TOPICS, schema

__all__ = ["LiveView", "parse_address", "require_foxglove", "RUN_TOPICS", "DEFAULT_PORT",
           "WS_SUBPROTOCOLS"]

#: Port of ``--live`` given without one (Foxglove's own default).
DEFAULT_PORT: int = 8765
#: The Foxglove WebSocket subprotocols a client offers: foxglove-sdk >= 0.2x speaks the first,
#: older servers (and the protocol's first version) the second.
WS_SUBPROTOCOLS: tuple[str, ...] = ("foxglove.sdk.v1", "foxglove.websocket.v1")
#: The topics a ``run`` publishes (a board reflex adds /board/state, a tactile method /tactile/frames).
RUN_TOPICS: tuple[str, ...] = ("/daq/samples", "/daq/imu", "/daq/flow", "/chain/state", "/chain/events",
                               "/chain/windows", "/hand/commands", "/hand/grip", "/faults", "/stats")


def parse_address(text: str, option: str = "--live") -> tuple[str, int]:
    """``[HOST:]PORT`` as ``(host, port)``; the host is loopback when not given.

    Parameters
    ----------
    text : str
    option : str
        The option named in errors.

    Raises
    ------
    ParameterError
        A port that is not a whole number in 0..65535 (0: any free port) or an empty host.

    Examples
    --------
    >>> parse_address("localhost:0")
    ('localhost', 0)
    >>> parse_address("eighty")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: --live 'eighty': give [HOST:]PORT with PORT a whole number in 0..65535
    """
    host, sep, port = str(text).strip().rpartition(":")
    if not sep:
        host = "127.0.0.1"
    host = host.strip("[]")
    if not port.isdigit() or int(port) > 65535 or not host:
        raise ParameterError(f"{option} {text!r}: give [HOST:]PORT with PORT a whole number in 0..65535")
    return host, int(port)


def require_foxglove(option: str = "--live") -> Any:
    """Import ``foxglove`` (foxglove-sdk) or say, in one line, how to install it.

    Raises
    ------
    ParameterError
        foxglove-sdk is not installed or does not load.

    Examples
    --------
    >>> require_foxglove().__name__  # doctest: +SKIP
    'foxglove'
    """
    try:
        import foxglove  # deferred: optional extra (live: foxglove)
    except ImportError as err:
        raise ParameterError(f"{option} needs foxglove-sdk: pip install 'slipreflex[live]' ({err})") from None
    return foxglove


class LiveView(Tap):
    """A Foxglove WebSocket server publishing a run's topics.

    The server starts in the constructor (a port in use is an error before the run
    starts); one channel per topic of ``topics`` is advertised with the recording's
    schema (JSON schema, JSON messages), and every message is logged with its
    recorded log time. Clients that subscribe get the messages from then on.

    Parameters
    ----------
    address : (str, int) or str
        Host and port (``"[HOST:]PORT"`` is parsed); port 0 takes any free port (see :attr:`port`).
    topics : iterable of str
        Topics of :data:`slipreflex.files.recording.TOPICS` to advertise (default :data:`RUN_TOPICS`).
        Messages on other topics are not published.
    name : str
        Server name shown by Foxglove.
    backlog : int
        Messages buffered per client before the oldest is dropped.

    Attributes
    ----------
    port : int
    url : str
        ``ws://HOST:PORT``.

    Raises
    ------
    ParameterError
        foxglove-sdk missing, an unknown topic.
    DeviceError
        The server cannot listen on the address (the message names it).

    Examples
    --------
    >>> with LiveView("127.0.0.1:0", ["/faults"]) as view:   # doctest: +SKIP
    ...     view.url.startswith("ws://127.0.0.1:")
    True
    """

    def __init__(self, address: tuple[str, int] | str = ("127.0.0.1", DEFAULT_PORT),
                 topics: Iterable[str] = RUN_TOPICS, *, name: str = "slipreflex",
                 backlog: int = 1 << 14) -> None:
        foxglove = require_foxglove()
        host, port = parse_address(address) if isinstance(address, str) else address
        topics = tuple(dict.fromkeys(topics))
        unknown = [t for t in topics if t not in TOPICS]
        if unknown:
            raise ParameterError(f"live view: unknown topic {unknown[0]!r} (known: {', '.join(TOPICS)})")
        super().__init__("live view")
        self.context = foxglove.Context()
        try:
            self.server = foxglove.start_server(name=name, host=host, port=port, context=self.context,
                                                message_backlog_size=backlog)
        except Exception as err:  # noqa: BLE001 - the SDK raises its own error types
            raise DeviceError(f"--live {host}:{port}: cannot start the Foxglove WebSocket server: {err}") from None
        self.host, self.port = host, int(self.server.port)
        self.url = f"ws://{host}:{self.port}"
        self.channels = {}
        for topic in topics:
            sname, data = schema(topic)
            self.channels[topic] = foxglove.Channel(
                topic, schema=foxglove.Schema(name=sname, encoding="jsonschema", data=data),
                message_encoding="json", context=self.context)

    def watched(self) -> bool:
        """Whether a client subscribes to every advertised channel (messages logged before a
        client's subscription reach it are not sent to it).

        Examples
        --------
        >>> with LiveView("127.0.0.1:0", ["/faults"]) as view:   # doctest: +SKIP
        ...     view.watched()
        False
        """
        return all(channel.has_sinks() for channel in self.channels.values())

    def handle(self, topic: str, msg: Mapping[str, Any], log_time_ns: int) -> None:
        """Log one message on its channel (the tap's thread)."""
        channel = self.channels.get(topic)
        if channel is not None:
            channel.log(json.dumps(msg, separators=(",", ":")).encode(), log_time=log_time_ns)

    def shutdown(self) -> None:
        """Stop the server (after the queued messages went out)."""
        for channel in self.channels.values():
            channel.close()
        self.server.stop()
