"""The split search's drone-split set bounds and monotone lifting (:mod:`taopt.fleet.split`)."""

from __future__ import annotations

import numpy as np
import pytest

import taopt
from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.problem import FleetProblem
from taopt.fleet.search import label_search
from taopt.fleet.split import (
    _closure,
    _drone_split_bounds,
    _earliest,
    _keeps_releases,
    _members,
    _releases,
    _subset_max,
    split_search,
    sub_problem,
)
from taopt.runtime import Deadline


def _instance(seed: int, n: int, D: int, c: int, precedence: bool, objective: str) -> FleetProblem:
    """A tiny two-truck instance; odd seeds make every customer drone-only (the bound's case)."""
    problem = tiny_instance(seed, n, 2, D, c, precedence, objective, stops=2)
    if seed % 2:
        problem = problem.replace(service=["drone"] * n, customer_stop=[None] * n)
    return problem


CASES = [
    (seed, D, c, precedence, objective)
    for seed, D, c, precedence, objective in [
        (1, 1, 1, True, "last_service"),
        (1, 1, 2, False, "return"),
        (3, 2, 1, True, "last_service"),
        (3, 2, 2, True, "last_service"),
        (3, 2, 2, False, "return"),
        (5, 2, 2, True, "return"),
        (0, 2, 2, True, "last_service"),
        (4, 1, 2, True, "return"),
    ]
]


@pytest.mark.parametrize("seed, D, c, precedence, objective", CASES)
def test_drone_split_bound_never_exceeds_the_part_optimum(seed, D, c, precedence, objective):
    """B_D[X] <= the brute-force optimum of one truck with D drones serving exactly X."""
    problem = _instance(seed, 3, D, c, precedence, objective)
    bound = _drone_split_bounds(problem, _closure(problem), {D}, Deadline(None))[D]
    for mask in range(1, 8):
        members = _members(mask)
        value = brute_force(sub_problem(problem, members, D))[0]
        assert bound[mask] <= value + 1e-9, members


def test_drone_split_bound_is_tight_for_one_drone_only_customers():
    """D = 1, drone-only customers: the bound is the one-drone table, equal to the optimum."""
    problem = _instance(1, 3, 1, 2, True, "last_service")
    bound = _drone_split_bounds(problem, _closure(problem), {1}, Deadline(None))[1]
    full = brute_force(sub_problem(problem, [0, 1, 2], 1))[0]
    assert bound[7] == pytest.approx(full, rel=1e-9)


def test_subset_max_is_the_largest_value_of_a_subset():
    """_subset_max(v)[X] equals max over the subsets Y of X of v[Y] (checked by enumeration)."""
    rng = np.random.default_rng(0)
    values = rng.uniform(0, 10, 32)
    out = _subset_max(values)
    for X in range(32):
        assert out[X] == max(values[Y] for Y in range(32) if Y & ~X == 0)


def _released_optima(problem: FleetProblem, D: int) -> dict[int, float]:
    """Every part's optimum (label search, exact) with its split releases."""
    closure, early = _closure(problem), _earliest(problem)
    out = {}
    for mask in range(1, 1 << problem.n):
        members = _members(mask)
        sub = sub_problem(problem, members, D, closure)
        found = label_search(sub, release=_releases(closure, early, mask, members), beam=0)
        assert found["stopped_by"] == "optimal"
        out[mask] = float(found["value"])
    return out


@pytest.mark.parametrize(
    "seed, objective", [(0, "last_service"), (1, "return"), (3, "last_service"), (7, "return")]
)
def test_lifting_never_exceeds_the_superset_optimum(seed, objective):
    """Monotonicity: opt(Y) <= opt(X) for Y within X when X keeps Y's releases, and without
    releases for every Y within X."""
    problem = _instance(seed, 4, 1, 2, True, objective)
    closure, early = _closure(problem), _earliest(problem)
    preds: list[list[int]] = [[] for _ in range(problem.n)]
    for r, j in closure:
        preds[j].append(r)
    released = _released_optima(problem, 1)
    free = {
        mask: float(label_search(sub_problem(problem, _members(mask), 1, closure), beam=0)["value"])
        for mask in range(1, 16)
    }
    kept = 0
    for outer in range(1, 16):
        for inner in range(1, 16):
            if inner == outer or inner & ~outer:
                continue
            assert free[inner] <= free[outer] + 1e-9, (inner, outer)
            if _keeps_releases(preds, early, inner, outer):
                kept += 1
                assert released[inner] <= released[outer] + 1e-9, (inner, outer)
    assert kept > 0


@pytest.mark.parametrize("seed, D, c, precedence, objective", CASES[:6])
def test_split_search_with_lifting_equals_brute_force(seed, D, c, precedence, objective):
    """K = 2: the split search (drone-split bounds, lifting, pairing) equals the brute force."""
    problem = _instance(seed, 3, D, c, precedence, objective)
    value, plan, _ = brute_force(problem)
    assert plan is not None
    found = split_search(problem)
    assert found["stopped_by"] == "optimal"
    assert found["value"] == pytest.approx(value, rel=1e-9, abs=1e-9)
    assert taopt.evaluate(problem, found["plan"]) == pytest.approx(found["value"])


def test_time_limited_split_with_lifting_keeps_its_bound_below_the_optimum():
    """A tiny time limit: time_limit or optimal, bound never above the brute-force optimum."""
    problem = _instance(3, 3, 2, 2, True, "last_service")
    value = brute_force(problem)[0]
    found = split_search(problem, time_limit=0.01)
    assert found["bound"] <= value + 1e-9
    assert found["stopped_by"] in ("time_limit", "optimal")
