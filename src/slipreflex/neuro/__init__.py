"""The reflex in the neuromorphic ecosystem (docs/neuromorphic.md).

* :mod:`~slipreflex.neuro.graph` - the chain's encoder as a NIR graph (:func:`chain_graph`),
  NIR files in and out;
* :mod:`~slipreflex.neuro.interpreter` - a reference executor of NIR graphs, one step per sample;
* :mod:`~slipreflex.neuro.method` - the registered method ``nir``: the reflex whose spikes a graph decides;
* :mod:`~slipreflex.neuro.events` - spikes out as AEDAT4, tonic's ``events_struct`` and NIR event data;
* :mod:`~slipreflex.neuro.backends` - the graph run in Spyx (JAX) and Nengo;
* :mod:`~slipreflex.neuro.agreement` - the graph held against Eq. 1-9, stage by stage.

Only the graph, the executor and the method run on the base install; files and backends need
the ``neuro`` extra (``pip install 'slipreflex[neuro]'``).

Examples
--------
>>> from slipreflex.neuro import chain_graph
>>> chain_graph().output_size
2
"""

from .graph import SpikingGraph, chain_graph, read_graph, write_graph
from .interpreter import GraphExecutor
from .method import NIRReflex

__all__ = ["SpikingGraph", "chain_graph", "read_graph", "write_graph", "GraphExecutor", "NIRReflex"]
