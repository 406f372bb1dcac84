"""The simulated rig: grasp physics with stick-slip, the i-Limb hand and the paper's sensors.

Stands in for the paper's hardware (docs/method.md sections 3 and 4) so the
whole system runs without it, deterministically under a seed.

Public API
----------
Data (frozen, validated; see :mod:`slipreflex.sim.objects`):
    :class:`Bottle`, :class:`Surface`, :class:`Drop`, :class:`Pour`,
    :data:`BOTTLES` ("TR", "DK", "TX"), :data:`SURFACES` (incl. "white",
    "black"), :data:`PAPER_DROP`, :data:`PAPER_POUR`, :func:`load_objects`.
Parameters (see :mod:`slipreflex.sim.params`):
    :class:`HandParams`, :class:`SlipSensorParams`, :class:`ImuParams`,
    :class:`TactileParams`, :class:`FlowParams`, :class:`PhysicsParams`,
    :class:`WaterParams` (the pour's splash and slosh).
The rig (see :mod:`slipreflex.sim.rig`):
    :class:`Rig` (``advance``/``advance_to``/``advance_block``, ``hand``,
    ``grasp``, ``perturb``, ``tactile_sampler``, truth accessors),
    :class:`SimHand`, :class:`TactileSampler`, :class:`DaqBlock`,
    :class:`GraspResult`, :class:`SlipEvent`.
Runs (see :mod:`slipreflex.sim.loop`):
    :func:`run_closed_loop`, :func:`simulate_open_loop`, :class:`SimTrace`.
Characterization (see :mod:`slipreflex.sim.scan`):
    :func:`scan`, :class:`ScanResult`.
Uncertain constants (see :mod:`slipreflex.sim.uncertain`):
    :data:`UNCERTAIN`, :class:`UncertainConstant`, :class:`Plant`,
    :func:`plant_from_values`, :func:`load_ranges`.

Examples
--------
>>> from slipreflex.sim import Rig, Drop, simulate_open_loop
>>> rig = Rig("TR", seed=1)
>>> _ = rig.grasp()
>>> rig.perturb(Drop(), at=rig.t + 0.2)
>>> tr = simulate_open_loop(rig, 1.0)
>>> len(tr.onsets) > 0
True
"""

from .loop import TRACE_COLUMNS, SimTrace, run_closed_loop, simulate_open_loop
from .objects import BOTTLES, PAPER_DROP, PAPER_POUR, SURFACES, Bottle, Drop, Objects, Pour, Surface, load_objects
from .params import FlowParams, HandParams, ImuParams, PhysicsParams, SlipSensorParams, TactileParams, WaterParams
from .rig import DaqBlock, GraspResult, Rig, SimHand, SlipEvent, TactileSampler
from .scan import ScanResult, scan
from .uncertain import UNCERTAIN, Plant, UncertainConstant, load_ranges, plant_from_values

__all__ = [
    "Bottle", "Surface", "Drop", "Pour", "Objects", "BOTTLES", "SURFACES", "PAPER_DROP", "PAPER_POUR",
    "load_objects", "HandParams", "SlipSensorParams", "ImuParams", "TactileParams", "FlowParams",
    "PhysicsParams", "WaterParams", "Rig", "SimHand", "TactileSampler", "DaqBlock", "GraspResult", "SlipEvent",
    "SimTrace", "TRACE_COLUMNS", "run_closed_loop", "simulate_open_loop", "ScanResult", "scan",
    "UNCERTAIN", "UncertainConstant", "Plant", "plant_from_values", "load_ranges",
]
