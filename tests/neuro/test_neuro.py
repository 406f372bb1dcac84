"""The chain's encoder as a NIR graph: its construction, its executor, its distance to Eq. 1-2, the nir method."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from slipreflex import methods
from slipreflex.core.errors import DataError
from slipreflex.methods.chain import run_chain
from slipreflex.neuro.graph import METADATA_KEY, Node, SpikingGraph, chain_graph, host_params
from slipreflex.neuro.interpreter import GraphExecutor
from slipreflex.neuro.method import NIRReflex, graph_spikes
from slipreflex.testing import check_method

THETA = 0.008


def _chain_polarity(raw, **kw):
    res = run_chain(raw, **kw)
    return np.where(res.events, np.sign(res.accumulator), 0).astype(int), res


def test_the_graph_is_an_affine_split_into_two_if_neurons_with_a_cross_reset():
    g = chain_graph(THETA)
    assert [g.nodes[k].kind for k in g.order()] == ["Input", "Affine", "IF", "Linear", "Output"]
    assert g.nodes["polarity"].params["weight"].tolist() == [[1.0], [-1.0]]
    enc = g.nodes["encoder"].params
    assert enc["v_threshold"].tolist() == [THETA, THETA] and enc["v_reset"].tolist() == [0.0, 0.0]
    assert g.nodes["cross"].params["weight"].tolist() == [[0.0, THETA], [THETA, 0.0]]
    assert g.delayed() == {("cross", "encoder")}
    record = json.loads(g.metadata[METADATA_KEY])
    assert record["stands_for"] == "fixed" and record["n"] == 16 and record["kp"] == 5.0


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_on_a_signal_that_never_turns_the_graph_fires_exactly_the_chains_spikes(sign):
    # One polarity only: each IF neuron is Eq. 1-2 exactly (integrate, strictly above theta, reset to 0).
    rng = np.random.default_rng(3)
    raw = 0.4 + sign * np.cumsum(rng.uniform(0.0, 0.003, 400))
    chain_pol, _ = _chain_polarity(raw)
    assert np.count_nonzero(chain_pol) > 20
    assert graph_spikes(chain_graph(), raw).tolist() == chain_pol.tolist()


def test_where_the_signal_turns_the_graph_loses_the_overshoot_of_the_other_neuron():
    # A rise of 1.5 theta fires ON (the chain's accumulator back to 0); OFF got only +theta back,
    # so it sits 0.5 theta lower than the chain's accumulator: a fall of 1.2 theta fires the chain, not the graph.
    d = np.array([0.0, 1.5, -1.2, 0.0]) * THETA
    chain_pol, _ = _chain_polarity(np.cumsum(d) + 0.4, filter=False)
    graph_pol = graph_spikes(chain_graph(), np.cumsum(d) + 0.4, filter=False)
    assert chain_pol.tolist() == [0, 1, -1, 0]
    assert graph_pol.tolist() == [0, 1, 0, 0]


def test_the_executor_reads_nir_if_literally():
    g = chain_graph(threshold=0.5)
    out = GraphExecutor(g).run(np.array([0.5, 0.01, 0.6, -0.2]))
    # 0.5 is not above 0.5 (strict); 0.51 is; then reset to 0, so 0.6 fires again at once
    assert out[:, 0].tolist() == [0.0, 1.0, 1.0, 0.0]


def test_a_graph_the_executor_cannot_run_is_refused_by_name():
    with pytest.raises(DataError, match="'Conv3d' is not supported"):
        Node("Conv3d", {})
    nodes = {"in": Node("Input", {"shape": [1]}), "out": Node("Output", {"shape": [1]}),
             "lost": Node("Scale", {"scale": [1.0]})}
    with pytest.raises(DataError, match="lost not reachable"):
        SpikingGraph(nodes, (("in", "out"),))
    with pytest.raises(DataError, match="NaN"):
        Node("Scale", {"scale": [math.nan]})


def test_the_host_reads_its_stages_from_the_graphs_metadata():
    g = chain_graph(0.01, host={"n": 8, "kp": 3.0, "cutoff": 20.0})
    p = host_params(g, p0=50.0)
    assert (p.n, p.kp, p.cutoff, p.threshold, p.p0) == (8, 3.0, 20.0, 0.01, 50.0)


@pytest.mark.slow
def test_the_nir_reflex_with_the_exported_graph_gives_the_chains_commands_where_the_spikes_agree():
    rng = np.random.default_rng(5)
    raw = 0.4 + np.cumsum(rng.uniform(0.0, 0.002, 1600))      # rising: the graph is exact here
    res = run_chain(raw, p0=120.0)
    r = NIRReflex(p0=120.0)
    got = [c for c in (r.step(float(v)) for v in raw) if c is not None]
    assert got == res.commands.tolist() and res.commands[-1] > 120.0


def test_the_nir_reflex_skips_a_nan_sample_as_the_chain_does():
    r = NIRReflex(p0=100.0)
    assert r.step(math.nan) is None and not r.last_event and math.isnan(r.last_filtered)
    assert r.step(0.4) is None and r.last_filtered == pytest.approx(0.4)


@pytest.mark.slow
def test_the_nir_method_is_registered_and_keeps_the_reflex_contract():
    assert "nir" in methods.names() and "nir" not in methods.names(paper=True)
    report = check_method("nir")
    assert report.commands > 0 and report.events > 0


@pytest.mark.slow
def test_reproduce_runs_the_exported_graph_beside_the_chain_and_reports_both(tmp_path):
    import csv

    from slipreflex.cli import main
    from slipreflex.neuro.graph import write_graph

    pytest.importorskip("nir", reason="the neuro extra (pip install 'slipreflex[neuro]')")
    graph = write_graph(chain_graph(), tmp_path / "fixed.nir")
    default = methods.get("nir")
    try:
        code = main(["reproduce", "--methods", "fixed,nir", "--nir-graph", str(graph), "--trials", "1",
                     "--bottles", "TR", "--jobs", "1", "--no-figures", "--no-progress", "--out", str(tmp_path / "o")])
        assert methods.get("nir").build.args == (str(graph),)        # the method runs the file given
    finally:
        methods.register(default, replace=True)
    assert code == 0
    rows = list(csv.DictReader((tmp_path / "o" / "summary.csv").read_text().splitlines()))
    got = {(r["experiment"], r["method"]): r for r in rows}
    for exp in ("drop", "pour"):
        assert {(exp, "fixed"), (exp, "nir")} <= set(got)
        # the first spike after rest is a rise or a fall from the chain's own state: the same response
        assert got[(exp, "nir")]["response_mean_ms"] == got[(exp, "fixed")]["response_mean_ms"]
    assert "NIR graph" in (tmp_path / "o" / "report.md").read_text()


def test_nir_export_and_spikes_refuse_a_taken_name_even_a_dangling_link(tmp_path, capsys):
    from slipreflex.cli import main

    outside = tmp_path / "outside"
    (tmp_path / "g.nir").symlink_to(outside)
    assert main(["nir", "export", "-o", str(tmp_path / "g.nir")]) == 2
    (tmp_path / "s.npy").symlink_to(outside)
    example = Path(__file__).resolve().parents[2] / "examples" / "slip_example.csv"
    assert main(["spikes", str(example), "-o", str(tmp_path / "s"), "--format", "tonic"]) == 2
    err = capsys.readouterr().err
    assert err.count("exists;") == 2 and not outside.exists()
