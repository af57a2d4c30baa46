"""Chapter 2 bounds: Algorithm 1 as printed, the valid arborescence bound, f_da, the LP bound."""

from __future__ import annotations

import numpy as np
import pytest

import taopt
import taopt.bounds
import taopt.heuristics
from taopt.errors import InstanceError
from taopt.orchestration.studies.routing_claims import exact_optimum
from taopt.routing import bounds


def small_problems(count: int, seed: int, symmetric: bool | None = None, max_n: int = 7):
    """Random small instances; ``symmetric`` True/False forces the class, None mixes."""
    rng = np.random.default_rng(seed)
    for index in range(count):
        n = int(rng.integers(1, max_n + 1))
        m = int(rng.integers(1, 4))
        sym = bool(index % 2) if symmetric is None else symmetric
        if sym:
            pts = rng.uniform(0, 100, size=(n + m, 2))
            cost = np.linalg.norm(pts[:, None] - pts[None], axis=2)
        else:
            cost = rng.uniform(0, 100, size=(n + m, n + m))
        yield taopt.AssignmentProblem(cost, n)


def test_greedy_trap_by_hand():
    """One vehicle (point 2), targets 0 and 1 (the docstring example of thesis_mcga).

    t(2,0) = 1, t(2,1) = 10, t(0,1) = 10, t(1,0) = 0 (a metric matrix).
    Algorithm 1 adds target 0 (1), then target 1 from {2, 0} (10): f_a = 11.
    The optimum is 2 -> 1 -> 0 = 10 + 0 = 10, and so is the min arborescence
    (edges 2 -> 1, 1 -> 0). Lemma 2.4 (f_a <= f_o) fails here.
    """
    cost = np.array([[0, 10, 9], [0, 0, 9], [1, 10, 0]], dtype=float)
    problem = taopt.AssignmentProblem(cost, 2)
    assert taopt.bounds.thesis_mcga(problem) == 11.0
    assert taopt.bounds.arborescence(problem) == 10.0
    assert exact_optimum(problem)[0] == 10.0
    tree = bounds.mcga_tree(problem)
    assert tree.parent.tolist() == [2, 2] and tree.order.tolist() == [0, 1]
    # f_da duplicates the edges 2 -> 0 and 2 -> 1: (1 + 9) + (10 + 9) = 29.
    assert bounds.f_da(problem) == 29.0


def test_arborescence_never_above_optimum_or_mcga():
    for problem in small_problems(40, seed=0):
        optimum = exact_optimum(problem)[0]
        valid = taopt.bounds.arborescence(problem)
        assert valid <= optimum + 1e-9
        assert valid <= taopt.bounds.thesis_mcga(problem) + 1e-9


def test_dense_edmonds_agrees_with_networkx():
    rng = np.random.default_rng(1)
    for trial in range(60):
        n, m = int(rng.integers(1, 10)), int(rng.integers(1, 4))
        cost = rng.uniform(0, 10, size=(n + m, n + m))
        if trial % 3 == 0:
            cost = np.round(cost)  # many ties
        problem = taopt.AssignmentProblem(cost, n)
        assert bounds.arborescence_bound(problem) == pytest.approx(
            bounds.arborescence_bound(problem, method="networkx"), abs=1e-9
        )


def test_mcga_is_the_min_arborescence_on_symmetric_costs():
    """Prim's growth is optimal for symmetric costs: Lemma 2.4's f_a is valid there."""
    for problem in small_problems(30, seed=2, symmetric=True):
        assert bounds.thesis_mcga(problem) == pytest.approx(bounds.arborescence_bound(problem))
        assert bounds.thesis_mcga(problem) <= exact_optimum(problem)[0] + 1e-9
        # Lemma 2.5, second statement.
        assert bounds.f_da(problem) == pytest.approx(2 * bounds.thesis_mcga(problem))


def test_mcga_tree_is_the_extended_voronoi_clustering():
    """Algorithm 1's subtrees are EV's clusters (2.12)-(2.14), and its value is f_a."""
    from taopt.heuristics.clustering import extended_voronoi_clusters

    for problem in small_problems(20, seed=3):
        tree = bounds.mcga_tree(problem)
        assert tree.value == pytest.approx(bounds.thesis_mcga(problem))
        assert (tree.vehicle == extended_voronoi_clusters(problem)).all()
        # Each edge weight is a real cost; each target's parent is a vehicle or an earlier target.
        rank = {int(k): i for i, k in enumerate(tree.order)}
        for k in range(problem.n):
            assert tree.weight[k] == problem.cost[tree.parent[k], k]
            if tree.parent[k] < problem.n:
                assert rank[int(tree.parent[k])] < rank[k]
                assert tree.vehicle[tree.parent[k]] == tree.vehicle[k]
            else:
                assert tree.vehicle[k] == tree.parent[k] - problem.n


def test_f_da_is_an_upper_bound_on_metric_matrices():
    """Lemma 2.5 (f_o <= f_da) under the triangle inequality, with either tree."""
    from scipy.sparse.csgraph import shortest_path

    rng = np.random.default_rng(4)
    for _ in range(30):
        n, m = int(rng.integers(1, 7)), int(rng.integers(1, 4))
        cost = shortest_path(rng.uniform(1, 50, size=(n + m, n + m)), directed=True)
        problem = taopt.AssignmentProblem(cost, n)
        optimum = exact_optimum(problem)[0]
        assert optimum <= bounds.f_da(problem) + 1e-9
        assert optimum <= bounds.f_da(problem, tree="edmonds") + 1e-9


def test_f_da_rejects_unknown_tree():
    problem = next(small_problems(1, seed=5))
    with pytest.raises(InstanceError, match="tree"):
        bounds.f_da(problem, tree="prim")
    with pytest.raises(InstanceError, match="method"):
        bounds.arborescence_bound(problem, method="prim")


def test_lp_bound_is_valid():
    """The LP relaxation of helper-2's model is a lower bound (fails loudly if missing)."""
    for problem in small_problems(4, seed=6, max_n=6):
        lp = taopt.models.lp_bound(problem)  # DFJ: all of (2.5)
        assert lp <= exact_optimum(problem)[0] + 1e-6
        assert lp >= bounds.arborescence_bound(problem) - 1e-6


@pytest.mark.parametrize("seed", range(4))
def test_core_dfj_lp_bound_equals_the_models_lp_and_is_valid(seed):
    """The core's DFJ LP (taopt.routing.bounds.lp_bound) equals taopt.models.lp_bound and is
    never above the brute-force optimum (asymmetric costs)."""
    from reference import brute_force_routing

    import taopt.models

    rng = np.random.default_rng([31, seed])
    n, m = int(rng.integers(3, 7)), int(rng.integers(1, 3))
    cost = rng.uniform(1.0, 30.0, size=(n + m, n + m))
    problem = taopt.AssignmentProblem(cost, n_targets=n)
    value = bounds.lp_bound(problem)
    assert value == pytest.approx(taopt.models.lp_bound(problem), rel=1e-6)
    assert value <= brute_force_routing(problem.cost, n) * (1 + 1e-9)
