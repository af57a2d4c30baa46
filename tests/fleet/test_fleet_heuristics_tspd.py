"""The fleet heuristics where a truck or a drone may serve a customer: the TSP-D instances
(objective ``"return"``, published optima of Bouman, Agatz & Schmidt 2018) and the encoding's
service modes (:data:`taopt.heuristics.fleet.TRUCK` / :data:`~taopt.heuristics.fleet.DRONE`).
"""

from __future__ import annotations

from pathlib import Path

import networkx as nx
import numpy as np
import pytest

import taopt
from taopt.errors import InstanceError
from taopt.fleet import FleetProblem, evaluate_fleet
from taopt.fleet.instances import residential_fleet
from taopt.fleet.tspd import TSPD_FOLDER, published_optimum
from taopt.heuristics.fleet import DRONE, TRUCK, decode, final_customers
from taopt.heuristics.fleet_search import (
    _anchors,
    _Search,
    route_first,
    trucks_only_value,
    two_opt,
)
from taopt.runtime import Deadline

#: Small shipped instances (5-7 nodes).
SMALL = ("uniform-1-n5", "uniform-11-n6", "uniform-21-n7")
#: Iteration budgets (no wall clock in tests).
OPTIONS = {"NIA": {}, "MMA": {}, "SMMA": {}, "3P": {"iterations": 2}, "ILS": {"iterations": 3}}


def _tspd(name: str) -> tuple[FleetProblem, float]:
    path = TSPD_FOLDER / f"{name}.txt"
    return FleetProblem.from_tspd(path), published_optimum(path)


@pytest.mark.parametrize("name", SMALL)
@pytest.mark.parametrize("method", list(OPTIONS))
def test_tspd_heuristics_feasible_and_never_below_the_published_optimum(method, name):
    """Every heuristic's TSP-D plan re-scores to its objective and is >= the published optimum."""
    problem, optimum = _tspd(name)
    found = taopt.solve(problem, method, seed=0, **OPTIONS[method])
    assert evaluate_fleet(problem, found.solution) == pytest.approx(found.objective, rel=1e-9)
    assert found.objective >= optimum * (1 - 1e-9)


@pytest.mark.parametrize("name", SMALL)
def test_tspd_searches_within_a_factor_of_the_optimum(name):
    """3P and ILS are within 1.2x the published optimum (1.9-2.4x before modes were searched)."""
    problem, optimum = _tspd(name)
    for method in ("3P", "ILS"):
        found = taopt.solve(problem, method, seed=0, **OPTIONS[method])
        assert found.objective <= 1.2 * optimum, (method, found.objective / optimum)


def test_decode_all_truck_modes_gives_a_truck_only_tour():
    """Modes all TRUCK: no sortie, the truck visits every customer's stop, evaluate agrees."""
    problem, _ = _tspd("uniform-21-n7")
    order = list(range(problem.n))
    builder = decode(problem, order, [0] * problem.n, modes=[TRUCK] * problem.n)
    plan = builder.plan()
    assert all(not sorties for sorties in plan.sorties[0])
    assert sorted(j for _, j in plan.truck_service[0]) == order
    assert evaluate_fleet(problem, plan) == pytest.approx(builder.objective(), rel=1e-12)


def test_decode_drone_mode_serves_by_a_sortie():
    """A customer in mode DRONE is served by a sortie, the others by the truck."""
    problem, _ = _tspd("uniform-21-n7")
    modes = [TRUCK] * problem.n
    modes[2] = DRONE
    plan = decode(problem, list(range(problem.n)), [0] * problem.n, modes=modes).plan()
    flown = [j for sortie in plan.sorties[0][0] for j in sortie.customers]
    assert flown == [2]
    assert 2 not in [j for _, j in plan.truck_service[0]]


def test_decode_rejects_truck_mode_for_a_drone_only_customer():
    """Mode TRUCK for a drone-only customer raises an error naming the customer."""
    problem = residential_fleet(4, trucks=1, drones=1, capacity=1, seed=0)
    with pytest.raises(InstanceError, match="customer 0 by truck"):
        decode(problem, [0, 1, 2, 3], [0] * 4, modes=[TRUCK] * 4)


def test_final_customers_marks_the_last_of_each_truck():
    """final_customers marks exactly the last customer of each truck in the order."""
    problem = residential_fleet(6, trucks=2, drones=1, capacity=1, seed=0)
    final = final_customers(problem, [3, 0, 5, 1, 4, 2], [0, 1, 1, 0, 0, 1])
    assert list(np.flatnonzero(final)) == [2, 4]


def test_two_opt_keeps_precedence_and_never_worsens_the_truck_routes():
    """2-opt of phase 1 returns a topological order no worse in the trucks-only objective."""
    for objective in ("last_service", "return"):
        problem = residential_fleet(
            30, trucks=2, drones=1, capacity=1, density=0.3, seed=3, objective=objective
        )
        order = list(nx.topological_sort(problem.precedence_graph))
        order += [j for j in range(problem.n) if j not in order]
        trucks = np.array([j % 2 for j in range(problem.n)])
        anchor = _anchors(problem)
        better = two_opt(problem, order, trucks, anchor)
        position = {j: i for i, j in enumerate(better)}
        assert sorted(better) == list(range(problem.n))
        assert all(position[r] < position[j] for r, j in problem.precedences)
        assert trucks_only_value(problem, better, trucks, anchor) <= trucks_only_value(
            problem, order, trucks, anchor
        )


def test_mode_moves_keep_precedence_on_the_fleet_example():
    """Every N4 move (flips, far moves, mode swaps) on the shipped example decodes feasibly."""
    problem = FleetProblem.load(Path(taopt.__file__).parent / "data/examples/fleet_problem.json")
    search = _Search(problem, np.random.default_rng(0), Deadline(None))
    (order, trucks, modes), value, _ = route_first(search)
    assert evaluate_fleet(problem, decode(problem, order, trucks, modes=modes).plan()) == (
        pytest.approx(value, rel=1e-9)
    )
    moves = search.flips(order, trucks, modes, far=True)
    assert moves
    for new_order, new_trucks, new_modes in moves:
        builder = decode(problem, new_order, new_trucks, modes=new_modes)  # checks precedence
        assert evaluate_fleet(problem, builder.plan()) == pytest.approx(
            builder.objective(), rel=1e-9
        )
