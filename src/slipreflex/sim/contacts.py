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
1.958
"""

from __future__ import annotations

import math

import numpy as np

from . import kernel as K
from .objects import Bottle
from .params import HandParams

__all__ = ["CONTACT_NAMES", "contact_normal_stiffness", "normal_stiffness", "grip_gain", "static_capacity",
           "fill_contact_params"]

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
    pads = P[K.P_C0:K.P_C0 + 2 * K.PC_SIZE].reshape(2, K.PC_SIZE)
    P[K.P_PADS_SAME] = 1.0 if np.array_equal(pads[0], pads[1]) else 0.0
    return P
