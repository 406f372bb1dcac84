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

from dataclasses import dataclass, field
from typing import Any

from ..errors import ParameterError
from ..hardware import SLIP_FINGER, TRIPOD, Finger
from ..interfaces import DaqSample

__all__ = ["SimRig", "SimGrasp"]


@dataclass(frozen=True, slots=True)
class SimGrasp:
    """Outcome of :meth:`SimRig.grasp`.

    Attributes
    ----------
    position : float
        Measured middle-finger position after the grasp: the reflex's ``p0``.
    force : float
        Normal force per contact (N) after settling.
    stable : bool
        Whether the bottle hangs still in the fingers.
    t : float
        Rig time (s) when the grasp routine finished.
    positions : dict of Finger to float
        Measured position of every tripod finger after the grasp: the
        per-finger ``p0`` that ``slipreflex run --p0`` takes (the thumb often
        stops at another position than the index and middle).

    Examples
    --------
    >>> SimGrasp(position=212.0, force=0.8, stable=True, t=2.5).position
    212.0
    """

    position: float
    force: float
    stable: bool
    t: float
    positions: dict = field(default_factory=dict)

    def p0_text(self) -> str:
        """The positions as ``run --p0`` takes them: ``thumb=149,index=147,middle=147``.

        Examples
        --------
        >>> SimGrasp(147.0, 0.8, True, 2.5, {Finger.THUMB: 149.0, Finger.MIDDLE: 147.0}).p0_text()
        'thumb=149,middle=147'
        """
        return ",".join(f"{f.name.lower()}={v:g}" for f, v in self.positions.items())


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

    def grasp(self, force: float | None = None) -> SimGrasp:
        """Grasp the bottle (the simulator's tripod routine, 0.8 N contact or ``force``) and let it settle.

        Returns
        -------
        SimGrasp

        Examples
        --------
        >>> SimRig("TX").grasp().stable
        True
        """
        g = self.rig.grasp() if force is None else self.rig.grasp(force)
        return SimGrasp(position=float(g.positions[SLIP_FINGER]), force=float(g.force_n),
                        stable=bool(g.stable), t=self.rig.t,
                        positions={f: float(g.positions[f]) for f in TRIPOD})

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
        """Start the paper's "drop" or "pour" now.

        Examples
        --------
        >>> r = SimRig("TR"); r.perturb("pour"); len(r.rig.perturbations)
        1
        """
        if kind == "drop":
            self.rig.perturb(self.drop, at=self.rig.t)
        elif kind == "pour":
            self.rig.perturb(self.pour, at=self.rig.t)
        else:
            raise ParameterError(f"unknown perturbation {kind!r}: drop or pour")

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
