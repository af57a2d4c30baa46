"""Two-truck splits with cross pairs both ways (:mod:`taopt.fleet.twoway`): the box search
against the brute force restricted to the split, and the follower deadlines it relies on
(:func:`taopt.fleet.coupled.coupled_search`'s ``due``)."""

from __future__ import annotations

import math

import pytest

from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.coupled import coupled_search, leader_of
from taopt.fleet.evaluate import evaluate_fleet, schedule
from taopt.fleet.problem import FleetProblem
from taopt.fleet.split import _closure, _earliest, _split_releases
from taopt.fleet.twoway import two_way_search
from taopt.runtime import Deadline

#: (precedences, owner): two trucks, closure cross pairs both ways
CASES = [
    ([(0, 2), (3, 1)], [0, 0, 1, 1]),
    ([(0, 2), (2, 1), (1, 3)], [0, 0, 1, 1]),
    ([(0, 3), (2, 1)], [0, 0, 1, 1]),
    ([(2, 0), (1, 2)], [0, 1, 0, 1]),
    ([(0, 1), (1, 2), (2, 3)], [0, 1, 0, 1]),
]

#: (seed, D, c, objective, case, leading): the first four split boxes (the leader's
#: relaxation is below the optimum there), the rest cover D = 2 and both objectives
ROWS = [
    (3, 1, 2, "last_service", 0, 1),
    (7, 1, 1, "last_service", 4, 1),
    (7, 1, 2, "return", 0, 0),
    (8, 1, 1, "return", 4, 1),
    (1, 2, 1, "last_service", 1, 0),
    (2, 2, 2, "return", 1, 1),
    (3, 2, 2, "last_service", 4, 0),
    (4, 2, 1, "return", 4, 1),
    (5, 1, 2, "return", 2, 0),
    (6, 1, 1, "last_service", 2, 1),
]


def _problem(seed: int, D: int, c: int, objective: str, case: int) -> tuple[FleetProblem, list]:
    """A tiny two-truck instance with the case's precedences; odd seeds drone-only."""
    pairs, owner = CASES[case]
    n = 4 if D == 1 else 3
    problem = tiny_instance(seed, n, 2, D, c, False, objective, stops=2)
    if seed % 2:
        problem = problem.replace(service=["drone"] * n, customer_stop=[None] * n)
    problem = problem.replace(precedences=[(r, j) for r, j in pairs if r < n and j < n])
    return problem, owner[:n]


def _two_way(problem: FleetProblem, owner: list) -> bool:
    ways = {(owner[r], owner[j]) for r, j in _closure(problem) if owner[r] != owner[j]}
    return len(ways) == 2


@pytest.mark.parametrize("seed, D, c, objective, case, leading", ROWS)
def test_two_way_search_equals_the_restricted_brute_force(seed, D, c, objective, case, leading):
    """Cross pairs both ways: the box search's optimum (with and without the topological
    releases, one leader or both in turn) equals the brute force over the split's plans, its
    plan scores it and its bound is never above it."""
    problem, owner = _problem(seed, D, c, objective, case)
    assert leader_of(problem, owner) is None and _two_way(problem, owner)
    value = brute_force(problem, truck_of=owner)[0]
    L = _split_releases(problem, owner, _closure(problem), _earliest(problem), Deadline(None))
    for release, lead in ((None, leading), (L, leading), (L, None)):
        found = two_way_search(problem, owner, release=release, leading=lead)
        assert found["stopped_by"] == "optimal"
        assert found["bound"] <= value + 1e-9
        if math.isinf(value):
            assert math.isinf(found["value"])
            continue
        assert found["value"] == pytest.approx(value, rel=1e-6)
        assert evaluate_fleet(problem, found["plan"]) == pytest.approx(found["value"], rel=1e-9)


def test_two_way_search_splits_a_box_where_the_relaxation_is_below():
    """Where the leader's relaxation is below the optimum, the search splits boxes and
    still ends on the brute-force optimum."""
    for seed, D, c, objective, case, leading in ROWS[:4]:
        problem, owner = _problem(seed, D, c, objective, case)
        value = brute_force(problem, truck_of=owner)[0]
        found = two_way_search(problem, owner, leading=leading)
        assert found["boxes"] > 1
        assert found["value"] == pytest.approx(value, rel=1e-6)


def test_time_limited_two_way_search_keeps_a_bound_below_the_optimum():
    """Stopped at once, then resumed with its memo: a proven bound never above the
    restricted brute-force optimum, then the optimum."""
    seed, D, c, objective, case, leading = ROWS[0]
    problem, owner = _problem(seed, D, c, objective, case)
    value = brute_force(problem, truck_of=owner)[0]
    memo: dict = {}
    first = two_way_search(problem, owner, time_limit=0.0, memo=memo, leading=leading)
    assert first["stopped_by"] in ("time_limit", "optimal")
    assert first["bound"] <= value + 1e-9
    found = two_way_search(problem, owner, memo=memo, leading=leading)
    assert found["stopped_by"] == "optimal"
    assert found["value"] == pytest.approx(value, rel=1e-6)


def test_coupled_search_meets_its_deadlines():
    """A deadline no later than the optimum's own time keeps the optimum; a tighter one
    gives a plan that meets it (scored by the earliest schedule), never below the optimum."""
    problem, owner = _problem(3, 1, 2, "last_service", 0)
    free = coupled_search(problem, owner)
    t = schedule(problem, free["plan"]).service
    j = int(max(range(problem.n), key=lambda x: t[x]))
    due = [math.inf] * problem.n
    due[j] = float(t[j])
    assert coupled_search(problem, owner, due=due)["value"] == pytest.approx(free["value"])
    for r in range(problem.n):
        due = [math.inf] * problem.n
        due[r] = float(t[r]) - 1.0
        found = coupled_search(problem, owner, due=due)
        assert found["stopped_by"] == "optimal"
        if found["plan"] is None:
            continue
        assert found["value"] >= free["value"] - 1e-9
        assert schedule(problem, found["plan"]).service[r] <= due[r] + 1e-6
