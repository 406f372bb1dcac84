"""A grasp force that holds: checked on a run's own trial grasps before a force is suggested.

``config`` below is a :class:`slipreflex.reproduce.experiments.ReproduceConfig` (its bottles, plant,
variations, rest and grasp force); ``seeds`` the run's trial seeds of one bottle
(:func:`slipreflex.reproduce.experiments.grasp_seeds`).

Examples
--------
>>> GRASP_MARGIN > 1
True
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["GRASP_MARGIN", "GRASP_CHECK_TRIALS", "grasp_holds", "verified_grasp_force", "check_run_grasp"]

#: The force a failed grasp check suggests is the weakest that held every checked trial grasp
#: of the run, times this margin (an estimate: trial-to-trial variation of placement and
#: friction beyond the checked seeds; 1.2 is the margin above which no trial of the jar
#: example fell in 40 grasps, tests/journeys/test_first_day.py).
GRASP_MARGIN: float = 1.2
#: At most this many of a run's trial grasps are simulated to verify a suggested force.
GRASP_CHECK_TRIALS: int = 20


def grasp_holds(config: Any, bottle: str, force: float, seeds) -> list[bool]:
    """Per trial seed: whether a ``force`` grasp of ``bottle`` holds it through the rest before the load.

    The run's own trial grasp (its variations included), then ``config.rest_s`` of rest:
    what a trial does before its perturbation.

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig, grasp_seeds
    >>> cfg = ReproduceConfig(trials=1, bottles=("TR",))
    >>> grasp_holds(cfg, "TR", 0.8, grasp_seeds(cfg, "TR")[:1])
    [True]
    """
    from ..sim.variations import VariationSpread, grasped_rig  # deferred: heavy (numba kernels)

    plant = {} if config.plant is None else {"rig_kwargs": config.plant.rig_kwargs(),
                                             "bottles": dict(config.plant.bottles)}
    held = []
    for seed in seeds:
        rig, _ = grasped_rig(bottle, seed, force, spread=None if config.variations else VariationSpread.none(),
                             **plant)
        rig.advance(config.rest_s)
        held.append(not rig.fallen)
    return held


def verified_grasp_force(config: Any, bottle: str, seeds) -> tuple[float, float, int]:
    """A grasp force for ``bottle`` verified on the run's trial grasps: (suggested, weakest, grasps).

    ``weakest`` is the weakest force (steps of 10 % from the run's) that held every one of
    ``seeds`` (the run's first :data:`GRASP_CHECK_TRIALS` trial grasps) through the rest; the
    suggestion is ``weakest`` times :data:`GRASP_MARGIN`, rounded up to 0.1 N, and
    simulated again on the same grasps before it is returned (raised further if any fell).

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig, grasp_seeds
    >>> cfg = ReproduceConfig(trials=2, bottles=("TR",), grasp_force_n=0.8)
    >>> force, weakest, n = verified_grasp_force(cfg, "TR", grasp_seeds(cfg, "TR"))
    >>> force >= weakest * GRASP_MARGIN, n
    (True, 4)
    """
    seeds = list(seeds)[:GRASP_CHECK_TRIALS]
    weakest = config.grasp_force_n
    for _ in range(40):
        if all(grasp_holds(config, bottle, weakest, seeds)):
            break
        weakest *= 1.1
    force = math.ceil(weakest * GRASP_MARGIN * 10.0 - 1e-9) / 10.0
    while not all(grasp_holds(config, bottle, force, seeds)):
        force = math.ceil(force * 11.0 - 1e-9) / 10.0
    return force, weakest, len(seeds)


def check_run_grasp(config: Any, bottle: str, seeds) -> None:
    """Refuse a run whose grasp cannot hold ``bottle``, suggesting a force verified on its trials.

    :func:`slipreflex.sim.calibration.check_grasp` decides (one nominal grasp); when it
    refuses, the force the message suggests comes from :func:`verified_grasp_force`: it
    held every checked trial grasp of this run (``seeds``) through the rest, with a margin.

    Raises
    ------
    slipreflex.sim.calibration.GraspFailed

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> check_run_grasp(ReproduceConfig(trials=1, bottles=("TR",)), "TR", [1])
    """
    from ..sim.calibration import GraspFailed, check_grasp  # deferred: heavy (numba kernels)

    try:
        check_grasp(config.bottle(bottle), config.grasp_force_n)
    except GraspFailed as err:
        text = str(err)
        reason = text.split(": use ", 1)[0] if ": use " in text else text
        force, weakest, n = verified_grasp_force(config, bottle, seeds)
        raise GraspFailed(
            f"{reason}: use --grasp-force {force:.1f} (simulated before this message: it held the bottle "
            f"through the grasp and the {config.rest_s:g} s rest in {n} of {n} of this run's trial grasps, "
            f"variations included; {weakest:.2f} N was the weakest that held them all, plus "
            f"{100 * (GRASP_MARGIN - 1):.0f} % margin), or pads that grip better") from None
