"""The covering-walk bound of the fleet family (:mod:`taopt.fleet.cover`)."""

from __future__ import annotations

import pytest

from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.cover import CoverTables, cover_bound, coverable

CASES = [
    # (seed, n, K, D, c, precedence, objective, stops)
    (11, 3, 1, 1, 1, False, "last_service", 3),
    (12, 3, 1, 1, 2, True, "return", 3),
    (13, 3, 2, 1, 1, False, "return", 3),
    (14, 3, 2, 1, 2, True, "last_service", 2),
    (15, 2, 1, 2, 2, False, "return", 3),
    (16, 2, 2, 2, 1, True, "last_service", 3),
    (17, 3, 2, 2, 2, False, "last_service", 2),
    (18, 3, 1, 2, 1, True, "return", 2),
]


@pytest.mark.parametrize("case", CASES)
def test_cover_bound_never_exceeds_the_brute_force_optimum(case):
    """The root covering-walk bound is <= the brute-force optimum, both objectives."""
    problem = tiny_instance(*case[:7], stops=case[7])
    value, plan, _ = brute_force(problem)
    assert plan is not None
    bound = cover_bound(problem, 0.0, 10.0 * value + 100.0)
    assert bound <= value * (1 + 1e-9) + 1e-9
    # the optimum's value itself is coverable (the relaxation admits the optimal plan)
    tab = CoverTables(problem)
    trucks = [(problem.depot, 0.0, 0.0, d) for d in problem.drones]
    assert coverable(tab, value * (1 + 1e-12) + 1e-12, trucks, list(range(problem.n)))


def test_cover_bound_certifies_an_incumbent_it_cannot_beat():
    """With the optimum as the upper value the bound is the optimum within the tolerance or
    below it, never above."""
    problem = tiny_instance(21, 3, 2, 1, 1, False, "last_service", stops=3)
    value = brute_force(problem)[0]
    bound = cover_bound(problem, 0.0, value)
    assert bound <= value
