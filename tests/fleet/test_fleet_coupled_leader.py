"""The coupled problem of one split, any drones per truck (:mod:`taopt.fleet.coupled`):
the leader search (one-way cross pairs) and the joint search, against the brute force
restricted to the split."""

from __future__ import annotations

import itertools
import math

import pytest

from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.coupled import coupled_search, leader_of, leader_search
from taopt.fleet.evaluate import evaluate_fleet
from taopt.fleet.problem import FleetProblem
from taopt.fleet.split import _closure, _earliest, _split_releases
from taopt.runtime import Deadline

#: (seed, D, c, objective, precedences, owner): two trucks, cross pairs one way
ONE_WAY = [
    (seed, D, c, objective, pairs, owner)
    for (seed, D, c, objective), (pairs, owner) in zip(
        itertools.product((1, 2, 3), (1, 2), (1, 2), ("last_service", "return")),
        itertools.cycle(
            [
                ([(0, 2), (1, 3)], [0, 0, 1, 1]),
                ([(0, 1), (1, 2), (2, 3)], [0, 0, 1, 1]),
                ([(2, 0), (2, 1)], [1, 1, 0, 0]),
                ([(0, 2), (1, 2)], [0, 1, 1, 1]),
            ]
        ),
    )
]


def _problem(seed: int, D: int, c: int, objective: str, pairs: list) -> FleetProblem:
    """A tiny two-truck instance with the given precedences; odd seeds drone-only."""
    n = 4 if D == 1 else 3
    problem = tiny_instance(seed, n, 2, D, c, False, objective, stops=2)
    if seed % 2:
        problem = problem.replace(service=["drone"] * n, customer_stop=[None] * n)
    return problem.replace(precedences=[(r, j) for r, j in pairs if r < n and j < n])


def _owner(problem: FleetProblem, owner: list[int]) -> list[int]:
    return owner[: problem.n]


@pytest.mark.parametrize("seed, D, c, objective, pairs, owner", ONE_WAY)
def test_leader_search_equals_the_restricted_brute_force(seed, D, c, objective, pairs, owner):
    """One-way cross pairs: the leader search's optimum (with and without the topological
    releases) equals the brute force over the split's plans, and its plan scores it."""
    problem = _problem(seed, D, c, objective, pairs)
    owner = _owner(problem, owner)
    if leader_of(problem, owner) is None:
        pytest.skip("no cross pair left at this size")
    value = brute_force(problem, truck_of=owner)[0]
    L = _split_releases(problem, owner, _closure(problem), _earliest(problem), Deadline(None))
    for release in (None, L):
        found = leader_search(problem, owner, release=release)
        assert found["stopped_by"] == "optimal"
        if math.isinf(value):
            assert math.isinf(found["value"])
            continue
        assert found["value"] == pytest.approx(value, rel=1e-9, abs=1e-9)
        assert found["bound"] <= value + 1e-9
        assert evaluate_fleet(problem, found["plan"]) == pytest.approx(value, rel=1e-9)


@pytest.mark.parametrize("seed, D, c, objective, pairs, owner", ONE_WAY[:8])
def test_coupled_search_equals_the_restricted_brute_force(seed, D, c, objective, pairs, owner):
    """The joint search with each truck's own part bound equals the brute force over the
    split's plans, with the topological releases too."""
    problem = _problem(seed, D, c, objective, pairs)
    owner = _owner(problem, owner)
    value = brute_force(problem, truck_of=owner)[0]
    L = _split_releases(problem, owner, _closure(problem), _earliest(problem), Deadline(None))
    for release in (None, L):
        found = coupled_search(problem, owner, release=release)
        assert found["stopped_by"] == "optimal"
        assert found["value"] == pytest.approx(value, rel=1e-9, abs=1e-9)


def test_coupled_search_handles_two_way_cross_pairs():
    """Cross pairs both ways (no leader): the joint search still equals the brute force."""
    problem = _problem(3, 1, 2, "last_service", [(0, 2), (3, 1)])
    owner = [0, 0, 1, 1]
    assert leader_of(problem, owner) is None
    value = brute_force(problem, truck_of=owner)[0]
    assert coupled_search(problem, owner)["value"] == pytest.approx(value, rel=1e-9)


def test_time_limited_leader_search_keeps_a_bound_below_the_optimum():
    """Stopped at once: a proven bound never above the restricted brute-force optimum."""
    problem = _problem(1, 1, 2, "last_service", [(0, 1), (1, 2), (2, 3)])
    owner = [0, 0, 1, 1]
    value = brute_force(problem, truck_of=owner)[0]
    found = leader_search(problem, owner, time_limit=0.0)
    assert found["stopped_by"] in ("time_limit", "optimal")
    assert found["bound"] <= value + 1e-9


def test_leader_search_resumed_with_its_memo_equals_the_brute_force():
    """A run stopped at once, then resumed with the same memo (the split search's slices):
    the optimum over the split, as the brute force."""
    problem = _problem(3, 1, 2, "return", [(0, 2), (1, 3)])
    owner = [0, 0, 1, 1]
    value = brute_force(problem, truck_of=owner)[0]
    memo: dict = {}
    first = leader_search(problem, owner, time_limit=0.0, memo=memo)
    assert first["bound"] <= value + 1e-9
    found = leader_search(problem, owner, memo=memo)
    assert found["stopped_by"] == "optimal"
    assert found["value"] == pytest.approx(value, rel=1e-9)


@pytest.mark.parametrize(
    "seed, D, c, objective",
    [
        (1, 1, 1, "last_service"),
        (2, 1, 2, "return"),
        (3, 2, 1, "last_service"),
        (5, 1, 2, "return"),
    ],
)
def test_leader_relaxation_bounds_two_way_splits(seed, D, c, objective):
    """Cross pairs both ways, either truck leading: the leader search's value is a bound
    never above the brute force over the split's plans, and equal to it when it ends
    "optimal"."""
    problem = _problem(seed, D, c, objective, [(0, 2), (3, 1)])
    owner = _owner(problem, [0, 0, 1, 1])
    if leader_of(problem, owner) is not None:
        pytest.skip("one way at this size")
    value = brute_force(problem, truck_of=owner)[0]
    L = _split_releases(problem, owner, _closure(problem), _earliest(problem), Deadline(None))
    for leading in (0, 1):
        found = leader_search(problem, owner, release=L, leading=leading)
        assert found["bound"] <= value + 1e-9
        if found["stopped_by"] == "optimal":
            assert found["value"] == pytest.approx(value, rel=1e-9)
        else:
            assert found["stopped_by"] == "relaxed"
