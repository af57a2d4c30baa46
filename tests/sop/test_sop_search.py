"""SOP-3-exchange local search and the iterated local search (issue 33's warm start): the
best move equals the best of every feasible segment swap enumerated, and every order
returned keeps the precedences and is never costlier than its start."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import taopt.models.sop as sop_model
import taopt.models.sop_dp as sop_dp
from taopt.models.sop import solve_sop_problem
from taopt.models.sop_search import (
    before_matrix,
    best_exchange,
    iterated_local_search,
    local_search,
)
from taopt.result import OPTIMAL, TIME_LIMIT, Order
from taopt.sop.problem import SopProblem, evaluate_order
from tests.reference_exact import sop_brute_force, sop_instance, sop_orders


def _random(seed: int, n: int = 9) -> SopProblem:
    """``n`` nodes, random integer costs, about a fifth of the inner pairs ordered."""
    rng = np.random.default_rng([36, seed])
    cost = rng.integers(0, 30, (n, n)).astype(float)
    pairs = [(a, b) for a, b in itertools.combinations(range(1, n - 1), 2) if rng.random() < 0.2]
    return SopProblem(cost, pairs, 0, n - 1, name=f"random-{seed}")


def _swaps(
    problem: SopProblem, order: list[int], lo: int = 0, hi: int = 10**9
) -> list[tuple[float, list[int]]]:
    """Every segment swap of ``order`` with ``lo <= h`` and ``j < hi`` that keeps the
    precedences, with its change of cost."""
    n, base = len(order), evaluate_order(problem, order)
    where_ok = {tuple(o) for o in sop_orders(problem)}
    found = []
    for h, i, j in itertools.combinations(range(n - 1), 3):
        if h < lo or j >= hi:
            continue
        new = order[: h + 1] + order[i + 1 : j + 1] + order[h + 1 : i + 1] + order[j + 1 :]
        if tuple(new) in where_ok:
            found.append((evaluate_order(problem, new) - base, new))
    return found


@pytest.mark.parametrize("seed", range(12))
def test_best_exchange_is_the_best_feasible_swap(seed: int) -> None:
    """The best move's change equals the best over every feasible swap enumerated."""
    problem = _random(seed, 7)
    order = next(iter(sop_orders(problem)))
    swaps = _swaps(problem, order)
    delta, h, i, j = best_exchange(problem.cost, before_matrix(problem), order)
    if not swaps:
        assert delta == np.inf
        return
    assert delta == pytest.approx(min(d for d, _ in swaps))
    moved = order[: h + 1] + order[i + 1 : j + 1] + order[h + 1 : i + 1] + order[j + 1 :]
    assert evaluate_order(problem, moved) == pytest.approx(evaluate_order(problem, order) + delta)


@pytest.mark.parametrize("seed", range(6))
def test_best_exchange_in_a_span(seed: int) -> None:
    """Within a span, the best move equals the best feasible swap enumerated inside it."""
    problem = _random(seed, 8)
    order = next(iter(sop_orders(problem)))
    for lo, hi in ((0, 4), (1, 6), (2, 7), (3, 5)):
        swaps = _swaps(problem, order, lo, hi)
        delta, h, _, j = best_exchange(problem.cost, before_matrix(problem), order, (lo, hi))
        assert delta == pytest.approx(min((d for d, _ in swaps), default=np.inf))
        if swaps:
            assert lo <= h and j < hi


@pytest.mark.parametrize("seed", range(10))
def test_local_search_ends_feasible_and_no_costlier(seed: int) -> None:
    """A descent keeps the precedences, never raises the cost, and ends where no swap helps."""
    problem = _random(seed)
    before = before_matrix(problem)
    for order in itertools.islice(sop_orders(problem), 0, 200, 40):
        improved = [int(v) for v in local_search(problem.cost, before, order)]
        assert evaluate_order(problem, improved) <= evaluate_order(problem, order)
        assert best_exchange(problem.cost, before, improved)[0] >= -1e-9


@pytest.mark.parametrize("seed", range(8))
def test_iterated_search_reaches_the_brute_force_optimum(seed: int) -> None:
    """On tiny SOPs 30 iterations find the optimum; the order is feasible, its cost right."""
    problem = sop_instance(seed)
    start = next(iter(sop_orders(problem)))
    value, order, info = iterated_local_search(problem, start, iterations=30, seed=seed)
    assert evaluate_order(problem, order) == pytest.approx(value)
    assert value == pytest.approx(sop_brute_force(problem))
    assert info["start"] >= value


def test_iterated_search_is_seeded() -> None:
    """The same seed gives the same order."""
    problem = _random(3, 12)
    start = next(iter(sop_orders(problem)))
    first = iterated_local_search(problem, start, iterations=20, seed=5)
    assert iterated_local_search(problem, start, iterations=20, seed=5)[1] == first[1]


def test_iterated_search_stops_without_progress() -> None:
    """With a patience of 5, a search that finds no better order stops after 5 iterations."""
    problem = sop_instance(0)
    optimum = min(sop_orders(problem), key=lambda order: evaluate_order(problem, order))
    _, _, info = iterated_local_search(problem, optimum, iterations=100, patience=5)
    assert info["iterations"] == 5


@pytest.mark.parametrize("seed", range(0, 30, 3))
def test_portfolio_with_the_search_matches_brute_force(monkeypatch, seed: int) -> None:
    """When the first DP stage stops with the costliest order (made to, bound 0), the search
    runs on it and the portfolio still gives the brute-force optimum with a feasible order."""
    problem = sop_instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    worst = max(sop_orders(problem), key=lambda order: evaluate_order(problem, order))
    real = sop_dp.solve_sop_dp
    calls: list[int] = []

    def first_stopped(*args, **kwargs):
        result = real(*args, **kwargs)
        calls.append(1)
        if len(calls) > 1:
            return result
        value = evaluate_order(problem, worst)
        return result.replace(solution=Order(worst), objective=value, bound=0.0, status=TIME_LIMIT)

    monkeypatch.setattr(sop_dp, "solve_sop_dp", first_stopped)
    monkeypatch.setattr(sop_model, "CUTS_FIRST_SHARE", 2.0)  # the DP first
    monkeypatch.setattr(sop_model, "PROOF_STAGE", False)  # its first call is the first DP stage
    monkeypatch.setattr(sop_model, "ILS_MIN_GAP", -1.0)
    monkeypatch.setattr(sop_model, "ILS_PATIENCE", 30)
    result = solve_sop_problem(problem, ideal_cap=1, max_states=2, cpsat=False, seed=seed)
    assert isinstance(result.info["ils"], dict)
    assert result.info["ils"]["to"] <= evaluate_order(problem, worst)
    assert result.status == OPTIMAL
    assert evaluate_order(problem, result.order) == pytest.approx(optimum)
    assert result.objective == pytest.approx(optimum)


class _Expired:
    """A deadline that has always expired."""

    def expired(self, margin: float = 0.0) -> bool:
        return True


@pytest.mark.parametrize("seed", range(4))
def test_best_exchange_stops_between_chunks(monkeypatch, seed: int) -> None:
    """With one h per chunk and an expired deadline, the scan keeps its first chunk: the best
    move equals the best feasible swap with h = 0."""
    import taopt.models.sop_search as sop_search

    problem = _random(seed, 7)
    order = next(iter(sop_orders(problem)))
    monkeypatch.setattr(sop_search, "CHUNK_CELLS", 1)
    delta, h, _, _ = best_exchange(problem.cost, before_matrix(problem), order, None, _Expired())
    swaps = [d for d, new in _swaps(problem, order) if new[1] != order[1]]
    assert delta == pytest.approx(min(swaps, default=np.inf))
    if swaps:
        assert h == 0
