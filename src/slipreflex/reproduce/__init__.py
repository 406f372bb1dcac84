"""The reproduction of the paper's experiments in simulation.

One trial (:mod:`.experiments`: :class:`~.experiments.ReproduceConfig` and
:func:`~.experiments.run_trial`), the grid of trials and its workers
(:mod:`.grid`), the paper's experiment set-ups (:mod:`.paper_experiments`,
:mod:`.grasping`, :mod:`.warmup`), the methods' operating points
(:mod:`.thresholds`) and independent replications (:mod:`.replication`).
"""
