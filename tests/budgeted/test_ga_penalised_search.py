"""The budgeted GA's penalised local search: every move priced exactly, checked by brute force."""

from __future__ import annotations

import numpy as np
import pytest

from taopt.budgeted import BudgetedProblem
from taopt.errors import InstanceError
from taopt.heuristics.budgeted import penalised_cost
from taopt.heuristics.ga_local_search import _apply
from taopt.heuristics.ga_penalised_search import PenalisedSearch, _apply_all, _independent
from taopt.heuristics.ga_routing import nodes_to_genes, path_matrix, path_nodes


def allowed_moves(nodes: np.ndarray, n: int):
    """Every move of the search's neighbourhood, enumerated one by one (the moves of chapter
    2's local search that keep every route start in place), as ``_apply`` arguments."""
    inner = nodes.size - 2
    start = nodes >= n
    route = np.cumsum(start) - 1
    for i in range(1, inner + 1):
        for j in range(i + 1, inner + 1):
            if not start[i : j + 1].any():
                yield ("reverse", i - 1, j - 1, 0)
    for length in (1, 2, 3):
        for i in range(1, inner - length + 2):
            if start[i : i + length].any():
                continue
            for p in range(inner + 1):
                if not i - 1 <= p <= i + length - 1:
                    yield ("relocate", i - 1, p, length)
    for i in range(1, inner + 1):
        for j in range(i + 2, inner + 1):
            if not start[i] and not start[j]:
                yield ("exchange", i - 1, j - 1, 0)
    for c in range(1, inner + 2):
        for d in range(c + 1, inner + 2):
            if route[c - 1] != route[d - 1]:
                yield ("tails", c - 1, d - 1, 0)


def random_case(seed: int) -> tuple[BudgetedProblem, np.ndarray, float, float]:
    """A small problem with some limits, a random path, a penalty weight and unit."""
    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(2, 7)), int(rng.integers(1, 4))
    cost = rng.integers(0, 20, size=(n + m, n + m)).astype(float)
    np.fill_diagonal(cost, 0.0)
    capacity = [int(rng.integers(0, n + 1)) if rng.random() < 0.7 else None for _ in range(m)]
    max_time = [float(rng.integers(5, 60)) if rng.random() < 0.6 else None for _ in range(m)]
    problem = BudgetedProblem(cost, n, capacity=capacity, max_time=max_time)
    nodes = path_nodes(problem.routing, rng.permutation(n + m - 1))[0]
    return problem, nodes, float(rng.choice([0.0, 1.0, 10.0])), float(rng.choice([1.0, 3.5]))


def fitness(problem: BudgetedProblem, nodes: np.ndarray, weight: float, unit: float) -> float:
    """The GA's penalised fitness of a path (the function the search descends)."""
    return float(
        penalised_cost(problem, nodes_to_genes(problem.routing, nodes), weight, unit)[0][0]
    )


@pytest.mark.parametrize("seed", range(80))
def test_one_move_is_the_best_move_by_enumeration(seed):
    """One step makes the move whose penalised fitness is lowest among all moves tried one
    by one (the tables price every move exactly), and none when no move improves."""
    problem, nodes, weight, unit = random_case(seed)
    now = fitness(problem, nodes, weight, unit)
    values = [
        fitness(problem, _apply(nodes.copy(), *move), weight, unit)
        for move in allowed_moves(nodes, problem.n)
    ]
    best = min(values, default=now)
    moved, moves = PenalisedSearch(problem, weight, unit).run(
        path_matrix(problem.routing), nodes.copy(), max_moves=1
    )
    tolerance = 1e-9 * max(1.0, abs(now))
    if best < now - tolerance:
        assert moves == 1
        assert fitness(problem, moved, weight, unit) == pytest.approx(best, abs=tolerance)
    else:
        assert moves == 0
        assert moved.tolist() == nodes.tolist()


@pytest.mark.parametrize("seed", range(30))
def test_descent_never_worsens_and_keeps_the_route_starts(seed):
    problem, nodes, weight, unit = random_case(1000 + seed)
    moved, _ = PenalisedSearch(problem, weight, unit).run(path_matrix(problem.routing), nodes)
    assert fitness(problem, moved, weight, unit) <= fitness(problem, nodes, weight, unit) + 1e-9
    assert sorted(moved.tolist()) == sorted(nodes.tolist())
    assert moved[0] == nodes[0] and moved[-1] == nodes[-1]
    starts = [int(x) for x in nodes if x >= problem.n]
    assert [int(x) for x in moved if x >= problem.n] == starts
    # a local optimum: no single move improves it
    again, moves = PenalisedSearch(problem, weight, unit).run(
        path_matrix(problem.routing), moved, max_moves=1
    )
    assert moves == 0 and again.tolist() == moved.tolist()


def test_the_penalty_pulls_a_route_back_within_its_capacity():
    """Chapter 2's local search keeps the cheap path that overloads vehicle 0; with the
    penalty the search hands a target to vehicle 1."""
    x = np.array([1.0, 2.0, 0.0, 3.0])
    problem = BudgetedProblem(abs(x[:, None] - x[None, :]), 2, capacity=[1, 1])
    nodes = path_nodes(problem.routing, np.array([0, 1, 2]))[0]
    moved, _ = PenalisedSearch(problem, 10.0, 1.0).run(path_matrix(problem.routing), nodes)
    assert penalised_cost(problem, nodes_to_genes(problem.routing, moved), 10.0, 1.0)[2][0] == 0


@pytest.mark.parametrize("seed", range(60))
def test_moves_on_disjoint_routes_add_up(seed):
    """One pass makes every improving move it kept whose routes no better move touches: the
    penalised fitness falls by exactly the sum of their own changes, and each one applied
    alone gives what chapter 2's ``_apply`` gives."""
    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(6, 11)), int(rng.integers(3, 6))
    weight, unit = float(rng.choice([1.0, 10.0])), float(rng.choice([1.0, 3.5]))
    cost = rng.integers(0, 20, size=(n + m, n + m)).astype(float)
    np.fill_diagonal(cost, 0.0)
    problem = BudgetedProblem(
        cost, n, capacity=[int(rng.integers(1, 4))] * m, max_time=[float(rng.integers(10, 40))] * m
    )
    nodes = path_nodes(problem.routing, rng.permutation(n + m - 1))[0]
    search = PenalisedSearch(problem, weight, unit)
    found = search._improving_moves(path_matrix(problem.routing), nodes)
    chosen = _independent(found, nodes >= n, 1000)
    if not chosen:
        return
    value = dict((move, change) for change, move in reversed(found))
    after = _apply_all(nodes, chosen, n)
    change = fitness(problem, after, weight, unit) - fitness(problem, nodes, weight, unit)
    assert change == pytest.approx(sum(value[move] for move in chosen), abs=1e-7)
    for move in chosen:
        alone = _apply_all(nodes, [move], n)
        assert alone.tolist() == _apply(nodes.copy(), *move).tolist()


def test_neighbourhood_is_checked_and_kept():
    problem, nodes, weight, unit = random_case(3)
    with pytest.raises(InstanceError, match="unknown local-search moves"):
        PenalisedSearch(problem, weight, unit, neighbourhood=("swap",))
    # exchanges only: every route keeps its number of targets
    moved, _ = PenalisedSearch(problem, 10.0, 1.0, neighbourhood=("exchange",)).run(
        path_matrix(problem.routing), nodes
    )

    def sizes(path):
        return np.diff(np.flatnonzero(path >= problem.n)).tolist()

    assert sizes(moved) == sizes(nodes)
