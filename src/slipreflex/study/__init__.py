"""``slipreflex study``: which of the paper's claims hold across every plausible plant.

A study draws N plants from the uncertain constants
(:mod:`slipreflex.sim.uncertain`) with a space-filling design
(:mod:`~slipreflex.study.design`), runs the reproduce grid on each, on Dask or
in this process (:mod:`~slipreflex.study.runner`), and maps where each claim
of the paper holds and which constants decide it
(:mod:`~slipreflex.study.analyse`).

Examples
--------
>>> from slipreflex.study import StudyConfig
>>> StudyConfig(plants=4, design="lhs").plants
4
"""

from .design import DESIGNS, draw_design, unit_design, varying
from .runner import (
                     DEFAULT_PLANTS,
                     DEFAULT_TRIALS,
                     PlantOutcome,
                     StudyConfig,
                     StudyRun,
                     read_parts,
                     run_plant,
                     run_study,
)

__all__ = ["DESIGNS", "draw_design", "unit_design", "varying", "DEFAULT_PLANTS", "DEFAULT_TRIALS",
           "PlantOutcome", "StudyConfig", "StudyRun", "read_parts", "run_plant", "run_study"]
