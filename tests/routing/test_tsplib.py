"""TSPLIB ATSP certification of the exact model through the one-vehicle reduction."""

from __future__ import annotations

from itertools import permutations

import numpy as np
import pytest

import taopt
from taopt.errors import InstanceError
from taopt.models import solve_routing
from taopt.routing.tsplib import (
    KNOWN_OPTIMA,
    AtspInstance,
    atsp_to_assignment,
    load_atsp,
    shipped,
    tour_length,
)


def test_shipped_files_load():
    names = shipped()
    for name in ("br17", "ftv33", "ftv35", "ftv38", "p43"):
        assert name in names
    for name in names:
        atsp = load_atsp(name)
        assert atsp.distance.shape == (atsp.dimension, atsp.dimension)
        assert int(atsp.header["DIMENSION"]) == atsp.dimension
        assert atsp.header["TYPE"] == "ATSP"
        off = atsp.distance[~np.eye(atsp.dimension, dtype=bool)]
        assert off.min() >= 0
    assert load_atsp("ftv33").dimension == 34  # ftvN has N + 1 nodes
    assert load_atsp("p43").distance[0, 0] == 0  # p43's diagonal is 0 and must be ignored
    assert load_atsp("br17").distance[0, 0] == 9999


@pytest.mark.parametrize("name", ["br17", "ftv33"])
def test_known_optimum(name):
    atsp = load_atsp(name)
    problem = atsp_to_assignment(atsp)
    solution = solve_routing(problem, sec="dfj")
    assert solution.status == "optimal"
    assert solution.objective == pytest.approx(KNOWN_OPTIMA[name], abs=1e-6)
    assert taopt.evaluate(problem, solution.routes) == pytest.approx(solution.objective, rel=1e-9)
    # the open route ends at the copy of city 0 and is a closed tour of the same length
    assert solution.routes[0][-1] == atsp.dimension - 1
    assert tour_length(atsp, solution.routes[0]) == KNOWN_OPTIMA[name]
    assert solution.bound <= solution.objective


def brute_force_atsp(distance: np.ndarray) -> float:
    cities = len(distance)
    best = np.inf
    for order in permutations(range(1, cities)):
        tour = (0, *order, 0)
        best = min(best, sum(distance[a, b] for a, b in zip(tour[:-1], tour[1:], strict=False)))
    return float(best)


@pytest.mark.parametrize("seed", range(4))
def test_reduction_matches_brute_force(seed):
    """Random asymmetric ATSPs (not metric, big diagonal): reduction optimum == tour optimum."""
    rng = np.random.default_rng(seed)
    distance = rng.integers(0, 50, size=(7, 7)).astype(float)
    np.fill_diagonal(distance, 9999)
    atsp = AtspInstance("random", {}, distance)
    problem = atsp_to_assignment(atsp)
    expected = brute_force_atsp(distance)
    for sec in ("dfj", "mtz", "flow"):
        solution = solve_routing(problem, sec=sec)
        assert solution.objective == pytest.approx(expected)
        assert tour_length(atsp, solution.routes[0]) == pytest.approx(expected)


def test_reduction_structure():
    atsp = load_atsp("br17")
    problem = atsp_to_assignment(atsp)
    n = atsp.dimension
    assert (problem.n, problem.m) == (n, 1)
    prohibitive = problem.cost[n - 1, 0]
    # larger than any tour: every tour is at most the sum of row maxima
    off = np.where(np.eye(n, dtype=bool), -np.inf, atsp.distance)
    assert prohibitive > off.max(axis=1).sum()
    assert problem.cost[n, 0] == atsp.distance[0, 1]  # vehicle at city 0 -> target 0 = city 1
    assert problem.cost[0, 1] == atsp.distance[1, 2]


def test_bad_files(tmp_path):
    with pytest.raises(InstanceError, match="no shipped"):
        load_atsp("nope")
    bad = tmp_path / "bad.atsp"
    bad.write_text(
        "NAME: bad\nTYPE: ATSP\nDIMENSION: 3\nEDGE_WEIGHT_TYPE: EXPLICIT\n"
        "EDGE_WEIGHT_FORMAT: FULL_MATRIX\nEDGE_WEIGHT_SECTION\n0 1 2\n3 0 4\nEOF\n"
    )
    with pytest.raises(InstanceError, match="6 weights"):
        load_atsp(bad)
    bad.write_text("NAME: bad\nTYPE: TSP\nDIMENSION: 1\nEDGE_WEIGHT_SECTION\n0\n")
    with pytest.raises(InstanceError, match="ATSP"):
        load_atsp(bad)
    with pytest.raises(InstanceError, match="does not exist"):
        load_atsp(tmp_path / "missing.atsp")
