"""Which plants a study runs: a space-filling design over the uncertain constants.

Every constant of the table (:data:`slipreflex.sim.uncertain.UNCERTAIN`, or
a table narrowed by a ranges file) whose range is not a single value is one
dimension of the unit cube. A design draws points in that cube from a seed
and :meth:`~slipreflex.sim.uncertain.UncertainConstant.value_at` maps each
coordinate onto the constant's distribution; a fixed constant takes its one
value in every plant.

* ``sobol``: scrambled Sobol' points (``scipy.stats.qmc.Sobol``); a power of
  two keeps their balance, other counts take the first N points;
* ``lhs``: a Latin hypercube (``scipy.stats.qmc.LatinHypercube``);
* ``saltelli``: SALib's Saltelli scheme for Sobol' indices,
  ``B (D + 2)`` plants for a base ``B`` (a power of two) and ``D`` varying
  constants, rounded up from the plants asked for; the only design whose
  sensitivity table carries Sobol' indices.

Examples
--------
>>> from slipreflex.sim.uncertain import UNCERTAIN
>>> d = draw_design(UNCERTAIN, 4, "lhs", seed=1)
>>> len(d), sorted(d[0]) == sorted(UNCERTAIN)
(4, True)
>>> d == draw_design(UNCERTAIN, 4, "lhs", seed=1)
True
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping

import numpy as np

from ..core.errors import ParameterError

__all__ = ["DESIGNS", "varying", "unit_design", "design_size", "draw_design", "values_at"]

#: Design kinds ``slipreflex study --design`` accepts.
DESIGNS: tuple[str, ...] = ("sobol", "lhs", "saltelli")


def varying(table: Mapping) -> list[str]:
    """Names of the constants whose range is not a single value, in table order.

    Examples
    --------
    >>> from slipreflex.sim.uncertain import UNCERTAIN
    >>> len(varying(UNCERTAIN)) == sum(not c.fixed for c in UNCERTAIN.values())
    True
    """
    return [k for k, c in table.items() if not c.fixed]


def design_size(kind: str, n: int, d: int) -> int:
    """Plants a design of ``kind`` draws when ``n`` are asked for over ``d`` dimensions.

    Examples
    --------
    >>> design_size("lhs", 10, 5), design_size("saltelli", 10, 5)
    (10, 14)
    """
    if kind != "saltelli":
        return n
    base = 2 ** max(0, math.ceil(math.log2(math.ceil(n / (d + 2)))))
    return base * (d + 2)


def unit_design(kind: str, n: int, d: int, seed: int) -> np.ndarray:
    """Points of the unit cube, shape ``(design_size(kind, n, d), d)``, reproducible from ``seed``.

    Examples
    --------
    >>> u = unit_design("sobol", 8, 3, seed=0)
    >>> u.shape, bool(((u >= 0) & (u < 1)).all())
    ((8, 3), True)
    """
    if kind not in DESIGNS:
        raise ParameterError(f"design: unknown {kind!r} (known: {', '.join(DESIGNS)})")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ParameterError(f"plants must be an integer >= 1, got {n!r}")
    if d == 0:
        return np.zeros((design_size(kind, n, d), 0))
    from scipy.stats import qmc  # deferred: heavy (scipy.stats)

    rng = np.random.default_rng(np.random.SeedSequence(seed))
    if kind == "lhs":
        return qmc.LatinHypercube(d, rng=rng).random(n)
    if kind == "sobol":
        with warnings.catch_warnings():   # balance is lost unless n is a power of two: documented
            warnings.simplefilter("ignore", UserWarning)
            return qmc.Sobol(d, scramble=True, rng=rng).random(n)
    from SALib.sample import sobol as saltelli  # deferred: optional extra (study: SALib)

    problem = {"num_vars": d, "names": [f"x{i}" for i in range(d)], "bounds": [[0.0, 1.0]] * d}
    base = design_size(kind, n, d) // (d + 2)
    return np.clip(saltelli.sample(problem, base, calc_second_order=False, seed=int(seed) % 2**32), 0.0, 1.0)


def draw_design(table: Mapping, n: int, kind: str = "sobol", seed: int = 0) -> list[dict[str, float]]:
    """The plants of a study: one dict of constant values (every constant of ``table``) per plant.

    Parameters
    ----------
    table : mapping of str to UncertainConstant
    n : int
        Plants asked for (``saltelli`` rounds up, see :func:`design_size`).
    kind : {"sobol", "lhs", "saltelli"}
    seed : int

    Returns
    -------
    list of dict

    Examples
    --------
    >>> from slipreflex.sim.uncertain import UNCERTAIN
    >>> draw_design(UNCERTAIN, 2, seed=3)[1] != draw_design(UNCERTAIN, 2, seed=4)[1]
    True
    """
    return values_at(table, unit_design(kind, n, len(varying(table)), seed))


def values_at(table: Mapping, points: np.ndarray) -> list[dict[str, float]]:
    """The plants at ``points`` of the unit cube (one coordinate per :func:`varying` constant).

    Examples
    --------
    >>> from slipreflex.sim.uncertain import UNCERTAIN
    >>> u = unit_design("sobol", 2, len(varying(UNCERTAIN)), seed=3)
    >>> values_at(UNCERTAIN, u) == draw_design(UNCERTAIN, 2, seed=3)
    True
    """
    names = varying(table)
    out = []
    for row in points:
        vals = {k: float(c.low) for k, c in table.items()}   # a fixed constant: its one value
        for k, x in zip(names, row):
            vals[k] = table[k].value_at(float(x))
        out.append(vals)
    return out
