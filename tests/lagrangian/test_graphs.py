"""nhham.lagrangian.graphs: the union-find components agree with networkx's on random
graphs, and the provenance data gives the DiGraph networkx would build step by step."""

import random

import networkx as nx
import pytest

from nhham.lagrangian.graphs import Provenance, connected_components


@pytest.mark.parametrize("seed", range(20))
def test_components_agree_with_networkx(seed):
    rng = random.Random(seed)
    n = rng.randint(1, 25)
    edges = [(rng.randrange(n), rng.randrange(n)) for _ in range(rng.randint(0, 2 * n))]
    G = nx.Graph()
    G.add_nodes_from(range(n))
    G.add_edges_from(edges)
    want = sorted(sorted(c) for c in nx.connected_components(G))
    got = connected_components(range(n), edges)
    assert sorted(sorted(c) for c in got) == want
    assert [c[0] for c in got] == sorted(c[0] for c in got)      # order of first node
    assert all(c == sorted(c) for c in got)                     # each in node order


def test_provenance_graph_matches_a_graph_built_step_by_step():
    G = nx.DiGraph()
    p = Provenance()
    for lab, kind in (("constraints[0]", "primary"), ("holonomic[0]", "holonomic"),
                      ("holonomic[0].lift", "lift")):
        G.add_node(lab, stage=1, kind=kind)
        p = p.with_node(lab, stage=1, kind=kind)
    G.add_node("secondary[0]", stage=2, kind="secondary")
    G.add_edge("constraints[0]", "secondary[0]", stage=1)
    G.add_edge("holonomic[0].lift", "secondary[0]", stage=1)
    p = p.with_node("secondary[0]", stage=2, kind="secondary")
    p = p.with_edge("constraints[0]", "secondary[0]", stage=1)
    p = p.with_edge("holonomic[0].lift", "secondary[0]", stage=1)
    G.add_edge("holonomic[0]", "holonomic[0].lift", stage=1)
    p = p.with_edge("holonomic[0]", "holonomic[0].lift", stage=1)
    for node in G.nodes:
        G.nodes[node]["block"] = "x,y"
    p = p.with_attribute("block", "x,y")
    other = Provenance().with_node("constraints[1]", stage=1, kind="primary")
    H = nx.DiGraph()
    H.add_node("constraints[1]", stage=1, kind="primary")
    both = Provenance.union([p, other]).graph()
    want = nx.compose_all([G, H])
    assert list(both.nodes(data=True)) == list(want.nodes(data=True))
    assert list(both.edges(data=True)) == list(want.edges(data=True))
    assert p.labels(kind="secondary") == ("secondary[0]",)
    assert p.has_node("holonomic[0]") and not p.has_node("secondary[1]")


def test_docstring_examples():
    import doctest

    from nhham.lagrangian import graphs

    assert doctest.testmod(graphs).failed == 0
