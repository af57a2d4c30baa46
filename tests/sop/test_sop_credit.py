"""The DP's prefix bound with row credit (issue 33): at most the cost of every order through
every prefix of it on random tiny SOPs, and the DP with it gives the brute-force optimum."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from taopt.models.sop_cuts import SopCutModel
from taopt.models.sop_dp import RowCredit, solve_sop_dp
from taopt.result import OPTIMAL
from taopt.sop.problem import SopProblem, evaluate_order
from tests.reference_exact import sop_brute_force, sop_instance, sop_orders


def _clustered(seed: int, n: int = 8) -> SopProblem:
    """``n`` nodes in three clusters on a line (cheap inside, dear across) with random
    precedences: the root loop prices many subtour and path cuts that orders cross twice."""
    rng = np.random.default_rng([33, seed])
    where = rng.integers(0, 3, n) * 40 + rng.integers(0, 10, n)
    cost = (np.abs(where[:, None] - where[None, :]) + rng.integers(0, 15, (n, n))).astype(float)
    np.fill_diagonal(cost, 0.0)
    pairs = [(a, b) for a, b in itertools.combinations(range(1, n - 1), 2) if rng.random() < 0.2]
    return SopProblem(cost, pairs, 0, n - 1, name=f"clustered-{seed}")


def _instance(seed: int) -> SopProblem:
    """Even seeds: the shared tiny SOPs; odd seeds: :func:`_clustered`."""
    return sop_instance(seed) if seed % 2 == 0 else _clustered(seed)


def _prices(problem: SopProblem) -> tuple[tuple[float, np.ndarray], RowCredit]:
    """The root loop's Lagrangian bound and its row credit."""
    model = SopCutModel(problem)
    model.root()
    prices = model.lagrangian_prices()
    credit = model.row_credit()
    assert prices is not None and credit is not None
    return prices, credit


def _prefix_bound(credit: RowCredit, order: list[int], length: int) -> float:
    """The row-credit bound of the first ``length`` nodes of ``order``, written out plainly."""
    prefix = order[:length]
    arcs = list(zip(prefix[:-1], prefix[1:], strict=True))
    value = credit.constant + sum(credit.reduced[u, w] for u, w in arcs)
    for r, weight in enumerate(credit.weights):
        crossings = sum(1 for u, w in arcs if (int(credit.bits[u, w]) >> r) & 1)
        value += weight * max(crossings - 1, 0)
    seen, last = set(prefix), prefix[-1]
    for tail, head, d in zip(*credit.negative, strict=True):
        if head not in seen and (tail not in seen or tail == last):
            value += d
    return float(value)


@pytest.mark.parametrize("seed", range(20))
def test_row_credit_bound_holds_on_every_prefix(seed):
    """The bound of every prefix of every order is at most that order's cost."""
    problem = _instance(seed)
    if not math.isfinite(sop_brute_force(problem)):
        return
    _, credit = _prices(problem)
    for order in sop_orders(problem):
        cost = evaluate_order(problem, order)
        for length in range(1, len(order) + 1):
            assert _prefix_bound(credit, order, length) <= cost + 1e-6


@pytest.mark.parametrize("seed", range(20))
def test_dp_with_row_credit_matches_brute_force(seed):
    """The DP dropping states by the row-credit bound, from a middling order, gives the
    brute-force optimum."""
    problem = _instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    lagrange, credit = _prices(problem)
    orders = sorted(sop_orders(problem), key=lambda o: evaluate_order(problem, o))
    start = orders[len(orders) // 2]
    result = solve_sop_dp(problem, incumbent=start, lagrange=lagrange, credit=credit, beam_width=0)
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(optimum)
    assert evaluate_order(problem, result.order) == pytest.approx(optimum)


@pytest.mark.parametrize("seed", range(20))
def test_dp_with_row_credit_proves_an_optimal_order(seed):
    """Given an optimal order, the DP with the row credit proves it (no false gap), and a
    run stopped by its state cap keeps a bound at most the optimum."""
    problem = _instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    lagrange, credit = _prices(problem)
    best = min(sop_orders(problem), key=lambda o: evaluate_order(problem, o))
    result = solve_sop_dp(problem, incumbent=best, lagrange=lagrange, credit=credit, beam_width=0)
    assert result.status == OPTIMAL
    assert result.bound == pytest.approx(optimum)
    capped = solve_sop_dp(problem, max_states=1, lagrange=lagrange, credit=credit, beam_width=0)
    assert capped.bound is not None and capped.bound <= optimum + 1e-6


def test_row_credit_drops_more_states():
    """From an optimal order the row credit drops at least the states the prefix's reduced
    cost alone drops, summed over the small instances."""
    plain = credited = 0
    for seed in range(12):
        problem = _instance(seed)
        if not math.isfinite(sop_brute_force(problem)):
            continue
        lagrange, credit = _prices(problem)
        best = min(sop_orders(problem), key=lambda o: evaluate_order(problem, o))
        kept = [
            solve_sop_dp(problem, incumbent=best, lagrange=lagrange, credit=c, beam_width=0)
            for c in (None, credit)
        ]
        plain += kept[0].info["states"]
        credited += kept[1].info["states"]
    assert credited <= plain
