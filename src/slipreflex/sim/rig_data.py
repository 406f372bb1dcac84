"""What a rig hands out: DAQ blocks, its live kernel arrays and its slip events (:class:`slipreflex.sim.Rig`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.interfaces import DaqSample
from . import kernel as K

if TYPE_CHECKING:
    pass

__all__ = ["DaqBlock", "KernelArrays", "SlipEvent", "slip_episodes"]


@dataclass(frozen=True)
class DaqBlock:
    """DAQ samples (and the truth at the same instants) as arrays.

    Attributes
    ----------
    seq : ndarray of int64
        Sample numbers since the rig started (not wrapped).
    t, volts : ndarray
        Sample time (s) and slip-sensor volts (ADC-quantized).
    accel : ndarray, shape (n, 3)
        Latest accelerometer reading (g) at each sample.
    accel_fresh : ndarray of bool
        Whether a new accelerometer reading arrived since the previous sample.
    flow_pulses : ndarray of int64
        Cumulative flow-sensor pulses.
    displacement, velocity, slip : ndarray
        Truth: bottle position below the grasp (m), its velocity (m/s, down
        positive), sliding distance at the contacts (m).
    stuck, fallen : ndarray of bool
        Truth: contacts stuck; bottle fallen out.
    normal_force : ndarray
        Truth: normal force per fingertip contact (N).
    load_mass : ndarray
        Truth: bottle + water + landed masses (kg).
    fingers : ndarray, shape (n, 3)
        Finger positions (thumb, index, middle), i-Limb units.
    accel_true : ndarray
        Truth: bottle acceleration (m/s^2, down positive).
    accel_lateral : ndarray
        Truth: the bottle's sideways acceleration (m/s^2) from the water's slosh,
        along the accelerometer's x axis.
    load_force : ndarray
        Truth: the axial load on the grasp (N): weight of bottle and water, the
        jet's push and splash, a landing mass's contact force.
    water_force_lateral : ndarray
        Truth: the water's sideways force on the bottle (N): the slosh and the
        jet's drive of it (see :class:`~slipreflex.sim.params.WaterParams`).

    Notes
    -----
    Every array is read-only: a compiled closed loop's block shares the rig's
    history (its columns are views of the rows the rig keeps; copying them cost
    a fifth of a held pour's closed loop). Copy an array to change it.

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> b = Rig("DK").advance_block(0.01)
    >>> b.t.shape == b.volts.shape
    True
    """

    seq: np.ndarray
    t: np.ndarray
    volts: np.ndarray
    accel: np.ndarray
    accel_fresh: np.ndarray
    flow_pulses: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    slip: np.ndarray
    stuck: np.ndarray
    fallen: np.ndarray
    normal_force: np.ndarray
    load_mass: np.ndarray
    fingers: np.ndarray
    accel_true: np.ndarray
    accel_lateral: np.ndarray
    load_force: np.ndarray
    water_force_lateral: np.ndarray

    @classmethod
    def from_rows(cls, rows: np.ndarray, seq0: int) -> DaqBlock:
        """Build from kernel rows (internal layout).

        A column that is contiguous in ``rows`` (a compiled loop's column-major rows) is
        taken as a view, any other is copied; every array of the block is read-only, as
        the rig's history it may share.

        Examples
        --------
        >>> import numpy as np
        >>> DaqBlock.from_rows(np.zeros((0, K.O_SIZE)), 0).t.size
        0
        >>> b = DaqBlock.from_rows(np.zeros((4, K.O_SIZE), order="F"), 0)
        >>> b.volts.flags.writeable, b.volts.flags.owndata
        (False, False)
        """
        n = rows.shape[0]

        def kept(a: np.ndarray) -> np.ndarray:
            a = a if a.shape[0] < 2 or a.strides[0] == a.itemsize else a.copy(order="F")
            a.flags.writeable = False
            return a

        def col(c: int) -> np.ndarray:
            return kept(rows[:, c])

        def cols(c0: int, c1: int) -> np.ndarray:
            return kept(rows[:, c0:c1 + 1])

        return cls(
            seq=kept(np.arange(seq0, seq0 + n, dtype=np.int64)), t=col(K.O_T),
            volts=col(K.O_VOLTS), accel=cols(K.O_AX, K.O_AZ),
            accel_fresh=kept(rows[:, K.O_AFRESH] > 0), flow_pulses=kept(rows[:, K.O_PULSES].astype(np.int64)),
            displacement=col(K.O_X), velocity=col(K.O_V), slip=col(K.O_S),
            stuck=kept(rows[:, K.O_STUCK] > 0), fallen=kept(rows[:, K.O_FALLEN] > 0), normal_force=col(K.O_NC),
            load_mass=col(K.O_MASS), fingers=cols(K.O_Q0, K.O_Q2),
            accel_true=col(K.O_A), accel_lateral=col(K.O_ALAT),
            load_force=col(K.O_LOAD), water_force_lateral=col(K.O_FWAT))

    def samples(self) -> list[DaqSample]:
        """The block as :class:`~slipreflex.core.interfaces.DaqSample` objects.

        Examples
        --------
        >>> from slipreflex.sim import Rig
        >>> Rig("TR").advance_block(0.006).samples()[0].seq
        0
        """
        out = []
        for i in range(self.t.size):
            acc = (float(self.accel[i][0]), float(self.accel[i][1]), float(self.accel[i][2])) \
                if self.accel_fresh[i] else None
            out.append(DaqSample(seq=int(self.seq[i]), t=float(self.t[i]), slip_volts=float(self.volts[i]),
                                 accel_g=acc, flow_pulses=int(self.flow_pulses[i])))
        return out


@dataclass(frozen=True)
class KernelArrays:
    """The rig's live kernel arrays (:meth:`Rig.kernel_arrays`); layouts in :mod:`slipreflex.sim.kernel`.

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> Rig("TR").kernel_arrays().C.dtype
    dtype('int64')
    """

    S: np.ndarray
    C: np.ndarray
    P: np.ndarray
    keys: np.ndarray
    D: np.ndarray
    W: np.ndarray
    track: np.ndarray
    tac_rates: np.ndarray
    tac_next: np.ndarray
    tac_contact: np.ndarray
    targets: np.ndarray
    speeds: np.ndarray


@dataclass(frozen=True)
class SlipEvent:
    """One episode of sliding (truth), from the first stick -> slip transition
    after a quiet period to the last re-stick before the next quiet period.

    Attributes
    ----------
    onset, end : float
        Times (s); ``end`` is None if the contact was still sliding (or the
        bottle fell) when the record ends.
    distance : float
        Sliding distance (m) over the episode.

    Examples
    --------
    >>> SlipEvent(1.0, 1.2, 0.002).duration
    0.2
    """

    onset: float
    end: float | None
    distance: float

    @property
    def duration(self) -> float | None:
        """``end - onset`` (s), or None while open.

        Examples
        --------
        >>> SlipEvent(1.0, None, 0.0).duration is None
        True
        """
        return None if self.end is None else round(self.end - self.onset, 12)


def slip_episodes(events: np.ndarray, quiet: float, open_end: bool, displacement: float) -> list[SlipEvent]:
    """Group a rig's stick/slip transitions (:meth:`slipreflex.sim.Rig.events` rows) into episodes separated
    by ``quiet`` seconds of sticking (what :meth:`slipreflex.sim.Rig.slip_events` returns); ``open_end``: the
    contacts slide (or the bottle has fallen) now, at ``displacement`` (m).

    Examples
    --------
    >>> ev = np.array([[1.0, K.E_ONSET, 0.0], [1.1, K.E_STICK, 0.002], [2.0, K.E_ONSET, 0.002]])
    >>> [(e.onset, e.end) for e in slip_episodes(ev, 0.1, True, 0.01)]
    [(1.0, 1.1), (2.0, None)]
    """
    out: list[SlipEvent] = []
    onset = None
    last_stick = None
    s_on = 0.0
    x_stick = 0.0
    for t, kind, x in events:
        if kind == K.E_ONSET:
            if onset is not None and last_stick is not None and t - last_stick >= quiet:
                out.append(SlipEvent(onset, last_stick, x_stick - s_on))
                onset = None
            if onset is None:
                onset, s_on = float(t), float(x)
            last_stick = None
        elif kind == K.E_STICK and onset is not None:
            last_stick, x_stick = float(t), float(x)
        elif kind == K.E_FALLEN and onset is not None:
            out.append(SlipEvent(onset, None, float(x) - s_on))
            onset = None
    if onset is not None:
        if last_stick is not None and not open_end:
            out.append(SlipEvent(onset, last_stick, x_stick - s_on))
        else:
            out.append(SlipEvent(onset, None, displacement - s_on))
    return out
