"""A reproduction's run time: its estimate, and its numba kernels compiled once before the workers.

A first run on a machine (or after a kernel's source changed) compiles the kernels;
:func:`cold_kernels` tells, so the run-time estimate can say so, and
:func:`warm_kernels` compiles the closed loops once in the parent process, so forked
workers inherit them instead of each compiling its own.

Examples
--------
>>> len(KERNELS) > 0 and COLD_COMPILE_S > 0
True
"""

from __future__ import annotations

import dataclasses
import importlib
from typing import Any

from ..core.hardware import SLIP_FINGER

__all__ = ["COLD_COMPILE_S", "KERNELS", "cold_kernels", "warm_kernels", "TRIAL_SIM_SPEED", "STARTUP_S",
           "estimate_wall_s"]

#: Simulated seconds per wall second of one trial (simulation, reflex, analysis) on one
#: worker, for the run-time estimate printed before a reproduction starts.
#: ``python benchmarks/bench_reproduce.py --jobs 2`` prints it as simulated s per CPU s (798 at load
#: average 1.4, 514-562 at 2.9-3.8, default grid, compiled closed loop, an AMD EPYC core); 600
#: leaves a margin. A busy machine runs slower, and the progress lines say so.
TRIAL_SIM_SPEED: float = 600.0
#: Wall seconds before the first trial: imports, threshold calibration, worker start.
STARTUP_S: float = 3.0


def estimate_wall_s(config: Any, jobs: int, *, cold: bool = False) -> float:
    """A rough run time (s) of ``config`` on ``jobs`` workers, before it starts.

    From the simulated time of every trial and :data:`TRIAL_SIM_SPEED`, plus
    :data:`COLD_COMPILE_S` when the kernels must be compiled first (``cold``:
    ``bool(cold_kernels())``); the progress lines then measure the real pace. ``config`` is a
    :class:`slipreflex.reproduce.experiments.ReproduceConfig`.

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> small = ReproduceConfig(trials=1, bottles=("TR",), methods=("dath",))
    >>> estimate_wall_s(small, 1) < estimate_wall_s(ReproduceConfig(), 1)
    True
    >>> estimate_wall_s(small, 2, cold=True) > estimate_wall_s(small, 2) + 10
    True
    """
    per_trial = [config.duration(e) for e in config.experiments]
    sim_s = sum(per_trial) * config.trials * len(config.bottles) * len(config.methods)
    cells = config.trials * len(config.bottles) * len(config.methods) * len(config.experiments)
    return STARTUP_S + (COLD_COMPILE_S if cold else 0.0) + sim_s / (TRIAL_SIM_SPEED * max(1, min(jobs, cells)))


#: Wall seconds to compile every kernel of a reproduction when numba's disk cache is cold
#: (the first run on a machine, or after the kernels' source changed), compiled once in the
#: parent before the workers start. ``python benchmarks/bench_cold_compile.py`` (an empty
#: ``NUMBA_CACHE_DIR``): threshold calibration 55.1 s, the slip closed loop 14.7 s, the tactile one
#: 15.4 s, 85.2 s together at load average 0.7 on an AMD EPYC core (1.2 s with the cache it filled);
#: 90 leaves a margin. The physics kernel compiles its pieces inlined into one function, which is
#: most of the threshold calibration's share.
COLD_COMPILE_S: float = 90.0

#: The numba kernels a reproduction calls (module, function): their disk cache decides a
#: cold start (the helpers they inline are compiled into them and never cached alone).
KERNELS: tuple[tuple[str, str], ...] = (
    ("slipreflex.sim.kernel", "step_until"), ("slipreflex.sim.kernel", "tactile_frames"),
    ("slipreflex.sim.kernel", "normal"), ("slipreflex.sim.kernel", "normal_pair"),
    ("slipreflex.sim.kernel", "derive_key"), ("slipreflex.sim.closed", "_closed_slip"),
    ("slipreflex.sim.closed", "_closed_tactile"), ("slipreflex.methods.chain._kernels", "chain_step"),
    ("slipreflex.methods.baselines._kernels", "tactile_step"))


def cold_kernels() -> list[str]:
    """The kernels of :data:`KERNELS` that numba's disk cache cannot load yet, nor this process has.

    Not empty on a first run (or after their source changed): they will be compiled,
    which :data:`COLD_COMPILE_S` estimates.

    Examples
    --------
    >>> isinstance(cold_kernels(), list)
    True
    """

    cold = []
    for module, name in KERNELS:
        disp = getattr(importlib.import_module(module), name)
        if disp.signatures:
            continue
        try:
            warm = bool(disp._cache._cache_file._load_index())
        except Exception:           # noqa: BLE001 - no cache, or an unreadable index: cold
            warm = False
        if not warm:
            cold.append(f"{module.rsplit('.', 1)[-1]}.{name}")
    return cold




def warm_kernels(config: Any, context: Any, specs: dict[str, Any], seed: int) -> list[str]:
    """Compile the closed-loop kernels the run's methods need, once, in this process.

    Runs 20 ms of closed loop for one method of each input kind (slip sensor, tactile)
    on the run's first bottle (grasped with ``seed``), each reflex built with ``context``
    (a :class:`~slipreflex.methods.MethodContext`), so that worker processes forked
    afterwards inherit the compiled kernels (and a cold numba cache is filled once, not
    once per worker). ``config`` is a :class:`slipreflex.reproduce.experiments.ReproduceConfig`.
    Returns the methods it ran.

    Examples
    --------
    >>> from slipreflex import methods
    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> cfg = ReproduceConfig(trials=1, bottles=("TR",), methods=("dath",))
    >>> warm_kernels(cfg, methods.MethodContext(), {"dath": methods.get("dath")}, 1)
    ['dath']
    """
    from ..sim import run_closed_loop  # deferred: heavy (numba kernels)
    from ..sim.variations import VariationSpread, grasped_rig  # deferred: heavy (numba kernels)

    plant = {} if config.plant is None else {"rig_kwargs": config.plant.rig_kwargs(),
                                             "bottles": dict(config.plant.bottles)}
    ran, kinds = [], set()
    for name, spec in specs.items():
        if spec.input_kind in kinds:
            continue
        kinds.add(spec.input_kind)
        rig, grasp = grasped_rig(config.bottles[0], seed, config.grasp_force_n, spread=VariationSpread.none(),
                                 **plant)
        p0 = float(round(grasp.positions[SLIP_FINGER]))
        reflex = spec.build(p0, dataclasses.replace(context, method=spec.name))
        run_closed_loop(rig, reflex, 0.02)
        ran.append(name)
    return ran
