"""The three contacts of the tripod grasp: which surface touches the bottle, and with what.

The thumb and the index finger touch the bottle through the silicone pads
of their tactile sensors; the middle finger through the rigid 3D-printed
cuff that holds the slip sensor (paper Fig. 2). Each contact has its own
normal compliance, tangential compliance and friction law
(:class:`~slipreflex.sim.Bottle` holds the friction of pad and cuff on that
bottle, :class:`~slipreflex.sim.HandParams` the compliances).

Three radial forces 120 degrees apart balance only when they are equal, so
every contact carries the same normal force; the grasp's stiffness per
contact is three over the sum of the three series compliances.

Examples
--------
>>> from slipreflex.sim import BOTTLES, HandParams
>>> from slipreflex.sim.contacts import grip_gain, static_capacity
>>> round(grip_gain(HandParams(), BOTTLES["TR"]), 3)       # N per position unit, per contact
0.102
>>> round(static_capacity(BOTTLES["TR"], 1.0), 3)          # N, at 1 N per contact
1.937
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import kernel as K
from .objects import Bottle
from .params import HandParams

__all__ = ["CONTACT_NAMES", "contact_normal_stiffness", "normal_stiffness", "grip_gain", "static_capacity",
           "fill_contact_params", "GripCurve", "grip_curve"]

#: The contacts in kernel order (thumb, index, middle).
CONTACT_NAMES: tuple[str, ...] = ("thumb pad", "index pad", "middle cuff")

_LAW = {"rate-state": K.LAW_RATE_STATE, "coulomb": K.LAW_COULOMB}


def contact_normal_stiffness(hand: HandParams, bottle: Bottle) -> tuple[float, float, float]:
    """Normal stiffness (N/m) of each contact: pad or cuff, finger and bottle wall in series.

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> [round(k) for k in contact_normal_stiffness(HandParams(), BOTTLES["TR"])]
    [488, 488, 566]
    """
    common = 1.0 / hand.finger_stiffness_n_m + 1.0 / bottle.wall_stiffness_n_m
    pad = 1.0 / (1.0 / hand.pad_normal_stiffness_n_m + common)
    cuff = 1.0 / (1.0 / hand.cuff_normal_stiffness_n_m + common)
    return pad, pad, cuff


def normal_stiffness(hand: HandParams, bottle: Bottle) -> float:
    """Stiffness (N/m) of the normal force per contact against the mean fingertip travel.

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> round(normal_stiffness(HandParams(), BOTTLES["TR"]))
    511
    """
    return 3.0 / sum(1.0 / k for k in contact_normal_stiffness(hand, bottle))


def grip_gain(hand: HandParams, bottle: Bottle) -> float:
    """Normal force added per contact (N) by one position unit of the tripod past contact.

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> grip_gain(HandParams(), BOTTLES["TR"]) > 0
    True
    """
    return normal_stiffness(hand, bottle) * hand.travel_per_unit_m


@dataclass(frozen=True, slots=True)
class GripCurve:
    """The normal force per contact against the mean fingertip travel past contact: three straight pieces.

    The wall follows its linear law up to the dent ``wall_linear_range_m``
    (force ``n1``, travel ``pen1``), then ovalizes with the softer stiffness
    ``(1 - wall_softening) k_w`` up to the dent ``wall_collapse_m`` (force
    ``n2``, travel ``pen2``), then is rigid; pad (or cuff) and finger stay
    linear throughout, in series. Every contact carries the same force, so
    the mean travel is ``N mean(1/k_surface + 1/k_finger) + d_wall(N)``,
    which inverts piece by piece.

    Parameters
    ----------
    k1, k2, k3 : float
        Slopes (N/m) of the three pieces.
    pen1, pen2 : float
        Mean travel (m) where the pieces meet.
    n1, n2 : float
        Force (N) per contact there.

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> c = grip_curve(HandParams(), BOTTLES["TR"])
    >>> round(c.n1, 2), round(c.force(0.5 * c.pen1) / c.n1, 3)
    (1.8, 0.5)
    """

    k1: float
    k2: float
    k3: float
    pen1: float
    pen2: float
    n1: float
    n2: float

    def force(self, pen: float) -> float:
        """Normal force (N) per contact at mean travel ``pen`` (m) past contact (0 before contact).

        Examples
        --------
        >>> from slipreflex.sim import BOTTLES
        >>> grip_curve(HandParams(), BOTTLES["TR"]).force(-1e-3)
        0.0
        """
        if pen <= 0.0:
            return 0.0
        if pen <= self.pen1:
            return self.k1 * pen
        if pen <= self.pen2:
            return self.n1 + self.k2 * (pen - self.pen1)
        return self.n2 + self.k3 * (pen - self.pen2)


def grip_curve(hand: HandParams, bottle: Bottle) -> GripCurve:
    """The normal force per contact against the mean fingertip travel (:class:`GripCurve`).

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> c = grip_curve(HandParams(), BOTTLES["TR"])
    >>> round(c.k1) == round(normal_stiffness(HandParams(), BOTTLES["TR"])), round(c.k3)
    (True, 3462)
    """
    kw = bottle.wall_stiffness_n_m
    # the contacts' own series compliance (pad or cuff, and finger), averaged over the three
    ch = sum(1.0 / k for k in (hand.pad_normal_stiffness_n_m, hand.pad_normal_stiffness_n_m,
                               hand.cuff_normal_stiffness_n_m)) / 3.0 + 1.0 / hand.finger_stiffness_n_m
    kw2 = (1.0 - bottle.wall_softening) * kw
    n1 = kw * bottle.wall_linear_range_m
    pen1 = n1 * (ch + 1.0 / kw)
    n2 = n1 + kw2 * (bottle.wall_collapse_m - bottle.wall_linear_range_m)
    pen2 = pen1 + (n2 - n1) * (ch + 1.0 / kw2)
    return GripCurve(k1=1.0 / (ch + 1.0 / kw), k2=1.0 / (ch + 1.0 / kw2), k3=1.0 / ch, pen1=pen1, pen2=pen2,
                     n1=n1, n2=n2)


def static_capacity(bottle: Bottle, normal_force: float) -> float:
    """Largest slowly rising load (N) the three contacts hold at ``normal_force`` per contact.

    The cuff is stiffer tangentially than the pads and grips less, so under
    a rising load it yields first and then carries its kinetic friction
    while the pads hold with their (fully healed) static friction.

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> static_capacity(BOTTLES["TR"], 2.0) == 2 * static_capacity(BOTTLES["TR"], 1.0)
    True
    """
    return (2.0 * bottle.mu_s + bottle.cuff_mu_k) * float(normal_force)


def fill_contact_params(P: np.ndarray, hand: HandParams, bottle: Bottle, dt: float) -> np.ndarray:
    """Write the three contacts' friction and compliance into a kernel parameter vector.

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> P = fill_contact_params(np.zeros(K.P_SIZE), HandParams(), BOTTLES["TX"], 1e-4)
    >>> float(P[K.P_C0 + 2 * K.PC_SIZE + K.PC_MUS]) == BOTTLES["TX"].cuff_mu_s
    True
    """
    pad = (_LAW[bottle.friction_law], bottle.mu_s, bottle.mu_k, bottle.rate_a, bottle.slip_distance_m,
           hand.pad_shear_stiffness_n_m, hand.pad_shear_damping_n_s_m)
    cuff = (_LAW[bottle.cuff_friction_law], bottle.cuff_mu_s, bottle.cuff_mu_k, bottle.cuff_rate_a,
            bottle.cuff_slip_distance_m, hand.cuff_shear_stiffness_n_m, hand.cuff_shear_damping_n_s_m)
    for i, (law, mus, muk, a, dc, kt, ct) in enumerate((pad, pad, cuff)):
        b = K.P_C0 + i * K.PC_SIZE
        P[b + K.PC_LAW] = law
        P[b + K.PC_MUS] = mus
        P[b + K.PC_MUK] = muk
        P[b + K.PC_VS] = bottle.stribeck_velocity_m_s
        P[b + K.PC_A] = a * muk   # the rate coefficient is given relative to mu_k
        P[b + K.PC_V0] = bottle.rate_v0_m_s
        P[b + K.PC_DC] = dc
        P[b + K.PC_HEAL] = bottle.heal_s
        P[b + K.PC_KT] = kt
        P[b + K.PC_CT] = ct
        P[b + K.PC_DECAY] = math.exp(-dt * kt / ct)
        P[b + K.PC_HEAL_DECAY] = math.exp(-dt / bottle.heal_s)
    P[K.P_KN] = normal_stiffness(hand, bottle)
    curve = grip_curve(hand, bottle)
    P[K.P_WALL_PEN1] = curve.pen1
    P[K.P_WALL_PEN2] = curve.pen2
    P[K.P_WALL_N1] = curve.n1
    P[K.P_WALL_N2] = curve.n2
    P[K.P_WALL_K2] = curve.k2
    P[K.P_WALL_K3] = curve.k3
    kw = bottle.wall_stiffness_n_m
    P[K.P_WALL_KW_INV] = 1.0 / kw
    P[K.P_WALL_KW2_INV] = 1.0 / ((1.0 - bottle.wall_softening) * kw)
    P[K.P_WALL_DLIN] = bottle.wall_linear_range_m
    P[K.P_WALL_DCOL] = bottle.wall_collapse_m
    P[K.P_CUFF_INV] = 1.0 / hand.cuff_normal_stiffness_n_m
    pads = P[K.P_C0:K.P_C0 + 2 * K.PC_SIZE].reshape(2, K.PC_SIZE)
    P[K.P_PADS_SAME] = 1.0 if np.array_equal(pads[0], pads[1]) else 0.0
    return P
