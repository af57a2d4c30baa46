"""The covering-walk bound of the fleet family (:mod:`taopt.fleet.cover`)."""

from __future__ import annotations

import pytest

from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.cover import (
    CoverTables,
    SortieTables,
    cover_bound,
    coverable,
    fleet_cover_bound,
    fleet_coverable,
    release_times,
)

CASES = [
    # (seed, n, K, D, c, precedence, objective, stops)
    (11, 2, 1, 1, 1, False, "last_service", 3),
    (12, 2, 1, 1, 2, True, "return", 2),
    (13, 2, 2, 1, 1, False, "return", 2),
    (14, 2, 2, 1, 2, True, "last_service", 2),
    (15, 2, 1, 2, 2, False, "return", 2),
    (16, 2, 2, 2, 1, True, "last_service", 2),
]


def _check(case: tuple) -> None:
    problem = tiny_instance(*case[:7], stops=case[7])
    value, plan, _ = brute_force(problem)
    assert plan is not None
    top = 10.0 * value + 100.0
    assert cover_bound(problem, 0.0, top) <= value * (1 + 1e-9) + 1e-9
    assert fleet_cover_bound(problem, 0.0, top) <= value * (1 + 1e-9) + 1e-9
    tab = CoverTables(problem)
    trucks = [(problem.depot, 0.0, 0.0, d) for d in problem.drones]
    T = value * (1 + 1e-12) + 1e-12
    assert coverable(tab, T, trucks, list(range(problem.n)))
    stab = SortieTables(problem, list(range(problem.n)))
    assert fleet_coverable(tab, stab, T, trucks, release_times(problem))


@pytest.mark.parametrize("case", CASES)
def test_cover_bounds_never_exceed_the_brute_force_optimum(case):
    """Both root bounds (covering walks, sortie walks) are <= the brute-force optimum, and the
    optimum's value passes both relaxations, under both objectives."""
    _check(case)


@pytest.mark.slow
def test_cover_bounds_on_64_tiny_instances():
    """Every K, D, c in {1, 2}, with and without precedence, both objectives, two seeds, n = 3:
    both root bounds are <= the brute-force optimum."""
    import itertools

    for seed, K, D, c, prec, objective in itertools.product(
        (31, 32), (1, 2), (1, 2), (1, 2), (False, True), ("last_service", "return")
    ):
        _check((seed, 3, K, D, c, prec, objective, 2))


def test_cover_bound_certifies_an_incumbent_it_cannot_beat():
    """With the optimum as the upper value the bound is the optimum within the tolerance or
    below it, never above."""
    problem = tiny_instance(21, 2, 2, 1, 1, False, "last_service", stops=3)
    value = brute_force(problem)[0]
    bound = cover_bound(problem, 0.0, value)
    assert bound <= value


def test_root_sortie_walk_bound_certifies_without_search():
    """Two trucks with two drones each: the root bound meets the incumbent, so the exact
    method is optimal without a label, at the brute-force optimum (33.855975..., computed by
    :func:`~taopt.fleet.brute.brute_force` in 99 s, so recorded here)."""
    import taopt
    from taopt.models.fleet import solve_fleet

    problem = tiny_instance(38, 3, 2, 2, 2, False, "last_service", stops=3)
    solution = solve_fleet(problem, algorithm="search")
    assert solution.status == "optimal"
    assert solution.info["algorithm"] == "search" and "labels" not in solution.info
    assert solution.objective == pytest.approx(33.85597515507222, rel=1e-9)
    assert taopt.evaluate(problem, solution.solution) == pytest.approx(solution.objective)
