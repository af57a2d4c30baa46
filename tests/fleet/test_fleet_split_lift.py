"""The split search's drone-split set bounds and monotone lifting (:mod:`taopt.fleet.split`)."""

from __future__ import annotations

import numpy as np
import pytest

import taopt
from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.problem import FleetProblem
from taopt.fleet.search import label_search
from taopt.fleet.split import (
    _chain_tables,
    _closure,
    _dominates,
    _drone_split_bounds,
    _earliest,
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


def _released_optima(
    problem: FleetProblem, D: int, chain: bool
) -> tuple[dict[int, float], dict[int, dict[int, float]]]:
    """Every part's optimum (label search, exact) with its split releases (with the other
    truck's chain bound when ``chain``), and those releases."""
    closure, early = _closure(problem), _earliest(problem)
    table = _chain_tables(problem, closure, {D}, Deadline(None))[D] if chain else None
    values, releases = {}, {}
    for mask in range(1, 1 << problem.n):
        members = _members(mask)
        release = _releases(closure, early, mask, members, table)
        releases[mask] = dict(zip(members, release, strict=True))
        sub = sub_problem(problem, members, D, closure)
        found = label_search(sub, release=release, beam=0)
        assert found["stopped_by"] == "optimal"
        values[mask] = float(found["value"])
    return values, releases


@pytest.mark.parametrize(
    "seed, objective, chain",
    [
        (0, "last_service", False),
        (1, "return", True),
        (3, "last_service", True),
        (7, "return", False),
    ],
)
def test_lifting_never_exceeds_the_superset_optimum(seed, objective, chain):
    """Monotonicity: opt(Y) <= opt(X) for Y within X when X's releases are no earlier on Y
    (the lifting rule), and without releases for every Y within X."""
    problem = _instance(seed, 4, 1, 2, True, objective)
    closure = _closure(problem)
    released, releases = _released_optima(problem, 1, chain)
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
            if _dominates(releases[outer], releases[inner], inner):
                kept += 1
                assert released[inner] <= released[outer] + 1e-9, (inner, outer)
    assert kept > 0


@pytest.mark.parametrize(
    "seed, c, objective", [(0, 1, "last_service"), (3, 2, "return"), (7, 2, "last_service")]
)
def test_chain_releases_bound_the_split_optimum(seed, c, objective):
    """Two trucks: the parts priced with the chain releases never exceed the optimum
    restricted to their split (brute force), for every split, and are never below the
    releases without the chain."""
    from taopt.fleet.brute import brute_force as brute

    problem = _instance(seed, 3, 1, c, True, objective)
    closure, early = _closure(problem), _earliest(problem)
    table = _chain_tables(problem, closure, {1}, Deadline(None))[1]
    for mask in range(1, 8):
        owner = [0 if mask >> j & 1 else 1 for j in range(3)]
        restricted = brute(problem, truck_of=owner)[0]
        for part in (mask, 7 ^ mask):
            if not part:
                continue
            members = _members(part)
            weak = _releases(closure, early, part, members)
            strong = _releases(closure, early, part, members, table)
            assert all(a <= b + 1e-12 for a, b in zip(weak, strong, strict=True))
            sub = sub_problem(problem, members, 1, closure)
            value = label_search(sub, release=strong, beam=0)["value"]
            assert value <= restricted + 1e-9, (mask, part)


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
    problem = _instance(3, 3, 1, 2, True, "last_service")
    value = brute_force(problem)[0]
    found = split_search(problem, time_limit=0.01)
    assert found["bound"] <= value + 1e-9
    assert found["stopped_by"] in ("time_limit", "optimal")


@pytest.mark.parametrize("objective", ["last_service", "return"])
def test_split_search_with_exact_chains_equals_brute_force(objective):
    """A chain 0 -> 1 -> 2 over two trucks (a cross predecessor with an ancestor on its own
    truck: the exact chain solve runs): the split search equals the brute force."""
    problem = _instance(1, 3, 1, 1, True, objective).replace(precedences=[(0, 1), (1, 2)])
    value, plan, _ = brute_force(problem)
    assert plan is not None
    found = split_search(problem)
    assert found["stopped_by"] == "optimal"
    assert found["value"] == pytest.approx(value, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize(
    "seed, c, objective", [(1, 1, "last_service"), (3, 2, "return"), (5, 2, "last_service")]
)
def test_topological_releases_bound_the_split_optimum(seed, c, objective):
    """The split's topological releases L: each part re-solved with them stays at or below
    the brute-force optimum restricted to that split (K = 2, D = 1, every split)."""
    from taopt.fleet.split import _split_releases

    problem = _instance(seed, 3, 1, c, True, objective).replace(precedences=[(0, 1), (1, 2)])
    closure, early = _closure(problem), _earliest(problem)
    for mask in range(1, 8):
        owner = [0 if mask >> j & 1 else 1 for j in range(3)]
        restricted = brute_force(problem, truck_of=owner)[0]
        L = _split_releases(problem, owner, closure, early, Deadline(None))
        assert all(a >= b - 1e-12 for a, b in zip(L, early, strict=True))
        for part in (mask, 7 ^ mask):
            if not part:
                continue
            members = _members(part)
            sub = sub_problem(problem, members, 1, closure)
            value = label_search(sub, release=[L[j] for j in members], beam=0)["value"]
            assert value <= restricted + 1e-9, (mask, part)
