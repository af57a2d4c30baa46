"""Cost model (5.8)–(5.11), G^d edges, Fig. 5.2's simplification, Proposition 5.3's bound."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

import taopt
from taopt.bounds import arborescence
from taopt.delivery.bounds import arborescence_bound
from taopt.delivery.costs import (
    deployment_times,
    drone_cost_matrix,
    edge_cost_matrix,
    feasible_edges,
    remaining_range,
    simplify_precedences,
    successor_sets,
    viable_stops,
)
from taopt.delivery.dags import layered_dag, paired_precedences
from taopt.delivery.evaluate import timeline
from taopt.delivery.instance import DeliveryInstance
from taopt.delivery.schedule import optimal_plan, schedule
from taopt.errors import InstanceError

# Fig. 5.2 reconstructed from §5.3.1, §5.4.1 and the NIA example of §5.4.2, customers
# c1..c7 as indices 0..6. (b): c1->c3, c1->c2, c2->c5, c3->c4, c5->c4, c4->c7, c7->c6.
# (a) adds the redundant c1->c4 (paths c1->c3->c4, c1->c2->c4 exist) and c2->c4.
FIG52_B = {(0, 2), (0, 1), (1, 4), (2, 3), (4, 3), (3, 6), (6, 5)}
FIG52_A = FIG52_B | {(0, 3), (1, 3)}


def test_fig_5_2_simplification_and_topological_sort():
    assert set(simplify_precedences(FIG52_A, 7)) == FIG52_B
    graph = nx.DiGraph(FIG52_B)
    # §5.4.1: c1 is the only customer without a predecessor
    assert [v for v in graph if graph.in_degree(v) == 0] == [0]
    # after c1 is inserted, c2 and c3 are viable
    graph.remove_node(0)
    assert sorted(v for v in graph if graph.in_degree(v) == 0) == [1, 2]
    # NIA example: with R = {c1, c2, c5} the only viable customer is c3
    graph.remove_nodes_from([1, 4])
    assert [v for v in graph if graph.in_degree(v) == 0] == [2]
    # the example's final path c1, c3, c2, c5, c4, c7, c6 is a topological order of (a)
    path = [0, 2, 1, 4, 3, 6, 5]
    assert all(path.index(r) < path.index(j) for r, j in FIG52_A)
    with pytest.raises(InstanceError, match="precedence cycle"):
        simplify_precedences([(0, 1), (1, 0)], 2)


def test_thesis_successor_sets_miss_an_edge_the_nia_example_uses():
    sets = successor_sets(FIG52_B, 7)
    assert sets[5] == set()  # S_6: customers outside V^p (none here)
    assert sets[6] == {5}  # S_7 = S_6 ∪ {c6}
    assert sets[0] == {1, 2, 3, 4, 5, 6}
    # the NIA example serves c3 right before c2, but c2 is not in S_3 as printed
    assert 1 not in sets[2]


def grid_instance(seed, n=6, k=3, side=200.0, precedences="layered", tau=0.0, ratio=None):
    rng = np.random.default_rng(seed)
    customers = rng.uniform(0, side, (n, 2))
    h = side / (k - 1)
    L = (ratio or rng.uniform(1.45, 3.5)) * h  # 2 * max nearest distance <= sqrt(2) h
    if precedences == "layered":
        pairs = layered_dag(n, layers=int(rng.integers(1, 4)), density=0.3, seed=rng)
    elif precedences == "pairs":
        pairs = paired_precedences(n, seed=rng)
    else:
        pairs = ()
    return DeliveryInstance.grid(customers, k, side, rng.uniform(0.7, 2.0), 1.0, L, pairs, tau)


def test_viable_stops_and_remaining_range():
    inst = grid_instance(0)
    for j, stops in enumerate(viable_stops(inst)):
        d = inst.flight_distance[j]
        assert set(stops) == {i for i in range(inst.s) if d[i] + d.min() <= inst.flight_limit}
    assert remaining_range(inst) == pytest.approx(
        inst.flight_range - inst.flight_distance.min(axis=1)
    )


def test_patterns_beta_and_gamma_never_beat_alpha():
    for seed in range(5):
        inst = grid_instance(seed, n=8, k=4)
        times = deployment_times(inst)
        star = drone_cost_matrix(inst)[:-1, :-1]
        off = ~np.eye(inst.n, dtype=bool)
        assert (times["alpha"] <= times["beta"] + 1e-12).all()
        assert (times["beta"] <= times["gamma"] + 1e-12).all()
        assert np.allclose(star[off], times["alpha"][off])
        assert (
            drone_cost_matrix(inst, truck_metric="euclidean") <= drone_cost_matrix(inst) + 1e-12
        ).all()


@pytest.mark.parametrize("tau", [0.0, 7.0])
def test_t_star_never_exceeds_the_true_time_between_services(tau):
    """Validity of (5.11) under the timing semantics, on DP-scheduled random orders."""
    rng = np.random.default_rng(1)
    for seed in range(6):
        inst = grid_instance(seed, n=10, k=4, precedences="none", tau=tau)
        D = drone_cost_matrix(inst)
        for _ in range(5):
            order = [int(x) for x in rng.permutation(inst.n)]
            line = timeline(inst, schedule(inst, order).plan)
            t = line.service_time
            assert t[0] >= D[inst.n, order[0]] - 1e-9
            gaps = np.diff(t)
            lower = D[order[:-1], order[1:]]
            assert (gaps >= lower - 1e-9).all()


def test_feasible_edges_rules():
    inst = DeliveryInstance.grid(np.full((7, 2), 50.0), 3, 100, 1, 1, 150, tuple(FIG52_A))
    precede = set(feasible_edges(inst, "precede"))
    consecutive = set(feasible_edges(inst, "consecutive"))
    thesis = set(feasible_edges(inst, "thesis"))
    assert {(7, 0)} == {e for e in precede if e[0] == 7}  # depot -> c1 only
    assert (2, 1) in precede and (2, 1) in consecutive and (2, 1) not in thesis
    assert (3, 0) not in precede  # c1 must precede c4
    assert (0, 3) in precede and (0, 3) not in consecutive  # c2/c3/c5 lie between
    assert consecutive <= precede
    finite = np.isfinite(edge_cost_matrix(inst))
    assert {tuple(e) for e in np.argwhere(finite) if e[0] != e[1]} == precede
    with pytest.raises(InstanceError, match="rule"):
        feasible_edges(inst, "nope")


def test_numpy_and_networkx_bounds_agree():
    """Both methods of Proposition 5.3's bound (the dense Edmonds itself is checked
    against networkx in tests/core/test_arborescence.py)."""
    inst = grid_instance(3, n=12, k=4)
    assert arborescence_bound(inst) == pytest.approx(arborescence_bound(inst, method="networkx"))


def enumerate_optimum(inst: DeliveryInstance) -> float:
    """Exact optimum: every precedence-feasible order, each scheduled by the exact DP."""
    return min(
        schedule(inst, order).objective for order in nx.all_topological_sorts(inst.precedence_graph)
    )


@pytest.mark.parametrize("seed", range(6))
def test_subset_dp_matches_enumeration(seed):
    kind = ("layered", "pairs", "none")[seed % 3]
    inst = grid_instance(50 + seed, n=4 + seed % 2 * 2, k=3, precedences=kind, tau=seed % 2 * 3.0)
    exact = optimal_plan(inst)
    assert exact.status == "optimal" and exact.bound == exact.objective
    assert taopt.evaluate(inst, exact) == pytest.approx(exact.objective, rel=1e-12)
    assert exact.objective == pytest.approx(enumerate_optimum(inst), rel=1e-12)


@pytest.mark.parametrize("seed", range(20))
def test_bound_never_exceeds_the_optimum(seed):
    """20 random instances: 6 customers, 9 stops (3x3 grid), random precedences."""
    kind = ("layered", "pairs", "none")[seed % 3]
    inst = grid_instance(seed, n=6, k=3, precedences=kind, tau=float(seed % 2) * 5.0)
    best = optimal_plan(inst).objective
    precede = arborescence_bound(inst)
    consecutive = arborescence_bound(inst, rule="consecutive")
    assert 0 < precede <= consecutive <= best + 1e-9
    assert arborescence_bound(inst, truck_metric="euclidean") <= precede + 1e-9
    assert arborescence(inst) == precede


def test_thesis_rule_for_E_d_can_exceed_the_optimum():
    """Counterexample to Prop. 5.3 with E^d built from S_r as printed (§5.3.2).

    Customers on the street x-axis at 100, 500, 600, 700 m, pairs c0 -> c1 and c2 -> c3,
    unit speeds. Optimal order 0, 1, 2, 3 serves the last at 700 s. S_1 = S_3 = ∅, so the
    printed G^d has no edge 1 -> 2 and its arborescence must pay w0 -> c2 (600 s):
    100 + 400 + 600 + 100 = 1200 > 700. The rule "precede" gives 700 (tight).
    """
    customers = [[100, 0], [500, 0], [600, 0], [700, 0]]
    inst = DeliveryInstance.grid(customers, 11, 1000, 1.0, 1.0, 150, [(0, 1), (2, 3)])
    assert optimal_plan(inst).objective == pytest.approx(700.0)
    assert arborescence_bound(inst, rule="thesis") == pytest.approx(1200.0)
    assert arborescence_bound(inst) == pytest.approx(700.0)
