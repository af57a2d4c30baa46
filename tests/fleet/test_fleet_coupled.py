"""The joint DP of one split (:mod:`taopt.fleet.coupled`) and the split DP that uses it, against
the brute force restricted to the split."""

from __future__ import annotations

import itertools

import networkx as nx
import pytest

import taopt
from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.coupled import coupled_applies, coupled_dp
from taopt.fleet.problem import FleetProblem
from taopt.fleet.sorties import _sequences, _table


def _drone_only(seed: int, n: int, trucks: int, capacity: int, objective: str) -> FleetProblem:
    p = tiny_instance(seed, n, trucks, 1, capacity, True, objective, stops=3)
    return p.replace(service=["drone"] * p.n, customer_stop=[None] * p.n, service_time=2.0)


def _splits(p: FleetProblem):
    closure = sorted(
        (int(r), int(j)) for r, j in nx.transitive_closure_dag(p.precedence_graph).edges
    )
    seqs = _sequences(p, set(closure))
    pre = (seqs, _table(p, seqs))
    for assign in itertools.product(range(p.K), repeat=p.n):
        split = tuple(sum(1 << j for j in range(p.n) if assign[j] == k) for k in range(p.K))
        yield list(assign), split, pre, closure


@pytest.mark.parametrize("objective", ["last_service", "return"])
@pytest.mark.parametrize("capacity", [1, 2])
def test_coupled_dp_equals_the_brute_force_restricted_to_the_split(capacity, objective):
    """Where it applies, the joint DP's value is the split's optimum and its plan scores it."""
    checked = 0
    for seed in range(1):
        p = _drone_only(900 + seed, 3, 2, capacity, objective)
        for owner, split, pre, closure in _splits(p):
            if not coupled_applies(p, split):
                continue
            value = brute_force(p, truck_of=owner)[0]
            got = coupled_dp(p, split, pre, closure)
            assert got["stopped_by"] == "optimal"
            assert got["value"] == pytest.approx(value, rel=1e-9, abs=1e-9)
            assert taopt.evaluate(p, got["plan"]) == pytest.approx(value, rel=1e-9, abs=1e-9)
            checked += 1
    assert checked > 0


@pytest.mark.slow
def test_coupled_dp_relaxations_never_above_the_restricted_optimum():
    """Where the trucks' cross pairs form a cycle (c = 2), each truck order's relaxation (with
    the split DP's releases left out) is a lower bound on the split's optimum."""
    seen = 0
    for seed in range(12):
        p = _drone_only(950 + seed, 4, 2, 2, "last_service")
        for owner, split, pre, closure in _splits(p):
            if coupled_applies(p, split):
                continue
            value = brute_force(p, truck_of=owner)[0]
            for order in itertools.permutations(range(2)):
                got = coupled_dp(p, split, pre, closure, order=order)
                assert got["bound"] <= value + 1e-9
            seen += 1
            if seen >= 4:
                return
    assert seen > 0


@pytest.mark.parametrize("trucks", [2, 3])
@pytest.mark.parametrize("objective", ["last_service", "return"])
def test_split_dp_certifies_the_brute_force_optimum(trucks, objective):
    """K = 2, 3 with one drone each and precedences: the split DP (releases, then the joint DP
    of the splits left open) certifies the brute-force optimum."""
    from taopt.models.fleet import solve_fleet

    for seed in range(1):
        p = _drone_only(980 + seed, 3, trucks, 2, objective)
        value = brute_force(p)[0]
        solution = solve_fleet(p, algorithm="split_dp")
        assert solution.status == "optimal"
        assert solution.objective == pytest.approx(value, rel=1e-9, abs=1e-9)
        assert taopt.evaluate(p, solution.solution) == pytest.approx(value, rel=1e-9, abs=1e-9)


def _one_drone_check(n: int, seeds: range, objective: str) -> None:
    from taopt.models.fleet import _one_drone_floor

    for seed in seeds:
        p = tiny_instance(990 + seed, n, 1, 2, 1 + seed % 2, True, objective, stops=3)
        p = p.replace(service=["drone"] * p.n, customer_stop=[None] * p.n)
        value = brute_force(p)[0]
        assert 0.0 < _one_drone_floor(p, None) <= value + 1e-9


@pytest.mark.parametrize("objective", ["last_service", "return"])
def test_one_drone_relaxation_never_above_the_brute_force_optimum(objective):
    """One truck with two drones (n = 2): two trucks with one drone each bound the optimum."""
    _one_drone_check(2, range(3), objective)


@pytest.mark.slow
@pytest.mark.parametrize("objective", ["last_service", "return"])
def test_one_drone_relaxation_never_above_the_optimum_at_three_customers(objective):
    """One truck with two drones (n = 3): the one-drone relaxation bounds the optimum."""
    _one_drone_check(3, range(3), objective)
