"""The simulated rig (:class:`slipreflex.sim.Rig`) as a rig for the virtual devices.

:class:`SimRig` grasps the bottle with the simulator's tripod routine (close
until the index and thumb tactile arrays read 0.8 N), then maps the virtual
devices' wall-clock time onto rig time and the perturbation names "drop" and
"pour" onto the paper's drop (10 g from 2 cm) and pour (500 ml at 1 L/min).

Examples
--------
>>> rig = SimRig("TR", seed=1)
>>> p0 = rig.grasp().position
>>> 0 < p0 < 500
True
>>> samples = rig.advance_to(0.03)
>>> len(samples), samples[0].seq > 0
(10, True)
"""

from __future__ import annotations

from typing import Any

from .. import experiment_specs
from ..errors import ParameterError
from ..interfaces import DaqSample, GraspResult

__all__ = ["SimRig"]


class SimRig:
    """Adapter of :class:`slipreflex.sim.Rig` to :class:`~slipreflex.devices.virtual.VirtualDevices`.

    Parameters
    ----------
    bottle : str or Bottle
        Bottle name ("TX", "TR", "DK") or object.
    seed : int
        Simulation seed.
    drop, pour : Drop, Pour, optional
        What "drop" and "pour" mean (default: the paper's).

    Examples
    --------
    >>> SimRig("DK").rig.bottle.name
    'DK'
    """

    def __init__(self, bottle: Any = "TR", seed: int = 0, *, drop: Any = None, pour: Any = None) -> None:
        from ..sim import PAPER_DROP, PAPER_POUR, Rig

        self.rig = Rig(bottle, seed=seed)
        self.drop = drop if drop is not None else PAPER_DROP
        self.pour = pour if pour is not None else PAPER_POUR
        self._t0: float | None = None

    @property
    def hand(self) -> Any:
        """The simulated i-Limb (a :class:`~slipreflex.interfaces.Hand` with ``command``)."""
        return self.rig.hand

    def grasp(self, force: float | None = None) -> GraspResult:
        """Grasp the bottle (the simulator's tripod routine, 0.8 N contact or ``force``) and let it settle.

        Returns
        -------
        GraspResult

        Examples
        --------
        >>> SimRig("TX").grasp().stable
        True
        """
        return self.rig.grasp() if force is None else self.rig.grasp(force)

    def advance_to(self, t: float) -> list[DaqSample]:
        """Advance to ``t`` seconds after the first call; return the new samples.

        Examples
        --------
        >>> r = SimRig("TR"); len(r.advance_to(0.0)), len(r.advance_to(0.1))
        (0, 34)
        """
        if self._t0 is None:
            self._t0 = self.rig.t
        return self.rig.advance_to(self._t0 + t)

    def perturb(self, kind: str) -> None:
        """Start a registered experiment's perturbation ("drop", "pour") now.

        Examples
        --------
        >>> r = SimRig("TR"); r.perturb("pour"); len(r.rig.perturbations)
        1
        """
        try:
            exp = experiment_specs.get(kind)
        except ParameterError:
            raise ParameterError(f"unknown perturbation {kind!r} (known: {', '.join(experiment_specs.names())})") \
                from None
        self.rig.perturb(exp.perturbation(self), at=self.rig.t)   # reads this rig's drop and pour

    def status(self) -> str:
        """One line of truth: displacement, slip, fallen, load.

        Examples
        --------
        >>> SimRig("TR").status().startswith("bottle")
        True
        """
        r = self.rig
        return (f"bottle {r.bottle.name}: displaced {r.displacement * 1e3:.2f} mm, slid "
                f"{r.slip * 1e3:.2f} mm, load {r.load_mass * 1e3:.1f} g, "
                f"{'FALLEN' if r.fallen else 'held'} at t={r.t:.2f} s")
