"""A reference executor of NIR graphs in discrete time: one step per DAQ sample.

NIR defines its nodes as continuous-time equations; this executor steps them with forward
Euler at a time step ``dt`` (in the graph's time unit; the chain's graph uses the sample, so
``dt = 1``), in the order NIR's equations give for a spiking neuron within one step:
integrate the input, compare with the threshold (strictly greater, NIR's ``v > v_thr``), reset
the neurons that spiked to ``v_reset``. A node reads the outputs its predecessors produced in
the same step, summed when several feed it; an edge that closes a cycle (from a node computed
later in the step) carries the previous step's output, the one delay a discrete step needs.

This is the executor the ``nir`` method runs (no extra needed); the backends of
:mod:`slipreflex.neuro.backends` run the same graphs in Spyx and Nengo.

Examples
--------
>>> import numpy as np
>>> from slipreflex.neuro.graph import chain_graph
>>> ex = GraphExecutor(chain_graph(threshold=0.5))
>>> ex.run(np.array([[0.3], [0.3], [-0.2], [-0.9]])).astype(int).tolist()
[[0, 0], [1, 0], [0, 0], [0, 1]]
"""

from __future__ import annotations

import numpy as np

from ..core.errors import DataError, ParameterError
from .graph import SpikingGraph

__all__ = ["GraphExecutor"]

_STATEFUL = ("IF", "LIF", "I", "LI")


class GraphExecutor:
    """Steps a :class:`~slipreflex.neuro.graph.SpikingGraph` one input vector at a time.

    Parameters
    ----------
    graph : SpikingGraph
    dt : float
        Time step in the graph's time unit (1.0: one step is one unit, the chain's sample).

    Examples
    --------
    >>> from slipreflex.neuro.graph import chain_graph
    >>> ex = GraphExecutor(chain_graph(threshold=0.5))
    >>> ex.step([0.6]).tolist(), ex.step([0.0]).tolist()
    ([1.0, 0.0], [0.0, 0.0])
    """

    __slots__ = ("graph", "dt", "_order", "_preds", "_v", "_delayed", "_last")

    def __init__(self, graph: SpikingGraph, dt: float = 1.0) -> None:
        if not (np.isfinite(dt) and dt > 0):
            raise ParameterError(f"dt must be > 0, got {dt!r}")
        self.graph, self.dt = graph, float(dt)
        self._order = graph.order()
        self._preds = {k: graph.predecessors(k) for k in self._order}
        self._delayed = graph.delayed()
        for name in self._order:
            node = graph.nodes[name]
            if node.kind != "Input" and not self._preds[name]:
                raise DataError(f"NIR graph: node {name!r} ({node.kind}) has no input edge")
        self._v: dict[str, np.ndarray] = {}
        self._last: dict[str, np.ndarray] = {}
        self.reset()

    def reset(self) -> None:
        """Every neuron back to its initial state (membrane 0)."""
        self._v = {k: np.zeros(self.graph.nodes[k].size_out) for k in self._order
                   if self.graph.nodes[k].kind in _STATEFUL}
        self._last = {k: np.zeros(self.graph.nodes[k].size_out) for k in self._order}

    def step(self, u) -> np.ndarray:
        """One time step: ``u`` (the Input's values) in, the Output's values out."""
        u = np.asarray(u, dtype=np.float64).reshape(-1)
        g = self.graph
        if u.size != g.input_size:
            raise DataError(f"NIR graph input takes {g.input_size} value(s) per step, got {u.size}")
        out: dict[str, np.ndarray] = {}
        for name in self._order:
            node = g.nodes[name]
            if node.kind == "Input":
                out[name] = u
                continue
            x = sum(self._last[p] if (p, name) in self._delayed else out[p] for p in self._preds[name])
            out[name] = self._apply(name, node.kind, node.params, np.asarray(x, dtype=np.float64))
        self._last = out
        return out[g.output_name]

    def _apply(self, name: str, kind: str, p, x: np.ndarray) -> np.ndarray:
        dt = self.dt
        if kind == "Output":
            return x
        if kind == "Affine":
            return p["weight"] @ x + p["bias"]
        if kind == "Linear":
            return p["weight"] @ x
        if kind == "Scale":
            return p["scale"] * x
        if kind == "Threshold":
            return (x > p["threshold"]).astype(np.float64)
        v = self._v[name]
        if kind == "I":
            v += dt * p["r"] * x
            return v.copy()
        if kind == "LI":
            v += dt / p["tau"] * (p["v_leak"] - v + p["r"] * x)
            return v.copy()
        if kind == "IF":
            v += dt * p["r"] * x
        else:                                     # LIF
            v += dt / p["tau"] * (p["v_leak"] - v + p["r"] * x)
        z = v > p["v_threshold"]
        v[z] = p["v_reset"][z]
        return z.astype(np.float64)

    def run(self, inputs) -> np.ndarray:
        """Run a whole input array (steps x input size) from the initial state; returns steps x outputs."""
        rows = np.asarray(inputs, dtype=np.float64)
        if rows.ndim == 1:
            rows = rows[:, None]
        self.reset()
        out = np.empty((rows.shape[0], self.graph.output_size))
        for k in range(rows.shape[0]):
            out[k] = self.step(rows[k])
        return out
