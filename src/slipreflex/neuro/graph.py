"""The chain's encoder as a spiking graph, in the Neuromorphic Intermediate Representation (NIR).

:func:`chain_graph` builds the graph of the fixed-threshold chain (or the closest graph of
DATH) as a :class:`SpikingGraph`: a small, dependency-free description whose nodes carry
NIR's node names and parameters, so the reflex (:mod:`slipreflex.neuro.method`) runs it
without the ``neuro`` extra. :func:`to_nir` and :func:`from_nir` convert it to and from
``nir.NIRGraph`` (the ``neuro`` extra); :func:`write_graph` and :func:`read_graph` write and
read ``.nir`` files (HDF5).

What the graph holds and what stays on the host (docs/method.md, "The chain as a NIR graph"):

* host: the low-pass filter (section 1.1) and the sample-to-sample change
  d_k = x_k - x_(k-1) of Eq. 1: the graph's one input is d_k, in volts per sample;
* graph: ``polarity`` (Affine, weights +1 and -1) feeding ``encoder`` (IF, two neurons,
  r = 1, threshold theta, reset to 0): the ON neuron integrates d_k, the OFF neuron -d_k;
  output spike of either is the chain's y_k, its sign the polarity;
* host: the windows (Eq. 3) and the MPI (Eq. 5-9), read from the graph's spikes.

One time step is one DAQ sample (NIR's time unit here is the sample: IF's r = 1 adds d_k per
step). The graph's metadata records the host stages' parameters, so an imported graph is run
with the filter, windows and controller it was exported with.

Examples
--------
>>> g = chain_graph()
>>> [g.nodes[k].kind for k in g.order()]
['Input', 'Affine', 'IF', 'Linear', 'Output']
>>> float(g.nodes["encoder"].params["v_threshold"][0])
0.008
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..core.errors import DataError, ParameterError

__all__ = ["Node", "SpikingGraph", "chain_graph", "to_nir", "from_nir", "write_graph", "read_graph",
           "host_params", "SUPPORTED", "METADATA_KEY"]

#: The NIR node kinds this package's interpreter runs, with the parameters each needs.
SUPPORTED: dict[str, tuple[str, ...]] = {
    "Input": ("shape",), "Output": ("shape",),
    "Affine": ("weight", "bias"), "Linear": ("weight",), "Scale": ("scale",),
    "IF": ("r", "v_threshold", "v_reset"), "LIF": ("tau", "r", "v_leak", "v_threshold", "v_reset"),
    "I": ("r",), "LI": ("tau", "r", "v_leak"), "Threshold": ("threshold",),
}

#: The metadata key under which an exported graph records the chain it stands for (a JSON string).
METADATA_KEY = "slipreflex"


@dataclass(frozen=True, eq=False)
class Node:
    """One node: a NIR kind and its parameters (float arrays; ``shape`` for Input and Output).

    Examples
    --------
    >>> Node("Scale", {"scale": [2.0]}).params["scale"].dtype
    dtype('float64')
    """

    kind: str
    params: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.kind not in SUPPORTED:
            raise DataError(f"NIR node kind {self.kind!r} is not supported (supported: {', '.join(SUPPORTED)})")
        missing = [p for p in SUPPORTED[self.kind] if p not in self.params]
        if missing:
            raise DataError(f"NIR {self.kind} node lacks {', '.join(missing)}")
        arrays = {k: np.array(v, dtype=np.int64 if k == "shape" else np.float64) for k, v in self.params.items()
                  if k in SUPPORTED[self.kind]}
        for k, a in arrays.items():
            if not np.all(np.isfinite(a)):
                raise DataError(f"NIR {self.kind} node: {k} has a NaN or infinite value")
            a.setflags(write=False)
        object.__setattr__(self, "params", arrays)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Node) or other.kind != self.kind or set(other.params) != set(self.params):
            return False
        return all(np.array_equal(v, other.params[k]) for k, v in self.params.items())

    def __hash__(self) -> int:
        return hash(self.kind)

    @property
    def size_out(self) -> int:
        """Number of outputs of the node (rows of a weight, length of a neuron parameter)."""
        p = self.params
        if self.kind in ("Input", "Output"):
            return int(np.prod(p["shape"]))
        if self.kind in ("Affine", "Linear"):
            return int(p["weight"].shape[0])
        key = {"Scale": "scale", "Threshold": "threshold", "IF": "r", "LIF": "r", "I": "r", "LI": "r"}[self.kind]
        return int(p[key].size)


@dataclass(frozen=True)
class SpikingGraph:
    """A NIR graph held without the ``nir`` package: named nodes, directed edges, metadata.

    Examples
    --------
    >>> g = chain_graph()
    >>> g.input_size, g.output_size, sorted(g.metadata)
    (1, 2, ['slipreflex'])
    """

    nodes: Mapping[str, Node]
    edges: tuple[tuple[str, str], ...]
    metadata: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "edges", tuple((str(a), str(b)) for a, b in self.edges))
        for a, b in self.edges:
            for end in (a, b):
                if end not in self.nodes:
                    raise DataError(f"NIR graph: edge {a} -> {b} names no node {end!r}")
        inputs = [k for k, n in self.nodes.items() if n.kind == "Input"]
        outputs = [k for k, n in self.nodes.items() if n.kind == "Output"]
        if len(inputs) != 1 or len(outputs) != 1:
            raise DataError(f"NIR graph: needs one Input and one Output node, has {len(inputs)} and {len(outputs)}")
        self.order()                       # refuses a node the input does not reach, naming it

    @property
    def input_name(self) -> str:
        """The Input node's name."""
        return next(k for k, n in self.nodes.items() if n.kind == "Input")

    @property
    def output_name(self) -> str:
        """The Output node's name."""
        return next(k for k, n in self.nodes.items() if n.kind == "Output")

    @property
    def input_size(self) -> int:
        """Inputs per time step."""
        return self.nodes[self.input_name].size_out

    @property
    def output_size(self) -> int:
        """Outputs per time step."""
        return self.nodes[self.output_name].size_out

    def predecessors(self, name: str) -> list[str]:
        """Nodes with an edge into ``name``, in edge order."""
        return [a for a, b in self.edges if b == name]

    def order(self) -> list[str]:
        """The nodes in the order a time step computes them: breadth first from the Input.

        An edge from a node later in this order (a cycle's back edge) carries that node's
        output of the previous step; every node must be reachable from the Input.

        Examples
        --------
        >>> chain_graph().order()
        ['input', 'polarity', 'encoder', 'cross', 'output']
        """
        out, queue = [self.input_name], [self.input_name]
        while queue:
            k = queue.pop(0)
            for a, b in self.edges:
                if a == k and b not in out:
                    out.append(b)
                    queue.append(b)
        if len(out) != len(self.nodes):
            cut = sorted(set(self.nodes) - set(out))
            raise DataError(f"NIR graph: {', '.join(cut)} not reachable from the input {self.input_name!r}")
        return out

    def delayed(self) -> set[tuple[str, str]]:
        """The edges that carry the previous step's output (from a node not earlier in :meth:`order`).

        Examples
        --------
        >>> sorted(chain_graph().delayed())
        [('cross', 'encoder')]
        """
        rank = {k: i for i, k in enumerate(self.order())}
        return {(a, b) for a, b in self.edges if rank[a] >= rank[b]}


def chain_graph(threshold: float = 0.008, *, dath: bool = False, fs: float | None = None,
                host: Mapping[str, Any] | None = None) -> SpikingGraph:
    """The spiking graph of the chain's encoder, with the host stages in its metadata.

    Parameters
    ----------
    threshold : float
        The encoder's threshold theta (V); for DATH its base threshold theta0.
    dath : bool
        The DATH graph: the same construction (NIR has no adaptive threshold), marked as
        standing for DATH; docs/method.md gives what it loses.
    fs : float, optional
        The DAQ rate (Hz); default the DAQ's.
    host : mapping, optional
        The chain parameters the host runs around the graph (``cutoff``, ``filter``, ``x0``,
        ``n``, ``kp``, ``ki``, ``reset_after``, ``lo``, ``hi``); default the paper's.

    Returns
    -------
    SpikingGraph

    Examples
    --------
    >>> json.loads(chain_graph(dath=True).metadata[METADATA_KEY])["stands_for"]
    'dath'
    """
    from ..methods.chain.params import ReflexParams  # deferred: heavy (scipy, via the chain's filter design)

    theta = float(threshold)
    if not (math.isfinite(theta) and theta > 0):
        raise ParameterError(f"threshold must be > 0 V, got {threshold!r}")
    kwargs = {"threshold": theta, "dath": bool(dath), **({"fs": fs} if fs is not None else {}), **(host or {})}
    p = ReflexParams.from_dict(kwargs)
    if p.variants:
        raise ParameterError(f"the graph stands for the paper's chain; {', '.join(p.variants)} is not exported")
    record = {"stands_for": p.name, "fs": p.fs, "cutoff": p.cutoff, "filter": p.filter, "x0": p.x0,
              "threshold": p.threshold, "dath_samples": p.dath_samples if p.dath else None,
              "n": p.n, "kp": p.kp, "ki": p.ki, "reset_after": p.reset_after, "lo": p.lo, "hi": p.hi,
              "time_step": "one DAQ sample", "input": "d_k = x_k - x_(k-1) of the low-passed signal, V per sample",
              "output": "spikes of ON (0) and OFF (1); either is the chain's event y_k"}
    nodes = {
        "input": Node("Input", {"shape": [1]}),
        "polarity": Node("Affine", {"weight": [[1.0], [-1.0]], "bias": [0.0, 0.0]}),
        "encoder": Node("IF", {"r": [1.0, 1.0], "v_threshold": [theta, theta], "v_reset": [0.0, 0.0]}),
        "cross": Node("Linear", {"weight": [[0.0, theta], [theta, 0.0]]}),
        "output": Node("Output", {"shape": [2]}),
    }
    edges = (("input", "polarity"), ("polarity", "encoder"), ("encoder", "cross"), ("cross", "encoder"),
             ("encoder", "output"))
    return SpikingGraph(nodes, edges, {METADATA_KEY: json.dumps(record, sort_keys=True)})


def host_params(graph: SpikingGraph, **overrides: Any):
    """The chain parameters the host runs around ``graph`` (from its metadata; else the paper's).

    The encoder fields (threshold, DATH) are the graph's business: they are kept from the
    metadata for the record but the reflex never runs the chain's encoder.

    Returns
    -------
    slipreflex.methods.chain.ReflexParams

    Examples
    --------
    >>> host_params(chain_graph(), p0=120.0).p0
    120.0
    """
    from ..methods.chain.params import ReflexParams  # deferred: heavy (scipy, via the chain's filter design)

    raw = graph.metadata.get(METADATA_KEY)
    record: dict[str, Any] = {}
    if raw is not None:
        try:
            record = dict(json.loads(raw if isinstance(raw, str) else bytes(raw).decode()))
        except (ValueError, TypeError) as err:
            raise DataError(f"NIR graph metadata {METADATA_KEY!r} is not JSON: {err}") from None
    keep = ("fs", "cutoff", "filter", "x0", "threshold", "n", "kp", "ki", "reset_after", "lo", "hi")
    fields = {k: record[k] for k in keep if k in record}
    fields["dath"] = record.get("stands_for") == "dath"
    return ReflexParams.from_dict({**fields, **overrides})


# --- NIR proper (the `neuro` extra) ----------------------------------------------------------------

def _nir():
    try:
        import nir  # deferred: optional extra (nir, pip install slipreflex[neuro])
    except ImportError:
        raise ParameterError("NIR graphs need the 'nir' package: pip install 'slipreflex[neuro]'") from None
    return nir


def to_nir(graph: SpikingGraph):
    """The graph as a ``nir.NIRGraph`` (needs the ``neuro`` extra).

    Examples
    --------
    >>> type(to_nir(chain_graph())).__name__        # doctest: +SKIP
    'NIRGraph'
    """
    nir = _nir()
    made = {}
    for name, node in graph.nodes.items():
        p = {k: np.asarray(v) for k, v in node.params.items()}
        if node.kind == "Input":
            made[name] = nir.Input(input_type={"input": p["shape"]})
        elif node.kind == "Output":
            made[name] = nir.Output(output_type={"output": p["shape"]})
        else:
            made[name] = getattr(nir, node.kind)(**p)
    return nir.NIRGraph(nodes=made, edges=list(graph.edges), metadata=dict(graph.metadata))


def from_nir(nir_graph) -> SpikingGraph:
    """A ``nir.NIRGraph`` as a :class:`SpikingGraph` (an unsupported node is refused, named).

    Examples
    --------
    >>> from_nir(to_nir(chain_graph())) == chain_graph()      # doctest: +SKIP
    True
    """
    nodes = {}
    for name, node in nir_graph.nodes.items():
        kind = type(node).__name__
        if kind not in SUPPORTED:
            raise DataError(f"NIR graph node {name!r} is a {kind}, which slipreflex does not run "
                            f"(supported: {', '.join(SUPPORTED)})")
        if kind == "Input":
            params = {"shape": np.asarray(next(iter(node.input_type.values())))}
        elif kind == "Output":
            params = {"shape": np.asarray(next(iter(node.output_type.values())))}
        else:
            params = {k: np.asarray(getattr(node, k)) for k in SUPPORTED[kind]}
        nodes[str(name)] = Node(kind, params)
    meta = {str(k): (v.decode() if isinstance(v, bytes) else v) for k, v in (nir_graph.metadata or {}).items()}
    return SpikingGraph(nodes, tuple(tuple(e) for e in nir_graph.edges), meta)


def write_graph(graph: SpikingGraph, path: str | Path) -> Path:
    """Write ``graph`` as a ``.nir`` file (NIR's HDF5 format; needs the ``neuro`` extra).

    Examples
    --------
    >>> write_graph(chain_graph(), "fixed.nir")       # doctest: +SKIP
    PosixPath('fixed.nir')
    """
    nir = _nir()
    path = Path(path)
    nir.write(str(path), to_nir(graph))
    return path


def read_graph(path: str | Path) -> SpikingGraph:
    """Read a ``.nir`` file as a :class:`SpikingGraph` (one-line errors naming the file).

    Examples
    --------
    >>> read_graph("fixed.nir").input_size             # doctest: +SKIP
    1
    """
    nir = _nir()
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: no such NIR graph file")
    try:
        loaded = nir.read(str(path))
    except Exception as err:   # h5py and nir raise many kinds; the user needs the file and the reason
        raise DataError(f"{path}: not a NIR graph ({type(err).__name__}: {err})") from None
    try:
        return from_nir(loaded)
    except DataError as err:
        raise DataError(f"{path}: {err}") from None
