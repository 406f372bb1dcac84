"""The registry of load kinds: how :meth:`slipreflex.sim.Rig.perturb` applies each kind of load.

A load kind names the class of its perturbation objects (:class:`~slipreflex.sim.Drop`,
:class:`~slipreflex.sim.Pour`, or one of a plugin's), the kernel table its rows go to, and
the function that turns one object, released at a rig time, into one row of that table:

``"drops"``
    a mass released above the bottom (:data:`slipreflex.sim.kernel.DROP`): it falls, lands
    and rests on the bottom, off the axis by the bottle's eccentricity;
``"timed"``
    a load that acts for a while from a start (:data:`slipreflex.sim.kernel.POUR`): water
    flowing in, with its jet's push, and the grip's own acceleration along the bottle's axis
    (``W_ACC sin(W_ACC_W t)``, felt by the held bottle and read by its IMU).

So a new kind of load whose physics the kernel already has (a lift, a shake, a heavier drop)
is one :func:`register_load` call in one file; :func:`kind_of` finds the kind of an object
(its exact class first, then the first registered base class).

Examples
--------
>>> from slipreflex.sim import Drop, Pour
>>> load_names()
('drop', 'pour')
>>> kind_of(Pour()).table, kind_of(Drop()).name
('timed', 'drop')
>>> kind_of(3.0)
Traceback (most recent call last):
...
slipreflex.core.errors.ParameterError: perturb: no load kind takes a float (known: drop, pour)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from ..core import hardware as hw
from ..core.errors import ParameterError
from ..core.registry import Registry
from ..core.validation import choice
from . import kernel as K
from .objects import WATER_DENSITY, Drop, Pour

__all__ = ["LoadKind", "LOAD_KINDS", "TABLES", "register_load", "get_load", "load_names", "kind_of", "drop_row",
           "pour_row"]

#: The kernel's tables a load's rows go to (the module notes say what each holds).
TABLES: tuple[str, ...] = ("drops", "timed")


@dataclass(frozen=True)
class LoadKind:
    """One kind of load: its objects' class and how the rig turns one into a kernel row.

    Parameters
    ----------
    name : str
        Registry key (lower case).
    type : type
        The class of the perturbation objects this kind applies.
    table : {"drops", "timed"}
        The kernel table its rows go to (:data:`TABLES`).
    row : callable
        ``row(what, at, rig) -> numpy.ndarray``: the row for ``what`` released or started at rig
        time ``at`` (s), a row of :data:`~slipreflex.sim.kernel.DROP` or
        :data:`~slipreflex.sim.kernel.POUR` (start from ``layout.new()``); checked complete.

    Examples
    --------
    >>> get_load("pour").type.__name__
    'Pour'
    """

    name: str
    type: type
    table: Literal["drops", "timed"]
    row: Callable[[Any, float, Any], np.ndarray]

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or self.name != self.name.lower():
            raise ParameterError(f"LoadKind.name must be a lower-case str, got {self.name!r}")
        if not isinstance(self.type, type):
            raise ParameterError(f"LoadKind {self.name}: type must be a class, got {self.type!r}")
        choice(f"LoadKind {self.name}: table", self.table, TABLES)
        if not callable(self.row):
            raise ParameterError(f"LoadKind {self.name}: row must be callable, got {self.row!r}")

    @property
    def layout(self) -> Any:
        """The kernel layout of this kind's rows.

        Examples
        --------
        >>> get_load("drop").layout.size == K.D_SIZE
        True
        """
        return K.DROP if self.table == "drops" else K.POUR


def _check_load(spec: LoadKind) -> None:
    """One kind per class: :func:`kind_of` must find one answer."""
    for other in LOAD_KINDS.specs():
        if other.type is spec.type and other.name != spec.name:
            raise ParameterError(f"LoadKind {spec.name}: {spec.type.__name__} is already load kind {other.name!r}")


#: The load-kind registry (the paper's two cannot be removed); the functions below read it.
LOAD_KINDS: Registry[LoadKind] = Registry("load kind", LoadKind, check=_check_load, protected=("drop", "pour"),
                                          group="slipreflex.loads")


def register_load(spec: LoadKind, *, replace: bool = False) -> None:
    """Add a load kind (an existing name is an error unless ``replace``).

    Examples
    --------
    >>> register_load(get_load("drop"))
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: load kind 'drop' is already registered (pass replace=True)
    """
    LOAD_KINDS.register(spec, replace=replace)


def get_load(name: str) -> LoadKind:
    """The load kind registered as ``name``.

    Examples
    --------
    >>> get_load("drop").table
    'drops'
    """
    return LOAD_KINDS.get(name)


def load_names() -> tuple[str, ...]:
    """The registered load kinds, in registration order.

    Examples
    --------
    >>> load_names()[:2]
    ('drop', 'pour')
    """
    return LOAD_KINDS.names()


def kind_of(what: Any) -> LoadKind:
    """The load kind that applies ``what``: its exact class, else the first registered base class.

    Examples
    --------
    >>> from slipreflex.sim import Drop
    >>> kind_of(Drop(mass_kg=0.02)).name
    'drop'
    """
    specs = LOAD_KINDS.specs()
    for spec in specs:
        if type(what) is spec.type:
            return spec
    for spec in specs:
        if isinstance(what, spec.type):
            return spec
    raise ParameterError(f"perturb: no load kind takes a {type(what).__name__} (known: {', '.join(LOAD_KINDS)})")


def drop_row(what: Drop, at: float, rig: Any) -> np.ndarray:
    """A drop's row: released at ``at`` from ``what.height_m`` above the rig's bottle's top.

    Its contact on the bottom is a spring and a damper whose damping ratio gives the
    drop's coefficient of restitution.

    Examples
    --------
    >>> from slipreflex.sim import Rig, Drop
    >>> row = drop_row(Drop(), 1.0, Rig("TR"))
    >>> float(row[K.D_REL]), float(row[K.D_M])
    (1.0, 0.01)
    """
    log_e = math.log(max(what.restitution, 1e-6))
    zeta = -log_e / math.sqrt(math.pi**2 + log_e**2)
    row = K.DROP.new()
    row[K.D_REL] = at
    row[K.D_M] = what.mass_kg
    row[K.D_H0] = rig.bottle.height_m + what.height_m
    row[K.D_KC] = what.contact_stiffness_n_m
    row[K.D_CC] = 2.0 * zeta * math.sqrt(what.contact_stiffness_n_m * what.mass_kg)
    return row


def pour_row(what: Pour, at: float, rig: Any) -> np.ndarray:
    """A pour's row: the pump started at ``at``, the water arriving after its fall.

    Examples
    --------
    >>> from slipreflex.sim import Rig, Pour
    >>> row = pour_row(Pour(rate_l_min=1.0, volume_ml=50), 0.5, Rig("TR"))
    >>> round(float(row[K.W_TOTAL_KG]), 3), float(row[K.W_ACC])
    (0.05, 0.0)
    """
    g = hw.GRAVITY
    rate_l_s = what.rate_l_min / 60.0
    row = K.POUR.new()
    row[K.W_START] = at
    row[K.W_RATE_L_S] = rate_l_s
    row[K.W_RATE_KG_S] = rate_l_s * 1e-3 * WATER_DENSITY
    row[K.W_DUR] = what.duration_s
    row[K.W_TOTAL_KG] = what.volume_ml * 1e-6 * WATER_DENSITY
    row[K.W_DELAY] = math.sqrt(2.0 * what.fall_height_m / g)
    row[K.W_JET_N] = row[K.W_RATE_KG_S] * math.sqrt(2.0 * g * what.fall_height_m)
    return row


# the paper's two loads (its Figs. 10-14 and 15-17)
register_load(LoadKind("drop", Drop, "drops", drop_row))
register_load(LoadKind("pour", Pour, "timed", pour_row))
