"""Exact model (2.2)–(2.5): checked against an independent DP, across the three
subtour eliminations, by the one scorer, and on bad input."""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pytest
from reference_exact import dp_optimum
from scipy.sparse.csgraph import floyd_warshall

import taopt
from taopt import AssignmentProblem
from taopt.errors import InstanceError
from taopt.models import solve_routing
from taopt.models.routing import build, decode, describe, entry_bound, greedy_routes, repair
from taopt.navigation import uniform_travel_times

SECS = ("dfj", "mtz", "flow")


def drift_problem(n: int, m: int, seed: int, side: float = 1000.0) -> AssignmentProblem:
    """Random points in a uniform current (closed-form travel times): asymmetric, metric."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(0, side, size=(n + m, 2))
    drift = rng.uniform(-0.5, 0.5, size=2)
    return AssignmentProblem(uniform_travel_times(drift, points[:, None], points[None, :]), n)


def metric_problem(n: int, m: int, seed: int) -> AssignmentProblem:
    """Random asymmetric costs closed under shortest paths (so the triangle inequality holds)."""
    rng = np.random.default_rng(seed)
    cost = rng.integers(1, 100, size=(n + m, n + m)).astype(float)
    np.fill_diagonal(cost, 0)
    return AssignmentProblem(floyd_warshall(cost), n)


CASES = [
    ("drift", 6, 2, 0),
    ("drift", 7, 3, 1),
    ("drift", 7, 1, 2),
    ("metric", 7, 2, 3),
    ("metric", 6, 3, 4),
    ("drift", 5, 5, 5),
]


def make(kind, n, m, seed):
    return drift_problem(n, m, seed) if kind == "drift" else metric_problem(n, m, seed)


@pytest.mark.parametrize("kind,n,m,seed", CASES)
def test_all_formulations_match_dp(kind, n, m, seed):
    """Every SEC certifies the subset-DP optimum; its LP relaxation lies below it."""
    problem = make(kind, n, m, seed)
    optimum = dp_optimum(problem)
    for sec in SECS:
        solution = solve_routing(problem, sec=sec)
        assert solution.status == "optimal"
        assert solution.objective == pytest.approx(optimum, rel=1e-6)
        # the one scorer agrees with the reported objective (docs/architecture.md, invariant 1)
        assert taopt.evaluate(problem, solution.routes) == pytest.approx(
            solution.objective, rel=1e-6
        )
        assert solution.bound <= solution.objective + 1e-9
        assert solution.bound == pytest.approx(optimum, rel=1e-5)
        lp = solve_routing(problem, sec=sec, relax=True)
        assert lp.status == "relaxation" and lp.routes is None
        assert lp.objective == lp.bound
        assert lp.objective <= optimum * (1 + 1e-7)


def test_lp_bounds_ordered_on_larger_instance():
    """DFJ's LP (all of (2.5), separated exactly) is at least MTZ's and flow's."""
    problem = drift_problem(25, 4, seed=11)
    exact = solve_routing(problem, sec="dfj")
    lp = {sec: solve_routing(problem, sec=sec, relax=True).objective for sec in SECS}
    assert lp["dfj"] >= lp["mtz"] - 1e-6
    assert lp["dfj"] >= lp["flow"] - 1e-6
    assert max(lp.values()) <= exact.objective * (1 + 1e-7)
    assert entry_bound(problem) <= exact.objective


def test_formulations_agree_on_medium_instance():
    """DFJ, MTZ and flow certify the same optimum at n = 14 (beyond the DP's reach in tests)."""
    problem = metric_problem(14, 3, seed=7)
    values = [solve_routing(problem, sec=sec).objective for sec in SECS]
    assert values == pytest.approx([values[0]] * 3, rel=1e-6)


def test_time_limit_returns_incumbent_and_valid_bound():
    """A tiny limit: the incumbent is feasible and the bound is below the true optimum."""
    problem = drift_problem(45, 5, seed=3)
    optimum = solve_routing(problem, sec="dfj").objective
    limited = solve_routing(problem, sec="dfj", time_limit=0.02)
    assert limited.status in ("time_limit", "optimal")
    assert limited.status == "time_limit"  # 0.02 s cannot prove this one
    assert taopt.evaluate(problem, limited.routes) == pytest.approx(limited.objective, rel=1e-6)
    # a separate full solve checks both sides: the bound is proven, the incumbent is real
    assert limited.bound <= optimum + 1e-9
    assert limited.objective >= optimum - 1e-9
    # "time_limit" means not proven: the reported gap is open and is the gap of these numbers
    assert limited.gap > 1e-6
    assert limited.gap == pytest.approx((limited.objective - limited.bound) / limited.objective)
    assert limited.info["stopped_by"] == "time_limit"
    mtz = solve_routing(problem, sec="mtz", time_limit=0.05)
    assert mtz.bound <= optimum + 1e-6 <= mtz.objective + 2e-6


def test_decode_and_repair_subtours():
    """decode separates routes from cycles; repair splices a cycle in at its cheapest place."""
    problem = metric_problem(5, 1, seed=0)
    model = build(problem, "dfj")
    # hand-made σ: vehicle -> 0 -> 1, cycle 2 -> 3 -> 4 -> 2
    values = np.zeros(len(model.tails))
    for tail, head in [(5, 0), (0, 1), (2, 3), (3, 4), (4, 2)]:
        values[np.flatnonzero((model.tails == tail) & (model.heads == head))] = 1
    routes, subtours = decode(problem, model, values)
    assert routes == [[0, 1]]
    assert sorted(subtours[0]) == [2, 3, 4]
    fixed = repair(problem, routes, subtours)
    assert sorted(fixed[0]) == [0, 1, 2, 3, 4]
    # brute force: every opening of the cycle spliced into every place of the route
    cycle = subtours[0]
    best = min(
        problem.evaluate([[0, 1][:q] + cycle[p:] + cycle[:p] + [0, 1][q:]])
        for p in range(len(cycle))
        for q in range(3)
    )
    assert taopt.evaluate(problem, fixed) == pytest.approx(best)


def test_describe_and_labels():
    """describe() counts every labelled family; the printed model names (2.3)-(2.5)."""
    problem = drift_problem(6, 2, seed=0)
    families = describe(problem, "mtz", show=False)
    rows = {f["family"]: f["rows"] for f in families}
    assert rows["(2.3) every target entered once"] == 6
    assert rows["(2.4) every point left at most once"] == 8
    assert rows["(2.5) MTZ: u_i - u_j + n sigma_ij <= n - 1"] == 6 * 5
    assert rows["variables sigma_ij (binary)"] == 8 * 6 - 6
    text = str(build(problem, "flow").problem)
    assert "(2.3)" in text and "(2.4)" in text and "(2.5) flow" in text


def test_dfj_cuts_are_thesis_25():
    """Every DFJ cut is a true (2.5) row: the optimum satisfies it."""
    problem = drift_problem(12, 2, seed=9)
    solution = solve_routing(problem, sec="dfj")
    successor = {}
    for k, route in enumerate(solution.routes):
        points = [problem.n + k, *route]
        successor.update(zip(points[:-1], points[1:], strict=False))
    for size in (2, 3):
        for subset in combinations(range(problem.n), size):
            inside = sum(1 for a, b in successor.items() if a in subset and b in subset)
            assert inside <= size - 1


@pytest.mark.parametrize(
    "cost,n,match",
    [
        (np.ones((3, 4)), 2, "square"),
        (np.array([[0, -1.0, 1], [1, 0, 1], [1, 1, 0]]), 2, "negative"),
        (np.array([[0, np.nan, 1], [1, 0, 1], [1, 1, 0]]), 2, "not finite"),
        (np.zeros((3, 3)), 0, "n_targets"),
        (np.zeros((3, 3)), 3, "vehicle"),
    ],
)
def test_bad_input_is_clear(cost, n, match):
    """Malformed matrices raise InstanceError naming the problem."""
    with pytest.raises(InstanceError, match=match):
        solve_routing(AssignmentProblem(cost, n))


def test_bad_arguments():
    """Unknown sec, a non-problem and a non-positive time limit are refused."""
    problem = drift_problem(4, 1, seed=0)
    with pytest.raises(InstanceError, match="sec"):
        solve_routing(problem, sec="nope")
    with pytest.raises(InstanceError, match="AssignmentProblem"):
        solve_routing(np.zeros((3, 3)))
    with pytest.raises(InstanceError, match="time_limit"):
        solve_routing(problem, time_limit=0)


def test_loose_mip_gap_is_not_called_optimal():
    """A loose mip_gap gives 'feasible' with a valid bound, never an unproven 'optimal'."""
    problem = drift_problem(25, 3, seed=3)
    optimum = solve_routing(problem).objective
    loose = solve_routing(problem, sec="mtz", mip_gap=0.5)
    assert loose.bound <= optimum + 1e-6 <= loose.objective + 2e-6
    if loose.status == "optimal":
        assert loose.objective == pytest.approx(optimum, rel=1e-6)
    else:
        assert loose.status == "feasible" and loose.info["stopped_by"] == "mip_gap"
        assert loose.gap <= 0.5 + 1e-9


def test_max_rounds_is_feasible_not_time_limit():
    """A DFJ loop cut short by max_rounds: repaired incumbent, status "feasible" (review item 7)."""
    problem = drift_problem(20, 2, seed=5)  # its first MIP round still has a subtour
    full = solve_routing(problem, sec="dfj")
    assert full.status == "optimal" and full.info["rounds"] > 1
    optimum = full.objective
    short = solve_routing(problem, sec="dfj", max_rounds=1)
    assert short.info["rounds"] == 1
    assert short.status == "feasible" and short.info["stopped_by"] == "max_rounds"
    assert taopt.evaluate(problem, short.routes) == pytest.approx(short.objective, rel=1e-9)
    assert short.bound <= optimum + 1e-9 and short.objective >= optimum - 1e-9
    assert short.gap > 1e-6


def navigation_problem(n: int, m: int, seed: int) -> AssignmentProblem:
    """Random points in thesis Fig. 2.1's linear field (100 m square), times by collocation."""
    from taopt.fields import thesis_field
    from taopt.navigation import travel_time_matrix

    points = np.random.default_rng(seed).uniform(0, 100, size=(n + m, 2))
    return AssignmentProblem(travel_time_matrix(thesis_field(1e-2), points, jobs=1), n)


def test_drift_field_instance_matches_independent_dp() -> None:
    """A true drift-field matrix (asymmetric, from navigation): MILP == subset DP (claims module)."""
    from taopt.orchestration.studies.routing_claims import exact_optimum

    problem = navigation_problem(10, 3, seed=11)
    assert not problem.is_symmetric
    reference, _ = exact_optimum(problem)
    for sec in SECS:
        sol = solve_routing(problem, sec=sec)
        assert sol.status == "optimal"
        assert sol.objective == pytest.approx(reference, rel=1e-6)
        assert taopt.evaluate(problem, sol.routes) == pytest.approx(sol.objective, rel=1e-9)


def test_drift_field_fifteen_targets_all_formulations_agree() -> None:
    """n = 15 in the drift field: DFJ, MTZ and flow certify the same optimum; no heuristic beats it."""
    import taopt.heuristics

    problem = navigation_problem(15, 3, seed=12)
    values = {sec: solve_routing(problem, sec=sec) for sec in SECS}
    optimum = values["dfj"].objective
    for sec, sol in values.items():
        assert sol.status == "optimal", sec
        assert sol.objective == pytest.approx(optimum, rel=1e-6), sec
    assert taopt.bounds.arborescence(problem) <= optimum * (1 + 1e-9)
    for name in ("VN", "VM", "EVN", "EVM", "MC", "GA"):
        heuristic = taopt.heuristics.run(
            name, problem, seed=0, **({"generations": 50} if name == "GA" else {})
        )
        assert heuristic.objective >= optimum * (1 - 1e-9), name


def test_one_status_rule_for_every_model():
    """taopt.status.decide: optimal only within 1e-6; else the reason decides."""
    from taopt.models.highs import relative_gap
    from taopt.status import decide

    assert decide("mip_gap", 100.0, 100.0 - 1e-5) == ("optimal", "optimal")
    assert decide("mip_gap", 100.0, 99.0) == ("feasible", "mip_gap")
    assert decide("max_rounds", 100.0, 99.0) == ("feasible", "max_rounds")
    assert decide("time_limit", 100.0, 99.0) == ("time_limit", "time_limit")
    assert decide("time_limit", 100.0, None) == ("time_limit", "time_limit")
    assert decide("mip_gap", 0.0, 0.0) == ("optimal", "optimal")
    assert relative_gap(0.0, -1.0) == float("inf")
    assert relative_gap(10.0, 12.0) == 0.0


# ------------------------------------------------------- the persistent DFJ model (issue 8)
def used_arcs(problem: AssignmentProblem, routes) -> list[tuple[int, int]]:
    """Arcs (i, j) of a solution, start points included."""
    arcs = []
    for k, route in enumerate(routes):
        points = [problem.n + k, *route]
        arcs.extend(zip(points[:-1], points[1:], strict=False))
    return arcs


def test_highs_model_adds_rows_and_relaxes_in_place():
    """HighsModel: rows added to the live model change the optimum; relax() gives the LP."""
    import cvxpy as cp
    import scipy.sparse as sp

    from taopt.models.highs import HighsModel

    x = cp.Variable(3, integer=True, name="x")
    problem = cp.Problem(cp.Minimize(cp.sum(x) + 5), [x >= 0.5, x <= 3])
    model = HighsModel(problem)
    assert model.solve().objective == pytest.approx(8.0)  # x = (1, 1, 1), offset 5
    model.add_rows(sp.csr_matrix(np.array([[1.0, 1.0, 0.0]])), lower=[3.5])
    run = model.solve()
    assert run.status == "optimal" and run.objective == pytest.approx(10.0)  # x0 + x1 = 4
    assert model.values(x).sum() == pytest.approx(5.0)
    model.relax(True)
    lp = model.solve()
    assert lp.objective == pytest.approx(9.0)  # x0 + x1 = 3.5, x2 = 0.5
    bound, _ = model.lagrangian_bound()
    assert bound == pytest.approx(9.0) and bound <= lp.objective + 1e-9
    problem.solve(solver=cp.HIGHS)  # the same model through cvxpy's own interface
    assert problem.value == pytest.approx(8.0)


def _knapsack(seed: int, n: int = 40):
    """A 0-1 knapsack HiGHS does not settle in presolve, and its optimum by dynamic
    programming over weights: (values, weights, capacity, optimal item vector)."""
    rng = np.random.default_rng(seed)
    weight = rng.integers(20, 60, n).astype(float)
    value = weight + rng.integers(0, 10, n)
    capacity = float(weight.sum() // 2)
    best = {0.0: (0.0, ())}  # weight -> (value, items)
    for i in range(n):
        for w, (v, items) in list(best.items()):
            w2 = w + weight[i]
            if w2 <= capacity and (w2 not in best or best[w2][0] < v + value[i]):
                best[w2] = (v + value[i], (*items, i))
    chosen = np.zeros(n)
    chosen[list(max(best.values())[1])] = 1.0
    return value, weight, capacity, chosen


@pytest.mark.parametrize("seed", range(3))
def test_highs_model_takes_an_offered_solution(seed):
    """solve(offer=...): HiGHS asks for a user solution, takes the offered optimum as its
    first incumbent (the first solution it reports), and one it cannot use changes nothing."""
    import scipy.sparse as sp

    from taopt.models.highs import HighsModel

    value, weight, capacity, optimum = _knapsack(seed)
    n = len(value)

    def build():
        return HighsModel.from_arrays(
            cost=-value, matrix=sp.csr_matrix(weight[None, :]), lower=np.array([-np.inf]),
            upper=np.array([capacity]), column_lower=np.zeros(n), column_upper=np.ones(n),
            integers=np.arange(n),
        )  # fmt: skip

    for offered, first_value in ((optimum, -value @ optimum), (np.ones(n), None)):
        asked, reported = [], []

        def offer(vector=offered, asked=asked):
            asked.append(1)
            return vector if len(asked) == 1 else None

        def report(x, reported=reported):
            reported.append(-value @ x)

        run = build().solve(offer=offer, on_solution=report)
        assert asked, "HiGHS never asked for a user solution"
        assert run.status == "optimal" and run.objective == pytest.approx(-value @ optimum)
        if first_value is not None:  # the offered optimum, taken before any search
            assert reported[0] == pytest.approx(first_value)
        else:  # all items exceed the capacity: never taken (its value is below the optimum)
            assert all(v >= -value @ optimum - 1e-6 for v in reported)


@pytest.mark.parametrize("seed", range(6))
def test_separation_is_exact_on_random_fractional_points(seed):
    """separate_subtours finds a violated (2.5) row iff brute force over all subsets does."""
    from taopt.models.routing import CUT_TOLERANCE, arc_list, separate_subtours

    rng = np.random.default_rng(seed)
    n, m = 7, 2
    problem = metric_problem(n, m, seed)
    tails, heads = arc_list(problem)
    values = np.zeros(len(tails))
    for j in range(n):  # (2.3): the arcs into every target sum to one, sparse weights
        into = np.flatnonzero(heads == j)
        chosen = rng.choice(into, size=rng.integers(1, 4), replace=False)
        weights = rng.dirichlet(np.ones(len(chosen)))
        values[chosen] = np.round(weights, 3)
        values[chosen[0]] += 1.0 - values[chosen].sum()
    violated = _violated_subsets(n, m, tails, heads, values, CUT_TOLERANCE)
    found = separate_subtours(problem, tails, heads, values)
    assert bool(found) == bool(violated)
    assert set(found) <= set(violated)


def _violated_subsets(n, m, tails, heads, values, tolerance):
    """Every subset of targets whose (2.5) row σ = ``values`` violates, by brute force."""
    violated = []
    for size in range(2, n + 1):
        for subset in combinations(range(n), size):
            inside = np.zeros(n + m, dtype=bool)
            inside[list(subset)] = True
            if values[~inside[tails] & inside[heads]].sum() < 1 - tolerance:
                violated.append(subset)
    return violated


@pytest.mark.parametrize("seed", range(8))
def test_separation_is_exact_along_chains_of_whole_arcs(seed):
    """Points where most targets are entered by one arc at σ = 1 (chains, and a cycle of
    such arcs that a tiny arc reaches): separation still finds a violated row iff one exists.
    Only the first target of a chain gets a flow, so this is the case that could miss one."""
    from taopt.models.routing import CUT_TOLERANCE, arc_list, separate_subtours

    rng = np.random.default_rng(100 + seed)
    n, m = 8, 2
    problem = metric_problem(n, m, seed)
    tails, heads = arc_list(problem)
    index = {(int(a), int(b)): k for k, (a, b) in enumerate(zip(tails, heads, strict=True))}
    values = np.zeros(len(tails))
    order = rng.permutation(n)
    rest = order
    if seed % 2:
        # a cycle of whole arcs on three targets, reached by a 1e-7 arc, the others on
        # whole paths from the start points: the cycle is the only violated set
        cycle, rest = order[:3], []
        for a, b in zip(cycle, np.roll(cycle, -1), strict=True):
            values[index[int(a), int(b)]] = 1.0
        values[index[n, int(cycle[0])]] = 1e-7
        for k, path in enumerate(np.array_split(order[3:], m)):
            for a, b in zip([n + k, *path[:-1]], path, strict=True):
                values[index[int(a), int(b)]] = 1.0
    for j in rest:
        into = np.flatnonzero(heads == j)
        if rng.random() < 0.6:  # one whole arc: chains of σ = 1
            values[rng.choice(into)] = 1.0
        else:
            chosen = rng.choice(into, size=rng.integers(2, 4), replace=False)
            weights = np.round(rng.dirichlet(np.ones(len(chosen))), 3)
            values[chosen] = weights
            values[chosen[0]] += 1.0 - weights.sum()
    violated = _violated_subsets(n, m, tails, heads, values, CUT_TOLERANCE)
    found = separate_subtours(problem, tails, heads, values)
    assert bool(found) == bool(violated)
    assert set(found) <= set(violated)


@pytest.mark.parametrize("kind,n,m,seed", [("drift", 12, 2, 9), ("metric", 10, 3, 1)])
def test_root_cuts_are_valid_and_root_bound_is_below_optimum(kind, n, m, seed):
    """Every root cut is a (2.5) row the optimum satisfies; the root LP bounds the optimum."""
    from taopt.models.routing import dfj_root

    problem = make(kind, n, m, seed)
    optimum = dp_optimum(problem)
    solution = solve_routing(problem, sec="dfj")
    assert solution.objective == pytest.approx(optimum, rel=1e-9)
    root = dfj_root(problem)
    assert root.complete and root.cuts
    arcs = used_arcs(problem, solution.routes)
    for subset in root.cuts:
        inside = sum(1 for a, b in arcs if a in subset and b in subset)
        assert inside <= len(subset) - 1
    assert root.bound <= optimum * (1 + 1e-9)
    assert root.bound == pytest.approx(root.value, rel=1e-7)
    assert root.value == pytest.approx(solve_routing(problem, relax=True).objective, rel=1e-9)


def test_reduced_costs_bound_every_solution():
    """The rule behind the core: a solution costs at least L + Σ max(d_a, 0) over its arcs."""
    import taopt.heuristics
    from taopt.models.routing import DfjModel

    problem = drift_problem(30, 4, seed=2)
    dfj = DfjModel(problem)
    root = dfj.root()
    optimum = solve_routing(problem, sec="dfj")
    solutions = [optimum.routes, greedy_routes(problem)]
    solutions += [taopt.heuristics.run(name, problem, seed=0).routes for name in ("MC", "VN")]
    for routes in solutions:
        arcs = dfj.route_arcs(routes)
        floor = root.bound + np.maximum(root.reduced_costs[arcs], 0.0).sum()
        assert taopt.evaluate(problem, routes) >= floor - 1e-6 * abs(floor)


@pytest.mark.parametrize("sec", SECS)
def test_incumbent_gives_the_same_optimum(sec):
    """A MIP start (a heuristic's routes, or a poor greedy one) never changes the optimum."""
    import taopt.heuristics

    problem = drift_problem(18, 3, seed=4)
    plain = solve_routing(problem, sec=sec)
    mc = taopt.heuristics.run("MC", problem)
    for incumbent in (mc, mc.routes, greedy_routes(problem)):
        started = solve_routing(problem, sec=sec, incumbent=incumbent)
        assert started.status == "optimal"
        assert started.objective == pytest.approx(plain.objective, rel=1e-6)
        assert started.objective <= taopt.evaluate(problem, getattr(incumbent, "routes", incumbent))
        assert taopt.evaluate(problem, started.routes) == pytest.approx(started.objective)


def test_bad_incumbent_is_refused():
    """An incumbent that is not a feasible solution raises FeasibilityError naming it."""
    from taopt.errors import FeasibilityError

    problem = drift_problem(6, 2, seed=0)
    with pytest.raises(FeasibilityError):
        solve_routing(problem, incumbent=[[0, 1, 2], [2, 3, 4, 5]])
    with pytest.raises(FeasibilityError):
        solve_routing(problem, incumbent=[[0, 1, 2]])


def test_time_limit_mid_loop_keeps_incumbent_and_proven_bound():
    """A limit that strikes during the MIP rounds: status time_limit, bound below the optimum."""
    problem = drift_problem(60, 3, seed=1)
    optimum = solve_routing(problem, sec="dfj")
    assert optimum.status == "optimal"
    limited = solve_routing(problem, sec="dfj", time_limit=0.2, incumbent=greedy_routes(problem))
    assert taopt.evaluate(problem, limited.routes) == pytest.approx(limited.objective, rel=1e-9)
    assert limited.bound <= optimum.objective * (1 + 1e-9)
    assert limited.objective >= optimum.objective * (1 - 1e-9)
    if limited.status != "optimal":  # a fast machine may prove it in time
        assert limited.status == "time_limit" and limited.info["stopped_by"] == "time_limit"
        assert limited.gap > 1e-6


@pytest.mark.parametrize("name", ["br17", "ftv33"])
def test_tsplib_optimum_with_incumbent(name):
    """TSPLIB optima (br17 = 39, ftv33 = 1286) through the reduction, with a MIP start."""
    import taopt.heuristics
    from taopt.routing.tsplib import KNOWN_OPTIMA, atsp_to_assignment, load_atsp

    problem = atsp_to_assignment(load_atsp(name))
    incumbent = taopt.heuristics.run("MC", problem).routes
    solution = solve_routing(problem, sec="dfj", incumbent=incumbent)
    assert solution.status == "optimal"
    assert solution.objective == pytest.approx(KNOWN_OPTIMA[name], abs=1e-6)
    assert solution.bound == pytest.approx(KNOWN_OPTIMA[name], rel=1e-6)


@pytest.mark.parametrize("seed", range(40))
def test_assignment_bound_lies_between_entry_bound_and_optimum(seed):
    """assignment_bound ((2.2)-(2.4) without (2.5)) is >= entry_bound and <= the DP optimum."""
    from taopt.models.routing import assignment_bound

    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(1, 7)), int(rng.integers(1, 4))
    cost = rng.integers(0, 5, size=(n + m, n + m)).astype(float)
    problem = AssignmentProblem(cost, n)
    bound = assignment_bound(problem)
    assert entry_bound(problem) - 1e-9 <= bound <= dp_optimum(problem) + 1e-9


@pytest.mark.parametrize("sec", SECS)
@pytest.mark.parametrize("limit", [1e-3, 0.05, 0.3, 1.0])
def test_time_limit_contract_on_mid_size(sec, limit):
    """A tiny limit on n = 80: time_limit (or optimal), a real incumbent, a proven bound."""
    problem = drift_problem(80, 5, seed=4)
    limited = solve_routing(problem, sec=sec, time_limit=limit)
    assert limited.status in ("time_limit", "optimal")
    assert taopt.evaluate(problem, limited.routes) == pytest.approx(limited.objective, rel=1e-9)
    assert limited.bound is not None and entry_bound(problem) - 1e-9 <= limited.bound
    assert limited.bound <= limited.objective
    if limited.status == "time_limit":
        assert limited.info["stopped_by"] == "time_limit"


def test_time_limit_below_build_estimate_returns_bounds_without_model(monkeypatch):
    """When building the model cannot fit the limit, the incumbent and assignment bound return."""
    from taopt.models import routing
    from taopt.models.routing import compact, dfj

    problem = drift_problem(45, 5, seed=3)
    optimum = solve_routing(problem).objective
    monkeypatch.setattr(dfj, "BUILD_SECONDS_PER_ARC", 1.0)
    monkeypatch.setattr(compact, "COMPACT_SECONDS_PER_ARC", 1.0)

    def never(*args, **kwargs):  # returning at once: no model is built, no solver started
        raise AssertionError("a model was built although its build cannot fit the limit")

    for module, name in [
        (dfj, "DfjModel"),
        (dfj, "HighsModel"),
        (compact, "build"),
        (compact, "HighsModel"),
    ]:
        monkeypatch.setattr(module, name, never)
    for sec in SECS:
        limited = solve_routing(problem, sec=sec, time_limit=5.0)
        assert limited.info["stage"] == "build" and limited.status == "time_limit"
        assert limited.bound == pytest.approx(routing.assignment_bound(problem))
        assert limited.bound <= optimum + 1e-9 <= limited.objective + 2e-9


# ---------------------------------------------- lifted rows at the root (issue 18 item 1)
def feasible_successors(problem: AssignmentProblem):
    """Every solution of (2.2)–(2.5) of a tiny instance, as its list of used arcs."""
    from itertools import product

    n, m = problem.n, problem.m
    for predecessor in product(range(n + m), repeat=n):
        if any(p == j for j, p in enumerate(predecessor)):
            continue
        if len(set(predecessor)) < n:  # (2.4): every point left at most once
            continue
        ok = True
        for j in range(n):  # (2.5): following predecessors from j reaches a start point
            point, steps = j, 0
            while point < n and steps <= n:
                point, steps = predecessor[point], steps + 1
            ok &= point >= n
        if ok:
            yield [(p, j) for j, p in enumerate(predecessor)]


def lhs_and_rhs(cut, arcs, n):
    """Left-hand side of a lifted row on a solution's arcs, and its right-hand side."""
    from taopt.models.routing.separation import blossom_arcs, lifted_cycle_arcs

    if cut[0] == "blossom":
        coefficients, rhs = blossom_arcs(cut[1], cut[2])
    else:
        coefficients, rhs = lifted_cycle_arcs(cut[0], cut[1]), len(cut[1]) - 1
    used = set(arcs)
    return sum(c for a, b, c in coefficients if b < n and (a, b) in used), rhs


def test_lifted_rows_hold_for_every_solution_of_tiny_instances():
    """D_k^± and blossom rows on random sequences / handles never cut a feasible solution."""
    rng = np.random.default_rng(7)
    n, m = 5, 2
    problem = metric_problem(n, m, 0)
    solutions = list(feasible_successors(problem))
    assert len(solutions) > 100
    cuts = []
    for _ in range(40):
        k = int(rng.integers(3, n + 1))
        sequence = tuple(int(v) for v in rng.permutation(n)[:k])
        cuts += [("+", sequence), ("-", sequence)]
        handle = sorted(int(v) for v in rng.choice(n + m, size=rng.integers(1, 5), replace=False))
        outside = [v for v in range(n + m) if v not in handle]
        pairs = [(h, o) for h in handle for o in outside]
        t = min(len(pairs), int(rng.choice([1, 3, 5])))
        teeth = tuple(pairs[i] for i in rng.choice(len(pairs), size=t, replace=False))
        cuts.append(("blossom", tuple(handle), teeth))
    for cut in cuts:
        worst = max(lhs_and_rhs(cut, arcs, n)[0] for arcs in solutions)
        assert worst <= lhs_and_rhs(cut, [], n)[1] + 1e-9, cut


@pytest.mark.parametrize("kind,n,m,seed", [("drift", 12, 1, 2), ("metric", 9, 2, 5), *CASES[:3]])
def test_root_lifted_rows_keep_the_dp_optimum(kind, n, m, seed, monkeypatch):
    """Every lifted row separated at the root holds at the DP optimum's solution; optimum kept."""
    import taopt.models.routing.dfj as dfj_module
    from taopt.models.routing import DfjModel

    monkeypatch.setattr(dfj_module, "LIFTED_MIN_GAIN", 0.0)  # keep every lifted row
    problem = make(kind, n, m, seed)
    optimum = dp_optimum(problem)
    solution = solve_routing(problem, sec="dfj")
    assert solution.status == "optimal"
    assert solution.objective == pytest.approx(optimum, rel=1e-9)
    dfj = DfjModel(problem)
    root = dfj.root()
    assert root.bound <= optimum * (1 + 1e-9)
    arcs = used_arcs(problem, solution.routes)
    for cut in dfj.lifted:
        lhs, rhs = lhs_and_rhs(cut, arcs, n)
        assert lhs <= rhs + 1e-9, cut
    # the thesis's DFJ LP (no lifted rows) is never above the strengthened root
    assert root.bound >= solve_routing(problem, relax=True).objective - 1e-6 * optimum


def test_lifted_separation_finds_violated_rows_on_a_half_integral_point():
    """Two 0.5 directed triangles joined by three half 2-cycles (y = 1): a violated blossom."""
    from taopt.models.routing import arc_list
    from taopt.models.routing.separation import separate_blossoms

    problem = metric_problem(6, 1, 0)
    tails, heads = arc_list(problem)
    values = np.zeros(len(tails))
    index = {(int(a), int(b)): i for i, (a, b) in enumerate(zip(tails, heads, strict=True))}
    for a, b in [(0, 1), (1, 2), (2, 0), (4, 3), (3, 5), (5, 4)]:
        values[index[a, b]] = 0.5
    for a, b in [(0, 3), (1, 4), (2, 5)]:
        values[index[a, b]] = values[index[b, a]] = 0.5
    found = separate_blossoms(problem, tails, heads, values)
    assert found
    for _, handle, teeth in found:
        arcs_in = sum(values[index[a, b]] for a in handle for b in handle if a != b)
        tooth = sum(values[index[a, b]] + values[index[b, a]] for a, b in teeth if max(a, b) < 6)
        assert arcs_in + tooth > len(handle) + (len(teeth) - 1) / 2


def test_lifted_rows_that_do_not_pay_are_rolled_back(monkeypatch):
    """Below LIFTED_MIN_GAIN the model and root are exactly those without lifted rows."""
    import taopt.models.routing.dfj as dfj_module
    from taopt.models.routing import DfjModel

    problem = make("drift", 12, 1, 2)  # its root LP violates two blossom rows
    plain = DfjModel(problem)
    base = plain.root(lifted=0)
    monkeypatch.setattr(dfj_module, "LIFTED_MIN_GAIN", 0.0)
    kept = DfjModel(problem)
    strong = kept.root()
    assert kept.lifted and strong.bound >= base.bound - 1e-9
    monkeypatch.setattr(dfj_module, "LIFTED_MIN_GAIN", 1.0)
    rolled = DfjModel(problem)
    back = rolled.root()
    assert not rolled.lifted and rolled.cuts == plain.cuts
    assert rolled.model.n_rows == plain.model.n_rows == rolled.model.highs.getNumRow()
    assert back.bound == pytest.approx(base.bound) and back.rounds == base.rounds
    np.testing.assert_allclose(back.reduced_costs, base.reduced_costs)
    solution = solve_routing(problem)
    assert solution.status == "optimal"
    assert solution.objective == pytest.approx(dp_optimum(problem), rel=1e-9)


class _CountingImprover:
    """The registered improver, counting its calls and what it was given."""

    def __init__(self):
        from taopt.heuristics.ga_routing import improve_routes

        self.improve, self.calls = improve_routes, 0

    def __call__(self, problem, routes):
        self.calls += 1
        taopt.evaluate(problem, routes)  # it is only ever handed feasible routes
        return self.improve(problem, routes)


@pytest.mark.parametrize("kind,n,m,seed", [("drift", 10, 2, 3), ("metric", 9, 3, 5)])
def test_improver_is_called_and_the_optimum_is_unchanged(kind, n, m, seed):
    """``improve`` sees feasible routes on the first incumbent and after the rounds; the
    certified optimum is the brute-force one with and without it."""
    problem = make(kind, n, m, seed)
    optimum = dp_optimum(problem)
    improver = _CountingImprover()
    with_it = solve_routing(problem, improve=improver)
    without = solve_routing(problem)
    assert improver.calls >= 1
    assert 0 <= with_it.info["improved"] <= improver.calls
    assert without.info["improved"] == 0
    for solution in (with_it, without):
        assert solution.status == "optimal"
        assert solution.objective == pytest.approx(optimum, rel=1e-9)


def test_improver_returning_infeasible_routes_is_a_solver_error():
    """An improver that drops a target is caught, named, and never becomes the incumbent."""
    from taopt.errors import SolverError

    problem = make("metric", 6, 2, 1)
    with pytest.raises(SolverError, match="improve returned routes that are not feasible"):
        solve_routing(problem, improve=lambda p, routes: [routes[0][1:], *routes[1:]])


def test_taopt_solve_passes_the_registered_improver():
    """taopt.solve hands the exact DFJ loop the family's improver (the GA's local search);
    ``improve=None`` switches it off; both certify the same optimum."""
    from taopt.heuristics.ga_routing import improve_routes
    from taopt.registry import improver

    problem = make("drift", 12, 2, 9)
    assert improver(problem) is improve_routes
    on = taopt.solve(problem, "exact")
    off = taopt.solve(problem, "exact", improve=None)
    assert on.status == off.status == "optimal"
    assert on.objective == pytest.approx(off.objective, rel=1e-9)
    assert off.info["improved"] == 0 and "improved" in on.info
