"""The exact-reinsertion large neighbourhood search (issue 33's primal search): a repair equals
the cheapest order that keeps the other nodes in their order (brute force), and every order
the search returns keeps the precedences, is never costlier than its start and is the same for
the same seed."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from taopt.models.sop_lns import large_neighbourhood_search, random_order, repair
from taopt.models.sop_search import before_matrix
from taopt.sop.problem import SopProblem, evaluate_order
from tests.reference_exact import sop_brute_force, sop_instance, sop_orders


def _random(seed: int, n: int = 8, share: float = 0.3, forbid: float = 0.0) -> SopProblem:
    """``n`` nodes, random integer costs (a ``forbid`` share of the arcs infinite), about a
    ``share`` of the inner pairs ordered."""
    rng = np.random.default_rng([38, seed])
    cost = rng.integers(0, 30, (n, n)).astype(float)
    cost[rng.random((n, n)) < forbid] = np.inf
    pairs = [(a, b) for a, b in itertools.combinations(range(1, n - 1), 2) if rng.random() < share]
    return SopProblem(cost, pairs, 0, n - 1, name=f"random-{seed}")


def _gaps(order: list[int], kept: set[int]) -> dict[int, int]:
    """The gap of each removed node: the number of kept nodes before it, less one."""
    found, count = {}, -1
    for v in order:
        if v in kept:
            count += 1
        else:
            found[v] = count
    return found


def _cheapest_keeping(
    problem: SopProblem, order: list[int], removed: list[int], reach: int | None
) -> float:
    """Brute force: the cheapest feasible order with the kept nodes in ``order``'s order and
    each removed node at most ``reach`` gaps from its old one."""
    kept = [v for i, v in enumerate(order) if i not in removed]
    old = _gaps(order, set(kept))
    best = np.inf
    for other in sop_orders(problem):
        if [v for v in other if v in set(kept)] != kept:
            continue
        new = _gaps(other, set(kept))
        if reach is None or all(abs(new[v] - old[v]) <= reach for v in new):
            best = min(best, evaluate_order(problem, other))
    return best


@pytest.mark.parametrize("seed", range(24))
def test_repair_is_the_cheapest_reinsertion(seed: int) -> None:
    """A repair costs what the brute force over every reinsertion costs, with a feasible
    order, for any removed positions and reach (forbidden arcs in a third of the cases)."""
    problem = _random(seed, int(5 + seed % 4), 0.1 + 0.1 * (seed % 4), 0.1 * (seed % 3 == 0))
    orders = list(sop_orders(problem))
    if not orders:
        return
    rng = np.random.default_rng(seed)
    order = orders[int(rng.integers(len(orders)))]
    k = int(rng.integers(1, problem.n - 1))
    removed = sorted(int(i) for i in rng.choice(np.arange(1, problem.n - 1), k, replace=False))
    reach = None if seed % 2 else int(rng.integers(0, 3))
    value, repaired = repair(problem.cost, before_matrix(problem), order, removed, reach)
    assert value == pytest.approx(_cheapest_keeping(problem, order, removed, reach))
    assert evaluate_order(problem, [int(v) for v in repaired]) == pytest.approx(value)
    assert value <= evaluate_order(problem, order)


def test_repair_without_removal_keeps_the_order() -> None:
    """Removing no inner position (or only the ends) returns the order and its cost."""
    problem = _random(1)
    order = next(iter(sop_orders(problem)))
    before = before_matrix(problem)
    for removed in ([], [0, problem.n - 1]):
        value, same = repair(problem.cost, before, order, removed)
        assert [int(v) for v in same] == order
        assert value == pytest.approx(evaluate_order(problem, order))


@pytest.mark.parametrize("seed", range(8))
def test_random_order_keeps_the_precedences(seed: int) -> None:
    """A random greedy order visits every node once and keeps every precedence."""
    problem = _random(seed, 12, 0.4)
    order = random_order(problem, before_matrix(problem), np.random.default_rng(seed))
    assert np.isfinite(evaluate_order(problem, [int(v) for v in order]))


@pytest.mark.parametrize("seed", range(10))
def test_search_reaches_the_brute_force_optimum(seed: int) -> None:
    """On tiny SOPs 40 repair steps find the optimum from the first feasible order."""
    problem = sop_instance(seed)
    start = next(iter(sop_orders(problem)), None)
    if start is None:
        return
    value, order, info = large_neighbourhood_search(problem, start, iterations=40, seed=seed)
    assert evaluate_order(problem, order) == pytest.approx(value)
    assert value == pytest.approx(sop_brute_force(problem))
    assert info["iterations"] <= 40


@pytest.mark.parametrize("seed", range(6))
def test_search_is_feasible_and_never_costlier(seed: int) -> None:
    """On 14-node SOPs (forbidden arcs in half), 60 steps with kicks and restarts return a
    feasible order no costlier than the start, with a trace of falling costs."""
    problem = _random(seed, 14, 0.15, 0.1 * (seed % 2))
    before = before_matrix(problem)
    start = random_order(problem, before, np.random.default_rng(seed))
    cost = float(problem.cost[start[:-1], start[1:]].sum())
    if not np.isfinite(cost):
        return
    value, order, info = large_neighbourhood_search(problem, list(start), iterations=60, seed=seed)
    assert evaluate_order(problem, order) == pytest.approx(value)
    assert value <= cost
    costs = [c for _, c in info["trace"]]
    assert costs == sorted(costs, reverse=True) and costs[-1] == value


def test_search_kicks_and_restarts() -> None:
    """On a 9-node SOP the search soon stops improving, so it kicks, then restarts; its
    order is still feasible and no costlier than the start."""
    problem = _random(2, 9, 0.2)
    start = next(iter(sop_orders(problem)))
    value, order, info = large_neighbourhood_search(problem, start, iterations=100, seed=1)
    assert info["kicks"] > 0 and info["restarts"] > 0
    assert evaluate_order(problem, order) == pytest.approx(value)
    assert value <= evaluate_order(problem, start)


def test_search_is_seeded() -> None:
    """The same seed gives the same order."""
    problem = _random(3, 14, 0.15)
    start = random_order(problem, before_matrix(problem), np.random.default_rng(0))
    first = large_neighbourhood_search(problem, list(start), iterations=40, seed=5)
    assert large_neighbourhood_search(problem, list(start), iterations=40, seed=5)[1] == first[1]


def test_search_stops_without_progress() -> None:
    """With a patience of 7, a search from the optimum stops after 7 repair steps."""
    problem = sop_instance(0)
    optimum = min(sop_orders(problem), key=lambda order: evaluate_order(problem, order))
    _, _, info = large_neighbourhood_search(problem, optimum, iterations=100, patience=7)
    assert info["iterations"] == 7
