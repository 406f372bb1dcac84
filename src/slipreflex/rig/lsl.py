"""Lab Streaming Layer outlets for a run (``--lsl``): the lab's other streams and ours in one XDF.

:class:`LslOutlets` is a :class:`~slipreflex.core.taps.Tap` (it publishes off the loop's thread)
with two `LSL <https://labstreaminglayer.readthedocs.io>`_ outlets (the ``pylsl`` package,
whose wheels bundle liblsl; ``pip install 'slipreflex[lsl]'``):

``<name>-samples`` (type ``slip``, regular at the DAQ's rate, double64)
    one sample per DAQ sample: :data:`SAMPLE_CHANNELS` (the raw and filtered slip
    signal, the threshold in force, the spike flag, the slip-finger position, the IMU
    in g and the flow pulses; NaN where a value is missing), labelled with units in
    the stream's ``desc/channels``.
``<name>-markers`` (type ``Markers``, irregular, one string channel)
    ``spike``, ``command <target> sent`` / ``command <target> not sent
    (<note>)`` and ``fault <kind>: <message>``.

Time stamps are the DAQ's own clock mapped onto LSL's: at the first sample the
offset between the board's time ``t`` and :func:`pylsl.local_clock` at that
sample's arrival is fixed, and every sample and spike is stamped ``t + offset``
(the board's crystal, not the PC's scheduling, spaces them); a fault is stamped at
its arrival. LabRecorder's clock-offset measurements then put them on the
timeline of the lab's other streams (docs/runtime.md, "Lab Streaming Layer").

Examples
--------
>>> SAMPLE_CHANNELS[:3]
('slip_volts', 'filtered', 'threshold')
>>> marker_text("/hand/commands", {"target": 212.0, "sent": True, "note": ""})
'command 212 sent'
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

from ..core.errors import DeviceError, ParameterError
from ..core.hardware import DAQ_FS
from ..core.taps import Tap

__all__ = ["LslOutlets", "SAMPLE_CHANNELS", "SAMPLE_UNITS", "marker_text", "require_pylsl", "tactile_channels"]

#: The channels of the samples stream, in order.
SAMPLE_CHANNELS: tuple[str, ...] = ("slip_volts", "filtered", "threshold", "event", "position",
                                    "ax", "ay", "az", "flow_pulses")
#: Their units.
SAMPLE_UNITS: tuple[str, ...] = ("V", "V", "V", "bool", "i-Limb units", "g", "g", "g", "pulses")



def tactile_channels(taxels: int) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Channels and units of the samples stream of a run whose method reads tactile frames.

    Examples
    --------
    >>> tactile_channels(2)[0]
    ('total', 'peak', 'taxel_0', 'taxel_1', 'filtered', 'threshold', 'event', 'position')
    """
    names = ("total", "peak", *(f"taxel_{k}" for k in range(taxels)), "filtered", "threshold", "event",
             "position")
    return names, ("N",) * (2 + taxels) + ("N", "", "bool", "i-Limb units")


def require_pylsl(option: str = "--lsl") -> Any:
    """Import ``pylsl`` with its native liblsl, or say in one line what is missing.

    Raises
    ------
    ParameterError
        pylsl is not installed, or its liblsl does not load.

    Examples
    --------
    >>> require_pylsl().__name__  # doctest: +SKIP
    'pylsl'
    """
    try:
        import pylsl  # deferred: optional extra (lsl: pylsl)
    except ImportError as err:
        raise ParameterError(f"{option} needs pylsl: pip install 'slipreflex[lsl]' ({err})") from None
    except (OSError, RuntimeError) as err:  # pylsl raises when liblsl cannot be found or loaded
        raise ParameterError(f"{option}: pylsl cannot load liblsl ({err})") from None
    return pylsl


def _num(x: Any) -> float:
    return math.nan if x is None else float(x)


def marker_text(topic: str, msg: Mapping[str, Any]) -> str | None:
    """The marker string for a message, or None when the topic has no marker.

    Examples
    --------
    >>> marker_text("/chain/events", {"seq": 3, "t": 0.009})
    'spike'
    >>> marker_text("/faults", {"kind": "watchdog", "message": "no sample for 100 ms"})
    'fault watchdog: no sample for 100 ms'
    >>> marker_text("/hand/commands", {"target": 150.5, "sent": False, "note": "at start"})
    'command 150.5 not sent (at start)'
    """
    if topic == "/chain/events":
        return "spike"
    if topic == "/hand/commands":
        state = "sent" if msg.get("sent") else f"not sent ({msg.get('note') or 'held'})"
        return f"command {float(msg['target']):g} {state}"
    if topic == "/faults":
        return f"fault {msg['kind']}: {msg['message']}"
    return None


class LslOutlets(Tap):
    """The samples outlet and the markers outlet of one run.

    Parameters
    ----------
    name : str
        Stream name prefix (``<name>-samples``, ``<name>-markers``).
    source_id : str, optional
        Stable id of this source (LabRecorder reconnects by it); default ``name`` and the
        DAQ port or ``slipreflex``.
    fs : float
        Nominal rate of the samples stream (Hz).
    taxels : int
        For a run whose method reads tactile frames: taxels per frame; the samples stream
        then has one sample per frame with :func:`tactile_channels` (0: the slip sensor's
        :data:`SAMPLE_CHANNELS`).

    Attributes
    ----------
    offset : float or None
        LSL time minus board time, fixed at the first sample.
    pushed_samples, pushed_markers : int

    Raises
    ------
    ParameterError
        pylsl or liblsl missing.
    DeviceError
        liblsl cannot create an outlet.

    Examples
    --------
    >>> with LslOutlets("demo") as lsl:                        # doctest: +SKIP
    ...     lsl.put("/faults", {"kind": "watchdog", "message": "m"}, time.time_ns())
    """

    def __init__(self, name: str = "slipreflex", *, source_id: str | None = None,
                 fs: float = DAQ_FS, taxels: int = 0) -> None:
        pylsl = require_pylsl()
        super().__init__("lsl outlets")
        self.pylsl = pylsl
        sid = source_id or f"{name}@slipreflex"
        self.channels, units = tactile_channels(taxels) if taxels else (SAMPLE_CHANNELS, SAMPLE_UNITS)
        self._index = {c: k for k, c in enumerate(self.channels)}
        self._sample_topic = "/tactile/frames" if taxels else "/daq/samples"
        try:
            info = pylsl.StreamInfo(f"{name}-samples", "tactile" if taxels else "slip", len(self.channels),
                                    float(fs), pylsl.cf_double64, f"{sid}-samples")
            chans = info.desc().append_child("channels")
            for label, unit in zip(self.channels, units):
                ch = chans.append_child("channel")
                ch.append_child_value("label", label)
                ch.append_child_value("unit", unit)
            info.desc().append_child_value("clock", "DAQ board time mapped to LSL local_clock at the first sample")
            self.samples = pylsl.StreamOutlet(info)
            minfo = pylsl.StreamInfo(f"{name}-markers", "Markers", 1, pylsl.IRREGULAR_RATE,
                                     pylsl.cf_string, f"{sid}-markers")
            self.markers = pylsl.StreamOutlet(minfo)
        except (RuntimeError, OSError) as err:
            raise DeviceError(f"--lsl: liblsl cannot create the outlets: {err}") from None
        self.names = (f"{name}-samples", f"{name}-markers")
        self.source_id = sid
        # one (wall clock, LSL clock) pair maps the messages' log times onto LSL time
        self._wall0, self._lsl0 = time.time_ns(), pylsl.local_clock()
        self.offset: float | None = None
        self._row: list[float] | None = None
        self._seq: int | None = None
        self._t = 0.0
        self.pushed_samples = self.pushed_markers = 0

    def lsl_time(self, log_time_ns: int) -> float:
        """LSL time of a message's log time (wall-clock ns)."""
        return self._lsl0 + (log_time_ns - self._wall0) * 1e-9

    def _marker(self, text: str, stamp: float) -> None:
        self.markers.push_sample([text], stamp)
        self.pushed_markers += 1

    def handle(self, topic: str, msg: Mapping[str, Any], log_time_ns: int) -> None:
        """Build and push samples and markers (the tap's thread)."""
        index = self._index
        if topic == self._sample_topic:
            if self.offset is None:
                self.offset = self.lsl_time(log_time_ns) - msg["t"]
            row = [math.nan] * len(self.channels)
            for key, k in index.items():
                if key in msg and key not in ("event",):
                    row[k] = _num(msg[key])
            self._row, self._seq, self._t = row, msg["seq"], msg["t"]
            return
        if topic == "/daq/imu" and self._row is not None and msg["seq"] == self._seq:
            for axis in ("ax", "ay", "az"):
                self._row[index[axis]] = float(msg[axis])
            return
        if topic == "/chain/state" and self._row is not None and msg["seq"] == self._seq:
            row = self._row
            row[index["filtered"]] = _num(msg.get("filtered"))
            row[index["threshold"]] = _num(msg.get("threshold"))
            row[index["event"]] = 1.0 if msg.get("event") else 0.0
            self.samples.push_sample(row, self._t + (self.offset or 0.0))
            self.pushed_samples += 1
            self._row = None
            return
        text = marker_text(topic, msg)
        if text is None:
            return
        if topic == "/faults" or self.offset is None or "t" not in msg:
            stamp = self.lsl_time(log_time_ns)
        else:
            stamp = msg["t"] + self.offset
        self._marker(text, stamp)

    def shutdown(self) -> None:
        """Close the outlets (their consumers see the streams end)."""
        del self.samples, self.markers

