"""The budgeted family (§6.2): data, scorer, JSON, bounds and the exact model."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest

import taopt
from taopt.budgeted import BudgetedProblem, evaluate_budgeted, violations
from taopt.budgeted.bounds import (
    arborescence_bound,
    lower,
    min_routes,
    pruned_routing,
    start_count_bound,
    usable_arcs,
)
from taopt.errors import FeasibilityError, InstanceError, SolverError
from taopt.models.budgeted import solve_budgeted
from taopt.registry import family_of


def random_problem(n: int, m: int, seed: int, tight: float = 1.0) -> BudgetedProblem:
    """Random asymmetric matrix; capacities and time limits near each vehicle's fair share
    (``tight`` > 1 makes them tighter), some vehicles without one."""
    rng = np.random.default_rng(seed)
    cost = rng.uniform(1.0, 10.0, size=(n + m, n + m)).round(2)
    share = n / m
    capacity = [
        int(math.ceil(share * rng.uniform(1.0, 2.0) / tight)) if rng.random() < 0.8 else None
        for _ in range(m)
    ]
    max_time = [
        round(float(5.5 * (share + 1) * rng.uniform(0.5, 1.5) / tight), 1)
        if rng.random() < 0.6
        else None
        for _ in range(m)
    ]
    return BudgetedProblem(cost, n, capacity, max_time, name=f"random{seed}")


def brute_force(problem: BudgetedProblem) -> float:
    """Optimum by enumeration of every order of the targets cut into m routes (inf if none)."""
    n, m = problem.n, problem.m
    best = math.inf
    for order in itertools.permutations(range(n)):
        for cuts in itertools.combinations_with_replacement(range(n + 1), m - 1):
            bounds = (0, *cuts, n)
            routes = [list(order[bounds[k] : bounds[k + 1]]) for k in range(m)]
            if not violations(problem, routes):
                best = min(best, evaluate_budgeted(problem, routes))
    return best


SMALL = np.array([[0, 2, 9, 9], [1, 0, 9, 9], [4, 3, 0, 9], [5, 5, 9, 0]], dtype=float)


def test_validation_names_the_item():
    """A bad limit is refused with a message naming its entry."""
    with pytest.raises(InstanceError, match=r"capacity\[1\] = -1"):
        BudgetedProblem(SMALL, 2, capacity=[1, -1])
    with pytest.raises(InstanceError, match=r"max_time\[0\] = nan"):
        BudgetedProblem(SMALL, 2, max_time=[float("nan"), None])
    with pytest.raises(InstanceError, match=r"capacity\[0\] = 1.5 is not a whole"):
        BudgetedProblem(SMALL, 2, capacity=[1.5, None])
    with pytest.raises(InstanceError, match="capacity has 3 entries but there are 2 vehicles"):
        BudgetedProblem(SMALL, 2, capacity=[1, 1, 1])
    with pytest.raises(InstanceError, match=r"cost\[0, 1\]"):
        BudgetedProblem(np.where(np.eye(4) > 0, 0.0, -1.0), 2)


def test_limits_are_stored_with_inf_for_no_limit():
    """None (whole list or one entry) is stored as inf; the routing relaxation has no limit."""
    p = BudgetedProblem(SMALL, 2, capacity=[1, None])
    assert p.capacity.tolist() == [1.0, math.inf]
    assert p.max_time.tolist() == [math.inf, math.inf]
    assert isinstance(p.routing, taopt.AssignmentProblem) and p.routing.n == p.n == 2
    assert not isinstance(p, taopt.AssignmentProblem)


def test_json_round_trip(tmp_path):
    """save/load keeps matrix and limits (null for no limit) and goes through the registry."""
    p = BudgetedProblem(SMALL, 2, capacity=[1, None], max_time=[None, 7.5], name="tiny")
    data = p.to_dict()
    assert data["capacity"] == [1, None] and data["max_time"] == [None, 7.5]
    path = tmp_path / "p.json"
    p.save(path)
    q = BudgetedProblem.load(path)
    assert np.array_equal(q.cost, p.cost) and q.name == "tiny"
    assert np.array_equal(q.capacity, p.capacity) and np.array_equal(q.max_time, p.max_time)
    assert family_of(q).kind == "budgeted_problem"
    assert BudgetedProblem.from_dict(BudgetedProblem(SMALL, 2).to_dict()).capacity[0] == math.inf


def test_schema_rejects_bad_files(tmp_path):
    """The schema refuses a negative or fractional capacity and an unknown key, naming it."""
    data = BudgetedProblem(SMALL, 2, capacity=[1, None]).to_dict()
    for key, value, words in (
        ("capacity", [-1, None], "capacity[0]"),
        ("capacity", [1.5, None], "capacity[0]"),
        ("max_time", ["5", None], "max_time[0]"),
        ("speed", 3, "speed"),
    ):
        bad = json.loads(json.dumps(data))
        bad[key] = value
        with pytest.raises(InstanceError, match=words.replace("[", r"\[").replace("]", r"\]")):
            BudgetedProblem.from_dict(bad)


def test_shipped_example_loads_and_a_limit_binds(budgeted_example_file):
    """The example file loads, and its optimum differs from the unlimited one."""
    p = BudgetedProblem.load(budgeted_example_file)
    limited = solve_budgeted(p)
    free = taopt.solve(p.routing, "exact")
    assert limited.status == "optimal"
    assert limited.objective > free.objective + 1e-9


def test_evaluate_names_each_violation():
    """The scorer raises naming every broken limit; violations() lists them without raising."""
    p = BudgetedProblem(SMALL, 2, capacity=[1, None], max_time=[3, None])
    routes = [[1, 0], []]
    with pytest.raises(FeasibilityError) as caught:
        evaluate_budgeted(p, routes)
    assert "vehicle 0 serves 2 targets, capacity 1" in str(caught.value)
    assert "vehicle 0 travels 4 s, max_time 3" in str(caught.value)
    assert violations(p, routes) == [
        "vehicle 0 serves 2 targets, capacity 1",
        "vehicle 0 travels 4 s, max_time 3",
    ]
    assert violations(p, [[1], [0]]) == []
    assert evaluate_budgeted(p, [[1], [0]]) == pytest.approx(3.0 + 5.0)
    assert "never visited" in violations(p, [[1], []])[0]
    assert taopt.evaluate(p, taopt.Routes([[1], [0]])) == pytest.approx(8.0)


@pytest.mark.parametrize("seed", range(12))
def test_exact_equals_brute_force(seed):
    """The exact model's optimum equals enumeration on random n <= 6, m <= 3 with limits."""
    rng = np.random.default_rng(1000 + seed)
    n, m = int(rng.integers(3, 7)), int(rng.integers(2, 4))
    p = random_problem(n, m, seed, tight=1.5)
    expected = brute_force(p)
    result = solve_budgeted(p)
    if math.isinf(expected):
        assert result.status == "infeasible"
        assert result.routes is None
        return
    assert result.status == "optimal"
    assert result.objective == pytest.approx(expected, rel=1e-6)
    assert evaluate_budgeted(p, result.routes) == pytest.approx(result.objective)
    assert result.bound <= result.objective + 1e-9


@pytest.mark.parametrize("seed", range(4))
def test_arc_vehicle_form_agrees(seed):
    """The three-index model gives the resource model's optimum."""
    p = random_problem(5, 2, 50 + seed, tight=1.5)
    a, b = solve_budgeted(p), solve_budgeted(p, form="arc-vehicle")
    assert a.status == b.status
    if a.status == "optimal":
        assert a.objective == pytest.approx(b.objective, rel=1e-6)


@pytest.mark.parametrize("seed", range(6))
def test_improver_leaves_the_optimum_and_is_called(seed):
    """With an improver the exact model gives the optimum it gives without one, and calls it
    on its starts."""
    p = random_problem(6, 2, 300 + seed, tight=1.4)
    calls = []

    def spy(problem, routes):
        calls.append([list(route) for route in routes])
        return routes

    plain, spied = solve_budgeted(p), solve_budgeted(p, improve=spy)
    assert plain.status == spied.status
    if plain.status == "optimal":
        assert spied.objective == pytest.approx(plain.objective, rel=1e-9)
        assert calls and all(violations(p, routes) == [] for routes in calls)
        assert spied.info["improved"] == 0  # the spy never betters


def test_improving_during_a_round_keeps_the_optimum():
    """improve_during (answers HiGHS finds improved at once and offered back to it) gives the
    optimum found without it; on these n18m4 instances HiGHS's search finds answers the
    registered improver betters, so the offer path runs (info["offered"])."""
    import taopt.heuristics  # noqa: F401  (registers the family's improver)
    from taopt.registry import improver

    offered = 0
    for seed in (6, 9, 11, 38):
        p = random_problem(18, 4, seed, tight=1.3)
        during = solve_budgeted(p, improve=improver(p))
        after = solve_budgeted(p, improve=improver(p), improve_during=False)
        assert during.status == after.status == "optimal"
        assert during.objective == pytest.approx(after.objective, rel=1e-9)
        assert not violations(p, during.routes)
        offered += during.info["offered"]
        assert after.info["offered"] == 0
    assert offered >= 1, "no answer was improved during a round on any instance"


def test_improver_outside_the_limits_is_an_error():
    """An improver that returns routes breaking a limit is a SolverError naming it."""
    p = random_problem(6, 2, 301, tight=1.4)
    assert solve_budgeted(p).status == "optimal"

    def overload(problem, routes):
        return [[t for route in routes for t in route], *([] for _ in routes[1:])]

    with pytest.raises(SolverError, match="outside the limits: vehicle 0"):
        solve_budgeted(p, improve=overload)


def test_infeasible_is_a_status_not_an_exception():
    """Too little capacity, or a target out of every vehicle's time, gives status infeasible."""
    short = solve_budgeted(BudgetedProblem(SMALL, 2, capacity=[1, 0]))
    assert short.status == "infeasible" and "sum" in short.info["proof"]
    far = solve_budgeted(BudgetedProblem(SMALL, 2, max_time=[3.5, 4.0]))  # target 0 needs >= 4
    assert far.status == "infeasible" and far.routes is None
    assert far.info["proof"]


@pytest.mark.parametrize("seed", range(10))
def test_every_vehicle_time_limited_matches_brute_force(seed):
    """With a time limit on every vehicle the total-time cut-off (Σ_k T_k) keeps the optimum
    and proves infeasibility only where enumeration finds nothing."""
    from taopt.models.budgeted import total_time_cap

    rng = np.random.default_rng(7000 + seed)
    n, m = int(rng.integers(3, 6)), int(rng.integers(2, 4))
    cost = rng.uniform(1.0, 10.0, size=(n + m, n + m)).round(2)
    free = taopt.solve(BudgetedProblem(cost, n).routing, "exact").objective
    # from "the unlimited optimum barely fits in total" to "it does not fit"
    share = free / m * rng.uniform(0.9, 2.5)  # 5 of the 10 seeds are infeasible
    p = BudgetedProblem(cost, n, max_time=[round(share, 2)] * m)
    assert total_time_cap(p) >= sum(p.max_time)
    expected = brute_force(p)
    result = solve_budgeted(p)
    if math.isinf(expected):
        assert result.status == "infeasible" and result.routes is None
        assert result.info["proof"]
        return
    assert result.status == "optimal"
    assert result.objective == pytest.approx(expected, rel=1e-6)
    assert result.objective <= total_time_cap(p)


def test_total_time_proof_names_both_sides():
    """Σ_k T_k below the unlimited optimum: infeasible at once, the proof quotes both numbers."""
    from taopt.models.budgeted import total_time_cap

    # two targets 1 apart, 3 from both starts: the unlimited optimum is 4 (one vehicle);
    # vehicle 0 reaches either target within 3.2 but not both, vehicle 1 none within 0.5
    cost = np.array([[0, 1, 9, 9], [1, 0, 9, 9], [3, 3, 0, 9], [3, 3, 9, 0]], dtype=float)
    assert total_time_cap(BudgetedProblem(cost, 2, max_time=[3.2, None])) is None
    result = solve_budgeted(BudgetedProblem(cost, 2, max_time=[3.2, 0.5]))
    assert result.status == "infeasible" and result.bound == math.inf
    assert "Σ_k T_k = 3.7" in result.info["proof"] and "exceeds" in result.info["proof"]
    assert brute_force(BudgetedProblem(cost, 2, max_time=[3.2, 0.5])) == math.inf


def test_no_limit_is_chapter_two():
    """Without any finite limit the optimum is chapter 2's."""
    p = random_problem(6, 2, 3).replace(capacity=None, max_time=None)
    assert solve_budgeted(p).objective == pytest.approx(taopt.solve(p.routing, "exact").objective)


@pytest.mark.parametrize("seed", range(8))
def test_bounds_never_above_the_optimum(seed):
    """Every bound of the family is at most the brute-force optimum."""
    rng = np.random.default_rng(seed)
    p = random_problem(int(rng.integers(3, 7)), int(rng.integers(2, 4)), 200 + seed, tight=1.2)
    optimum = brute_force(p)
    values = {
        "arborescence": arborescence_bound(p),
        "start_count": start_count_bound(p),
        "fast": lower(p, "fast"),
        "auto": lower(p, "auto"),
        "generic": taopt.bounds.lower(p),
        "routing": taopt.bounds.arborescence(p.routing),
    }
    for name, value in values.items():
        assert value <= optimum + 1e-6, name
    assert values["auto"] >= values["fast"] - 1e-9
    assert values["arborescence"] >= values["routing"] - 1e-9


def test_capacity_bound_sees_forced_routes():
    """With capacity 1 everywhere every target is first on a route: the bound is the optimum."""
    p = BudgetedProblem(SMALL, 2, capacity=[1, 1])
    assert min_routes(p) == 2
    assert start_count_bound(p) == pytest.approx(brute_force(p))
    assert lower(p, "auto") > taopt.bounds.lower(p.routing) + 1e-9


def test_usable_arcs_keep_every_feasible_route():
    """No arc of an optimal route is pruned, and pruned_routing prices it the same."""
    p = random_problem(6, 2, 7, tight=1.5)
    result = solve_budgeted(p)
    usable = usable_arcs(p)
    pruned = pruned_routing(p)
    if result.status == "optimal":
        for k, route in enumerate(result.routes):
            points = [p.n + k, *route]
            assert all(usable[k, a, b] for a, b in zip(points, points[1:], strict=False))
        assert pruned.evaluate(result.routes) == pytest.approx(result.objective)


def test_time_limit_returns_time_limit_with_valid_bound():
    """A tiny limit on a hard instance gives status time_limit, bound <= objective."""
    from taopt.runtime import CancelToken, cancel_scope

    p = random_problem(40, 4, 11, tight=2.0).replace(capacity=[11, 11, 11, 11])
    result = solve_budgeted(p, time_limit=0.3)
    assert result.status in ("time_limit", "optimal")
    if result.status == "time_limit":
        assert result.bound is not None
        assert result.bound <= result.objective + 1e-9
        if result.routes is not None:
            assert evaluate_budgeted(p, result.routes) == pytest.approx(result.objective)
    # no clock: a deadline spent before the first loop head (a cancelled token) stops at once
    token = CancelToken()
    token.cancel()
    with cancel_scope(token):
        stopped = solve_budgeted(p, time_limit=0.3)
    assert stopped.status == "time_limit" and stopped.info["stopped_by"] == "time_limit"
    assert stopped.bound is not None and stopped.bound <= stopped.objective


@pytest.mark.timing
def test_time_limit_is_kept_on_a_hard_instance():
    """A 0.3 s limit on the hard instance above returns within 2 s of wall-clock time."""
    p = random_problem(40, 4, 11, tight=2.0).replace(capacity=[11, 11, 11, 11])
    assert solve_budgeted(p, time_limit=0.3).runtime < 2.0


def test_solve_through_the_registry_rejects_bad_incumbent_quietly():
    """taopt.solve runs 'exact'; an incumbent breaking a limit is ignored, and said."""
    p = BudgetedProblem(SMALL, 2, capacity=[1, None], max_time=[3, None])
    result = solve_budgeted(p, incumbent=[[1, 0], []])
    assert result.status == "optimal"
    assert "capacity" in result.info["incumbent_rejected"]
    assert taopt.solve(p, "exact").objective == pytest.approx(result.objective)


def test_route_counts_fewest_vehicles():
    """route_counts gives the fewest vehicles whose capacities hold s targets."""
    from taopt.models.budgeted import route_counts

    cost = np.ones((9, 9))
    p = BudgetedProblem(cost, 6, capacity=[1, 3, 2])
    assert route_counts(p).tolist() == [0, 1, 1, 1, 2, 2, 3]
    q = BudgetedProblem(cost, 6, capacity=[2, None, 2])  # no limit holds all n
    assert route_counts(q).tolist() == [0, 1, 1, 1, 1, 1, 1]


def sigma_of(problem: BudgetedProblem, arcs: dict[tuple[int, int], float]):
    """Chapter 2's arc list of ``problem`` and σ with the given arc values."""
    from taopt.models.routing import arc_list

    tails, heads = arc_list(problem.routing)
    sigma = np.zeros(len(tails))
    for (a, b), value in arcs.items():
        sigma[np.flatnonzero((tails == a) & (heads == b))[0]] = value
    return tails, heads, sigma


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4, 6])
def test_capacity_inequalities_hold_for_feasible_routes(seed):
    """Every rounded capacity and time inequality holds for feasible routes (each route
    exactly at its time limit); separation finds none."""
    from taopt.models.budgeted import (
        entry_times,
        greedy_budgeted,
        route_counts,
        separate_capacity,
        time_counts,
    )

    p = random_problem(6, 3, 300 + seed, tight=1.5)
    routes = greedy_budgeted(p)
    assert routes is not None and not violations(p, routes)
    p = p.replace(max_time=[max(p.route_cost(k, r), 0.01) for k, r in enumerate(routes)])
    assert not violations(p, routes)
    entry = entry_times(p)
    assert time_counts(p, 1.01 * p.max_time.max()) >= 2 and time_counts(p, 0.0) == 0
    arcs = {}
    for k, route in enumerate(routes):
        points = [p.n + k, *route]
        arcs.update({(a, b): 1.0 for a, b in zip(points, points[1:], strict=False)})
    tails, heads, sigma = sigma_of(p, arcs)
    need = route_counts(p)
    for size in range(1, p.n + 1):
        for subset in itertools.combinations(range(p.n), size):
            into = sigma[np.isin(heads, subset) & ~np.isin(tails, subset)].sum()
            assert into >= need[size] - 1e-9, subset
            assert into >= time_counts(p, entry[list(subset)].sum()) - 1e-9, subset
    assert separate_capacity(p, tails, heads, sigma, entry=entry) == []


def test_capacity_separation_finds_a_cut_subtours_miss():
    """A fractional σ meeting every (2.5) row but not capacity 2 gets a violated k=2 cut."""
    from taopt.models.budgeted import separate_capacity
    from taopt.models.routing import separate_subtours

    p = BudgetedProblem(np.ones((6, 6)), 4, capacity=[2, 2])
    tails, heads, sigma = sigma_of(
        p, {(4, 0): 0.5, (5, 2): 0.5, (0, 1): 1.0, (1, 2): 0.5, (2, 3): 1.0, (3, 0): 0.5}
    )
    assert separate_subtours(p.routing, tails, heads, sigma) == []
    found = separate_capacity(p, tails, heads, sigma)
    assert found
    for subset, k in found:
        into = sigma[np.isin(heads, subset) & ~np.isin(tails, subset)].sum()
        assert k == 2 and into < k - 1e-6


@pytest.mark.parametrize("seed", range(4))
def test_capacity_cuts_keep_the_optimum_and_raise_the_root_bound(seed):
    """With capacity cuts the optimum is the same and the root LP bound is no lower."""
    p = random_problem(7, 2, 400 + seed, tight=1.6).replace(max_time=None)
    with_cuts, without = solve_budgeted(p), solve_budgeted(p, capacity_cuts=False)
    assert with_cuts.status == without.status
    if with_cuts.status == "optimal":
        assert with_cuts.objective == pytest.approx(without.objective, rel=1e-6)
        assert with_cuts.info["lp_bound"] >= without.info["lp_bound"] - 1e-6
        assert with_cuts.info["lp_bound"] <= with_cuts.objective + 1e-6
