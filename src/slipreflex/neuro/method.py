"""The reflex run by a spiking graph: the registered method ``nir``.

:class:`NIRReflex` keeps the host stages of the chain (its low-pass filter and the
sample-to-sample change, its window counter and its MPI controller: the chain's own
streaming objects) and lets a NIR graph, run by :class:`~slipreflex.neuro.interpreter.GraphExecutor`,
decide the spikes. With the graph :func:`~slipreflex.neuro.graph.chain_graph` exports (the
default) it is the fixed-threshold chain with its encoder replaced by two IF neurons;
``--nir-graph FILE`` runs any graph of one input whose outputs are spikes.

Examples
--------
>>> import numpy as np
>>> from slipreflex.methods.chain import run_chain
>>> r = NIRReflex(p0=100.0)
>>> raw = np.r_[np.full(32, 0.40), np.linspace(0.40, 0.55, 64)]      # a rise: the graph is exact here
>>> [c for c in (r.step(v) for v in raw) if c is not None] == run_chain(raw, p0=100.0).commands.tolist()
True
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ..core import hardware as hw
from ..core.errors import DataError
from ..methods import Detections
from .graph import SpikingGraph, chain_graph, host_params, read_graph
from .interpreter import GraphExecutor

__all__ = ["NIRReflex", "build_nir", "build_nir_file", "nir_detections", "graph_spikes", "NAME"]

#: The registered method's name.
NAME = "nir"


class NIRReflex:
    """A :class:`~slipreflex.core.interfaces.Reflex` whose spikes come from a NIR graph.

    Parameters
    ----------
    graph : SpikingGraph, optional
        Default: the fixed-threshold chain's graph (:func:`~slipreflex.neuro.graph.chain_graph`).
    p0 : float
        Starting finger position.
    **host
        Host parameters over the graph's metadata (``n``, ``kp``, ``ki``, ``cutoff``, ...).

    Examples
    --------
    >>> NIRReflex().input_kind, round(NIRReflex().fs, 2)
    ('slip', 333.33)
    """

    input_kind = "slip"

    def __init__(self, graph: SpikingGraph | None = None, *, p0: float = 0.0, name: str = NAME,
                 **host: Any) -> None:
        from ..methods.chain import LowPass, MPIController, WindowCounter  # deferred: heavy (scipy filter design)

        self.graph = graph if graph is not None else chain_graph()
        if self.graph.input_size != 1:
            raise DataError(f"the nir method feeds one input (d_k), the graph takes {self.graph.input_size}")
        self.params = host_params(self.graph, p0=p0, **host)
        p = self.params
        self.name = name
        self._filter = LowPass(fs=p.fs, cutoff=p.cutoff, enabled=p.filter)
        self._windows = WindowCounter(n=p.n)
        self._mpi = MPIController(p0=p.p0, kp=p.kp, ki=p.ki, reset_after=p.reset_after, lo=p.lo, hi=p.hi)
        self._graph = GraphExecutor(self.graph)
        self.reset()

    @property
    def fs(self) -> float:
        """Sampling rate (Hz)."""
        return self.params.fs

    @property
    def command(self) -> float:
        """The current finger command."""
        return self._mpi.command

    def reset(self) -> None:
        """Every stage and every neuron back to its initial state."""
        self._filter.reset()
        self._windows.reset()
        self._mpi.reset()
        self._graph.reset()
        self._prev = self.params.x0
        self.last_event = False
        self.last_filtered = math.nan
        self.last_threshold: float | None = self.params.threshold
        self.last_count: int | None = None
        self.last_polarity = 0

    def step(self, sample: float, position: float | None = None) -> float | None:
        """One raw sample in (V); the command on a window's last sample, else None.

        A NaN or infinite sample is skipped as the chain skips it: no filter or graph step,
        no spike, the window still advances.
        """
        raw = float(sample)
        spikes = None
        if math.isfinite(raw):
            x = self._filter.step(raw)
            prev = x if self._prev is None else self._prev
            spikes = self._graph.step([x - prev])
            self._prev = x
            self.last_filtered = x
        else:
            self.last_filtered = math.nan
        self.last_event = bool(spikes is not None and spikes.any())
        self.last_polarity = _polarity(spikes) if spikes is not None and self.last_event else 0
        v = self._windows.step(self.last_event)
        self.last_count = v
        if v is None:
            return None
        return self._mpi.step(v, position)


def _polarity(spikes: np.ndarray) -> int:
    """+1 when the first output (ON) spiked, -1 for the second (OFF), 0 for none."""
    if spikes[0] > 0:
        return 1
    return -1 if spikes.size > 1 and spikes[1] > 0 else 0


def build_nir(p0: float, context: Any, graph: str | None = None, **params: Any) -> NIRReflex:
    """The registry's builder: ``graph`` a ``.nir`` file, else ``context.options["nir_graph"]``,
    else the fixed-threshold chain's graph.

    Examples
    --------
    >>> from slipreflex.methods import MethodContext
    >>> build_nir(120.0, MethodContext()).command
    120.0
    """
    path = graph if graph is not None else context.options.get("nir_graph")
    loaded = read_graph(Path(path)) if path is not None else None
    return NIRReflex(loaded, p0=p0, **params)


def build_nir_file(graph: str, p0: float, context: Any, **params: Any) -> NIRReflex:
    """The builder ``--nir-graph FILE`` registers: :func:`build_nir` with the file bound first.

    Examples
    --------
    >>> build_nir_file("missing.nir", 0.0, None)       # doctest: +SKIP
    Traceback (most recent call last):
    slipreflex.core.errors.DataError: missing.nir: no such NIR graph file
    """
    return build_nir(p0, context, graph=graph, **params)


def nir_detections(reflex: NIRReflex, volts: np.ndarray):
    """What a trial figure draws for the ``nir`` method: the filtered signal and the graph's spikes.

    Examples
    --------
    >>> nir_detections(NIRReflex(), np.full(40, 0.4)).event_label
    'events (graph spikes)'
    """
    fresh = NIRReflex(reflex.graph, p0=reflex.params.p0)
    x = np.empty(len(volts))
    events = np.zeros(len(volts), dtype=bool)
    for k, v in enumerate(volts):
        fresh.step(float(v))
        x[k], events[k] = fresh.last_filtered, fresh.last_event
    return Detections(x, "filtered (V)", events, "events (graph spikes)")


def graph_spikes(graph: SpikingGraph, raw: np.ndarray, **host: Any) -> np.ndarray:
    """The graph's per-sample polarity over a whole recording: +1 ON, -1 OFF, 0 none.

    Examples
    --------
    >>> graph_spikes(chain_graph(threshold=0.01), np.r_[0.0, 0.0, 0.02, 0.005], filter=False).tolist()
    [0, 0, 1, 0]
    """
    r = NIRReflex(graph, **host)
    out = np.zeros(len(raw), dtype=np.int8)
    for k, v in enumerate(np.asarray(raw, dtype=np.float64)):
        r.step(float(v))
        out[k] = r.last_polarity
    return out


#: The DAQ rate, the method's (kept here so the registry entry and the reflex agree).
FS: float = hw.DAQ_FS
