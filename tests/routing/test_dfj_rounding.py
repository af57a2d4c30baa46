"""The DFJ loop's rounded root point: a feasible incumbent, the routes themselves when the LP
point is integral, and a run that stops at the root when it meets the root bound."""

from __future__ import annotations

import numpy as np
import pytest
from reference_exact import dp_optimum, routing_instance

import taopt
from taopt.models.routing.dfj import DfjModel, rounded_routes
from taopt.routing.problem import evaluate_routes


@pytest.mark.parametrize("seed", range(12))
def test_rounded_root_routes_are_feasible_and_never_below_the_optimum(seed):
    """rounded_routes of the root LP point visits every target once and costs at least the
    brute-force (DP) optimum."""
    problem = routing_instance(seed)
    dfj = DfjModel(problem)
    root = dfj.root()
    routes = rounded_routes(problem, dfj, root.values)
    assert routes is not None
    assert sorted(t for route in routes for t in route) == list(range(problem.n))
    assert evaluate_routes(problem, routes) >= dp_optimum(problem) - 1e-9


@pytest.mark.parametrize("seed", range(6))
def test_rounding_an_integral_point_gives_its_routes(seed):
    """An integral point of given routes rounds back to exactly those routes."""
    problem = routing_instance(seed)
    dfj = DfjModel(problem)
    rng = np.random.default_rng(seed)
    order = [int(t) for t in rng.permutation(problem.n)]
    cuts = np.sort(rng.choice(np.arange(1, problem.n), size=problem.m - 1, replace=False))
    routes = [list(part) for part in np.split(np.asarray(order), cuts)]
    routes = [[int(t) for t in r] for r in routes]
    point = np.zeros(len(dfj.tails))
    point[dfj.route_arcs(routes)] = 1.0
    assert rounded_routes(problem, dfj, point) == routes


def test_a_run_whose_rounded_root_meets_the_bound_needs_no_mip_round():
    """When the rounded root point is optimal the loop proves it without a MIP round."""
    cost = np.full((4, 4), 9.0)
    np.fill_diagonal(cost, 0.0)
    cost[3, 0] = cost[0, 1] = cost[1, 2] = 1.0  # start 3 -> 0 -> 1 -> 2: the only cheap path
    problem = taopt.AssignmentProblem(cost, n_targets=3)
    solution = taopt.solve(problem, "exact")
    assert solution.status == "optimal"
    assert solution.objective == pytest.approx(dp_optimum(problem))
    assert solution.info["rounds"] == 0
