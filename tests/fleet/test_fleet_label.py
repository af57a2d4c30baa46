"""The fleet label search on one truck with several drones (:mod:`taopt.fleet.search`):
canonical appends, bound terms, time limits, and the synchronised incumbent
(:mod:`taopt.fleet.synced`)."""

from __future__ import annotations

import math

import pytest
from reference_fleet import best_completion, root_label

import taopt
from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.evaluate import evaluate_fleet
from taopt.fleet.instances import residential_fleet
from taopt.fleet.search import (
    _bound,
    _signature,
    _sortie_time_bound,
    _Tables,
    _walk_bound,
    _water_fill,
    label_search,
)
from taopt.fleet.synced import synced_plan

# (seed, D, c, precedence, objective, optimum): K = 1, n = 3, 2 stops; every D in {2, 3},
# c in {1, 2}, both objectives, with and without precedence. The optimum is
# taopt.fleet.brute.brute_force's (recomputed by the slow test below).
CASES = [
    (200, 2, 1, False, "last_service", 110.23968857594866),
    (213, 2, 1, False, "return", 95.550935661564),
    (227, 2, 1, True, "last_service", 61.81482960343733),
    (246, 2, 1, True, "return", 163.6866672714507),
    (254, 2, 2, False, "last_service", 26.243723058239976),
    (265, 2, 2, False, "return", 281.8561218175563),
    (291, 2, 2, True, "last_service", 30.258336907779736),
    (291, 2, 2, True, "return", 60.51667381555947),
    (304, 3, 1, False, "last_service", 67.76612778271655),
    (317, 3, 1, False, "return", 189.32493196028483),
    (330, 3, 1, True, "last_service", 121.00794726695304),
    (348, 3, 1, True, "return", 68.77390949136627),
    (357, 3, 2, False, "last_service", 12.540286209055406),
    (369, 3, 2, False, "return", 174.0142666625715),
    (398, 3, 2, True, "last_service", 43.24917207608939),
    (398, 3, 2, True, "return", 88.49834415217877),
]

#: The certified optimum of residential_fleet(5, 1, 2, 2, seed=1) (label search, 3-16 s).
N5_SEED1 = 400.3773994471987


def _instance(case: tuple):
    seed, D, c, prec, objective, _ = case
    return tiny_instance(seed, 3, 1, D, c, prec, objective, stops=2)


@pytest.mark.parametrize("case", CASES)
def test_search_equals_brute_force_one_truck_several_drones(case):
    """The label search (no beam, no incumbent) proves the brute-force optimum."""
    result = label_search(_instance(case), beam=0)
    assert result["stopped_by"] == "optimal"
    assert result["value"] == pytest.approx(case[5], rel=1e-9, abs=1e-9)
    assert result["bound"] == pytest.approx(case[5], rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("case", CASES)
def test_every_root_bound_term_is_below_the_optimum(case):
    """Each term of the root label bound is <= the brute-force optimum."""
    problem = _instance(case)
    tab = _Tables(problem)
    root = root_label(problem)
    trucks = root[3]
    top = case[5] * (1 + 1e-9) + 1e-9
    assert _walk_bound(tab, tab.full, trucks) <= top
    assert _sortie_time_bound(tab, tab.drone_only, trucks) <= top
    assert _water_fill(tab, 0, trucks) <= top
    assert _bound(tab, root) <= top


@pytest.mark.parametrize("objective", ["last_service", "return"])
@pytest.mark.parametrize("seed", [1000, pytest.param(1003, marks=pytest.mark.slow)])
def test_bound_never_above_a_labels_best_completion_with_waiting_drones(seed, objective):
    """At every label of a tiny drone-only instance with precedences and two drones of
    capacity 2 (a drone may wait in the air, empty, for a predecessor, then go on), the
    label bound, inf included, is <= the best completion below it (main's bound was not:
    129.4 over 53.2 on seed 1000)."""
    p = tiny_instance(seed, 3, 1, 2, 2, True, objective, stops=2)
    p = p.replace(service=("drone",) * 3, customer_stop=(None,) * 3)
    assert p.precedences
    tab = _Tables(p)
    seen: list = []
    assert best_completion(tab, root_label(p), {}, seen) < math.inf
    assert len(seen) > 1000
    for bound, best in seen:
        assert bound <= best * (1 + 1e-9) + 1e-9


def test_dominance_holds_between_labels_of_one_key():
    """Two labels of a tiny instance with precedences and waiting drones with the same
    dominance key (a sample of the pairs), one's vector <= the other's: its best completion
    is <= the other's (what lets the search drop a label dominated by a kept one or by one
    the bound pruned)."""
    p = tiny_instance(1000, 3, 1, 2, 2, True, "last_service", stops=2)
    p = p.replace(service=("drone",) * 3, customer_stop=(None,) * 3)
    tab = _Tables(p)
    memo: dict = {}
    best_completion(tab, root_label(p), memo, [])
    groups: dict = {}
    for label, best in memo.items():
        key, vec = _signature(tab, label)
        groups.setdefault(key, []).append((vec, best))
    pairs = 0
    for entries in groups.values():
        for vec, best in entries:
            for other, other_best in entries[:24]:  # (a sample: the pairs grow quadratically)
                if other is not vec and all(a <= b for a, b in zip(other, vec, strict=True)):
                    pairs += 1
                    assert other_best <= best * (1 + 1e-9) + 1e-9
    assert pairs > 100


#: A case with capacity 2 where the search still drops labels dominated by pruned ones
#: (CASES[15] no longer has any since the sortie-time term keeps the customers in reach of the
#: sorties in the air); the value is :func:`taopt.fleet.brute.brute_force`'s.
DOMINATED_BY_PRUNED = (400, 3, 2, True, "return", 49.63029674297544)


@pytest.mark.parametrize("case", [CASES[3], CASES[11], DOMINATED_BY_PRUNED])
def test_labels_dominated_by_pruned_ones_keep_the_optimum(case):
    """With the optimum as cutoff the search drops labels dominated by labels the bound
    pruned, and still proves the brute-force optimum."""
    result = label_search(_instance(case), beam=0, cutoff=case[5] * (1 + 1e-6))
    assert result["dominated_by_pruned"] > 0
    assert result["stopped_by"] == "optimal"
    assert result["value"] == pytest.approx(case[5], rel=1e-9, abs=1e-9)
    assert result["bound"] == pytest.approx(case[5], rel=1e-9, abs=1e-9)


@pytest.mark.slow
def test_cases_are_the_brute_force_optima():
    """CASES' optima are brute_force's (a few seconds)."""
    for case in CASES:
        value, plan, _ = brute_force(_instance(case))
        assert plan is not None
        assert value == pytest.approx(case[5], rel=1e-12, abs=1e-12)


@pytest.mark.slow
def test_canonical_appends_keep_the_optimum_with_precedences():
    """With precedences (lazy appends, canonical rule) the search on residential n = 5,
    seed 1, proves the certified optimum, and no complete plan is below it."""
    problem = residential_fleet(5, 1, 2, 2, seed=1)
    assert problem.precedences
    result = label_search(problem, beam=0)
    assert result["stopped_by"] == "optimal"
    assert result["value"] == pytest.approx(N5_SEED1, rel=1e-9)
    assert evaluate_fleet(problem, result["plan"]) == pytest.approx(N5_SEED1, rel=1e-9)


def test_zero_time_limit_returns_a_proven_bound():
    """A zero time limit stops the search at once with status time_limit and a bound
    between the root bound's validity and the incumbent: bound <= optimum <= value."""
    case = CASES[6]
    result = label_search(_instance(case), time_limit=0.0)
    assert result["stopped_by"] in ("time_limit", "optimal")
    assert result["bound"] <= case[5] * (1 + 1e-9) + 1e-9
    assert result["value"] >= case[5] * (1 - 1e-9)


def test_tiny_time_limit_through_solve_is_time_limit_with_a_valid_bound():
    """taopt.solve on n = 5 (optimum 400.38 needs seconds) with a 0.05 s limit returns
    status time_limit, a feasible plan and a bound <= the optimum <= the plan's value."""
    problem = residential_fleet(5, 1, 2, 2, seed=1)
    solution = taopt.solve(problem, "exact", time_limit=0.05)
    assert solution.status == "time_limit"
    assert solution.bound <= N5_SEED1 * (1 + 1e-9)
    assert solution.objective >= N5_SEED1 * (1 - 1e-9)
    assert evaluate_fleet(problem, solution.solution) == pytest.approx(solution.objective)


@pytest.mark.parametrize("case", CASES)
def test_synced_plan_is_feasible_and_never_below_the_optimum(case):
    """The synchronised-operations incumbent is scored by evaluate and >= the optimum."""
    problem = _instance(case)
    value, plan = synced_plan(problem)
    if plan is None:  # a truck-only customer: the DP does not apply
        assert any(not problem.drone_servable(j) for j in range(problem.n))
        return
    assert evaluate_fleet(problem, plan) == pytest.approx(value)
    assert value >= case[5] * (1 - 1e-9)


def test_synced_plan_on_a_residential_instance():
    """On residential n = 5 (two drones, c = 2, precedences) the synchronised plan is
    feasible, >= the certified optimum, and its operations launch every drone."""
    problem = residential_fleet(5, 1, 2, 2, seed=1)
    value, plan = synced_plan(problem)
    assert plan is not None
    assert evaluate_fleet(problem, plan) == pytest.approx(value)
    assert value >= N5_SEED1 * (1 - 1e-9)
    served = sorted(j for flights in plan.sorties[0] for s in flights for j in s.customers)
    assert served == list(range(problem.n))


@pytest.mark.parametrize("drones", [3, 4])
def test_least_largest_equals_every_assignment(drones):
    """The min-max subset convolution over three or four drones equals the least, over every
    assignment of m customers to drones, of the largest drone's end."""
    import itertools

    import numpy as np

    from taopt.fleet.search import _least_largest

    rng = np.random.default_rng(drones)
    for m in range(5):
        ends = [rng.uniform(0, 10, 1 << m) for _ in range(drones)]
        for e in ends:
            e[0] = 0.0
        expected = min(
            max(ends[i][sum(1 << b for b in range(m) if a[b] == i)] for i in range(drones))
            for a in itertools.product(range(drones), repeat=m)
        )
        assert _least_largest(ends, m)[-1] == pytest.approx(expected, abs=1e-12)


def test_three_drone_sortie_term_is_exact_and_below_the_optimum():
    """With three drones the sortie-time term splits the customers exactly (never below the
    size argument it replaces) and stays <= the brute-force optimum on the D = 3 cases."""
    import taopt.fleet.search as search

    for case in CASES:
        if case[1] != 3:
            continue
        problem = _instance(case)
        tab = _Tables(problem)
        trucks = root_label(problem)[3]
        exact = _sortie_time_bound(tab, tab.drone_only, trucks)
        saved = search.PARTITION_MAX_CUSTOMERS
        search.PARTITION_MAX_CUSTOMERS = -1
        try:
            sized = _sortie_time_bound(tab, tab.drone_only, trucks)
        finally:
            search.PARTITION_MAX_CUSTOMERS = saved
        assert sized <= exact + 1e-9
        assert exact <= case[5] * (1 + 1e-9) + 1e-9


def test_three_drone_sortie_term_lifts_the_residential_root():
    """On residential n = 6 with three drones the exact split lifts the root sortie term
    above the size argument, and stays below a feasible plan's value."""
    import taopt.fleet.search as search

    problem = residential_fleet(6, 1, 3, 2, seed=0)
    tab = _Tables(problem)
    trucks = root_label(problem)[3]
    exact = _sortie_time_bound(tab, tab.drone_only, trucks)
    saved = search.PARTITION_MAX_CUSTOMERS
    search.PARTITION_MAX_CUSTOMERS = -1
    try:
        sized = _sortie_time_bound(tab, tab.drone_only, trucks)
    finally:
        search.PARTITION_MAX_CUSTOMERS = saved
    value, plan = synced_plan(problem)
    assert plan is not None
    assert sized < exact <= value


def test_identical_drones_permuted_share_a_signature():
    """Two labels that differ only by a permutation of one truck's identical drones have the
    same dominance key and vector (and metric entries), so the search keeps one of them."""
    from taopt.fleet.search import _metric_entries, _signature

    problem = residential_fleet(5, 1, 3, 2, seed=1)
    tab = _Tables(problem)
    svc = (12.0, -1.0, -1.0, 40.0, -1.0)
    drones = (
        (0, 55.0),
        (1, 0, 1, 42.0, 90.0, True, True, 0b01001),
        (1, -3, 0, 30.0, 0.0, True, False, 0b01001),
    )
    labels = []
    for order in ((0, 1, 2), (2, 0, 1), (1, 2, 0)):
        trucks = ((4, 30.0, 30.0, True, False, 0.0, tuple(drones[i] for i in order)),)
        labels.append((0b01001, 40.0, svc, trucks))
    first = _signature(tab, labels[0])
    assert all(_signature(tab, label) == first for label in labels[1:])
    entries = _metric_entries(tab, labels[0])
    assert all(_metric_entries(tab, label) == entries for label in labels[1:])


#: (D, objective, brute-force optimum) of tiny_instance(291, 3, 1, D, 2, True, objective,
#: stops=2) made drone-only (recomputed by the slow test below)
RELAX_CASES = [
    (2, "last_service", 34.87062726675864),
    (2, "return", 60.51667381555947),
    (3, "last_service", 30.258336907779736),
    (3, "return", 60.51667381555947),
]


def _drone_only(drones: int, objective: str):
    p = tiny_instance(291, 3, 1, drones, 2, True, objective, stops=2)
    return p.replace(service=("drone",) * 3, customer_stop=(None,) * 3)


@pytest.mark.parametrize("case", RELAX_CASES)
def test_root_cover_from_the_relaxation_stays_below_the_optimum(case):
    """The sortie-walk bound started from the one-drone relaxation (the one-truck dispatch's
    order) is at least the relaxation and at most the brute-force optimum (drone-only, with
    precedence)."""
    from taopt.models.fleet import _one_drone_floor, _root_cover

    drones, objective, value = case
    p = _drone_only(drones, objective)
    relaxed = _one_drone_floor(p, None)
    assert 0.0 < relaxed <= value * (1 + 1e-9) + 1e-9
    bound, incumbent = _root_cover(p, None, None, relaxed)
    assert relaxed <= bound <= value * (1 + 1e-9) + 1e-9
    assert evaluate_fleet(p, incumbent) >= value * (1 - 1e-9)


@pytest.mark.slow
def test_relax_cases_are_the_brute_force_optima():
    """RELAX_CASES' optima are brute_force's (about 7 s)."""
    for drones, objective, value in RELAX_CASES:
        got, plan, _ = brute_force(_drone_only(drones, objective))
        assert plan is not None
        assert got == pytest.approx(value, rel=1e-12, abs=1e-12)


#: (seed, n, stops, c, precedence, objective): drone-only tiny instances (K = 1, D = 2) with
#: labels where two airborne drones' shared recoveries lift the sortie-time term
SHARED_CASES = [
    (4006, 4, 2, 1, False, "last_service"),
    (4006, 4, 2, 1, True, "last_service"),
    (4024, 4, 2, 2, True, "last_service"),
    (3015, 3, 3, 1, False, "return"),
    (3015, 3, 3, 1, True, "return"),
    (3015, 3, 3, 2, False, "return"),
]


@pytest.mark.parametrize("case", SHARED_CASES)
def test_shared_recoveries_never_above_a_labels_best_completion(case, monkeypatch):
    """At every label the bound with the shared-truck recovery term is <= the best completion
    below it, and the term lifts some labels above the independent drones' term."""
    import numpy as np

    import taopt.fleet.search as search

    seed, n, stops, c, precedence, objective = case
    p = tiny_instance(seed, n, 1, 2, c, precedence, objective, stops=stops)
    p = p.replace(service=("drone",) * n, customer_stop=(None,) * n)
    assert bool(p.precedences) == precedence
    tab = _Tables(p)
    seen: list = []
    memo: dict = {}
    best_completion(tab, root_label(p), memo, seen)
    for bound, best in seen:
        assert bound <= best * (1 + 1e-9) + 1e-9

    def independent(tab, cols, back1, back2, ends1, ends2, cutoff=math.inf):
        return float(np.maximum(ends1, ends2[::-1]).min())

    monkeypatch.setattr(search, "_shared_recoveries", independent)
    # (memo and seen are filled together, in the same order)
    lifted = sum(
        bound > _bound(tab, label) + 1e-9 for label, (bound, _) in zip(memo, seen, strict=True)
    )
    assert lifted > 0
