"""Chapter 4 route geometry: insertion and removal costs against brute force."""

from __future__ import annotations

import numpy as np
import pytest

from taopt.comm import random_problem
from taopt.comm.routes import (
    InsertionTable,
    distances_from,
    insert,
    insertion_costs,
    removal_savings,
    route_length,
)


def brute_length(start_point, route, targets) -> float:
    """Polyline length, point by point."""
    points = [np.asarray(start_point)] + [targets[q] for q in route]
    return float(sum(np.hypot(*(b - a)) for a, b in zip(points[:-1], points[1:], strict=True)))


def test_insertion_and_removal_match_brute_force() -> None:
    """(4.9)'s marginal cost and the significance equal differences of whole route lengths."""
    rng = np.random.default_rng(0)
    for seed in range(20):
        p = random_problem(9, 1, 1, 1.0, seed=seed)
        n, dist = p.n, p.distances[: p.n, : p.n]
        here = rng.uniform(0, 1000, 2)
        start = distances_from(here, p.targets)
        route = [int(q) for q in rng.permutation(n)[: 1 + seed % 6]]
        rest = np.array([q for q in range(n) if q not in route])
        base = brute_length(here, route, p.targets)
        assert route_length(start, route, dist) == pytest.approx(base)
        cost, position = insertion_costs(start, route, rest, dist)
        for q, c, pos in zip(rest, cost, position, strict=True):
            options = [
                brute_length(here, insert(route, q, k), p.targets) - base
                for k in range(len(route) + 1)
            ]
            assert c == pytest.approx(min(options), abs=1e-9)
            assert options[pos] == pytest.approx(min(options), abs=1e-9)
        savings = removal_savings(start, route, dist)
        for k, q in enumerate(route):
            shorter = [t for t in route if t != q]
            assert savings[k] == pytest.approx(base - brute_length(here, shorter, p.targets))


def test_insertion_table_is_bit_identical() -> None:
    """The incremental table equals a full recomputation after every insertion, to the bit."""
    rng = np.random.default_rng(1)
    for trial in range(60):
        p = random_problem(int(rng.integers(2, 30)), 1, 1, 1.0, seed=trial)
        n, dist = p.n, p.distances[: p.n, : p.n]
        start = distances_from(p.vehicles[0], p.targets)
        table = InsertionTable(start, np.arange(n), dist)
        for _ in range(n):
            rest = np.array([q for q in range(n) if q not in table.route])
            cost, position = insertion_costs(start, table.route, rest, dist)
            assert np.array_equal(cost, table.cost[rest])
            assert np.array_equal(position, table.position[rest])
            q = int(rng.choice(rest))
            table.insert(q, int(rng.integers(0, len(table.route) + 1)))
