"""``slipreflex nir``: the chain as a NIR graph (export, agreement with Eq. 1-9, a graph's summary).

Examples
--------
>>> from slipreflex.cli import main
>>> main(["nir", "export", "-o", "fixed.nir"])                    # doctest: +SKIP
wrote fixed.nir (fixed-threshold chain: Input -> Affine -> IF -> Output, theta 0.008 V)
>>> main(["nir", "agreement", "--backends", "reference,spyx"])    # doctest: +SKIP
"""

from __future__ import annotations

import argparse
import json
import math
import os
from pathlib import Path
from typing import Any

from .. import methods
from ..core.errors import ParameterError
from ..neuro import agreement as ag
from ..neuro.agreement import measure
from ..neuro.backends import BACKENDS, available
from ..neuro.graph import METADATA_KEY, chain_graph, read_graph, write_graph

NAME = "nir"
HELP = "the chain as a NIR graph: export it, measure it against the chain (Eq. 1-9), show a graph"
ORDER = 36


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex nir``."""
    p.add_argument("action", choices=ACTIONS,
                   help="export: write the fixed-threshold (or DATH) graph as a .nir file; agreement: the graphs "
                        "against the chain, per stage and per backend; show: a .nir file's nodes, edges and the "
                        "chain it stands for")
    p.add_argument("file", type=Path, nargs="?", default=None, help="show: the .nir file")
    p.add_argument("-o", "--out", type=Path, default=None, help="export: the .nir file to write (a new file)")
    p.add_argument("--graph", choices=("fixed", "dath"), default="fixed",
                   help="export: fixed, the fixed-threshold chain (default); dath, DATH's closest graph")
    p.add_argument("--threshold", type=float, default=0.008, help="export: theta (theta0 for dath), V (0.008)")
    p.add_argument("--backends", default="reference,spyx,nengo",
                   help="agreement: comma-separated reference (the package's executor), spyx, nengo (default: all)")
    p.add_argument("--no-simulated", action="store_true", help="agreement: only the shipped recordings")
    p.add_argument("--stages", action="store_true", help="agreement: print the per-stage table instead")


#: What ``slipreflex nir`` does.
ACTIONS: tuple[str, ...] = ("export", "agreement", "show")


def add_graph_option(p: Any) -> None:
    """``--nir-graph FILE`` for the commands that run a registered method (reproduce, run, virtual-rig)."""
    p.add_argument("--nir-graph", type=Path, default=None, metavar="FILE.nir",
                   help="the graph --method(s) nir runs (default: the fixed-threshold chain's, as 'nir export' "
                        "writes it)")


def apply_graph_option(args: argparse.Namespace) -> None:
    """Read ``--nir-graph`` (errors before any work) and bind the ``nir`` method to it."""
    path = getattr(args, "nir_graph", None)
    if path is None:
        return
    read_graph(path)                                   # a bad file: one line, before any work
    methods.register(methods.nir_method(str(path)), replace=True)


def _export(args: argparse.Namespace) -> int:
    if args.out is None:
        raise ParameterError("nir export needs -o FILE.nir")
    if not (math.isfinite(args.threshold) and args.threshold > 0):
        raise ParameterError(f"--threshold must be > 0 V, got {args.threshold}")
    if os.path.lexists(args.out):  # a dangling symlink too: the writer would follow it
        raise ParameterError(f"{args.out}: exists; nir export writes a new file (give another --out)")
    graph = chain_graph(args.threshold, dath=args.graph == "dath")
    write_graph(graph, args.out)
    what = "fixed-threshold chain" if args.graph == "fixed" else "DATH's closest graph (no adaptive threshold)"
    kinds = " -> ".join(graph.nodes[k].kind for k in graph.order())
    print(f"wrote {args.out} ({what}: {kinds}, theta {args.threshold:g} V)")
    return 0


def _agreement(args: argparse.Namespace) -> int:
    names = [b.strip() for b in args.backends.split(",") if b.strip()]
    for b in names:
        if b not in BACKENDS:
            raise ParameterError(f"--backends: unknown {b!r} (known: {', '.join(BACKENDS)})")
        if not available(b):
            raise ParameterError(f"--backends: {b} is not installed (pip install 'slipreflex[neuro]')")
    rows = measure(tuple(names), simulated=not args.no_simulated)
    print(ag.stage_table(rows) if args.stages else ag.table(rows))
    return 0


def _show(args: argparse.Namespace) -> int:
    if args.file is None:
        raise ParameterError("nir show needs the .nir FILE")
    g = read_graph(args.file)
    for name in g.order():
        node = g.nodes[name]
        params = ", ".join(f"{k}={v.tolist()}" for k, v in node.params.items())
        print(f"{name}: {node.kind}({params})")
    print("edges: " + ", ".join(f"{a} -> {b}" for a, b in g.edges))
    raw = g.metadata.get(METADATA_KEY)
    if raw is not None:
        print("stands for: " + json.dumps(json.loads(raw), sort_keys=True))
    return 0


def run(args: argparse.Namespace) -> int:
    """Do the action."""
    return {"export": _export, "agreement": _agreement, "show": _show}[args.action](args)
