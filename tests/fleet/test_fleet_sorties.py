"""The fleet's sortie DP (one truck, one multi-parcel drone) and the label search's work bound."""

from __future__ import annotations

import pytest

import taopt
from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.problem import FleetProblem


def drone_only(seed: int, n: int, capacity: int, precedence: bool, objective: str) -> FleetProblem:
    """A tiny one-truck, one-drone instance with every customer drone-only."""
    p = tiny_instance(seed, n, 1, 1, capacity, precedence, objective, stops=2 + seed % 2)
    return p.replace(service=["drone"] * p.n, customer_stop=[None] * p.n)


CASES = [
    (1, 2, 2, False, "last_service"),
    (2, 3, 2, True, "return"),
    (3, 2, 3, True, "last_service"),
    (4, 2, 2, False, "return"),
    (5, 3, 1, True, "return"),
    (6, 3, 3, False, "return"),
]


@pytest.mark.parametrize("case", CASES)
def test_sortie_dp_equals_brute_force(case):
    """The dispatched sortie DP is optimal and equals the brute-force optimum."""
    problem = drone_only(*case)
    value, plan, _ = brute_force(problem)
    assert plan is not None
    solution = taopt.solve(problem, "exact")
    assert solution.info["algorithm"] == "sortie_dp"
    assert solution.status == "optimal"
    assert solution.objective == pytest.approx(value, rel=1e-9, abs=1e-9)
    assert taopt.evaluate(problem, solution.solution) == pytest.approx(solution.objective)


@pytest.mark.slow
def test_sortie_dp_equals_brute_force_on_90_tiny_instances():
    """Thirty seeds x c in {1, 2, 3}, with and without precedence, both objectives."""
    from taopt.fleet.sorties import sortie_dp

    checked = 0
    for seed in range(30):
        for c in (1, 2, 3):
            p = drone_only(
                seed, 2 + seed % 2, c, bool(seed % 2), ("last_service", "return")[seed % 4 // 2]
            )
            if p.unservable():
                continue
            value = brute_force(p)[0]
            assert sortie_dp(p)["value"] == pytest.approx(value, rel=1e-9, abs=1e-9), (seed, c)
            checked += 1
    assert checked >= 60


def test_sortie_dp_equals_chapter5_ideal_dp_at_capacity_one():
    """c = 1, last_service (chapter 5's shape): the sortie DP equals chapter 5's ideal DP."""
    from taopt.fleet.instances import residential_fleet
    from taopt.models.fleet import solve_fleet

    problem = residential_fleet(6, 1, 1, 1, seed=4)
    ideal = solve_fleet(problem, algorithm="ideal_dp")
    sortie = solve_fleet(problem, algorithm="sortie_dp")
    assert ideal.status == sortie.status == "optimal"
    assert sortie.objective == pytest.approx(ideal.objective, rel=1e-9)


def test_sortie_dp_size_guard_stops_with_a_plan_and_a_proven_bound():
    """A step cap reached: stopped_by "size", a feasible plan and a bound below the optimum."""
    from taopt.fleet.instances import residential_fleet
    from taopt.models.fleet import solve_fleet

    problem = residential_fleet(6, 1, 1, 2, seed=1)
    optimum = solve_fleet(problem).objective
    stopped = solve_fleet(problem, max_labels=5)
    assert stopped.info["stopped_by"] == "size" and stopped.status != "optimal"
    assert stopped.bound <= optimum + 1e-9 <= stopped.objective + 2e-9
    assert taopt.evaluate(problem, stopped.solution) == pytest.approx(stopped.objective)


@pytest.mark.parametrize("seed", range(8))
def test_label_search_root_bound_never_above_the_optimum(seed):
    """The search's completion bound at the root (reach, work with recoveries) <= brute force."""
    from taopt.fleet.search import _bound, _Tables

    K, D, c = 1 + seed % 2, 1 + seed // 2 % 2, 1 + seed // 4 % 2
    objective = ("last_service", "return")[seed % 3 == 0]
    n = 3 if K * D == 1 else 2
    problem = tiny_instance(200 + seed, n, K, D, c, bool(seed % 2), objective, stops=2)
    value = brute_force(problem)[0]
    tab = _Tables(problem)
    trucks = tuple(
        (problem.depot, 0.0, 0.0, True, False, 0.0, tuple((0, 0.0) for _ in range(d)))
        for d in problem.drones
    )
    assert _bound(tab, (0, 0.0, (-1.0,) * problem.n, trucks)) <= value + 1e-9


@pytest.mark.parametrize("seed", range(6))
def test_split_dp_bound_and_plan_bracket_the_brute_force_optimum(seed):
    """Two trucks with one drone each: bound <= optimum <= plan; equal when certified."""
    from taopt.models.fleet import solve_fleet

    p = tiny_instance(300 + seed, 3, 2, 1, 1 + seed % 2, bool(seed % 3), "last_service", stops=2)
    p = p.replace(service=["drone"] * p.n, customer_stop=[None] * p.n)
    value = brute_force(p)[0]
    solution = solve_fleet(p, algorithm="split_dp")
    assert solution.bound <= value + 1e-9 <= solution.objective + 2e-9
    assert taopt.evaluate(p, solution.solution) == pytest.approx(solution.objective)
    if solution.status == "optimal":
        assert solution.objective == pytest.approx(value, rel=1e-9, abs=1e-9)
