"""The exported graph run in simulators of the neuromorphic field: Spyx (JAX) and Nengo.

Each backend takes a :class:`~slipreflex.neuro.graph.SpikingGraph` and an input array (steps x
inputs) and returns the output spikes (steps x outputs, 0 or 1), so they compare with the
package's own executor (:class:`~slipreflex.neuro.interpreter.GraphExecutor`) and with the chain.

* ``reference``: :class:`~slipreflex.neuro.interpreter.GraphExecutor`, NIR's IF read literally
  (integrate, ``v > v_thr``, reset to ``v_reset``, all in one step).
* ``spyx``: ``spyx.nir.from_nir``, Spyx's own NIR reader, run on JAX's CPU backend in float64.
  Spyx's IF differs from NIR's in two ways: it compares the membrane *before* adding the
  step's input (a spike comes one step late), and it resets by *subtracting* the threshold
  (what exceeded it is kept); it ignores ``r`` and ``v_reset``.
* ``nengo``: Nengo has no NIR reader in its package; the NIR project maps its graphs to Nengo
  by hand, and :func:`run_nengo` does the same for the nodes the chain's graph uses (Input,
  Affine, Linear, Scale, IF, Output): weights as Nengo Nodes, IF as an Ensemble whose neurons
  follow NIR's IF, edges as synapse-free connections (a cycle's edge through a zero-time-constant
  synapse, Nengo's one-step delay), run by Nengo's reference simulator at one step per sample.

Examples
--------
>>> import numpy as np
>>> from slipreflex.neuro.graph import chain_graph
>>> run_backend("reference", chain_graph(threshold=0.5), np.array([[0.6], [0.0]])).tolist()
[[1.0, 0.0], [0.0, 0.0]]
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..core.errors import DataError, ParameterError
from .graph import SpikingGraph, to_nir
from .interpreter import GraphExecutor

__all__ = ["BACKENDS", "run_backend", "run_reference", "run_spyx", "run_nengo", "available"]


def run_reference(graph: SpikingGraph, inputs: np.ndarray) -> np.ndarray:
    """The package's executor (no extra needed).

    Examples
    --------
    >>> from slipreflex.neuro.graph import chain_graph
    >>> run_reference(chain_graph(threshold=0.5), np.array([[0.3], [0.3]]))[:, 0].tolist()
    [0.0, 1.0]
    """
    return GraphExecutor(graph).run(inputs)


def run_spyx(graph: SpikingGraph, inputs: np.ndarray) -> np.ndarray:
    """Spyx's NIR reader and its IF neurons, on JAX's CPU backend in float64.

    Examples
    --------
    >>> from slipreflex.neuro.graph import chain_graph
    >>> run_spyx(chain_graph(threshold=0.5), np.array([[0.6], [0.0]]))[:, 0].tolist()  # doctest: +SKIP
    [0.0, 1.0]
    """
    try:
        with warnings.catch_warnings():       # a dependency's deprecation notice is not this package's to fix
            warnings.simplefilter("ignore", DeprecationWarning)
            import jax  # deferred: optional extra (jax, pip install slipreflex[neuro])

            jax.config.update("jax_platforms", "cpu")
            jax.config.update("jax_enable_x64", True)     # float32 rounding would hide the IF rule
            import jax.numpy as jnp  # deferred: optional extra (jax)
            import spyx.nir  # deferred: optional extra (spyx)
    except ImportError:
        raise ParameterError("the spyx backend needs spyx and jax: pip install 'slipreflex[neuro]'") from None
    x = jnp.asarray(np.asarray(inputs, dtype=np.float64)[:, None, :])       # (steps, batch 1, inputs)
    with warnings.catch_warnings():     # Spyx's layers hold float32 weights; loading ours warns of the cast
        warnings.filterwarnings("ignore", message="scatter inputs have incompatible types", category=FutureWarning)
        _, out = spyx.nir.from_nir(_spyx_form(to_nir(graph)), x, dt=1.0)
    return np.asarray(out, dtype=np.float64)[:, 0, :]


def _spyx_form(ng):
    """Spyx reads a recurrent IF layer as a sub-graph (Input, Linear, IF, Output): wrap each IF whose
    outputs come back to it through one Linear into that form (the same network, nested)."""
    import nir  # deferred: optional extra (nir)

    for name, node in list(ng.nodes.items()):
        if not isinstance(node, nir.IF):
            continue
        back = [b for a, b in ng.edges if a == name and (b, name) in ng.edges and isinstance(ng.nodes[b], nir.Linear)]
        if not back:
            continue
        w = back[0]
        size = np.array(node.r.shape)
        sub = nir.NIRGraph(nodes={f"{name}.input": nir.Input({"input": size}), f"{name}.w_rec": ng.nodes[w],
                                  f"{name}.lif": node, f"{name}.output": nir.Output({"output": size})},
                           edges=[(f"{name}.input", f"{name}.w_rec"), (f"{name}.w_rec", f"{name}.lif"),
                                  (f"{name}.lif", f"{name}.w_rec"), (f"{name}.lif", f"{name}.output")])
        nodes = {k: v for k, v in ng.nodes.items() if k not in (name, w)}
        nodes[name] = sub
        edges = [(a, b) for a, b in ng.edges if w not in (a, b)]
        ng = nir.NIRGraph(nodes=nodes, edges=edges, metadata=ng.metadata)
    return ng


def nir_if_type(threshold, reset):
    """A Nengo neuron type that follows NIR's IF: ``v += J dt``; spike where ``v > threshold``; ``v = reset``."""
    import nengo  # deferred: optional extra (nengo)
    from nengo.neurons import NeuronType  # deferred: optional extra (nengo)

    class NIRIF(NeuronType):
        state = {"voltage": nengo.dists.Choice([0.0])}
        spiking = True

        def __init__(self, threshold, reset):
            super().__init__()
            self._threshold = np.asarray(threshold, dtype=np.float64)
            self._reset = np.asarray(reset, dtype=np.float64)

        def gain_bias(self, max_rates, intercepts):     # gains and biases are given, never fitted
            raise NotImplementedError("give gain and bias")

        def max_rates_intercepts(self, gain, bias):     # only for Nengo's decoders, which nothing here uses
            return np.full_like(gain, np.nan), np.full_like(gain, np.nan)

        def step(self, dt, J, output, voltage):
            voltage += J * dt
            spiked = voltage > self._threshold
            output[...] = spiked / dt
            voltage[spiked] = self._reset[spiked]

    return NIRIF(threshold, reset)


def run_nengo(graph: SpikingGraph, inputs: np.ndarray) -> np.ndarray:
    """The graph as a Nengo network (NIR's IF as a Nengo neuron type), run by ``nengo.Simulator``.

    Examples
    --------
    >>> from slipreflex.neuro.graph import chain_graph
    >>> run_nengo(chain_graph(threshold=0.5), np.array([[0.6], [0.0]]))[:, 0].tolist()  # doctest: +SKIP
    [1.0, 0.0]
    """
    try:
        with warnings.catch_warnings():       # nengo 4.1 still reads numpy.core, which numpy 2 deprecates
            warnings.simplefilter("ignore", DeprecationWarning)
            import nengo  # deferred: optional extra (nengo, pip install slipreflex[neuro])
    except ImportError:
        raise ParameterError("the nengo backend needs nengo: pip install 'slipreflex[neuro]'") from None
    allowed = {"Input", "Output", "Affine", "Linear", "Scale", "IF"}
    kinds = {n.kind for n in graph.nodes.values()}
    if not kinds <= allowed:
        raise DataError(f"the nengo backend maps {', '.join(sorted(allowed))}; the graph has "
                        f"{', '.join(sorted(kinds - allowed))}")
    rows = np.asarray(inputs, dtype=np.float64).reshape(len(inputs), -1)
    delayed = graph.delayed()
    with nengo.Network(seed=0) as net:
        ends = {name: _nengo_object(nengo, node, rows) for name, node in graph.nodes.items()}
        for a, b in graph.edges:           # a cycle's edge waits one step (a synapse), the others none
            synapse: Any = 0 if (a, b) in delayed else None
            nengo.Connection(ends[a][1], ends[b][0], synapse=synapse)
        probe = nengo.Probe(ends[graph.output_name][1], synapse=_NONE)
    with nengo.Simulator(net, dt=1.0, progress_bar=False, optimize=False) as sim:
        sim.run_steps(rows.shape[0])
        return (np.asarray(sim.data[probe]) > 0).astype(np.float64)


def _nengo_object(nengo, node, rows: np.ndarray):
    """(what an edge into the node connects to, what an edge out of it connects from)."""
    p = node.params
    if node.kind == "Input":
        source = nengo.Node(nengo.processes.PresentInput(rows, presentation_time=1.0))
        return source, source
    if node.kind == "IF":
        ens = nengo.Ensemble(p["r"].size, 1, neuron_type=nir_if_type(p["v_threshold"], p["v_reset"]),
                             gain=np.asarray(p["r"]), bias=np.zeros(p["r"].size))
        return ens.neurons, ens.neurons
    if node.kind == "Output":
        out = nengo.Node(size_in=node.size_out)
        return out, out
    w = np.diag(p["scale"]) if node.kind == "Scale" else np.asarray(p["weight"])
    b = np.asarray(p["bias"]) if node.kind == "Affine" else np.zeros(w.shape[0])
    fn = nengo.Node(lambda t, x, w=w, b=b: w @ x + b, size_in=w.shape[1], size_out=w.shape[0])
    return fn, fn


_NONE: Any = None       # Nengo's "no synapse", typed as its stubs do not say

#: The backends by name.
BACKENDS = {"reference": run_reference, "spyx": run_spyx, "nengo": run_nengo}


def available(name: str) -> bool:
    """Whether the backend's packages are installed.

    Examples
    --------
    >>> available("reference")
    True
    """
    import importlib.util  # deferred: heavy (importlib machinery, only asked here)

    need = {"reference": (), "spyx": ("spyx", "jax", "nir"), "nengo": ("nengo",)}[name]
    return all(importlib.util.find_spec(m) is not None for m in need)


def run_backend(name: str, graph: SpikingGraph, inputs: np.ndarray) -> np.ndarray:
    """Run ``graph`` on ``inputs`` (steps x inputs) in the backend ``name``; spikes (steps x outputs).

    Examples
    --------
    >>> from slipreflex.neuro.graph import chain_graph
    >>> run_backend("loihi", chain_graph(), np.zeros((1, 1)))
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: backend 'loihi' is not one of reference, spyx, nengo
    """
    if name not in BACKENDS:
        raise ParameterError(f"backend {name!r} is not one of {', '.join(BACKENDS)}")
    return BACKENDS[name](graph, inputs)
