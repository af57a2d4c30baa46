"""The truck-walk and sortie-time terms of the fleet label search's bound
(:func:`taopt.fleet.cover.walk_table`, :func:`taopt.fleet.cover.sortie_time_table`)."""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np
import pytest
from reference_fleet import root_label

from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.cover import walk_table
from taopt.fleet.problem import FleetProblem
from taopt.fleet.search import _bound, _Tables, _walk_bound, label_search

# (seed, n, K, D, c, precedence, objective, stops): every K, D, c in {1, 2}, both objectives,
# with and without precedence; tiny_instance mixes drone-only, truck-only and either customers
SHAPES = [
    (41, 3, 1, 1, 1, False, "last_service", 3),
    (42, 3, 1, 1, 2, True, "return", 3),
    (43, 3, 1, 2, 1, True, "last_service", 3),
    (44, 3, 1, 2, 2, False, "return", 3),
    (45, 3, 2, 1, 1, True, "return", 2),
    (46, 3, 2, 1, 2, False, "last_service", 2),
    (47, 2, 2, 2, 1, False, "return", 3),
    (48, 2, 2, 2, 2, True, "last_service", 3),
]


@functools.cache
def _optimum(case: tuple) -> float:
    """The brute-force optimum of a SHAPES case (computed once for the tests that share it)."""
    value, plan, _ = brute_force(tiny_instance(*case[:7], stops=case[7]))
    assert plan is not None
    return value


def _reference_walk(problem: FleetProblem, drones: int) -> dict[tuple[int, int], float]:
    """The table of :func:`~taopt.fleet.cover.walk_table` by plain recursion, from the data."""
    p = problem
    n, s = p.n, p.s
    tt = p.truck_time.tolist()
    fs = p.flight_stop.tolist()
    vd, tau, ret = p.v_drone, p.service_time, p.objective == "return"
    home = [tt[w][p.depot] if ret else 0.0 for w in range(s)]
    near = [min(fs[j]) for j in range(n)]
    drone_home = [min(fs[j][q] / vd + tau + tt[q][p.depot] for q in range(s)) for j in range(n)]
    off = [[math.inf] * n for _ in range(s)]
    for w, j in itertools.product(range(s), range(n)):
        if p.truck_servable(j) and p.customer_stop[j] == w:
            off[w][j] = home[w]
        if drones and p.drone_servable(j) and fs[j][w] + near[j] <= p.flight_limit:
            off[w][j] = min(off[w][j], fs[j][w] / vd + tau + (drone_home[j] if ret else 0.0))
    cover = [sum(1 << j for j in range(n) if off[w][j] < math.inf) for w in range(s)]
    o = [[min(tt[q][w] + off[w][j] for w in range(s)) for j in range(n)] for q in range(s)]
    only = [not p.truck_servable(j) for j in range(n)]
    into = [
        min(
            [near[j]]
            + [float(p.flight_customer[i, j]) for i in range(n) if i != j and p.capacity > 1]
        )
        for j in range(n)
    ]
    rho = min(min(row) for row in fs) / vd + tau

    def end(R: int, q: int) -> float:
        members = [j for j in range(n) if R >> j & 1]
        e = max([home[q]] + [o[q][j] for j in members])
        if drones:
            work = sum(into[j] / vd + tau for j in members if only[j])
            sorties = -(-sum(only[j] for j in members) // p.capacity)
            e = max(e, (work + max(0, sorties - drones) * rho) / drones)
        return e

    @functools.cache
    def value(R: int, w: int) -> float:
        if R == 0:
            return home[w]
        best = math.inf
        for q in range(s):
            if R & cover[q]:
                best = min(best, tt[w][q] + max(end(R, q), value(R & ~cover[q], q)))
        return best

    return {(R, w): value(R, w) for R in range(1 << n) for w in range(s)}


@pytest.mark.parametrize("objective", ["last_service", "return"])
@pytest.mark.parametrize("drones", [0, 1, 2])
def test_walk_table_equals_plain_recursion(objective, drones):
    """walk_table's vectorised DP equals a plain-Python recursion over (set, stop)."""
    problem = tiny_instance(7, 4, 1, 1, 2, True, objective, stops=4)
    table = walk_table(problem, drones)
    assert table is not None
    for (R, w), v in _reference_walk(problem, drones).items():
        got = float(table.value[R, w])
        assert got == pytest.approx(v, rel=1e-12, abs=1e-12) or (math.isinf(v) and math.isinf(got))


def test_walk_table_is_skipped_above_its_cap():
    """Above WALK_MAX_CUSTOMERS no table is built (the bound runs without the term)."""
    from taopt.fleet.cover import WALK_MAX_CUSTOMERS
    from taopt.fleet.instances import residential_fleet

    problem = residential_fleet(WALK_MAX_CUSTOMERS + 1, 1, 1, 1, seed=0)
    assert walk_table(problem, 1) is None


@pytest.mark.parametrize("case", SHAPES)
def test_walk_bound_never_above_the_brute_force_optimum(case):
    """At the root, the walk term and the whole label bound are <= the brute-force optimum."""
    problem = tiny_instance(*case[:7], stops=case[7])
    value = _optimum(case)
    tab = _Tables(problem)
    root = root_label(problem)
    assert _walk_bound(tab, tab.full, root[3]) <= value * (1 + 1e-9) + 1e-9
    assert _bound(tab, root) <= value * (1 + 1e-9) + 1e-9


@pytest.mark.parametrize("case", SHAPES)
def test_search_with_walk_term_equals_brute_force(case):
    """The label search with the walk term, no beam and no incumbent, finds the brute-force
    optimum (a bound above some completion would prune it)."""
    problem = tiny_instance(*case[:7], stops=case[7])
    value = _optimum(case)
    result = label_search(problem, beam=0)
    assert result["stopped_by"] == "optimal"
    assert result["value"] == pytest.approx(value, rel=1e-9, abs=1e-9)


@pytest.mark.slow
def test_search_with_walk_term_on_64_tiny_instances():
    """Every K, D, c in {1, 2}, with and without precedence, both objectives, two seeds, n = 3:
    the root bound is <= the brute-force optimum and the search equals it."""
    for seed, K, D, c, prec, objective in itertools.product(
        (51, 52), (1, 2), (1, 2), (1, 2), (False, True), ("last_service", "return")
    ):
        problem = tiny_instance(seed, 3, K, D, c, prec, objective, stops=3)
        value, _, _ = brute_force(problem)
        tab = _Tables(problem)
        assert _bound(tab, root_label(problem)) <= value * (1 + 1e-9) + 1e-9
        assert label_search(problem, beam=0)["value"] == pytest.approx(value, rel=1e-9, abs=1e-9)


def test_two_trucks_take_the_best_split():
    """With two trucks the walk term is the least over the splits of the customers of the
    larger of the two trucks' walk values (checked against an explicit enumeration)."""
    problem = tiny_instance(9, 4, 2, 1, 1, False, "last_service", stops=4)
    tab = _Tables(problem)
    trucks = list(root_label(problem)[3])
    trucks[1] = (2, 5.0, 7.0, True, False, 0.0, trucks[1][6])
    table = tab.walk[1]
    U = tab.full
    want = min(
        max(
            0.0 + float(table.value[X & ~table.cover[problem.depot], problem.depot]),
            7.0 + float(table.value[(U ^ X) & ~table.cover[2], 2]),
        )
        for X in range(U + 1)
    )
    assert _walk_bound(tab, U, tuple(trucks)) == pytest.approx(want)
    assert np.isfinite(want)


def test_walk_term_raises_the_root_bound_on_a_residential_instance():
    """On a residential instance where the truck must carry its drones across the streets, the
    root bound with the walk term is above the one without it."""
    from taopt.fleet.instances import residential_fleet

    problem = residential_fleet(5, 1, 2, 2, seed=1)
    root = root_label(problem)
    assert _bound(_Tables(problem), root) > _bound(_Tables(problem, walk=False), root) + 1.0


def test_sortie_time_table_single_customers_match_the_direct_flight():
    """One drone serving one customer from stop w ends after the least drive to a launch stop
    in range plus the flight and τ (the sortie-time table's one-customer entries)."""
    from taopt.fleet.cover import sortie_time_table

    problem = tiny_instance(7, 4, 1, 1, 2, True, "last_service", stops=4)
    F = sortie_time_table(problem)
    assert F is not None
    fs, tt = problem.flight_stop, problem.truck_time
    for w, j in itertools.product(range(problem.s), range(problem.n)):
        if not problem.drone_servable(j):
            assert math.isinf(F[w, 1 << j])
            continue
        legal = [v for v in range(problem.s) if fs[j, v] + fs[j].min() <= problem.flight_limit]
        want = min(
            (tt[w, v] + fs[j, v] / problem.v_drone + problem.service_time for v in legal),
            default=math.inf,
        )
        assert F[w, 1 << j] == pytest.approx(want)


@pytest.mark.slow
def test_search_with_walk_term_three_trucks():
    """Three trucks (the walk term's and the sortie term's size arguments): the search with
    both terms, no beam and no incumbent, equals the brute force under both objectives."""
    for seed, objective in itertools.product((61, 62), ("last_service", "return")):
        problem = tiny_instance(seed, 3, 3, 1, 2, True, objective, stops=3)
        value, _, _ = brute_force(problem)
        assert label_search(problem, beam=0)["value"] == pytest.approx(value, rel=1e-9, abs=1e-9)
