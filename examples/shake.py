"""A shake experiment in one file: the hand shakes the held bottle up and down.

Load it with ``--plugin`` (or name it in ``SLIPREFLEX_PLUGINS``)::

    slipreflex reproduce --plugin examples/shake.py --experiments shake --trials 1

It registers a load kind, ``shake`` (a :class:`Shake`: the grip accelerates along the
bottle's axis as ``-A sin(2 pi f t)`` for whole cycles, up first), and an experiment of the
same name that shakes the grasped bottle once per trial. The physics is the simulator's
own term for a moving grip (the kernel's timed-load row carries the grip's acceleration:
the held bottle feels ``-m a`` in the grip's frame and its accelerometer reads ``a``);
this file only says how a shake fills that row.

Why these numbers: 3 Hz is inside the 2-5 Hz band of a brisk voluntary shake of the forearm
(faster than the ~1 Hz of reaching, slower than the 8-12 Hz of physiological tremor), and
+-2 cm of hand travel at 3 Hz is a peak acceleration of (2 pi 3)^2 0.02 = 7.1 m/s^2 (0.72 g);
three cycles last 1 s. They are an estimate for a demonstration, not a measured protocol.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from slipreflex.core.errors import ParameterError
from slipreflex.core.experiment_specs import EXPERIMENTS, ExperimentSpec
from slipreflex.sim import kernel as K
from slipreflex.sim.loads import LOAD_KINDS, LoadKind

#: Shake frequency (Hz): a brisk voluntary forearm shake (2-5 Hz).
SHAKE_HZ = 3.0
#: Peak acceleration of the grip (m/s^2): +-2 cm of hand travel at 3 Hz.
SHAKE_ACCEL_M_S2 = (2.0 * math.pi * SHAKE_HZ) ** 2 * 0.02
#: Whole cycles (acceleration and velocity end at zero, the hand back at rest).
SHAKE_CYCLES = 3


@dataclass(frozen=True)
class Shake:
    """The grip shaken along the bottle's axis: ``accel_m_s2`` peak at ``frequency_hz`` for ``cycles``."""

    accel_m_s2: float = SHAKE_ACCEL_M_S2
    frequency_hz: float = SHAKE_HZ
    cycles: int = SHAKE_CYCLES

    def __post_init__(self) -> None:
        for name in ("accel_m_s2", "frequency_hz"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ParameterError(f"Shake.{name} must be a finite number > 0, got {value!r}")
        if not isinstance(self.cycles, int) or self.cycles < 1:
            raise ParameterError(f"Shake.cycles must be a whole number >= 1, got {self.cycles!r}")

    @property
    def duration_s(self) -> float:
        """How long the shake lasts (s)."""
        return self.cycles / self.frequency_hz


def shake_row(what: Shake, at: float, rig: Any) -> Any:
    """The kernel's timed-load row of a shake: no water, only the grip's acceleration (up first)."""
    row = K.POUR.new()
    row[K.W_START] = at
    row[K.W_DELAY] = 0.0
    row[K.W_DUR] = what.duration_s
    row[K.W_RATE_L_S] = row[K.W_RATE_KG_S] = row[K.W_TOTAL_KG] = row[K.W_JET_N] = 0.0
    row[K.W_ACC] = -what.accel_m_s2   # down positive in the kernel: the grip moves up first
    row[K.W_ACC_W] = 2.0 * math.pi * what.frequency_hz
    return row


def shake_perturbation(config: Any) -> Shake:
    """Every trial's shake (the run's config has no shake options: the constants above)."""
    return Shake()


def describe_shake(shake: Shake) -> str:
    """A shake in words."""
    return f"{shake.cycles} x {shake.frequency_hz:g} Hz at {shake.accel_m_s2 / 9.80665:.2g} g"


def shake_load_s(shake: Shake) -> float:
    """The load lasts the shake."""
    return shake.duration_s


LOAD_KINDS.add_new(LoadKind("shake", Shake, "timed", shake_row))
EXPERIMENTS.add_new(ExperimentSpec(name="shake", title="shaken grip", perturbation=shake_perturbation,
                                   describe=describe_shake, load_s=shake_load_s, slip_events="segmented",
                                   zoom_s=(0.3, 1.5)))
