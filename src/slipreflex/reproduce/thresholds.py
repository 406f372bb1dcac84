"""Thresholds of the calibrated methods on the simulated rig (docs/method.md section 2).

The comparison methods' thresholds come from one rule
(:func:`slipreflex.methods.baselines.rest_threshold`, k standard deviations of the
method's statistic at rest). Here the rule meets the simulated rig: for every
built-in bottle, a calibration recording of the grasped bottle at rest, with a
seed from its own branch of the run's master seed, at the rate of every method
that has a rest statistic (:func:`slipreflex.methods.calibrated`); one
threshold per method, the same for every bottle and trial.

Examples
--------
>>> calibration_seed(1, "TR") != calibration_seed(1, "DK")
True
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import methods
from ..analysis.paper import BOTTLE_ORDER, EXPERIMENTS
from ..core.errors import ParameterError
from ..methods.baselines import rest_statistic

__all__ = ["calibration_seed", "calibrate"]


def calibration_seed(master: int, bottle: str) -> int:
    """Seed of the at-rest calibration recording of ``bottle`` (its own branch of the master).

    ``SeedSequence(master).spawn(len(EXPERIMENTS) + 1)[-1]``: the branch after
    the experiments' (:func:`slipreflex.reproduce.experiments.trial_seed`), one child per bottle.

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import trial_seed
    >>> calibration_seed(1, "TR") != trial_seed(1, "drop", "TR", 0)
    True
    """
    ss = np.random.SeedSequence(master).spawn(len(EXPERIMENTS) + 1)[len(EXPERIMENTS)]
    child = ss.spawn(len(BOTTLE_ORDER))[BOTTLE_ORDER.index(bottle)]
    return int(child.generate_state(2, dtype=np.uint64)[0] >> np.uint64(1))


def calibrate(config: Any) -> dict[str, float]:
    """Thresholds of the calibrated methods by the one rule (k sd of the statistic at rest).

    For every built-in bottle (always all three, whatever ``config.bottles``
    says), grasp with the bottle's calibration seed and record the index
    tactile array at rest for ``calibration_s`` at the rate of every method
    with a rest statistic (:func:`slipreflex.methods.calibrated`, in the
    method order: NMSD's 260 Hz, then SWT-SD's 380 Hz); pool the recordings of
    each method and apply :func:`slipreflex.methods.baselines.rest_threshold`'s rule.

    Returns
    -------
    dict
        Threshold by method name, e.g. ``{"nmsd": N/s, "swt": N}``.

    ``config`` is a :class:`slipreflex.reproduce.experiments.ReproduceConfig` (its
    ``seed``, ``calibration_s``, ``rest_k`` and ``plant`` are used).

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> th = calibrate(ReproduceConfig(calibration_s=0.5))
    >>> sorted(th), th["nmsd"] > 0 and th["swt"] > 0
    (['nmsd', 'swt'], True)
    """
    from ..sim import Rig, simulate_open_loop  # deferred: heavy (numba kernels)

    specs = [methods.get(m) for m in methods.calibrated()]
    stats: dict[str, list[np.ndarray]] = {s.name: [] for s in specs}
    for b in BOTTLE_ORDER:
        plant = getattr(config, "plant", None)
        seed = calibration_seed(config.seed, b)
        rig = Rig(b, seed=seed) if plant is None else plant.rig(b, seed=seed)
        rig.grasp(config.grasp_force_n)
        for spec in specs:
            tr = simulate_open_loop(rig, config.calibration_s, tactile_fs=spec.fs)
            stats[spec.name].append(rest_statistic(tr.tactile, spec.rest_statistic, spec.fs))
    out = {}
    for method, parts in stats.items():
        sd = float(np.std(np.concatenate(parts)))
        if not sd > 0:
            raise ParameterError(f"calibration: the simulated tactile array has no noise at rest; "
                                 f"cannot derive a {method} threshold")
        out[method] = float(config.rest_k) * sd
    return out
