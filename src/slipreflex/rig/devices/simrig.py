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

from ...core import experiment_specs
from ...core.errors import ParameterError
from ...core.hardware import TRIPOD
from ...core.interfaces import DaqSample, GraspResult
from ...files.recording import FINGER_FIELDS

__all__ = ["SimRig"]


class SimRig:
    """Adapter of :class:`slipreflex.sim.Rig` to :class:`~slipreflex.rig.devices.virtual.VirtualDevices`.

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
        from ...sim import PAPER_DROP, PAPER_POUR, Rig  # deferred: heavy (numba kernels)

        self.rig = Rig(bottle, seed=seed)
        self.drop = drop if drop is not None else PAPER_DROP
        self.pour = pour if pour is not None else PAPER_POUR
        self._t0: float | None = None

    @property
    def hand(self) -> Any:
        """The simulated i-Limb (a :class:`~slipreflex.core.interfaces.Hand` with ``command``)."""
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

    def tactile(self, finger: Any) -> Any:
        """One ``(4, 4)`` tactile frame (N) of a tripod finger now (the virtual Ability Hand's touch).

        Examples
        --------
        >>> from slipreflex.core.hardware import Finger
        >>> r = SimRig("TR"); _ = r.grasp(); float(r.tactile(Finger.INDEX).sum()) > 0.5
        True
        """
        return self.rig.tactile(finger)

    def truth(self) -> dict[str, Any]:
        """The rig's truth now, as a ``/rig/truth`` message (:data:`slipreflex.files.recording.TOPICS`).

        Examples
        --------
        >>> r = SimRig("TR"); _ = r.grasp(); m = r.truth()
        >>> m["fallen"], m["middle"] > 0, m["ring"] is None
        (False, True, True)
        """

        r = self.rig
        pos = r.hand.positions()
        fingers = {f.name.lower(): float(v) for f, v in pos.items() if f in TRIPOD}
        return {"t": r.t, "displacement": r.displacement, "slip": r.slip, "velocity": r.velocity,
                "normal_force": r.normal_force, "load_mass": r.load_mass, "slipping": bool(r.slipping),
                "fallen": bool(r.fallen), **{f: fingers.get(f) for f in FINGER_FIELDS}}

    def status(self) -> str:
        """One line of truth: displacement, slip, load, and held or when it fell.

        Times are on this rig's clock (seconds since the first :meth:`advance_to`, the
        virtual rig's); after a fall the displacement and the slide are capped at the
        grip's fall-out travel (the free fall after it is no slide).

        Examples
        --------
        >>> SimRig("TR").status().startswith("bottle")
        True
        """
        r = self.rig
        t0 = r.t if self._t0 is None else self._t0
        fell = r.fall_time
        cap = r.bottle.grip_travel_m if fell is not None else float("inf")
        where = (f"FALLEN at t={fell - t0:.2f} s (slid out of the grip's "
                 f"{r.bottle.grip_travel_m * 1e3:g} mm travel; stopped at t={r.t - t0:.2f} s)" if fell is not None
                 else f"held at t={r.t - t0:.2f} s")
        return (f"bottle {r.bottle.name}: displaced {min(r.displacement, cap) * 1e3:.2f} mm, slid "
                f"{min(r.slip, cap) * 1e3:.2f} mm, load {r.load_mass * 1e3:.1f} g, {where}")
