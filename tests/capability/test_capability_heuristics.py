"""Chapter 3 heuristics: DTAA (Algorithm 2 on a graph, Theorem 3.5), GA and MC per class."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

import taopt
from taopt.capability import CapabilityProblem
from taopt.capability.instances import thesis_scenario
from taopt.errors import InstanceError
from taopt.heuristics.clustering import evm, marginal_cost_sequence
from taopt.heuristics.dtaa import (
    ENTRY_BYTES,
    HEADER_BYTES,
    distributed_auction,
    dtaa,
    ordering_principle,
)
from taopt.orchestration.studies.capability_claims import (
    communication_graphs,
    random_problem,
    split_graph,
)
from taopt.routing.bounds import mcga_tree
from taopt.routing.problem import AssignmentProblem


def algorithm1_clusters(problem: CapabilityProblem) -> dict:
    """Algorithm 1's target set of every vehicle, per class (whole-problem indices)."""
    out = {}
    for cls in problem.classes:
        if cls.problem is None:
            continue
        tree = mcga_tree(cls.problem)
        for local, vehicle in enumerate(cls.vehicles):
            out[cls.capability, vehicle] = {
                cls.targets[t] for t in np.flatnonzero(tree.vehicle == local)
            }
    return out


def auction_clusters(problem: CapabilityProblem, graph) -> dict:
    auction = distributed_auction(problem, graph)
    assert auction.connected
    out = {}
    for result in auction.classes:
        assert result.consensus  # every vehicle saw the same (r*, winner) at every step
        for vehicle in [
            k for k, c in enumerate(problem.vehicle_capability) if c == result.capability
        ]:
            out[result.capability, vehicle] = set(result.assigned[vehicle])
    return out


@pytest.mark.parametrize("seed", range(8))
def test_theorem_3_5_on_complete_path_and_random_graphs(seed):
    """DTAA's assignment equals Algorithm 1's per class on three connected topologies."""
    rng = np.random.default_rng(seed)
    if seed < 3:
        problem = thesis_scenario(12, 5, 1 + seed, seed=seed).problem
    else:
        problem = random_problem("metric", 9, int(rng.integers(2, 6)), 2, rng)
    expected = algorithm1_clusters(problem)
    for name, graph in communication_graphs(problem.m, rng).items():
        assert nx.is_connected(graph), name
        assert auction_clusters(problem, graph) == expected, name


def test_dtaa_equals_evm_per_class():
    """DTAA = chapter 2's EVM on each class (Algorithm 1 clusters + (2.18) = (3.10))."""
    problem = thesis_scenario(30, 6, 3, seed=11).problem
    total = sum(evm(c.problem).objective for c in problem.classes if c.problem)
    assert dtaa(problem).objective == pytest.approx(total, rel=1e-12)


def test_ordering_principle_matches_chapter_2():
    """(3.10)-(3.11) gives the same sequence as chapter 2's (2.18) on random matrices."""
    rng = np.random.default_rng(0)
    for trial in range(60):
        k = int(rng.integers(1, 14))
        cost = rng.uniform(1, 100, (k + 1, k + 1))
        if trial % 2:
            cost = cost + cost.T
        problem = AssignmentProblem(cost, k)
        targets = list(rng.permutation(k))
        assert ordering_principle(problem.cost, k, targets) == marginal_cost_sequence(
            problem, 0, targets
        )


def test_communication_counts_follow_the_byte_model():
    """rounds = sum_q |T_q| |R|; messages = rounds * 2|E|; bytes = 8 + 12 |T_q^u| each."""
    problem = thesis_scenario(7, 4, 2, seed=2).problem
    graph = nx.path_graph(4)
    solution = taopt.solve(problem, "DTAA", graph=graph)
    m, edges = problem.m, graph.number_of_edges()
    sizes = [len(c.targets) for c in problem.classes if c.targets]
    assert solution.info["rounds"] == sum(s * m for s in sizes)
    assert solution.info["messages"] == solution.info["rounds"] * 2 * edges
    expected = sum(
        m * 2 * edges * (HEADER_BYTES + ENTRY_BYTES * left)
        for size in sizes
        for left in range(size, 0, -1)
    )
    assert solution.info["bytes"] == expected
    assert solution.info["computed_rounds"] == sum(s * 3 for s in sizes)  # path diameter 3
    complete = taopt.solve(problem, "DTAA")
    assert complete.info["messages"] == complete.info["rounds"] * m * (m - 1)
    assert complete.objective == solution.objective


def test_directed_ring_is_enough():
    """A strongly connected directed ring (j hears j - 1) gives the same assignment."""
    problem = random_problem("metric", 8, 4, 2, np.random.default_rng(5))
    ring = nx.DiGraph([(j, (j + 1) % 4) for j in range(4)])
    assert auction_clusters(problem, ring) == algorithm1_clusters(problem)


def test_disconnected_graph_serves_a_target_twice_and_is_refused():
    """Two components each holding class vehicles both take every target of the class."""
    x = np.array([5.0, 6.0, 0.0, 10.0])  # targets at 5 and 6; two vehicles of class a
    problem = CapabilityProblem(abs(x[:, None] - x[None, :]), 2, ["a", "a"], [{"a"}, {"a"}])
    auction = distributed_auction(problem, split_graph(2))
    assert not auction.connected and auction.components == [[0], [1]]
    served = auction.served()
    assert served[0, "a"] == [0, 1] and served[1, "a"] == [0, 1]  # each component took both
    with pytest.raises(InstanceError, match=r"disconnected \(components \[\[0\], \[1\]\]\)"):
        taopt.solve(problem, "DTAA", graph=split_graph(2))


def test_disconnected_component_without_the_class_takes_nothing():
    """A component with no vehicle of class q hears no finite bid and wins nothing."""
    x = np.array([5.0, 0.0, 10.0])
    problem = CapabilityProblem(abs(x[:, None] - x[None, :]), 1, ["a", "b"], [{"a"}])
    auction = distributed_auction(problem, nx.empty_graph(2))
    assert auction.served() == {(0, "a"): [0]}


def test_graph_validation():
    """Graph nodes must be vehicle indices; a missing vehicle is isolated (disconnected)."""
    problem = random_problem("metric", 4, 3, 1, np.random.default_rng(1))
    with pytest.raises(InstanceError, match="graph node 7 is not a vehicle index"):
        dtaa(problem, graph=nx.path_graph([0, 1, 7]))
    with pytest.raises(InstanceError, match="disconnected"):
        dtaa(problem, graph=nx.path_graph(2))


def test_ga_per_class_is_seeded_and_sized():
    """Same seed, same routes; population 3(|T_q| + |R_q|) per class (§3.7)."""
    problem = thesis_scenario(12, 4, 2, seed=3).problem
    a = taopt.solve(problem, "GA", seed=5, generations=30)
    b = taopt.solve(problem, "GA", seed=5, generations=30)
    assert a.routes == b.routes and a.objective == b.objective
    sizes = [3 * (len(c.targets) + len(c.vehicles)) for c in problem.classes if c.problem]
    assert [c["population"] for c in a.info["per_class"]] == sizes
    exact = taopt.solve(problem, "exact")
    assert a.objective >= exact.objective * (1 - 1e-9)


def test_mc_per_class_sums_chapter_2_mc():
    """MC per class = the sum of chapter 2's MC on each class problem."""
    from taopt.heuristics.clustering import mc

    problem = thesis_scenario(20, 5, 3, seed=9).problem
    total = sum(mc(c.problem).objective for c in problem.classes if c.problem)
    assert taopt.solve(problem, "MC").objective == pytest.approx(total, rel=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_complete_graph_shortcut_is_the_simulation(seed):
    """The complete-graph shortcut gives the per-vehicle simulation's result, pick for pick."""
    rng = np.random.default_rng(seed)
    problem = random_problem("metric", int(rng.integers(1, 14)), int(rng.integers(1, 6)), 1, rng)
    fast = distributed_auction(problem)
    slow = distributed_auction(problem, shortcut=False)
    for a, b in zip(fast.classes, slow.classes, strict=True):
        assert (a.assigned, a.picks, a.bytes, a.messages) == (
            b.assigned,
            b.picks,
            b.bytes,
            b.messages,
        )
