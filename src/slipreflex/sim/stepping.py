"""How a rig steps (adaptive or fixed, :data:`STEPPINGS`) and how it turns a seed into a SeedSequence."""

from __future__ import annotations

import os

import numpy as np

from ..core.errors import ParameterError

__all__ = ["STEP_ROUND", "STEPPINGS", "STEPPING_ENV", "COARSE_STEP_S", "default_stepping", "stepping",
           "seed_sequence"]

#: The rounding guard of a time turned into a step count (``ceil(t / dt - STEP_ROUND)``): a time a hair
#: past a step boundary from floating-point error stays on it.
STEP_ROUND: float = 1e-9

#: How the kernel steps: ``"adaptive"`` takes one coarse step of up to :data:`COARSE_STEP_S` while nothing
#: needs the fine step (every contact sticking with a margin, the cuff at most creeping, no finger moving,
#: no pad ringing, nothing in flight), ending where the next sample is due; ``"fixed"`` takes every
#: ``PhysicsParams.dt``, the reference (docs/simulator.md, "Time step").
STEPPINGS: tuple[str, ...] = ("adaptive", "fixed")
#: The environment variable that sets the stepping of rigs made without ``stepping=`` (worker processes
#: inherit it: ``SLIPREFLEX_STEPPING=fixed slipreflex reproduce`` runs the reference kernel).
STEPPING_ENV: str = "SLIPREFLEX_STEPPING"
#: Longest coarse step (s), the DAQ's period; a rig's own bound is shorter: the stiffest mode a calm rig
#: rings in (the bottle on its contacts' shear stiffness along the axis or sideways, the tilt on the pads)
#: stays at omega h <= 1, inside the semi-implicit Euler's stability bound (2), with its frequency off by
#: under (omega h)^2 / 24 = 4 % (:meth:`Rig.coarse_steps`).
COARSE_STEP_S: float = 3e-3


def default_stepping() -> str:
    """The stepping of a rig made without ``stepping=``: :data:`STEPPING_ENV`, or ``"adaptive"``.

    Examples
    --------
    >>> default_stepping() in STEPPINGS
    True
    """
    kind = os.environ.get(STEPPING_ENV, "adaptive") or "adaptive"
    if kind not in STEPPINGS:
        raise ParameterError(f"{STEPPING_ENV}={kind!r}: unknown stepping (known: {', '.join(STEPPINGS)})")
    return kind


class stepping:  # noqa: N801 - a context manager used like a function
    """Make rigs (in this process and in worker processes started inside) step as ``kind``.

    Sets :data:`STEPPING_ENV` for the block and restores it after.

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> with stepping("fixed"):
    ...     Rig("TR").stepping
    'fixed'
    """

    def __init__(self, kind: str) -> None:
        if kind not in STEPPINGS:
            raise ParameterError(f"stepping: unknown {kind!r} (known: {', '.join(STEPPINGS)})")
        self.kind = kind
        self._old: str | None = None

    def __enter__(self) -> stepping:
        self._old = os.environ.get(STEPPING_ENV)
        os.environ[STEPPING_ENV] = self.kind
        return self

    def __exit__(self, *exc: object) -> None:
        if self._old is None:
            os.environ.pop(STEPPING_ENV, None)
        else:
            os.environ[STEPPING_ENV] = self._old


def seed_sequence(seed: int | np.random.SeedSequence | np.random.Generator | None) -> np.random.SeedSequence:
    """Turn a seed, SeedSequence or Generator into a SeedSequence.

    Parameters
    ----------
    seed : int, SeedSequence, Generator or None
        None means 0 (the rig is deterministic by default).

    Returns
    -------
    numpy.random.SeedSequence

    Examples
    --------
    >>> seed_sequence(3).entropy
    3
    """
    if seed is None:
        return np.random.SeedSequence(0)
    if isinstance(seed, np.random.SeedSequence):
        return seed
    if isinstance(seed, np.random.Generator):
        return np.random.SeedSequence([int(v) for v in seed.integers(0, 2**63, size=4)])
    if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool) and seed >= 0:
        return np.random.SeedSequence(int(seed))
    raise ParameterError(f"seed must be a non-negative int, a SeedSequence or a Generator, got {seed!r}")
