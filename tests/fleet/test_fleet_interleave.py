"""The interleaved-sortie incumbent (taopt.heuristics.fleet_interleave): feasible plans, never
below the brute-force optimum, never worse than its start, seeded."""

from __future__ import annotations

import numpy as np
import pytest

import taopt.heuristics  # noqa: F401  (registers the fleet's methods)
from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.evaluate import evaluate_fleet
from taopt.fleet.instances import residential_fleet
from taopt.fleet.problem import FleetPlan
from taopt.heuristics.fleet_interleave import (
    _Decoder,
    _move,
    interleave_applies,
    interleave_plan,
    sortie_list,
)
from taopt.heuristics.fleet_search import ils_fleet, improve_fleet

# (seed, K, D, c, precedence, objective, optimum): n = 3, 2 stops, every customer drone-only;
# the optimum is taopt.fleet.brute.brute_force's (recomputed by the slow test below).
CASES = [
    (700, 1, 2, 1, False, "last_service", 82.15844227418857),
    (701, 1, 2, 2, True, "last_service", 53.98116459750478),
    (702, 1, 2, 1, True, "return", 100.07160540852433),
    (703, 1, 3, 1, True, "last_service", 24.536266281734658),
    (704, 1, 2, 2, False, "return", 229.614893585852),
    (705, 2, 2, 1, True, "last_service", 55.88461130874949),
    (706, 2, 2, 2, True, "return", 126.241583861079),
    (707, 1, 3, 2, True, "return", 79.9593924027163),
]


def _instance(case: tuple):
    seed, K, D, c, prec, objective, _ = case
    return tiny_instance(seed, 3, K, D, c, prec, objective, stops=2).replace(service="drone")


@pytest.mark.parametrize("case", CASES)
def test_plan_feasible_and_not_below_optimum(case):
    """Every plan found is feasible under evaluate and never below the brute-force optimum."""
    problem = _instance(case)
    plan = interleave_plan(problem, None, seed=1, iterations=60)
    assert isinstance(plan, FleetPlan)
    assert evaluate_fleet(problem, plan) >= case[-1] * (1 - 1e-9)


@pytest.mark.parametrize("case", CASES)
def test_never_worse_than_its_start(case):
    """The search returns its start when it finds nothing better (never a worse plan)."""
    problem = _instance(case)
    start = ils_fleet(problem, seed=0, iterations=2).solution
    plan = interleave_plan(problem, start, seed=0, iterations=40)
    assert evaluate_fleet(problem, plan) <= evaluate_fleet(problem, start) + 1e-9


def test_seeded():
    """The same seed gives the same plan."""
    problem = residential_fleet(6, 1, 2, 2, seed=1)
    start = ils_fleet(problem, seed=0, iterations=1).solution
    a = interleave_plan(problem, start, seed=3, iterations=40)
    b = interleave_plan(problem, start, seed=3, iterations=40)
    assert a.to_dict() == b.to_dict()


def test_decoded_value_bounds_the_earliest_schedule():
    """The decoder's value of a sortie list is at least the scored value of the plan it
    builds (its times satisfy every rule of the earliest schedule), on random lists."""
    problem = residential_fleet(6, 1, 2, 2, seed=2)
    rng = np.random.default_rng(0)
    start = ils_fleet(problem, seed=0, iterations=1).solution
    decoder = _Decoder(problem, 0)
    items = sortie_list(problem, start, 0)
    checked = 0
    for _ in range(60):
        moved = _move(items, decoder.D, decoder.c, rng)
        if moved is None or not decoder.valid(moved):
            continue
        value, events = decoder.decode(moved, 3)
        if events is None:  # a sortie out of range from every candidate stop
            assert value == float("inf")
            continue
        items = moved
        route, flights = decoder.route(events)
        plan = FleetPlan([route], [[]], [flights])
        assert evaluate_fleet(problem, plan) <= value * (1 + 1e-9)
        checked += 1
    assert checked >= 10


def test_two_trucks_with_cross_precedence():
    """With two trucks (releases from the other truck's schedule) the plan stays feasible and
    no worse than its start."""
    problem = residential_fleet(6, 2, 2, 1, seed=0)
    start = ils_fleet(problem, seed=0, iterations=1).solution
    plan = interleave_plan(problem, start, seed=0, iterations=30)
    assert evaluate_fleet(problem, plan) <= evaluate_fleet(problem, start) + 1e-9


def test_not_applied_with_truck_only_customers():
    """A customer only a truck may serve: the search does not apply; the start comes back."""
    problem = tiny_instance(700, 3, 1, 2, 1, False, "last_service", stops=2)
    problem = problem.replace(service=["truck", "drone", "drone"], customer_stop=[0, None, None])
    assert not interleave_applies(problem)
    start = ils_fleet(problem, seed=0, iterations=1).solution
    found = interleave_plan(problem, start, seed=0, iterations=10)
    assert found.to_dict() == start.to_dict()


def test_improver_never_worse_than_plan():
    """improve_fleet (ILS, then the interleaved search) never returns a worse plan."""
    problem = _instance(CASES[1])
    start = ils_fleet(problem, seed=0, iterations=0).solution
    found = improve_fleet(problem, start, time_limit=None)
    assert evaluate_fleet(problem, found) <= evaluate_fleet(problem, start) + 1e-9


@pytest.mark.slow
def test_cases_are_the_brute_force_optima():
    """CASES' optima are brute_force's (about a second each)."""
    for case in CASES:
        value, _, _ = brute_force(_instance(case))
        assert value == pytest.approx(case[-1], rel=1e-9)


def test_ils_interleaved_phase_never_worse():
    """The ILS with its interleaved phase is no worse than without it (same seed and
    iterations), and ``ils_objective`` records the ILS's own value when it improved."""
    problem = residential_fleet(6, 1, 2, 1, seed=0)
    plain = ils_fleet(problem, seed=2, iterations=1, interleave=False)
    full = ils_fleet(problem, seed=2, iterations=1)
    assert full.objective <= plain.objective + 1e-9
    assert evaluate_fleet(problem, full.solution) == pytest.approx(full.objective, rel=1e-12)
    if full.objective < plain.objective - 1e-9:
        assert full.info["ils_objective"] == pytest.approx(plain.objective, rel=1e-12)
