"""AssignmentProblem validation and the chapter 2 scorer (taopt.evaluate)."""

from __future__ import annotations

import numpy as np
import pytest

import taopt
from taopt import AssignmentProblem, FeasibilityError, InstanceError


def small_problem() -> AssignmentProblem:
    """3 targets, 2 vehicles, asymmetric costs; hand-checked routes below."""
    rng = np.random.default_rng(3)
    cost = rng.uniform(1, 10, size=(5, 5))
    return AssignmentProblem(cost, n_targets=3)


def test_evaluate_sums_open_routes() -> None:
    p = small_problem()
    c = p.cost
    routes = [[2, 0], [1]]
    expected = c[3, 2] + c[2, 0] + c[4, 1]
    assert taopt.evaluate(p, routes) == pytest.approx(expected, rel=1e-12)
    # An unused vehicle has an empty route.
    assert taopt.evaluate(p, [[], [0, 1, 2]]) == pytest.approx(c[4, 0] + c[0, 1] + c[1, 2])


@pytest.mark.parametrize(
    "routes, message",
    [
        ([[0, 1], [1, 2]], "target 1 is visited twice"),
        ([[0], [1]], "target 2 is never visited"),
        ([[0, 1, 7], [2]], "index 7 is not a target"),
        ([[0, 1, 2]], "expected 2 routes"),
        ([[0, 1.5], [2]], "not an integer"),
    ],
)
def test_evaluate_names_the_violation(routes, message) -> None:
    with pytest.raises(FeasibilityError, match=message):
        taopt.evaluate(small_problem(), routes)


@pytest.mark.parametrize(
    "cost, n, message",
    [
        (np.ones((3, 4)), 2, "square"),
        (np.array([[0, 1], [np.nan, 0]]), 1, r"cost\[1, 0\] = nan is not finite"),
        (np.array([[0, -1], [1, 0]]), 1, r"cost\[0, 1\] = -1.0 is negative"),
        (np.ones((3, 3)), 0, "n_targets must be >= 1"),
        (np.ones((3, 3)), 3, "at least one vehicle"),
    ],
)
def test_bad_problem_data(cost, n, message) -> None:
    with pytest.raises(InstanceError, match=message):
        AssignmentProblem(cost, n_targets=n)


def test_diagonal_is_ignored_and_cost_read_only() -> None:
    cost = np.full((3, 3), 5.0)
    np.fill_diagonal(cost, np.inf)
    p = AssignmentProblem(cost, n_targets=2)
    assert np.all(np.diag(p.cost) == 0)
    with pytest.raises(ValueError):
        p.cost[0, 1] = 1.0


def test_json_round_trip(tmp_path) -> None:
    p = small_problem()
    p.save(tmp_path / "p.json")
    q = AssignmentProblem.load(tmp_path / "p.json")
    assert q.n == p.n and np.array_equal(q.cost, p.cost)


def test_unknown_schema_version(tmp_path) -> None:
    data = small_problem().to_dict()
    data["schema_version"] = 99
    with pytest.raises(InstanceError, match="unknown schema_version 99"):
        AssignmentProblem.from_dict(data)


def test_solution_gap_and_summary() -> None:
    s = taopt.Solution(
        objective=110.0, status="time_limit", bound=100.0, runtime=1.5, method="exact-dfj"
    )
    assert s.gap == pytest.approx(10 / 110)
    assert "gap=9.091%" in s.summary() and "time_limit" in s.summary()
