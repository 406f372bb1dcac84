"""A hand twin in one file: a virtual hand behind the Hand contract, registered as ``twin``.

Load it with ``--plugin`` (or name it in ``SLIPREFLEX_PLUGINS``) and give a log file as
the hand's "port"::

    slipreflex virtual-rig --schedule "drop@1.0" --schedule-from start   # prints the daq path
    slipreflex run --plugin examples/hand_twin.py --hand-type twin --hand twin-log.jsonl \\
        --daq /dev/pts/N --p0 150 --duration 3 --no-record

The twin has no hardware: it moves its three tripod fingers as the commands say (closing
at the commanded speed until ``hold``, stopping at the i-Limb's 500 units) and reports
those positions, like a driver that reads its encoders. Every command is appended to the
log, one JSON line each (``{"t": s, "command": "close", "fingers": [...], "speed": u/s}``),
so what the reflex sent can be read after the run.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from slipreflex.core.errors import ParameterError
from slipreflex.core.hardware import FINGER_MAX, TRIPOD, Finger
from slipreflex.files.paths import create_new
from slipreflex.rig.hands import HANDS, HandSpec


class TwinHand:
    """A kinematic hand: positions follow the commands in time; every command is logged.

    Parameters
    ----------
    port : str or path
        The command log to write (JSON lines), created new: a name already taken (a symlink
        included) is refused, so an earlier log is never written over or followed.
    start : float
        Every finger's position when the twin opens (i-Limb units).
    """

    def __init__(self, port: Any, start: float = 150.0, **_options: Any) -> None:
        self.log_path = Path(str(port))
        try:
            self._log = create_new(self.log_path, "w")
        except OSError as err:
            raise ParameterError(f"--hand {self.log_path}: cannot create the twin's log ({err.strerror})") from None
        self._t0 = time.monotonic()
        self._pos = {f: float(start) for f in TRIPOD}
        self._speed = {f: 0.0 for f in TRIPOD}
        self._since = self._t0

    def _now(self) -> float:
        """Bring every closing finger to the present; returns the twin's clock (s)."""
        now = time.monotonic()
        for f, speed in self._speed.items():
            self._pos[f] = min(FINGER_MAX, self._pos[f] + speed * (now - self._since))
        self._since = now
        return now - self._t0

    def _write(self, command: str, fingers: Iterable[Finger], **extra: Any) -> None:
        names = sorted(f.name.lower() for f in fingers)
        self._log.write(json.dumps({"t": round(self._now(), 4), "command": command, "fingers": names, **extra}) + "\n")
        self._log.flush()

    def set_positions(self, targets: Mapping[Finger, float]) -> None:
        """Move the named fingers to their targets (a grasp routine's command)."""
        self._now()
        for f, target in targets.items():
            self._pos[f], self._speed[f] = min(FINGER_MAX, max(0.0, float(target))), 0.0
        self._write("set", targets, targets={f.name.lower(): float(v) for f, v in targets.items()})

    def close_fingers(self, fingers: Iterable[Finger], speed: float) -> None:
        """Start closing ``fingers`` at ``speed`` units/s, until ``hold``."""
        fingers = tuple(fingers)
        self._now()
        for f in fingers:
            self._speed[f] = max(0.0, float(speed))
        self._write("close", fingers, speed=float(speed))

    def hold(self, fingers: Iterable[Finger]) -> None:
        """Stop ``fingers`` where they are (never opens)."""
        fingers = tuple(fingers)
        self._now()
        for f in fingers:
            self._speed[f] = 0.0
        self._write("hold", fingers)

    def positions(self) -> dict[Finger, float]:
        """The twin's finger positions now."""
        self._now()
        return dict(self._pos)

    def close(self) -> None:
        """Close the log."""
        self._log.close()

    def __enter__(self) -> TwinHand:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


HANDS.add_new(HandSpec("twin", "hand twin", TwinHand))
