"""Claim 4's physical bounds: how much the grasp can hold through a drop, from the paper's setup alone.

Re-exported by :mod:`slipreflex.analysis.claims`.

Examples
--------
>>> round(first_slip_capacity_n(0.05, 200.0), 2) > 0
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ...core import hardware as hw
from ..paper import BOTTLE_ORDER

__all__ = [
    "DropBounds", "drop_bounds", "drop_slipout_capacity_n", "drop_momentum_capacity_n", "first_slip_capacity_n",
    "STATIC_OVER_KINETIC_MAX"
]


#: Generous upper bound of static over sliding friction for polymer and elastomer contacts on PET.
STATIC_OVER_KINETIC_MAX: float = 2.0
#: What claim 4's bounds assume, named in every report that prints them.
DROP_ASSUMPTIONS: str = ("one degree of freedom (the bottle slides along its axis, no tilt), a constant normal "
                         "force (the grasp neither loosens nor tightens), complete slippage = sliding the whole "
                         "grip travel to the shoulder, static/sliding friction ratio r")


def first_slip_capacity_n(bottle_mass_kg: float, volume_ml: float, *, rate_l_min: float = 1.0,
                          fall_height_m: float = 0.10) -> float:
    """Static capacity (N) of a grasp whose first pour slip comes at ``volume_ml``.

    At the first slip the grasp's friction capacity equals the load:
    ``C = (M + rho V) g + rho Q sqrt(2 g h)``, the bottle and water weight
    plus the jet's momentum flux (water 1 g/ml, flow Q, jet falling h).

    Examples
    --------
    >>> round(first_slip_capacity_n(0.040, 200.0), 2)
    2.38
    """
    rho_q = rate_l_min / 60.0  # kg/s of water
    return (bottle_mass_kg + volume_ml * 1e-3) * hw.GRAVITY + rho_q * math.sqrt(2 * hw.GRAVITY * fall_height_m)


def drop_slipout_capacity_n(bottle_mass_kg: float, drop_mass_kg: float, height_m: float, travel_m: float,
                            static_over_kinetic: float = STATIC_OVER_KINETIC_MAX) -> float:
    """Energy bound: the largest static capacity (N) at which a drop can end in complete slippage.

    The mass falls ``h`` (release height plus the bottle's depth) and the bottle
    then slides the grip travel ``d``. Generously, no energy is lost in the
    impact and friction falls to ``C / r`` the moment sliding starts. The work
    friction does over ``d`` must not exceed what falling supplies:
    ``(C / r) d <= m g (h + d) + M g d``, so ``C <= r [(M + m) g + m g h / d]``.

    Examples
    --------
    >>> round(drop_slipout_capacity_n(0.040, 0.010, 0.18, 0.03, 2.0), 2)
    2.16
    """
    g = hw.GRAVITY
    return static_over_kinetic * ((bottle_mass_kg + drop_mass_kg) * g + drop_mass_kg * g * height_m / travel_m)


def drop_momentum_capacity_n(bottle_mass_kg: float, drop_mass_kg: float, height_m: float, travel_m: float,
                             static_over_kinetic: float) -> float:
    """Momentum bound: the largest static capacity (N) at which a drop can end in complete slippage.

    The mass lands at ``v = sqrt(2 g h)`` in a fully inelastic impact, so the
    bottle and mass move on at ``u = m v / (M + m)``, then slide against
    ``C / r`` less their weight. They cover the grip travel ``d`` only if
    ``u^2 >= 2 d (C / r - (M + m) g) / (M + m)``, so
    ``C <= r [(M + m) g + m^2 g h / (d (M + m))]``.

    Examples
    --------
    >>> round(drop_momentum_capacity_n(0.040, 0.010, 0.18, 0.03, 2.0), 2)
    1.22
    """
    g, mm = hw.GRAVITY, bottle_mass_kg + drop_mass_kg
    return static_over_kinetic * (mm * g + drop_mass_kg ** 2 * g * height_m / (travel_m * mm))


@dataclass(frozen=True)
class DropBounds:
    """Claim 4's bounds for one bottle: can the paper's 10 g drop end in complete slippage?

    Attributes
    ----------
    bottle : str
    fall_height_m : float
        How far the mass falls: the drop's release height plus the bottle's depth (the rig's geometry).
    pour_capacity_n : float
        The grasp's static capacity that the paper's first pour slip (about 200 ml) implies.
    energy_n : float
        Energy bound with r = :data:`STATIC_OVER_KINETIC_MAX` (no impact loss).
    momentum_n, momentum_generous_n : float
        Momentum bound with the bottle's own r = mu_s / mu_k, and with r = 2.
    r_own : float

    Examples
    --------
    >>> b = drop_bounds()[0]
    >>> b.bottle, round(b.fall_height_m, 2), b.possible
    ('TR', 0.18, False)
    """

    bottle: str
    fall_height_m: float
    pour_capacity_n: float
    energy_n: float
    momentum_n: float
    momentum_generous_n: float
    r_own: float

    @property
    def possible(self) -> bool:
        """Whether even the energy bound allows a slip-out of the pour-calibrated grasp."""
        return self.energy_n >= self.pour_capacity_n

    def text(self) -> str:
        """One line: the bounds beside the pour's capacity."""
        return (f"{self.bottle}: fall {100 * self.fall_height_m:.0f} cm; slip-out needs C <= {self.energy_n:.2f} N "
                f"(energy, r {STATIC_OVER_KINETIC_MAX:g}) or {self.momentum_n:.2f}-{self.momentum_generous_n:.2f} N "
                f"(momentum, r {self.r_own:.2f}-{STATIC_OVER_KINETIC_MAX:g}); the first pour slip implies "
                f"C = {self.pour_capacity_n:.2f} N")


def drop_bounds(plant: Any = None, first_slip_ml: float = 200.0) -> list[DropBounds]:
    """Claim 4's bounds for every paper bottle of ``plant`` (default: the built-in bottles).

    Examples
    --------
    >>> [round(b.energy_n, 2) for b in drop_bounds()]
    [2.16, 2.16, 2.16]
    """
    from ...sim import BOTTLES, PAPER_DROP, PAPER_POUR  # deferred: heavy (numba kernels)

    bottles = BOTTLES if plant is None else plant.bottles
    out = []
    for name in BOTTLE_ORDER:
        b = bottles[name]
        h = PAPER_DROP.height_m + b.height_m
        args = (b.mass_kg, PAPER_DROP.mass_kg, h, b.grip_travel_m)
        out.append(DropBounds(name, h, first_slip_capacity_n(b.mass_kg, first_slip_ml, rate_l_min=PAPER_POUR.rate_l_min,
                                                             fall_height_m=PAPER_POUR.fall_height_m),
                              drop_slipout_capacity_n(*args), drop_momentum_capacity_n(*args, b.mu_s / b.mu_k),
                              drop_momentum_capacity_n(*args, STATIC_OVER_KINETIC_MAX), b.mu_s / b.mu_k))
    return out


