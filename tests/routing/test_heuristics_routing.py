"""Chapter 2 heuristics VN, VM, EVN, EVM, MC (§2.4) and the GA baseline (§2.5).

Solutions are checked without trusting the heuristics: re-scored by the one
scorer, compared with an exact optimum from an independent dynamic programme
(and with ``taopt.models.solve_routing``), and hand-computed examples.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import taopt
import taopt.heuristics
from taopt.errors import InstanceError
from taopt.heuristics import clustering, ga_routing
from taopt.orchestration.studies.routing_claims import exact_optimum

ROUTING = ["VN", "VM", "EVN", "EVM", "MC", "GA"]
GA_SMALL = {"population": 30, "generations": 40}


def line_problem(xs: list[float], n_targets: int) -> taopt.AssignmentProblem:
    """Points on a line with symmetric distances |x_i - x_j|."""
    x = np.asarray(xs, dtype=float)
    return taopt.AssignmentProblem(np.abs(x[:, None] - x[None, :]), n_targets)


def random_problems(count: int, seed: int, max_n: int = 6, max_m: int = 3):
    """Random small instances: Euclidean, asymmetric metric, and arbitrary non-metric."""
    from scipy.sparse.csgraph import shortest_path

    rng = np.random.default_rng(seed)
    for index in range(count):
        n = int(rng.integers(1, max_n + 1))
        m = int(rng.integers(1, max_m + 1))
        kind = index % 3
        if kind == 0:
            pts = rng.uniform(0, 100, size=(n + m, 2))
            cost = np.linalg.norm(pts[:, None] - pts[None], axis=2)
        elif kind == 1:
            cost = shortest_path(rng.uniform(1, 100, size=(n + m, n + m)), directed=True)
        else:
            cost = rng.uniform(0, 100, size=(n + m, n + m))
        yield taopt.AssignmentProblem(cost, n, name=f"random-{index}")


def run(name, problem, seed=0):
    options = GA_SMALL if name == "GA" else {}
    return taopt.heuristics.run(name, problem, seed=seed, **options)


@pytest.mark.parametrize("name", ROUTING)
def test_feasible_scored_and_never_below_optimum(name):
    for problem in random_problems(24, seed=1):
        solution = run(name, problem)
        assert solution.status == "feasible" and solution.bound is None
        assert solution.method == name and solution.seed == 0
        assert len(solution.routes) == problem.m
        # The one scorer re-checks feasibility (raises otherwise) and the objective.
        assert solution.objective == pytest.approx(taopt.evaluate(problem, solution.routes))
        optimum, _ = exact_optimum(problem)
        assert solution.objective >= optimum - 1e-9


@pytest.mark.parametrize("name", ROUTING)
def test_same_seed_same_result(name):
    problem = next(random_problems(1, seed=7, max_n=9))
    first, second = run(name, problem, seed=3), run(name, problem, seed=3)
    assert first.routes == second.routes and first.objective == second.objective


def test_exact_optimum_matches_enumeration():
    """The DP used as the reference agrees with plain enumeration of all route sets."""

    def enumerate_all(problem):
        n, m, best = problem.n, problem.m, np.inf
        for perm in itertools.permutations(range(n)):
            for cuts in itertools.combinations_with_replacement(range(n + 1), m - 1):
                bounds = [0, *cuts, n]
                routes = [list(perm[bounds[i] : bounds[i + 1]]) for i in range(m)]
                best = min(best, problem.evaluate(routes))
        return best

    for problem in random_problems(15, seed=2, max_n=5):
        value, routes = exact_optimum(problem)
        assert value == pytest.approx(enumerate_all(problem))
        assert problem.evaluate(routes) == pytest.approx(value)


def test_exact_optimum_agrees_with_milp():
    """Cross-check against helper-2's exact model (fails loudly if it is missing)."""
    from taopt.models import solve_routing

    for problem in random_problems(4, seed=5, max_n=6):
        result = solve_routing(problem)
        assert result.status == "optimal"
        assert result.objective == pytest.approx(exact_optimum(problem)[0], rel=1e-6)


def test_vn_worked_example():
    """One vehicle at 0, targets at x = 1, 2, 4 (indices 0, 1, 2), symmetric distances.

    (2.11): all targets go to the only vehicle. (2.16): from 0 the nearest is
    target 0 (1), then target 1 (1), then target 2 (2): route [0, 1, 2], cost 4.
    """
    problem = line_problem([1, 2, 4, 0], 3)
    solution = taopt.heuristics.run("VN", problem)
    assert solution.routes == [[0, 1, 2]] and solution.objective == 4.0


def test_mc_worked_example(ref_routing_small):
    """Targets at x = 1, 2, 4, vehicles at 0 and 5.

    (2.15) step 1: target 0 from vehicle 0 and target 2 from vehicle 1 both
    cost 1; ties go to the lowest target: target 0 -> vehicle 0. Step 2: target 1
    at vehicle 0's end costs 1 (in front of target 0: 2 + 1 - 1 = 2), target 2
    from vehicle 1 costs 1: lowest target, target 1 -> vehicle 0's end. Step 3:
    target 2 costs 1 from vehicle 1 (2 at vehicle 0's end). Routes [[0, 1], [2]],
    total 3 (= the optimum).
    """
    problem = ref_routing_small.problem
    solution = taopt.heuristics.run("MC", problem)
    assert solution.routes == ref_routing_small.solution
    assert solution.objective == ref_routing_small.optimum == 3.0
    assert exact_optimum(problem)[0] == 3.0


def test_marginal_cost_inserts_in_the_middle():
    """(2.18) may insert between the start and a target (position q = 2).

    One vehicle at 0, targets at x = 10 (index 0) and x = 5 (index 1), symmetric.
    Step 1: cheapest is target 1 (5). Step 2: target 0 at the end costs 5, in
    front of target 1 costs 10 + 5 - 5 = 10: [1, 0] (cost 10). Then two
    asymmetric matrices (worked in the comments) where the front wins.
    """
    problem = line_problem([10, 5, 0], 2)
    assert clustering.marginal_cost_sequence(problem, 0, [0, 1]) == [1, 0]
    # Asymmetric: the start reaches target 0 for 5 and target 0 reaches target 1 for 1,
    # while the start reaches target 1 for 5.5 and target 1 -> target 0 costs 9.
    cost = np.array([[0, 1, 9], [9, 0, 9], [5, 5.5, 0]], dtype=float)
    problem = taopt.AssignmentProblem(cost, 2)
    # (2.18) step 1: target 0 (5 < 5.5). Step 2: target 1 after target 0 costs 1;
    # between start and target 0 costs 5.5 + 9 - 5 = 9.5. Route [0, 1], cost 6.
    assert clustering.marginal_cost_sequence(problem, 0, [0, 1]) == [0, 1]
    # Now make inserting in front cheaper than appending: t(1 -> 0) = 0.
    cost[1, 0], cost[0, 1] = 0.0, 20.0
    problem = taopt.AssignmentProblem(cost, 2)
    # Step 1: target 0 (5). Step 2: end costs 20; front costs 5.5 + 0 - 5 = 0.5: [1, 0].
    assert clustering.marginal_cost_sequence(problem, 0, [0, 1]) == [1, 0]
    assert clustering.nearest_sequence(problem, 0, [0, 1]) == [0, 1]


def test_extended_voronoi_follows_clustered_targets():
    """(2.12): a target joins the vehicle of the closest *clustered* point.

    Vehicles at 0 and 10, targets at 4 (index 0) and 6.5 (index 1). Voronoi
    (2.11): target 0 -> vehicle 0 (4 < 6), target 1 -> vehicle 1 (3.5 < 6.5).
    Extended (2.12): the cheapest pair is (vehicle 1, target 1) at 3.5; then
    target 0 is 2.5 from target 1 < 4 from vehicle 0, so it joins vehicle 1.
    """
    problem = line_problem([4, 6.5, 0, 10], 2)
    assert clustering.voronoi_clusters(problem).tolist() == [0, 1]
    assert clustering.extended_voronoi_clusters(problem).tolist() == [1, 1]


def test_voronoi_boundary_ties_use_the_seed():
    """A target equidistant from two vehicles goes to either, at random with the seed."""
    problem = line_problem([5, 0, 10], 1)
    picks = {int(clustering.voronoi_clusters(problem, seed)[0]) for seed in range(30)}
    assert picks == {0, 1}
    assert clustering.voronoi_clusters(problem, 4).tolist() == (
        clustering.voronoi_clusters(problem, 4).tolist()
    )


def test_same_clusters_vn_vm_evn_evm():
    """VN/VM share the Voronoi assignment, EVN/EVM the extended one (§2.5)."""
    for problem in random_problems(9, seed=3, max_n=8):
        assign = {}
        for name in ("VN", "VM", "EVN", "EVM"):
            routes = taopt.heuristics.run(name, problem, seed=1).routes
            assign[name] = sorted(tuple(sorted(r)) for r in routes)
        assert assign["VN"] == assign["VM"] and assign["EVN"] == assign["EVM"]


def test_insertion_costs_match_rescoring():
    """Every entry of the (2.15) marginal cost table equals a re-scored difference."""
    rng = np.random.default_rng(4)
    problem = taopt.AssignmentProblem(rng.uniform(0, 10, size=(9, 9)), 7)
    route = [3, 0, 5]
    nodes = np.array([problem.n + 1, *route])
    candidates = np.array([1, 2, 4, 6])
    table = clustering.insertion_costs(problem.cost, nodes, candidates)
    base = problem.route_cost(1, route)
    for gap in range(len(nodes)):
        for column, k in enumerate(candidates):
            longer = route[:gap] + [int(k)] + route[gap:]
            assert table[gap, column] == pytest.approx(problem.route_cost(1, longer) - base)


def test_ga_fitness_equals_scorer_and_operators_keep_permutations():
    rng = np.random.default_rng(0)
    problem = taopt.AssignmentProblem(rng.uniform(0, 10, size=(12, 12)), 8)
    length = problem.n + problem.m - 1
    genes = rng.permuted(np.tile(np.arange(length), (40, 1)), axis=1)
    fitness = ga_routing.population_cost(problem, genes)
    for row, value in zip(genes, fitness, strict=True):
        assert value == pytest.approx(problem.evaluate(ga_routing.decode(problem, row)))
    for child in (
        ga_routing.order_crossover(genes[:20], genes[20:], rng),
        ga_routing.inversion_mutation(genes, rng),
    ):
        assert (np.sort(child, axis=1) == np.arange(length)).all()


def test_order_crossover_by_hand():
    """OX1 with cuts 3..6: keep parent 1's slice [3, 4, 5]; fill from position 6
    (wrapping) with parent 2's genes read from position 6: 2, 1, 0, 8, 7, 6."""

    class Cuts:
        def integers(self, low, high, size):
            return np.array([[3, 6]])

    child = ga_routing.order_crossover(
        np.array([[0, 1, 2, 3, 4, 5, 6, 7, 8]]), np.array([[8, 7, 6, 5, 4, 3, 2, 1, 0]]), Cuts()
    )
    assert child.tolist() == [[8, 7, 6, 3, 4, 5, 2, 1, 0]]


def test_ga_elitism_and_iteration_count():
    problem = next(random_problems(1, seed=11, max_n=9))
    solution = taopt.heuristics.run("GA", problem, seed=2, population=20, generations=15)
    history = solution.info["history"]
    assert len(history) == 16
    assert all(b <= a for a, b in zip(history, history[1:], strict=False))
    assert history[-1] == pytest.approx(solution.objective)


def test_ga_rejects_bad_options():
    problem = line_problem([1, 2, 0], 2)
    with pytest.raises(InstanceError, match="population"):
        taopt.heuristics.run("GA", problem, population=1)
    with pytest.raises(InstanceError, match="crossover_rate"):
        taopt.heuristics.run("GA", problem, crossover_rate=1.5)


def test_unknown_heuristic_is_an_instance_error():
    """An unregistered name is an InstanceError naming it and listing the methods."""
    with pytest.raises(InstanceError, match="no method 'XYZ'.*MC"):
        taopt.heuristics.run("XYZ", line_problem([1, 0], 1))


def test_single_target_and_many_vehicles():
    """n = 1 and m > n: exactly one non-empty route, the cheapest start."""
    cost = np.array([[0, 9, 9, 9], [4, 0, 0, 0], [2, 0, 0, 0], [3, 0, 0, 0]], dtype=float)
    problem = taopt.AssignmentProblem(cost, 1)
    for name in ROUTING:
        solution = run(name, problem)
        assert solution.routes == [[], [0], []] and solution.objective == 2.0
