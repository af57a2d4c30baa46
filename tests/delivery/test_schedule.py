"""The exact DP scheduler (taopt.delivery.schedule) checked against brute force."""

from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest

import taopt
from taopt.delivery.evaluate import evaluate_plan
from taopt.delivery.instance import DeliveryInstance, Plan
from taopt.delivery.schedule import optimal_plan, schedule
from taopt.errors import FeasibilityError, SolverError


def random_small_instance(seed: int, n: int = 3, s: int = 4) -> DeliveryInstance:
    """n customers, s stops on a random connected street graph with random street lengths
    (>= Euclidean), random speeds, range and landing time; every customer servable."""
    rng = np.random.default_rng(seed)
    stops = rng.uniform(0, 100, size=(s, 2))
    graph = nx.Graph()
    graph.add_nodes_from(range(s))
    perm = rng.permutation(s)
    for a, b in itertools.pairwise(perm):  # a spanning path keeps it connected
        graph.add_edge(int(a), int(b))
    for a, b in itertools.combinations(range(s), 2):
        if rng.random() < 0.3:
            graph.add_edge(a, b)
    for a, b in graph.edges:
        graph.edges[a, b]["length"] = np.hypot(*(stops[a] - stops[b])) * rng.uniform(1.0, 1.5)
    customers = rng.uniform(0, 100, size=(n, 2))
    nearest = np.sqrt(((customers[:, None] - stops[None]) ** 2).sum(-1)).min(1)
    flight_range = 2 * nearest.max() * rng.uniform(1.0, 3.0)
    return DeliveryInstance(
        customers,
        stops,
        graph,
        depot=int(rng.integers(s)),
        v_drone=rng.uniform(1, 3),
        v_truck=rng.uniform(0.5, 2),
        flight_range=flight_range,
        service_time=float(rng.choice([0.0, rng.uniform(0, 10)])),
    )


def brute_force(instance: DeliveryInstance, order: list[int]) -> float:
    """Minimum makespan over every (launch, landing) choice, each plan scored by evaluate."""
    best = np.inf
    pairs = list(itertools.product(range(instance.s), repeat=2))
    for choice in itertools.product(pairs, repeat=len(order)):
        plan = Plan(tuple(order), tuple(c[0] for c in choice), tuple(c[1] for c in choice))
        try:
            best = min(best, evaluate_plan(instance, plan))
        except FeasibilityError:
            continue
    return best


@pytest.mark.parametrize("seed", range(12))
def test_dp_matches_brute_force(seed):
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(1, 4))
    s = int(rng.integers(2, 5))
    inst = random_small_instance(seed, n=n, s=s)
    order = [int(x) for x in rng.permutation(n)]
    sol = schedule(inst, order)
    assert sol.objective == pytest.approx(brute_force(inst, order), rel=1e-12, abs=1e-12)
    # the DP's own objective is exactly what the one scorer says about its plan
    assert taopt.evaluate(inst, sol) == sol.objective
    assert sol.plan.order == tuple(order)


def test_schedule_matches_evaluate_on_a_large_grid():
    rng = np.random.default_rng(3)
    inst = DeliveryInstance.grid(
        rng.uniform(0, 1000, (60, 2)), 11, 1000, 1.4, 1.0, 300, service_time=2.0
    )
    for _ in range(3):
        order = [int(x) for x in rng.permutation(60)]
        sol = taopt.schedule(inst, order)
        assert evaluate_plan(inst, sol.plan) == sol.objective
        # never worse than launching and landing at the nearest stop every time
        near = tuple(int(k) for k in inst.flight_distance[order].argmin(1))
        assert sol.objective <= evaluate_plan(inst, Plan(tuple(order), near, near)) + 1e-9


def test_schedule_rejects_bad_orders():
    inst = DeliveryInstance.grid(
        [[10, 10], [50, 60], [90, 20]], 3, 100, 1.0, 1.0, 100, precedences=[(2, 0)]
    )
    with pytest.raises(FeasibilityError, match=r"\(5.7\) precedence \(2, 0\)"):
        schedule(inst, [0, 1, 2])
    with pytest.raises(FeasibilityError, match="customer 1 is missing"):
        schedule(inst, [2, 0])
    with pytest.raises(FeasibilityError, match="customer 2 appears 2 times"):
        schedule(inst, [2, 0, 2])
    with pytest.raises(FeasibilityError, match="customer 7"):
        schedule(inst, [2, 0, 7])
    partial = schedule(inst, [2, 0], complete=False)
    assert len(partial.plan) == 2
    with pytest.raises(FeasibilityError, match="predecessor 2"):
        schedule(inst, [0], complete=False)


def test_schedule_is_deterministic():
    inst = random_small_instance(5, n=3, s=4)
    a, b = schedule(inst, [2, 0, 1]), schedule(inst, [2, 0, 1])
    assert a.plan == b.plan and a.objective == b.objective


# ---------------------------------------------------------------------------------------------
# Review items 5 and 14: the one scorer, the one DP step
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(6))
def test_objective_is_the_scorers_value(seed):
    rng = np.random.default_rng(200 + seed)
    n = int(rng.integers(1, 6))
    inst = random_small_instance(300 + seed, n=n, s=int(rng.integers(2, 7)))
    order = [int(x) for x in rng.permutation(n)]
    sol = schedule(inst, order)
    assert sol.objective == evaluate_plan(inst, sol.plan)
    assert sol.info["dp_objective"] == pytest.approx(sol.objective, rel=1e-12, abs=0)
    best = optimal_plan(inst)
    assert best.status == "optimal" and best.objective == best.bound
    assert best.objective == evaluate_plan(inst, best.plan)
    assert best.info["dp_objective"] == pytest.approx(best.objective, rel=1e-12, abs=0)
    # the subset DP and the fixed-order DP (same step) agree on the optimum over all orders
    every = min(schedule(inst, list(o)).objective for o in itertools.permutations(range(n)))
    assert best.objective == pytest.approx(every, rel=1e-12, abs=1e-12)
    assert best.objective <= sol.objective + 1e-9


def test_scorer_disagreement_raises_solver_error(monkeypatch):
    import taopt.scoring as scoring

    inst = random_small_instance(4, n=3, s=4)
    good = schedule(inst, [0, 1, 2])
    true_value = evaluate_plan(inst, good.plan)
    # a disagreement within the tolerance is accepted, and the scorer's value is returned
    # (the DPs score their plan once, with taopt.evaluate, through make_solution)
    monkeypatch.setattr(scoring, "evaluate", lambda i, p: true_value * (1 + 1e-12))
    assert schedule(inst, [0, 1, 2]).objective == true_value * (1 + 1e-12)
    # beyond it, both DPs refuse to return a number the scorer does not confirm
    monkeypatch.setattr(scoring, "evaluate", lambda i, p: evaluate_plan(i, p) * (1 + 1e-6))
    with pytest.raises(SolverError, match="differs from evaluate_plan"):
        schedule(inst, [0, 1, 2])
    with pytest.raises(SolverError, match="differs from evaluate_plan"):
        optimal_plan(inst)


def test_partial_order_keeps_the_dp_value():
    """complete=False: a partial plan cannot be scored (evaluate rejects it); the objective
    is the DP's makespan of the listed sorties, equal to the timeline of the partial plan."""
    from taopt.delivery.evaluate import timeline

    rng = np.random.default_rng(11)
    inst = DeliveryInstance.grid(rng.uniform(0, 1000, (12, 2)), 5, 1000, 1.4, 1.0, 500)
    partial = schedule(inst, [3, 7, 1, 0], complete=False)
    assert partial.objective == partial.info["dp_objective"]
    assert partial.objective == timeline(inst, partial.plan, check=False).makespan
    with pytest.raises(FeasibilityError, match=r"\(5.2\)"):
        evaluate_plan(inst, partial.plan)
