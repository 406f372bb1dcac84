"""The paper's two experiments as the registry runs them (:mod:`slipreflex.core.experiment_specs` names these).

The sudden load (``drop``): a 10 g mass dropped from 2 cm into the bottle; one slip onset.
The gradual load (``pour``): 500 ml at 1 L/min; slips are looked for once the water has
landed, over the whole pour (docs/method.md). Both follow the run's overrides
(``--drop-mass``, ``--pour-volume``, ``--objects``) through :class:`ReproduceConfig`.

Examples
--------
>>> from slipreflex.reproduce.experiments import ReproduceConfig
>>> describe_drop(drop_perturbation(ReproduceConfig(drop_mass_kg=0.02)))
'20 g from 2 cm'
>>> round(pour_load_s(pour_perturbation(ReproduceConfig())), 1)
30.0
"""

from __future__ import annotations

import math
from typing import Any

from ..core import hardware as hw

__all__ = ["drop_perturbation", "pour_perturbation", "describe_drop", "describe_pour", "pour_load_s",
           "pour_settle_s", "paper_drop", "paper_pour", "LANDING_S"]

#: After the poured water lands, its knock (~30 ms in the simulator) is over by this time (s).
LANDING_S: float = 0.1


def drop_perturbation(config: Any) -> Any:
    """The run's sudden load, a :class:`slipreflex.sim.Drop` (``config.drop``).

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> drop_perturbation(ReproduceConfig(drop_height_m=0.05)).height_m
    0.05
    """
    return config.drop


def pour_perturbation(config: Any) -> Any:
    """The run's gradual load, a :class:`slipreflex.sim.Pour` (``config.pour``).

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> pour_perturbation(ReproduceConfig(pour_volume_ml=100)).volume_ml
    100
    """
    return config.pour


def describe_drop(drop: Any) -> str:
    """A drop in words.

    Examples
    --------
    >>> describe_drop(paper_drop())
    '10 g from 2 cm'
    """
    return f"{1e3 * drop.mass_kg:g} g from {1e2 * drop.height_m:g} cm"


def describe_pour(pour: Any) -> str:
    """A pour in words.

    Examples
    --------
    >>> describe_pour(paper_pour())
    '500 ml at 1 L/min'
    """
    return f"{pour.volume_ml:g} ml at {pour.rate_l_min:g} L/min"


def pour_load_s(pour: Any) -> float:
    """How long the water runs (s).

    Examples
    --------
    >>> pour_load_s(paper_pour())
    30.0
    """
    return pour.duration_s


def pour_settle_s(pour: Any) -> float:
    """When, after the tap opens, the water can first make the bottle slip: its fall from the
    spout, then :data:`LANDING_S` for the landing knock (which is not a slip).

    Examples
    --------
    >>> round(pour_settle_s(paper_pour()), 3) > LANDING_S
    True
    """
    return math.sqrt(2.0 * pour.fall_height_m / hw.GRAVITY) + LANDING_S


def paper_drop() -> Any:
    """The paper's drop (:data:`slipreflex.sim.PAPER_DROP`).

    Examples
    --------
    >>> paper_drop().mass_kg
    0.01
    """
    from ..sim import PAPER_DROP  # deferred: heavy (numba kernels)

    return PAPER_DROP


def paper_pour() -> Any:
    """The paper's pour (:data:`slipreflex.sim.PAPER_POUR`).

    Examples
    --------
    >>> paper_pour().volume_ml
    500.0
    """
    from ..sim import PAPER_POUR  # deferred: heavy (numba kernels)

    return PAPER_POUR
