"""Tests of the chapter 5 ordering heuristics (NIA, MMA, SMMA, GA) — helper-5's area.

Generic functions are checked on a hand-computed matrix, against a direct (slow)
transcription of (5.12)–(5.17), on random DAGs (with and without a forced end node) and on
TSPLIB SOP files; the registered delivery methods are re-scored by ``taopt.evaluate`` and
compared with the exact optimum of small instances found by enumeration.
"""

from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest

import taopt
from taopt.errors import InstanceError
from taopt.heuristics import run
from taopt.heuristics.ga_delivery import ga_order, ga_search
from taopt.heuristics.sequencing import (
    check_order,
    mma_order,
    nia_order,
    path_cost,
    smma_order,
)

# ---------------------------------------------------------------------------------------------
# Reference problems
# ---------------------------------------------------------------------------------------------

HAND = [[0, 6, 1, 9], [5, 0, 7, 3], [3, 6, 0, 9], [5, 1, 9, 0]]


def test_hand_example() -> None:
    """The matrix of the docstrings, start 0, pair (1, 2), worked by hand there.

    NIA: [0] -> 1 (6 < 9) -> 3 after 1 (3) -> 2 after 1 (7 < 9): [0, 1, 2, 3], cost 22.
    MMA: [0] -> 1 (6) -> 3 appended (3 < 4) -> 2 appended (9 < 13): [0, 1, 3, 2], cost 18.
    SMMA: [0] -> 1 (tie 9 = 9, lowest index) -> 2 (11 < 12) -> 3 between 0 and 1 (4):
    [0, 3, 1, 2], cost 17 = the optimum (the three feasible orders cost 22, 18, 17).
    """
    assert nia_order(HAND, [(1, 2)], 0) == [0, 1, 2, 3]
    assert mma_order(HAND, [(1, 2)], 0) == [0, 1, 3, 2]
    assert smma_order(HAND, [(1, 2)], 0) == [0, 3, 1, 2]
    assert [path_cost(HAND, o) for o in ([0, 1, 2, 3], [0, 1, 3, 2], [0, 3, 1, 2])] == [22, 18, 17]
    assert ga_order(HAND, [(1, 2)], 0, seed=3, generations=30) == [0, 3, 1, 2]


# A direct transcription of the printed rules (lists, no numpy), to check the vectorised code.
def _path_time(cost, path):
    return sum(cost[a][b] for a, b in zip(path[:-1], path[1:], strict=True))


def _viable(size, pairs, path, end):
    placed = set(path)
    return [
        j
        for j in range(size)
        if j not in placed and j != end and all(r in placed for r, s in pairs if s == j)
    ]


def _slots(path, pairs, node, end):
    where = {v: k for k, v in enumerate(path)}
    p = max((where[r] for r, s in pairs if s == node and r in where), default=0)
    return range(p, (len(path) - 1 if end is None else len(path) - 2) + 1)


def _put(path, slot, node):
    return path[: slot + 1] + [node] + path[slot + 1 :]


def _reference(cost, pairs, start, end, rule, lookahead="current"):
    size = len(cost)
    path = [start] + ([end] if end is not None else [])
    pairs = [(r, s) for r, s in pairs if r != start and s != end]
    while nodes := _viable(size, pairs, path, end):
        if rule == "NIA":  # (5.12): min t*(R(q), c_j); ties: lowest node, then slot
            _, node, slot = min(
                (cost[path[q]][j], j, q) for j in nodes for q in _slots(path, pairs, j, end)
            )
            path = _put(path, slot, node)
            continue
        options = [  # (5.14): t(R (+)q c) - t(R)
            (_path_time(cost, _put(path, q, j)) - _path_time(cost, path), j, q)
            for j in nodes
            for q in _slots(path, pairs, j, end)
        ]
        if rule == "MMA" or len(nodes) == 1:
            _, node, slot = min(options)
            path = _put(path, slot, node)
            continue
        best = None  # (5.17)
        for first in nodes:
            _, _, q1 = min(o for o in options if o[1] == first)
            grown = _put(path, q1, first)
            if lookahead == "current":
                seconds = [j for j in nodes if j != first]
            else:
                seconds = _viable(size, pairs, grown, end)
            two = min(
                _path_time(cost, _put(grown, q2, j2)) - _path_time(cost, path)
                for j2 in seconds
                for q2 in _slots(grown, pairs, j2, end)
            )
            if best is None or two < best[0]:
                best = (two, first, q1)
        path = _put(path, best[2], best[1])
    return path


def _random_problem(seed: int, size: int, with_end: bool, density: float = 0.3):
    rng = np.random.default_rng(seed)
    cost = rng.integers(1, 30, (size, size)).astype(float)  # integers: exact sums, exact ties
    np.fill_diagonal(cost, 0.0)
    end = size - 1 if with_end else None
    rank = rng.permutation(size)
    pairs = []
    for a, b in itertools.permutations(range(size), 2):
        if rank[a] < rank[b] and rng.random() < density and b != 0 and a != end:
            pairs.append((int(a), int(b)))
    # a pair into the end / out of the start always holds: keep one to exercise dropping it
    if with_end and size > 2:
        pairs.append((1, end))
    return cost, pairs, 0, end


@pytest.mark.parametrize("with_end", [False, True])
@pytest.mark.parametrize("seed", range(40))
def test_matches_printed_rules_and_is_feasible(seed: int, with_end: bool) -> None:
    size = 3 + seed % 7
    cost, pairs, start, end = _random_problem(seed, size, with_end)
    listed = cost.tolist()
    for rule, func, options in [
        ("NIA", nia_order, {}),
        ("MMA", mma_order, {}),
        ("SMMA", smma_order, {}),
        ("SMMA", smma_order, {"lookahead": "updated"}),
    ]:
        order = func(cost, pairs, start, end, **options)
        check_order(order, size, pairs, start, end)
        assert order == _reference(listed, pairs, start, end, rule, **options), (rule, options)
    order = ga_order(cost, pairs, start, end, seed=seed, generations=5)
    check_order(order, size, pairs, start, end)


def test_random_dags_larger() -> None:
    """Random DAGs on 60 nodes (networkx gnp), every order precedence-feasible."""
    rng = np.random.default_rng(7)
    for trial in range(6):
        size = 60
        graph = nx.gnp_random_graph(size, 0.05, seed=trial, directed=True)
        pairs = [(u, v) for u, v in graph.edges if u < v and u != 0 and v != size - 1]
        cost = rng.random((size, size)) * 100
        end = size - 1 if trial % 2 else None
        for order in (
            nia_order(cost, pairs, 0, end),
            mma_order(cost, pairs, 0, end),
            smma_order(cost, pairs, 0, end),
            smma_order(cost, pairs, 0, end, lookahead="updated"),
            ga_order(cost, pairs, 0, end, seed=trial, generations=10),
        ):
            check_order(order, size, pairs, 0, end)


def test_bad_input() -> None:
    cost = np.ones((4, 4))
    with pytest.raises(InstanceError, match="precedence cycle"):
        mma_order(cost, [(1, 2), (2, 3), (3, 1)], 0)
    with pytest.raises(InstanceError, match="before the start"):
        nia_order(cost, [(1, 0)], 0)
    with pytest.raises(InstanceError, match="after the end"):
        smma_order(cost, [(3, 1)], 0, end=3)
    with pytest.raises(InstanceError, match="self-precedence"):
        ga_order(cost, [(2, 2)], 0)
    with pytest.raises(InstanceError, match="square"):
        mma_order(np.ones((3, 4)), [], 0)
    with pytest.raises(InstanceError, match="NaN"):
        mma_order(np.full((3, 3), np.nan), [], 0)
    with pytest.raises(InstanceError, match="start node"):
        mma_order(cost, [], 7)
    with pytest.raises(InstanceError, match="node 9"):
        mma_order(cost, [(1, 9)], 0)
    with pytest.raises(InstanceError, match="lookahead"):
        smma_order(cost, [], 0, lookahead="later")
    with pytest.raises(InstanceError, match="mutation"):
        ga_order(cost, [], 0, mutation=2.0)


def test_ga_reproducible_and_elitist() -> None:
    cost, pairs, start, end = _random_problem(11, 12, with_end=False)
    first = ga_search(cost, pairs, start, end, seed=5, generations=40)
    again = ga_search(cost, pairs, start, end, seed=5, generations=40)
    generator = ga_search(cost, pairs, start, end, seed=np.random.default_rng(5), generations=40)
    assert first[0] == again[0] == generator[0]
    assert first[1] == again[1] == path_cost(cost, first[0])
    history = first[2]
    assert len(history) == 41 and np.all(np.diff(history) <= 0)  # elitism


# ---------------------------------------------------------------------------------------------
# TSPLIB SOP: never below the proven optimum
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["ESC07", "ESC11", "ESC12", "br17.10"])
def test_sop_orders_not_below_optimum(name: str) -> None:
    from taopt.sop.problem import KNOWN_OPTIMA, load_sop

    cost, pairs, start, end, _ = load_sop(name)
    for order in (
        nia_order(cost, pairs, start, end),
        mma_order(cost, pairs, start, end),
        smma_order(cost, pairs, start, end),
        ga_order(cost, pairs, start, end, seed=0, generations=20),
    ):
        check_order(order, len(cost), pairs, start, end)
        value = path_cost(cost, order)
        assert np.isfinite(value) and value >= KNOWN_OPTIMA[name]


# ---------------------------------------------------------------------------------------------
# The delivery problem: registered methods, scored by taopt.evaluate, against the optimum
# ---------------------------------------------------------------------------------------------


def _small_instance(seed: int, n: int = 6, pairs=((0, 1), (2, 3))):
    """n random customers on the 3x3 grid (side 1000 m), v_d/v_t = 1.4, L = 800 m."""
    rng = np.random.default_rng(seed)
    customers = rng.random((n, 2)) * 1000
    return taopt.DeliveryInstance.grid(
        customers, k=3, side=1000, v_drone=1.4, v_truck=1.0, flight_range=800, precedences=pairs
    )


def _optimum_by_enumeration(instance) -> float:
    best = np.inf
    before = list(instance.precedences)
    for order in itertools.permutations(range(instance.n)):
        where = {c: k for k, c in enumerate(order)}
        if all(where[r] < where[j] for r, j in before):
            best = min(best, taopt.schedule(instance, order).objective)
    return best


METHODS = ["NIA", "MMA", "SMMA", "GA"]


@pytest.mark.parametrize("seed", range(4))
def test_delivery_methods_scored_and_not_below_optimum(seed: int) -> None:
    instance = _small_instance(seed)
    optimum = _optimum_by_enumeration(instance)
    for name in METHODS:
        options = {"generations": 30} if name == "GA" else {}
        solution = run(name, instance, seed=seed, **options)
        assert solution.method == name and solution.status == "feasible"
        assert solution.runtime > 0
        value = taopt.evaluate(instance, solution.plan)
        assert value == pytest.approx(solution.objective, rel=1e-9)
        assert solution.objective >= optimum * (1 - 1e-12)
        assert np.isfinite(solution.info["tstar_cost"])


def test_delivery_tstar_cost_is_path_cost_of_order() -> None:
    from taopt.delivery.costs import drone_cost_matrix

    instance = _small_instance(9, n=7, pairs=((0, 1), (1, 2), (4, 3)))
    cost = drone_cost_matrix(instance)
    for name in METHODS:
        solution = run(name, instance, seed=1, **({"generations": 20} if name == "GA" else {}))
        path = [instance.n, *solution.plan.order]  # t*'s depot is node n
        assert solution.info["tstar_cost"] == pytest.approx(path_cost(cost, path), rel=1e-12)
        check_order(path, instance.n + 1, instance.precedences, start=instance.n)
        # t* is a per-step lower bound (costs.py): the t* path cost never exceeds the makespan
        assert solution.info["tstar_cost"] <= solution.objective * (1 + 1e-12)


def test_delivery_ga_same_seed_same_result() -> None:
    instance = _small_instance(3, n=8, pairs=((0, 1), (2, 3), (4, 5)))
    first = run("GA", instance, seed=4, generations=25)
    again = run("GA", instance, seed=4, generations=25)
    assert first.plan == again.plan and first.objective == again.objective


@pytest.mark.parametrize("seed", range(3))
def test_delivery_objective_is_exactly_the_scorers(seed: int) -> None:
    """Review item 5: every method's objective is taopt.evaluate's value (==, no tolerance),
    on random instances with and without a landing time τ; the subset-DP optimum too."""
    from taopt.delivery.schedule import optimal_plan

    rng = np.random.default_rng(500 + seed)
    n = int(rng.integers(5, 8))
    pairs = tuple((2 * k, 2 * k + 1) for k in range(int(rng.integers(0, 3))))
    instance = taopt.DeliveryInstance.grid(
        rng.random((n, 2)) * 1000,
        k=int(rng.integers(3, 6)),
        side=1000,
        v_drone=float(rng.uniform(1.0, 2.0)),
        v_truck=1.0,
        flight_range=float(rng.uniform(700, 1200)),
        precedences=pairs,
        service_time=float(rng.choice([0.0, 30.0])),
    )
    optimum = optimal_plan(instance)
    assert optimum.objective == taopt.evaluate(instance, optimum.plan)
    for name in METHODS:
        options = {"generations": 15} if name == "GA" else {}
        solution = run(name, instance, seed=seed, **options)
        assert solution.objective == taopt.evaluate(instance, solution.plan)
        assert solution.objective >= optimum.objective
