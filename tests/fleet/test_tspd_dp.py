"""The sparse TSP-D operations DP (taopt.fleet.tspd_dp) against the full operations DP, the
published optima, and the TSP-D generator."""

from __future__ import annotations

import pytest

import taopt
from taopt.errors import InstanceError, SolverError
from taopt.fleet import FleetProblem
from taopt.fleet.operations import operations_dp
from taopt.fleet.tspd import (
    TSPD_FOLDER,
    generate_tspd,
    generated_instances,
    published_optimum,
    write_tspd,
)
from taopt.fleet.tspd_dp import tspd_applies, tspd_dp

#: Optima of our generated instances by the sparse DP (6 decimals). The full operations DP
#: (``operations_dp(fast=False)``) gave the same values at 14-15 nodes (all six, in
#: ``benchmarks/bench_fleet.py --before``); see docs/families/fleet.md for 16-17.
GENERATED_OPTIMA = {
    "gen-1-n14": 263.068525,
    "gen-2-n14": 275.173872,
    "gen-3-n14": 230.471628,
    "gen-1-n15": 253.627775,
    "gen-2-n15": 258.691353,
    "gen-3-n15": 273.581081,
    "gen-1-n16": 222.448326,
    "gen-2-n16": 252.291175,
    "gen-3-n16": 260.053362,
    "gen-1-n17": 258.942456,
    "gen-2-n17": 250.134500,
    "gen-3-n17": 276.010153,
}

RANDOM_CASES = [
    (nodes, seed, maxfly, novisit)
    for nodes, seed in [(5, 1), (6, 2), (7, 3), (8, 4), (9, 5), (9, 6), (8, 7), (7, 8)]
    for maxfly, novisit in [(None, ()), (60.0, ()), (None, (1, 3))]
]


def _instance(tmp_path, nodes, seed, **options):
    return FleetProblem.from_tspd(
        write_tspd(tmp_path / f"r-{seed}-n{nodes}.txt", nodes, seed, **options)
    )


@pytest.mark.parametrize(("nodes", "seed", "maxfly", "novisit"), RANDOM_CASES)
def test_sparse_dp_equals_the_full_operations_dp(tmp_path, nodes, seed, maxfly, novisit):
    """Random TSP-D instances of 5-9 nodes (with a range, with truck-only nodes): same optimum."""
    problem = _instance(tmp_path, nodes, seed, maxfly=maxfly, novisit=novisit)
    assert tspd_applies(problem)
    fast = tspd_dp(problem)
    full = operations_dp(problem, fast=False)
    assert fast["stopped_by"] == full["stopped_by"] == "optimal"
    assert fast["value"] == pytest.approx(full["value"], rel=1e-12)
    assert taopt.evaluate(problem, fast["plan"]) == pytest.approx(fast["value"], rel=1e-12)


@pytest.mark.parametrize("name", ["uniform-2-n11", "uniform-5-n12", "uniform-7-n13"])
def test_sparse_dp_reaches_the_published_optimum(name):
    """Shipped 11-13 node instances: the sparse DP equals the published optimum (rel 1e-6)."""
    path = TSPD_FOLDER / f"{name}.txt"
    result = tspd_dp(FleetProblem.from_tspd(path))
    assert result["stopped_by"] == "optimal"
    assert result["value"] == pytest.approx(published_optimum(path), rel=1e-6)


def test_exact_dispatches_a_tspd_to_the_sparse_dp():
    """taopt.solve(..., "exact") on a TSP-D: certified, with the sparse DP's counters."""
    problem = FleetProblem.from_tspd(TSPD_FOLDER / "uniform-1-n11.txt")
    solution = taopt.solve(problem, "exact")
    assert solution.status == "optimal" and solution.info["algorithm"] == "operations"
    assert solution.info["combinations"] > 0
    assert solution.objective == pytest.approx(published_optimum(TSPD_FOLDER / "uniform-1-n11.txt"))


@pytest.mark.parametrize(
    ("trucks", "objective", "stops"), [(2, "return", 3), (1, "last_service", 3), (1, "return", 4)]
)
def test_other_operations_cases_keep_the_full_dp(trucks, objective, stops):
    """Several trucks, last_service, street networks: not a TSP-D, the full DP answers."""
    from taopt.fleet.brute import tiny_instance

    problem = tiny_instance(21, 4, trucks, 1, 1, False, objective, stops=stops)
    assert not tspd_applies(problem)
    with pytest.raises(SolverError, match="geometric TSP-D"):
        tspd_dp(problem)
    assert operations_dp(problem)["value"] == pytest.approx(
        operations_dp(problem, fast=False)["value"], rel=1e-12
    )


def test_time_limit_returns_a_feasible_plan_and_a_bound():
    """time_limit = 0: status time_limit, a feasible plan, bound <= its value."""
    problem = FleetProblem.from_tspd(TSPD_FOLDER / "uniform-1-n13.txt")
    result = tspd_dp(problem, time_limit=0.0)
    assert result["stopped_by"] == "time_limit"
    assert taopt.evaluate(problem, result["plan"]) == pytest.approx(result["value"])
    assert result["bound"] <= result["value"]


def test_generator_is_seeded_and_follows_the_published_distribution(tmp_path):
    """Same seed, same text; depot in [0, 1)², other nodes integers 0..99; speeds 1.0 / 0.5."""
    assert generate_tspd(12, 7) == generate_tspd(12, 7) != generate_tspd(12, 8)
    problem = _instance(tmp_path, 12, 7)
    assert problem.n == 11 and problem.v_truck == 1.0 and problem.v_drone == 2.0
    assert ((problem.stops[0] >= 0) & (problem.stops[0] < 1)).all()
    others = problem.stops[1:]
    assert ((others >= 0) & (others <= 99) & (others == others.round())).all()


def test_generator_names_a_bad_novisit_node():
    """A #NOVISIT node outside 1..N-1: InstanceError naming it."""
    with pytest.raises(InstanceError, match="node 9"):
        generate_tspd(5, 1, novisit=[9])


def test_generated_instances_are_shipped():
    """Three generated instances per size 14-17, readable, TSP-D shaped."""
    paths = generated_instances()
    assert [FleetProblem.from_tspd(p).s for p in paths] == [
        n for n in range(14, 18) for _ in range(3)
    ]
    assert all(tspd_applies(FleetProblem.from_tspd(p)) for p in paths)


@pytest.mark.slow
def test_generated_14_to_17_node_instances_keep_their_optima():
    """Every generated instance: certified by the exact method, its recorded optimum (6 dp)."""
    paths = generated_instances()
    assert sorted(p.stem for p in paths) == sorted(GENERATED_OPTIMA)
    for path in paths:
        solution = taopt.solve(FleetProblem.from_tspd(path), "exact")
        assert solution.status == "optimal", path.name
        assert solution.objective == pytest.approx(GENERATED_OPTIMA[path.stem], abs=2e-6), path.name
