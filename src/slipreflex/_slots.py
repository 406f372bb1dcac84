"""Read-only views of one slot of a state vector (the compiled kernels' ``_S`` arrays).

The chain's reflex and the simulated rig keep their state in a flat float array that the numba
kernels update in place; their public read-outs are each one slot of it, cast.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


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
