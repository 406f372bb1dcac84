"""Named slots of the compiled kernels' flat float arrays, and read-only views of one slot.

The chain, the tactile baselines and the simulated rig keep their parameters (``P``) and state
(``S``) in flat float64 vectors that the numba kernels read and update in place. Each vector's
layout is one :class:`Layout`: the slot names in order (a block of several slots is
``NAME:n``), each slot's initial value where it has one (``NAME=0``, ``NAME:3=1``). A vector
is made by :meth:`Layout.new`, NaN in every slot without an initial value, filled by name,
and checked by :meth:`Layout.check` before a kernel runs: a slot nobody filled is an error
naming it, never a silent 0.0. The modules bind the slot indices to constants for the
kernels (``(P_A, P_B) = LAYOUT.slots``); ``tests/house/test_slots.py`` checks every such constant
against its layout's name.

Their public read-outs are each one slot of the state, cast (:func:`slot`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

__all__ = ["Layout", "LayoutError", "slot"]


class LayoutError(RuntimeError):
    """A vector does not fit its layout: a slot left unfilled (NaN) or the wrong size."""


class Layout:
    """The named slots of one flat float64 vector.

    Parameters
    ----------
    what : str
        What the vector is (for messages): "the chain's parameters P".
    spec : str
        Slot names in order, whitespace-separated; ``NAME:n`` is a block of ``n`` slots,
        ``NAME=v`` (or ``NAME:n=v``) gives its initial value (``nan`` allowed: a slot whose
        value may stay NaN).
    prefix : str
        The prefix of the module constants bound to the slots (``"P_"``).
    start : int
        Index of the first slot (a layout may continue another).

    Examples
    --------
    >>> L = Layout("a demo vector", "A B:2=0 C=nan D", prefix="X_")
    >>> L.slots, L.size, L.names
    ((0, 1, 3, 4), 5, ('A', 'B', 'C', 'D'))
    >>> v = L.new(); v[L.index("A")] = 1.5
    >>> L.check(v)
    Traceback (most recent call last):
    ...
    slipreflex.core._slots.LayoutError: a demo vector: slot(s) not filled: D
    >>> v[4] = 2.0; L.check(v).tolist()
    [1.5, 0.0, 0.0, nan, 2.0]
    """

    def __init__(self, what: str, spec: str, *, prefix: str = "", start: int = 0) -> None:
        self.what, self.prefix, self.start = what, prefix, int(start)
        names: list[str] = []
        slots: list[int] = []
        widths: list[int] = []
        init: list[float] = []
        may_be_nan: list[bool] = []
        at = self.start
        for token in spec.split():
            head, _, value = token.partition("=")
            name, _, width = head.partition(":")
            n = int(width) if width else 1
            if not name.isidentifier() or name in names or n < 1:
                raise ValueError(f"{what}: bad or repeated slot {token!r}")
            names.append(name)
            slots.append(at)
            widths.append(n)
            init.extend([float(value) if value else math.nan] * n)
            may_be_nan.extend([value.lower() == "nan"] * n)
            at += n
        self.names: tuple[str, ...] = tuple(names)
        self.slots: tuple[int, ...] = tuple(slots)
        self.widths: tuple[int, ...] = tuple(widths)
        self.size: int = at
        self._init = np.array(init, dtype=np.float64)
        self._may_be_nan = np.array(may_be_nan, dtype=bool)

    def index(self, name: str) -> int:
        """The index of slot ``name`` (the first of a block)."""
        try:
            return self.slots[self.names.index(name)]
        except ValueError:
            raise KeyError(f"{self.what}: no slot {name!r}") from None

    def constants(self) -> dict[str, int]:
        """``{prefix + name: index}``: what the module binds for its kernels."""
        return {self.prefix + n: i for n, i in zip(self.names, self.slots)}

    def new(self, extra: int = 0, *, tail: float = math.nan) -> np.ndarray:
        """A vector: the initial values, NaN in every other slot, then ``extra`` slots of ``tail``."""
        out = np.full(self.size - self.start + extra, tail, dtype=np.float64)
        out[: self.size - self.start] = self._init
        return out

    def unfilled(self, vector: np.ndarray) -> list[str]:
        """The slots of ``vector`` still NaN that must not be."""
        v = np.asarray(vector, dtype=np.float64)[: self.size - self.start]
        bad = np.isnan(v) & ~self._may_be_nan
        if not bad.any():    # the usual answer, without a look at every slot
            return []
        out = []
        for name, first, n in zip(self.names, self.slots, self.widths):
            k = first - self.start
            if bad[k:k + n].any():
                out.append(name if n == 1 else f"{name}[{', '.join(str(j) for j in np.flatnonzero(bad[k:k + n]))}]")
        return out

    def check(self, vector: np.ndarray, *, skip: Iterable[str] = ()) -> np.ndarray:
        """``vector`` itself, once every slot is filled (NaN only where declared ``=nan``).

        Raises
        ------
        LayoutError
            Naming the slots left unfilled, or when ``vector`` is shorter than the layout.
        """
        if np.asarray(vector).shape[0] < self.size - self.start:
            raise LayoutError(f"{self.what}: {np.asarray(vector).shape[0]} slots, the layout has "
                              f"{self.size - self.start}")
        ignore = set(skip)
        bad = [n for n in self.unfilled(vector) if n.partition("[")[0] not in ignore]
        if bad:
            raise LayoutError(f"{self.what}: slot(s) not filled: {', '.join(bad)}")
        return vector


def slot(index: int, cast: Callable[[Any], Any], doc: str) -> Any:  # a property, read as its value
    """A read-only property: ``cast(self._S[index])``, documented by ``doc``.

    Examples
    --------
    >>> import numpy as np
    >>> class Box:
    ...     _S = np.array([0.0, 2.5])
    ...     level = slot(1, float, "The level (m).")
    >>> Box().level, Box.level.__doc__
    (2.5, 'The level (m).')
    """
    def read(self: Any) -> Any:
        return cast(self._S[index])

    return property(read, doc=doc)
