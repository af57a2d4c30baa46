"""The one dense Chu–Liu/Edmonds (:mod:`taopt.arborescence`), checked against networkx."""

from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest

from taopt.arborescence import degree_penalised_arborescence, min_arborescence
from taopt.errors import InstanceError


def networkx_value(weights: np.ndarray, root: int) -> float:
    """networkx's minimum spanning arborescence forced to ``root`` (no edge enters it)."""
    size = len(weights)
    graph = nx.DiGraph()
    graph.add_nodes_from(range(size))
    for u, v in itertools.permutations(range(size), 2):
        if v != root and np.isfinite(weights[u, v]):
            graph.add_edge(u, v, weight=float(weights[u, v]))
    try:
        tree = nx.minimum_spanning_arborescence(graph, preserve_attrs=True)
    except nx.NetworkXException:  # no spanning arborescence
        return float("inf")
    assert [v for v, d in tree.in_degree() if d == 0] == [root]
    return float(sum(d["weight"] for *_, d in tree.edges(data=True)))


@pytest.mark.parametrize("seed", range(4))
def test_matches_networkx_on_random_dense_digraphs(seed):
    """Random sizes, densities, roots; integer weights in half the cases (many ties)."""
    rng = np.random.default_rng(seed)
    unreachable = 0
    for trial in range(40):
        size = int(rng.integers(2, 16))
        weights = rng.uniform(0, 10, (size, size))
        if trial % 2:
            weights = np.round(weights)
        weights[rng.random((size, size)) < rng.uniform(0, 0.7)] = np.inf  # missing edges
        root = int(rng.integers(size))
        expected = networkx_value(weights, root)
        value = min_arborescence(weights, root)
        if np.isinf(expected):
            unreachable += 1
            assert value == np.inf
        else:
            assert value == pytest.approx(expected, rel=1e-12, abs=1e-12)
    assert 0 < unreachable < 40  # both outcomes were exercised


def test_larger_graph_with_nested_cycles():
    """40 vertices, cheap back edges that make the greedy choice cycle at several levels."""
    rng = np.random.default_rng(7)
    weights = rng.uniform(50, 100, (40, 40))
    order = rng.permutation(40)
    weights[order[1:], order[:-1]] = rng.uniform(0, 1, 39)  # cheap edges backwards
    assert min_arborescence(weights, int(order[0])) == pytest.approx(
        networkx_value(weights, int(order[0])), rel=1e-12
    )


def test_cycle_trap_and_unreachable_vertex():
    """Cheapest in-edges 1 -> 2 -> 1 form a cycle; Edmonds must break it.

    Root 0 -> 1 (10), 0 -> 2 (12), 1 -> 2 (1), 2 -> 1 (1): best is 0 -> 1 -> 2 = 11.
    """
    inf = np.inf
    weights = np.array([[inf, 10, 12], [inf, inf, 1], [inf, 1, inf]])
    assert min_arborescence(weights, root=0) == 11.0
    weights[0, 1] = weights[0, 2] = inf
    assert min_arborescence(weights, root=0) == inf
    assert min_arborescence(np.zeros((1, 1)), root=0) == 0.0


def test_input_is_not_modified_and_bad_input_is_clear():
    weights = np.array([[0.0, 1.0], [2.0, 0.0]])
    copy = weights.copy()
    assert min_arborescence(weights, 1) == 2.0
    assert (weights == copy).all()
    with pytest.raises(InstanceError, match="square"):
        min_arborescence(np.zeros((2, 3)), 0)
    with pytest.raises(InstanceError, match="NaN"):
        min_arborescence(np.array([[0, np.nan], [1, 0]]), 0)
    with pytest.raises(InstanceError, match="root"):
        min_arborescence(weights, 2)


# -- the tree on request and the degree-penalised arborescence (moved from
# test_delivery_bounds.py with the code, from taopt.delivery.relaxation)
REL = 1e-9


def _is_arborescence(parent: np.ndarray, root: int) -> bool:
    graph = nx.DiGraph([(int(p), v) for v, p in enumerate(parent) if v != root])
    graph.add_nodes_from(range(len(parent)))
    return parent[root] == -1 and nx.is_arborescence(graph)


@pytest.mark.parametrize("seed", range(30))
def test_min_arborescence_tree_matches_edmonds(seed):
    """The hand-written Edmonds returns the reference weight and a tree of that weight."""
    rng = np.random.default_rng(seed)
    size = int(rng.integers(2, 30))
    weights = rng.uniform(-5.0, 20.0, size=(size, size)).round(int(rng.integers(0, 3)))
    weights[rng.random((size, size)) < 0.3] = np.inf
    weights[0, 1:] = np.where(np.isfinite(weights[0, 1:]), weights[0, 1:], 50.0)
    value, parent = min_arborescence(weights, 0, tree=True)
    assert value == pytest.approx(min_arborescence(weights, 0), rel=REL, abs=1e-9)
    assert _is_arborescence(parent, 0)
    tree_weight = sum(weights[parent[v], v] for v in range(1, size))
    assert tree_weight == pytest.approx(value, rel=REL, abs=1e-9)


def test_min_arborescence_tree_unreachable():
    """A vertex without in-edges: no arborescence (inf, None)."""
    weights = np.array([[0.0, 1.0, np.inf], [1.0, 0.0, np.inf], [1.0, 1.0, 0.0]])
    assert min_arborescence(weights, 0, tree=True) == (np.inf, None)


def test_degree_penalised_arborescence_finds_a_forced_path():
    """On a line graph whose arborescence is a star, the Lagrangian reaches the path's cost."""
    # root 0 and points 1, 2, 3: a star from 0 costs 3, any path 0-1-2-3 costs 1 + 1 + 1 = 3,
    # but 0 -> 1 (1), 0 -> 2 (1.1), 0 -> 3 (1.2) with 1 -> 2, 2 -> 3 costing 1.5: star 3.3,
    # best path 0 -> 1 -> 2 -> 3 = 4.0
    w = np.full((4, 4), np.inf)
    w[0, 1:] = [1.0, 1.1, 1.2]
    w[1, 2] = w[2, 3] = 1.5
    w[1, 3] = w[3, 2] = w[2, 1] = w[3, 1] = 5.0
    capacity = np.array([1.0, 1.0, 1.0, np.inf])
    result = degree_penalised_arborescence(w, 0, capacity, np.ones(4, dtype=bool), target=4.0)
    assert result.arborescence == pytest.approx(3.3)
    assert result.arborescence < result.value <= 4.0 + 1e-9
