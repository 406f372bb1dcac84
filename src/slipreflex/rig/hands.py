"""The registry of hands: one specification per hand driver, as :mod:`slipreflex.methods` for methods.

A hand is a driver behind :class:`slipreflex.core.interfaces.Hand` (``set_positions``,
``positions``, ``hold``) on a serial port. ``run --hand-type NAME`` opens the registered
hand NAME, ``virtual-rig --hand-type NAME`` puts its virtual twin behind the hand's
pseudo-terminal. Adding a hand is one module (its protocol, its driver, its virtual
twin) and one :func:`register_hand` call.

Built in:

``ilimb``
    Touch Bionics i-Limb behind its control unit (:class:`slipreflex.rig.devices.ilimb.ILimb`),
    the paper's hand; reports no positions and has no touch sensors.
``ability``
    PSYONIC Ability Hand on its UART (:class:`slipreflex.rig.devices.ability.AbilityHand`):
    reports its finger positions, and its index fingertip's six touch sites are a
    :class:`~slipreflex.core.interfaces.TactileSource` for a tactile method.

Examples
--------
>>> hand_names()
('ilimb', 'ability')
>>> get_hand("Ability").tactile, get_hand("ilimb").tactile
(True, False)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..core.errors import ParameterError
from ..core.registry import EntryPoint, Registry
from ..core.validation import flag, text

__all__ = ["HandSpec", "HANDS", "register_hand", "get_hand", "hand_names", "open_hand", "ILIMB", "ABILITY"]

ILIMB, ABILITY = "ilimb", "ability"


@dataclass(frozen=True)
class HandSpec:
    """What the package needs to know about one hand.

    Parameters
    ----------
    name, label : str
        Registry key (lower case) and how messages name it.
    open : callable
        ``open(port, **options) -> Hand``: the driver on a port (a path or pyserial URL);
        it has ``close()``. Options: ``fs`` (the tactile rate) for a tactile hand.
    tactile : bool
        The driver is also a :class:`~slipreflex.core.interfaces.TactileSource`.
    tactile_shape : tuple of int
        The shape of its tactile frames (empty for a hand without touch sensors).
    virtual : callable, optional
        ``virtual(rig)``: the hand's side of its protocol on a rig, with ``feed(bytes) ->
        bytes`` (the replies to write back) and ``commands`` / ``rejected`` counters; None
        for a hand the virtual devices speak natively (the i-Limb).

    Examples
    --------
    >>> get_hand("ilimb").label
    'i-Limb'
    """

    name: str
    label: str
    open: Callable[..., Any]
    tactile: bool = False
    virtual: Callable[[Any], Any] | None = None
    tactile_shape: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        text("HandSpec.name", self.name)
        if self.name != self.name.lower():
            raise ParameterError(f"HandSpec.name must be lower case, got {self.name!r}")
        text("HandSpec.label", self.label)
        flag("HandSpec.tactile", self.tactile)
        if not callable(self.open) or not (self.virtual is None or callable(self.virtual)):
            raise ParameterError(f"HandSpec {self.name}: open and virtual must be callable")


def _check_hand(spec: HandSpec) -> None:
    """A tactile hand says the shape of its frames; a hand without touch sensors has none."""
    if bool(spec.tactile_shape) != spec.tactile:
        raise ParameterError(f"HandSpec {spec.name}: tactile={spec.tactile} but tactile_shape={spec.tactile_shape!r} "
                             "(a tactile hand gives its frames' shape, another gives ())")


#: The hand registry (``--hand-type`` names one); the functions below read it.
HANDS: Registry[HandSpec] = Registry("hand", HandSpec, any_case=True, label="--hand-type", check=_check_hand,
                                   group="slipreflex.hands")


def register_hand(spec: HandSpec, *, replace: bool = False) -> None:
    """Add a hand to the registry.

    Examples
    --------
    >>> register_hand(get_hand("ilimb"))
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: hand 'ilimb' is already registered (pass replace=True)
    """
    HANDS.register(spec, replace=replace)


def get_hand(name: str) -> HandSpec:
    """The specification of a registered hand (any case); an unknown one is a one-line error.

    Examples
    --------
    >>> get_hand("shadow")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: --hand-type: unknown 'shadow' (known: ilimb, ability)
    """
    return HANDS.get(name)


def hand_names() -> tuple[str, ...]:
    """Registered hands, in registration order.

    Examples
    --------
    >>> "ability" in hand_names()
    True
    """
    return HANDS.names()


def open_hand(name: str, port: Any, **options: Any) -> Any:
    """Open the hand ``name`` on ``port`` (its driver; close it when done).

    Examples
    --------
    >>> import serial
    >>> hand = open_hand("ilimb", serial.serial_for_url("loop://")); hand.positions()
    {}
    """
    return get_hand(name).open(port, **options)


# The drivers sit above the registry: named by entry point, imported when a hand is opened.
register_hand(HandSpec(ILIMB, "i-Limb", EntryPoint("slipreflex.rig.devices.ilimb:ILimb")))
register_hand(HandSpec(ABILITY, "Ability Hand", EntryPoint("slipreflex.rig.devices.ability:AbilityHand"), tactile=True,
                       virtual=EntryPoint("slipreflex.rig.devices.ability:VirtualAbilityHand"), tactile_shape=(6,)))
