"""Limit-aware MC, EVM, GA and the PyVRP / OR-Tools peers on BudgetedProblem (thesis §6.2)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from taopt.budgeted import BudgetedProblem, evaluate_budgeted, violations
from taopt.budgeted.problem import TIME_TOLERANCE
from taopt.errors import InstanceError
from taopt.heuristics import budgeted, budgeted_peers, clustering, ga_routing
from taopt.heuristics.ga_routing import encode
from taopt.registry import improver
from taopt.routing.problem import AssignmentProblem

GA_SMALL = {"population": 30, "generations": 40}


def random_cost(n: int, m: int, seed: int) -> np.ndarray:
    """Asymmetric travel times: Euclidean distances scaled by a random drift-like factor."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(0, 100, size=(n + m, 2))
    distance = np.linalg.norm(points[:, None] - points[None, :], axis=2)
    return distance * rng.uniform(0.8, 1.25, size=distance.shape)


def enumerate_solutions(cost: np.ndarray, n: int, m: int) -> tuple[np.ndarray, ...]:
    """Every solution by enumeration (each order of the targets, each split into m routes):
    total travel time, per-vehicle times and per-vehicle counts."""
    problem = AssignmentProblem(cost, n)
    totals, times, counts = [], [], []
    for order in itertools.permutations(range(n)):
        for cuts in itertools.combinations_with_replacement(range(n + 1), m - 1):
            bounds = (0, *cuts, n)
            routes = [list(order[bounds[j] : bounds[j + 1]]) for j in range(m)]
            route_times = [problem.route_cost(j, r) for j, r in enumerate(routes)]
            totals.append(sum(route_times))
            times.append(route_times)
            counts.append([len(r) for r in routes])
    return np.array(totals), np.array(times), np.array(counts)


def brute_force(problem: BudgetedProblem, table: tuple[np.ndarray, ...]) -> float:
    """The optimum of ``problem`` over the enumerated solutions (inf when none is feasible)."""
    totals, times, counts = table
    ok = (counts <= problem.capacity).all(axis=1) & (times <= problem.max_time * (1 + 1e-9)).all(
        axis=1
    )
    return float(totals[ok].min()) if ok.any() else math.inf


def reference_problems() -> list[tuple[str, BudgetedProblem, float]]:
    """Small instances whose limits bite (the optimum rises) and their brute-force optima."""
    out = []
    for seed, (n, m) in enumerate([(6, 2), (6, 3), (5, 2)]):
        cost = random_cost(n, m, seed)
        table = enumerate_solutions(cost, n, m)
        free = float(table[0].min())
        longest = float(table[1][np.argmin(table[0])].max())
        q = math.ceil(n / m)
        for tau in (0.7, 0.8, 0.9, 0.95, 1.0):  # the tightest travel time that stays feasible
            timed = BudgetedProblem(cost, n, max_time=[tau * longest] * m)
            if math.isfinite(brute_force(timed, table)):
                break
        for label, problem in (
            ("capacity", BudgetedProblem(cost, n, capacity=[q] * m)),
            ("time", timed),
            ("both", BudgetedProblem(cost, n, capacity=[q + 1] * m, max_time=[longest] * m)),
        ):
            optimum = brute_force(problem, table)
            assert optimum >= free
            out.append((f"n{n}m{m}-{label}", problem, optimum))
    return out


REFERENCES = reference_problems()


def heuristic_runs(problem: BudgetedProblem):
    yield "MC", budgeted.mc(problem)
    yield "EVM", budgeted.evm(problem)
    for memetic in budgeted.MEMETIC_STEPS:
        yield (
            f"GA {memetic}",
            budgeted.genetic_algorithm(problem, seed=3, memetic=memetic, **GA_SMALL),
        )


@pytest.mark.parametrize(
    ("label", "problem", "optimum"), REFERENCES, ids=[r[0] for r in REFERENCES]
)
def test_heuristics_feasible_and_never_below_the_optimum(label, problem, optimum):
    """Every answer keeps the limits, is scored by the one scorer and is >= the brute-force optimum."""
    assert math.isfinite(optimum), f"{label}: the reference instance should be feasible"
    answered = 0
    for name, solution in heuristic_runs(problem):
        if solution.status == "no_solution":
            assert solution.solution is None and math.isinf(solution.objective), name
            continue
        answered += 1
        assert violations(problem, solution.routes) == [], name
        assert solution.objective == pytest.approx(evaluate_budgeted(problem, solution.routes))
        assert solution.objective >= optimum - 1e-9, name
    assert answered >= 1, f"{label}: no heuristic answered"


@pytest.mark.parametrize("memetic", budgeted.MEMETIC_STEPS)
@pytest.mark.parametrize(
    ("label", "problem", "optimum"), REFERENCES, ids=[r[0] for r in REFERENCES]
)
def test_ga_reaches_the_optimum_on_small_instances(label, problem, optimum, memetic):
    """With a modest budget the GA finds the brute-force optimum of a 5-6 target instance,
    with either memetic step."""
    solution = budgeted.genetic_algorithm(
        problem, seed=0, population=40, generations=60, memetic=memetic
    )
    assert solution.objective == pytest.approx(optimum)
    assert solution.info["memetic"] == memetic


def test_ga_memetic_step_is_checked():
    with pytest.raises(InstanceError, match="memetic must be one of"):
        budgeted.genetic_algorithm(REFERENCES[0][1], memetic="chapter 2")


def test_without_limits_mc_and_evm_are_chapter_2s():
    """With no limit MC and EVM give chapter 2's routes exactly."""
    cost = random_cost(12, 3, 7)
    free = BudgetedProblem(cost, 12)
    routing = AssignmentProblem(cost, 12)
    assert budgeted.mc(free).routes == clustering.mc(routing).routes
    assert budgeted.evm(free).routes == clustering.evm(routing).routes


def test_limited_local_search_keeps_limits_and_never_worsens():
    """The limit-aware descent stays within every limit and never raises the travel time."""
    for _label, problem, optimum in REFERENCES:
        start = budgeted.mc(problem)
        if start.status != "feasible":
            continue
        routes, _moves = budgeted.limited_local_search(problem, start.routes)
        assert violations(problem, routes) == []
        assert optimum - 1e-9 <= evaluate_budgeted(problem, routes) <= start.objective + 1e-9


def test_improver_keeps_limits_never_worsens_and_is_registered():
    """The exact model's improver (the GA's memetic step) stays within every limit, is never
    worse than its input and never better than the optimum; it is the family's improver."""
    improved = 0
    for _label, problem, optimum in REFERENCES:
        assert improver(problem) is budgeted.improve_budgeted
        start = budgeted.mc(problem)
        if start.status != "feasible":
            continue
        routes = budgeted.improve_budgeted(problem, start.routes)
        assert violations(problem, routes) == []
        value = evaluate_budgeted(problem, routes)
        assert optimum - 1e-9 <= value <= start.objective + 1e-9
        improved += value < start.objective - 1e-9
    assert improved  # it does something on the references


def test_one_limited_descent_serves_many_starts():
    """A :class:`LimitedDescent` kept across calls (as the GA keeps one) gives what a fresh
    :func:`limited_local_search` gives, start after start."""
    for _label, problem, _optimum in REFERENCES:
        descent = budgeted.LimitedDescent(problem)
        for method in (budgeted.mc, budgeted.evm):
            start = method(problem)
            if start.status != "feasible":
                continue
            assert descent.run(start.routes) == budgeted.limited_local_search(problem, start.routes)


def test_mc_refuses_a_vehicle_at_its_capacity():
    """A vehicle with capacity 1 never gets a second target, although MC would give it one."""
    x = np.array([1.0, 2.0, 4.0, 0.0, 5.0])
    cost = abs(x[:, None] - x[None, :])
    assert clustering.mc(AssignmentProblem(cost, 3)).routes[0] == [0, 1]
    for method in (budgeted.mc, budgeted.evm):
        routes = method(BudgetedProblem(cost, 3, capacity=[1, None])).routes
        assert routes[0] == [0]


def test_a_vehicle_with_no_time_takes_nothing():
    """max_time 0 refuses every target to that vehicle: the others serve all (MC and EVM)."""
    cost = random_cost(8, 3, 2)
    problem = BudgetedProblem(cost, 8, max_time=[0.0, None, None])
    for method in (budgeted.mc, budgeted.evm):
        solution = method(problem)
        assert solution.routes[0] == [] and violations(problem, solution.routes) == []


def test_no_vehicle_can_take_a_target_gives_no_solution():
    """Capacities summing below n: status "no_solution", no payload, the unassigned count; never feasible."""
    problem = BudgetedProblem(random_cost(6, 2, 1), 6, capacity=[2, 2])
    for solution in (budgeted.mc(problem), budgeted.evm(problem)):
        assert solution.status == "no_solution" and solution.solution is None
        assert solution.info["unassigned"] == 2 and "not a proof" in solution.info["error"]
    ga = budgeted.genetic_algorithm(problem, seed=0, population=10, generations=5)
    assert ga.status == "no_solution" and math.isinf(ga.objective)


def test_ga_same_seed_same_result():
    """Same seed, same routes and history."""
    problem = REFERENCES[0][1]
    first = budgeted.genetic_algorithm(problem, seed=11, **GA_SMALL)
    second = budgeted.genetic_algorithm(problem, seed=11, **GA_SMALL)
    assert first.routes == second.routes and first.info["history"] == second.info["history"]


def test_route_times_match_the_scorer():
    """The vectorised per-vehicle times and counts equal route_cost and len of decoded routes."""
    problem = BudgetedProblem(random_cost(9, 3, 4), 9)
    rng = np.random.default_rng(0)
    genes = rng.permuted(np.tile(np.arange(11), (20, 1)), axis=1)
    times, counts = budgeted.route_times(problem, genes)
    for row, chromosome in enumerate(genes):
        routes = ga_routing.decode(problem.routing, chromosome, "vehicle")
        assert np.allclose(times[row], [problem.route_cost(j, r) for j, r in enumerate(routes)])
        assert counts[row].tolist() == [len(r) for r in routes]


def test_repair_keeps_limits_and_leaves_feasible_routes_alone():
    """Repair returns routes within every limit; feasible routes come back unchanged."""
    cost = random_cost(8, 2, 9)
    problem = BudgetedProblem(cost, 8, capacity=[4, 4])
    fixed = budgeted.repair(problem, [list(range(8)), []])
    assert fixed is not None and violations(problem, fixed) == []
    assert budgeted.repair(problem, [[0, 1, 2, 3], [4, 5, 6, 7]]) == [[0, 1, 2, 3], [4, 5, 6, 7]]
    penalised, plain, over = budgeted.penalised_cost(problem, encode(problem.routing, fixed), 10, 1)
    assert over[0] == 0 and penalised[0] == pytest.approx(plain[0])


# -- peers (each in its own worker process) ---------------------------------------------------

PEERS = [
    ("pyvrp", lambda p: budgeted_peers.pyvrp_budgeted(p, time_limit=None, max_iterations=300)),
    # OR-Tools' guided local search may not reach a solution count on a tight instance: capped
    ("ortools", lambda p: budgeted_peers.ortools_budgeted(p, time_limit=1.0, solution_limit=50)),
]


@pytest.mark.parametrize(("name", "run"), PEERS, ids=[p[0] for p in PEERS])
def test_peers_feasible_and_never_below_the_optimum(name, run):
    """Both peers keep the limits natively and never beat the brute-force optimum."""
    for label, problem, optimum in REFERENCES:
        solution = run(problem)
        assert solution.status == "feasible", (label, solution.info.get("error"))
        assert violations(problem, solution.routes) == []
        assert optimum - 1e-9 <= solution.objective, label


def test_pyvrp_same_seed_same_result():
    """PyVRP stopped on iterations: same seed, same routes."""
    problem = REFERENCES[1][1]
    first = budgeted_peers.pyvrp_budgeted(problem, time_limit=None, max_iterations=200, seed=4)
    second = budgeted_peers.pyvrp_budgeted(problem, time_limit=None, max_iterations=200, seed=4)
    assert first.routes == second.routes


def test_a_peer_answer_that_breaks_a_limit_is_reported(monkeypatch):
    """Routes breaking a capacity come back as status "no_solution" with the violation named."""
    problem = BudgetedProblem(random_cost(4, 2, 0), 4, capacity=[1, 3])

    def fake_call(peer, request, deadline):
        assert request["options"]["capacity"] == [1, 3]
        reply = {"routes": [[0, 1], [2, 3]], "objective": 1}
        return budgeted_peers.peers._Answer(reply, "fake", 0.0)

    monkeypatch.setattr(budgeted_peers.peers, "_call", fake_call)
    solution = budgeted_peers.ortools_budgeted(problem, time_limit=1.0)
    assert solution.status == "no_solution" and solution.solution is None
    assert "vehicle 0 serves 2 targets, capacity 1" in solution.info["violations"]


def test_integer_time_limit_keeps_the_boundary_and_the_tolerance():
    """T_k in integer units admits a route of exactly T_k and nothing beyond the scorer's tolerance."""
    problem = BudgetedProblem(random_cost(6, 2, 5), 6, max_time=[120.0, None])
    scale = 1e8
    _, max_time = budgeted_peers.integer_limits(problem, scale)
    assert max_time[1] is None
    assert 120.0 * scale + 0.5 * problem.n <= max_time[0]
    assert max_time[0] + 0.5 * problem.n <= 120.0 * scale * (1 + TIME_TOLERANCE)


def test_peers_keep_a_route_that_takes_exactly_the_limit():
    """At tau = 1 (T = the longest route of the unlimited optimum) both peers still answer."""
    for label, problem, _optimum in REFERENCES:
        if label.endswith("-time") and problem.max_time[0] > 0:
            for _name, run in PEERS:
                assert run(problem).status == "feasible", label


def _improving_moves(problem: BudgetedProblem, routes: list[list[int]]) -> list:
    """Every relocate / exchange that keeps the limits and lowers the total, by re-walking."""
    total = evaluate_budgeted(problem, routes)
    found = []
    spots = [(j, i) for j, route in enumerate(routes) for i in range(len(route))]
    for j, i in spots:
        k = routes[j][i]
        for dest in range(problem.m):  # relocate k into every gap of every route
            for gap in range(len(routes[dest]) + (dest != j)):
                trial = [list(r) for r in routes]
                trial[j].pop(i)
                trial[dest].insert(gap, k)
                if (
                    not violations(problem, trial)
                    and evaluate_budgeted(problem, trial) < total - 1e-7
                ):
                    found.append(("relocate", k, dest, gap))
        for j2, i2 in spots:  # exchange with a target of another route
            if j2 != j:
                trial = [list(r) for r in routes]
                trial[j][i], trial[j2][i2] = routes[j2][i2], k
                if (
                    not violations(problem, trial)
                    and evaluate_budgeted(problem, trial) < total - 1e-7
                ):
                    found.append(("exchange", k, routes[j2][i2]))
    return found


@pytest.mark.parametrize("seed", range(4))
def test_limited_local_search_ends_at_a_local_optimum(seed):
    """After the descent no relocate/exchange found by re-walking every route improves."""
    n, m = 12, 3
    cost = random_cost(n, m, 20 + seed)
    start = budgeted.mc(BudgetedProblem(cost, n, capacity=[5] * m)).routes
    longest = max(AssignmentProblem(cost, n).route_cost(j, r) for j, r in enumerate(start))
    problem = BudgetedProblem(cost, n, capacity=[5] * m, max_time=[longest] * m)
    assert violations(problem, start) == []
    routes, _moves = budgeted.limited_local_search(problem, start)
    assert violations(problem, routes) == []
    assert sorted(k for r in routes for k in r) == list(range(n))
    assert _improving_moves(problem, routes) == []
