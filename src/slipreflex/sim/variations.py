"""What differs physically between repeats of one trial, drawn from the trial's seed.

On the real rig, ten repeats of "drop, TR, DATH" are not ten copies: the
arm places the hand a little differently around the bottle (so the fingers
meet it, and the grasp stops, at another position; the slip sensor looks at
another stretch of the surface; the fingertips hold it a little higher or
lower), and the friction of the pads on the bottle scatters from repeat to
repeat (skin oils, dust, humidity, wear). :func:`draw_variation` draws these
from the trial's seed; :func:`trial_rig` builds the rig of one trial with
them, so a cell's standard deviation reflects repeat-to-repeat physics and
not only sensor noise.

The spreads are estimates (docs/simulator.md):

* placement of the bottle in the hand: sd 1 mm radially (a UR10 repeats to
  0.1 mm, the bottle is placed on its stand by hand), which moves the contact
  by about 5 position units;
* grip height: sd 3 mm along the bottle (how far the fingertips sit below
  the shoulder, so how far the bottle can slide before it is lost);
* friction: sd 5 % of every coefficient of the pads and, independently, of
  the cuff (rubber friction on polymers scatters by 5-10 % between repeats on
  one surface; Persson 2006 and fingertip studies);
* the spot's stretch of texture: the surface texture is drawn from the seed
  already (:class:`~slipreflex.sim.Rig`).

Examples
--------
>>> from slipreflex.sim.variations import draw_variation, trial_rig
>>> v = draw_variation(7)
>>> v == draw_variation(7), v == draw_variation(8)
(True, False)
>>> trial_rig("TR", 7).bottle.mu_s != trial_rig("TR", 8).bottle.mu_s
True
"""

from __future__ import annotations

import copy
import pickle
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..core.errors import ParameterError
from .objects import BOTTLES, Bottle
from .params import HandParams
from .rig import Rig, default_stepping

__all__ = ["TrialVariation", "VariationSpread", "draw_variation", "apply_variation", "trial_rig", "grasped_rig"]


@dataclass(frozen=True, slots=True)
class VariationSpread:
    """Standard deviations of the repeat-to-repeat variations (see the module notes).

    Examples
    --------
    >>> VariationSpread().friction_rel
    0.05
    >>> VariationSpread.none().placement_m
    0.0
    """

    placement_m: float = 1e-3
    grip_height_m: float = 3e-3
    friction_rel: float = 0.05

    def __post_init__(self) -> None:
        for f in ("placement_m", "grip_height_m", "friction_rel"):
            v = getattr(self, f)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v) or v < 0:
                raise ParameterError(f"VariationSpread.{f} must be a finite number >= 0, got {v!r}")

    @classmethod
    def none(cls) -> VariationSpread:
        """No variation: every repeat is the same plant.

        Examples
        --------
        >>> VariationSpread.none().friction_rel
        0.0
        """
        return cls(0.0, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class TrialVariation:
    """One trial's draw: offsets and factors applied to the nominal plant.

    Attributes
    ----------
    placement_m : float
        Radial offset of the bottle's surface toward the fingertips (m):
        positive means the fingers meet it earlier.
    grip_height_m : float
        Change of the grip travel before the bottle is lost (m).
    pad_friction, cuff_friction : float
        Factors on the pads' and the cuff's friction coefficients.

    Examples
    --------
    >>> TrialVariation(0.0, 0.0, 1.0, 1.0).pad_friction
    1.0
    """

    placement_m: float
    grip_height_m: float
    pad_friction: float
    cuff_friction: float


def draw_variation(seed: int, spread: VariationSpread | None = None) -> TrialVariation:
    """Draw one trial's variation from its seed (independent of the rig's noise streams).

    Examples
    --------
    >>> draw_variation(3, VariationSpread.none())
    TrialVariation(placement_m=0.0, grip_height_m=0.0, pad_friction=1.0, cuff_friction=1.0)
    """
    spread = spread or VariationSpread()
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParameterError(f"seed must be a non-negative int, got {seed!r}")
    # a stream of its own: the rig spawns its streams from SeedSequence(seed), this one from (seed, 1)
    z = np.random.default_rng(np.random.SeedSequence([int(seed), 1])).standard_normal(4)
    clip = np.clip(z, -3.0, 3.0)          # no repeat is absurdly far from the nominal plant
    # "+ 0.0" turns a zero spread's -0.0 into 0.0
    return TrialVariation(placement_m=float(spread.placement_m * clip[0]) + 0.0,
                          grip_height_m=float(spread.grip_height_m * clip[1]) + 0.0,
                          pad_friction=float(1.0 + spread.friction_rel * clip[2]),
                          cuff_friction=float(1.0 + spread.friction_rel * clip[3]))


def apply_variation(bottle: Bottle, hand: HandParams, v: TrialVariation) -> tuple[Bottle, HandParams]:
    """The bottle and hand of one repeat.

    Examples
    --------
    >>> b, h = apply_variation(BOTTLES["TR"], HandParams(), TrialVariation(1e-3, 0.0, 1.1, 1.0))
    >>> round(b.mu_s / BOTTLES["TR"].mu_s, 6), round(h.aperture_radius_m, 4)
    (1.1, 0.059)
    """
    b = replace(bottle, mu_s=bottle.mu_s * v.pad_friction, mu_k=bottle.mu_k * v.pad_friction,
                cuff_mu_s=bottle.cuff_mu_s * v.cuff_friction, cuff_mu_k=bottle.cuff_mu_k * v.cuff_friction,
                grip_travel_m=max(bottle.grip_travel_m + v.grip_height_m, 0.005))
    h = replace(hand, aperture_radius_m=hand.aperture_radius_m - v.placement_m)
    return b, h


def trial_rig(bottle: str | Bottle, seed: int, *, spread: VariationSpread | None = None,
              rig_kwargs: dict[str, Any] | None = None, bottles: dict[str, Bottle] | None = None, **kwargs: Any):
    """The :class:`~slipreflex.sim.Rig` of one trial: the plant with the variation drawn from ``seed``.

    Parameters
    ----------
    bottle : str or Bottle
        A bottle or a name of ``bottles`` (default :data:`~slipreflex.sim.BOTTLES`).
    seed : int
        The trial's seed (the rig's noise and texture, and the variation).
    spread : VariationSpread, optional
        ``VariationSpread.none()`` gives the nominal plant.
    rig_kwargs : dict, optional
        Parameter objects of the plant (``Plant.rig_kwargs()``).

    Examples
    --------
    >>> trial_rig("DK", 3, spread=VariationSpread.none()).bottle == BOTTLES["DK"]
    True
    """

    table = bottles if bottles is not None else BOTTLES
    if isinstance(bottle, str):
        if bottle not in table:
            raise ParameterError(f"bottle: unknown bottle {bottle!r} (known: {', '.join(table)})")
        bottle = table[bottle]
    kw = dict(rig_kwargs or {})
    hand = kw.pop("hand", None) or HandParams()
    b, h = apply_variation(bottle, hand, draw_variation(seed, spread))
    return Rig(b, seed=seed, hand=h, **kw, **kwargs)


#: The grasped rigs this process made last, by everything that decides them. A trial's rig
#: and grasp depend on its bottle, seed and plant, not on the method that then runs, so the
#: methods of a paired trial start from copies of one grasp.
_GRASPED: dict[bytes, tuple] = {}
_GRASPED_KEEP = 8


def grasped_rig(bottle: str | Bottle, seed: int, force: float, *, spread: VariationSpread | None = None,
                rig_kwargs: dict[str, Any] | None = None, bottles: dict[str, Bottle] | None = None):
    """:func:`trial_rig` after ``Rig.grasp(force)``, and the grasp's result: a fresh copy each call.

    The process keeps the last few grasped rigs and returns deep copies of them: a copy
    runs exactly as the rig it copies (same state, same random streams), and costs well
    under a millisecond where a grasp costs about ten.

    Examples
    --------
    >>> a, ga = grasped_rig("TR", 5, 0.8)
    >>> b, gb = grasped_rig("TR", 5, 0.8)
    >>> a is not b, a.t == b.t, ga == gb
    (True, True, True)
    """
    # the stepping is part of the key: a rig grasped by the other kernel is another rig
    key = pickle.dumps((bottle, seed, force, spread, rig_kwargs, bottles, default_stepping()))
    if key not in _GRASPED:
        rig = trial_rig(bottle, seed, spread=spread, rig_kwargs=rig_kwargs, bottles=bottles)
        grasp = rig.grasp(force)
        while len(_GRASPED) >= _GRASPED_KEEP:
            _GRASPED.pop(next(iter(_GRASPED)))
        _GRASPED[key] = (rig, grasp)
    return copy.deepcopy(_GRASPED[key])
