"""Replication over master seeds: the grid again where one run's trials leave a claim unresolved.

A claim about a random quantity is judged with an interval (:mod:`slipreflex.analysis.claims`);
when that interval straddles the claim's criterion on one run's trials, the run alone cannot
decide it. :func:`replicate_undecided` then runs the grid again on derived master seeds
(:func:`~slipreflex.analysis.claims.replicate_seed`), only for the methods the undecided
claims read, and the claims are judged on the pooled rows
(:func:`~slipreflex.analysis.outputs.judged_claims`). ``slipreflex reproduce`` does this after
its grid; ``scripts/docs/claims_seeds.py`` does it for each master seed it compares.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

from ..analysis.claims import REPLICATES_MAX, replicate_seed, undecided_methods
from ..analysis.outputs import ReproduceResult, judged_claims
from ..files.interrupts import Interrupted
from . import experiments

__all__ = ["replicate_undecided"]


def replicate_undecided(result: ReproduceResult, *, jobs: int | None = None, progress: bool = False,
                        max_replicates: int = REPLICATES_MAX,
                        on_replicate: Callable[[int, int, tuple[str, ...]], None] | None = None) -> ReproduceResult:
    """Replicate the grid on derived master seeds while one run's trials leave a claim unresolved.

    After each grid the claims are judged on the pooled rows
    (:func:`slipreflex.analysis.outputs.judged_claims`); while one is ``unresolved``, the
    grid runs again on master seed :func:`~slipreflex.analysis.claims.replicate_seed`
    ``(seed, k)``, only for the methods those claims read
    (:func:`~slipreflex.analysis.claims.undecided_methods`), at most ``max_replicates``
    times. A partial run, or one without the paper's cells, is returned unchanged.

    Parameters
    ----------
    result : ReproduceResult
        The run (its ``replicates`` and ``replicate_seeds`` are extended in place).
    jobs, progress
        As for :func:`run_reproduce`.
    max_replicates : int
        Most replicate grids (0: judge on the run alone).
    on_replicate : callable, optional
        Called as ``on_replicate(k, seed, methods)`` before replicate ``k`` runs.

    Returns
    -------
    ReproduceResult
        ``result``. Ctrl-C during a replicate keeps the finished replicates and raises
        :class:`~slipreflex.files.interrupts.Interrupted` carrying ``result``.

    Examples
    --------
    A run without rows leaves nothing to judge, so nothing to replicate:

    >>> from slipreflex.reproduce.experiments import ReproduceConfig
    >>> replicate_undecided(ReproduceResult(ReproduceConfig(), [], [], {}, {}, 0.0, 1)).replicate_seeds
    ()
    """
    if result.partial_note or max_replicates < 0:
        return result
    for k in range(len(result.replicate_seeds) + 1, max_replicates + 1):
        wanted = tuple(m for m in undecided_methods(judged_claims(result)) if m in result.config.methods)
        if not wanted:
            break
        seed = replicate_seed(result.config.seed, k)
        if on_replicate is not None:
            on_replicate(k, seed, wanted)
        config = dataclasses.replace(result.config, seed=seed, methods=wanted)
        try:
            rep = experiments.run_reproduce(config, jobs=jobs, progress=progress, plots=False)
        except Interrupted:
            raise Interrupted(result, "interrupted during a replicate grid") from None
        result.replicates.extend(rep.rows)
        result.replicate_seeds += (seed,)
    return result
