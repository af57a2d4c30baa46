"""The iterated local search over orders (ILS) for chapter 5 and the SOP.

Checked: every plan is feasible and re-scored by ``taopt.evaluate``; it respects the
precedences, is never worse than SMMA's and never below the exact optimum of the subset DP;
the same seed gives the same result; the incremental evaluation of a move (DP restarted from
the stored prefix states, pruned by the monotone/shift-equivariant bound) agrees with a full
``schedule`` of the moved order. Every search here stops on an iteration count.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import taopt
from taopt.delivery.schedule import optimal_plan, schedule
from taopt.errors import InstanceError
from taopt.heuristics.ils_delivery import (
    TOLERANCE,
    ScheduleStates,
    Screen,
    _moves,
    _Precedence,
    forward_states,
)
from taopt.heuristics.sequencing import delivery_cost_matrix, path_cost
from taopt.orchestration.studies.delivery import study_instance
from taopt.sop.problem import SopProblem, evaluate_order

SMALL = [(i, r) for i in range(4) for r in (0.15, 0.45, 0.9)]


def respects_precedences(instance, order) -> bool:
    """Whether every pair (r, j) of the instance has r before j in ``order``."""
    where = {c: k for k, c in enumerate(order)}
    return all(where[r] < where[j] for r, j in instance.precedences)


@pytest.mark.parametrize(("index", "ratio"), SMALL)
def test_ils_feasible_between_optimum_and_smma(index, ratio):
    """On n = 7: feasible, precedence-respecting, scored by evaluate, optimum <= ILS <= SMMA."""
    inst = study_instance("small", index, seed=1, ratio=ratio)
    result = taopt.solve(inst, "ILS", seed=3, iterations=5)
    assert result.method == "ILS"
    assert taopt.evaluate(inst, result.plan) == result.objective
    assert respects_precedences(inst, result.plan.order)
    smma = taopt.solve(inst, "SMMA").objective
    optimum = optimal_plan(inst).objective
    assert result.objective <= smma
    assert result.objective >= optimum * (1 - 1e-9)


@pytest.mark.parametrize("ratio", [0.15, 0.6])
def test_ils_on_dag40_improves_on_smma_and_is_feasible(ratio):
    """On a 40-customer dag40 instance ILS is feasible, respects (5.7) and is <= SMMA."""
    inst = study_instance("dag40", 1, seed=1, ratio=ratio)
    result = taopt.solve(inst, "ILS", seed=0, iterations=2, window=4)
    assert taopt.evaluate(inst, result.plan) == pytest.approx(result.objective, rel=1e-12)
    assert respects_precedences(inst, result.plan.order)
    assert result.objective <= taopt.solve(inst, "SMMA").objective
    assert result.objective <= result.info["start_objective"]
    assert result.info["stopped_by"] == "iterations"


def test_ils_same_seed_same_result():
    """Two runs with one seed give the same order and makespan."""
    inst = study_instance("dag40", 2, seed=1, ratio=0.3)
    first = taopt.solve(inst, "ILS", seed=7, iterations=3, window=4)
    second = taopt.solve(inst, "ILS", seed=7, iterations=3, window=4)
    assert first.plan == second.plan
    assert first.objective == second.objective


def test_ils_time_limit_returns_a_feasible_plan():
    """A (tiny) wall-clock limit stops the search with a feasible plan, never an error."""
    inst = study_instance("dag40", 0, seed=1, ratio=0.45)
    result = taopt.solve(inst, "ILS", seed=0, iterations=10_000, time_limit=0.05)
    assert result.info["stopped_by"] == "time_limit"
    assert taopt.evaluate(inst, result.plan) == pytest.approx(result.objective, rel=1e-12)
    assert result.objective <= taopt.solve(inst, "SMMA").objective


def test_ils_without_the_tstar_screen():
    """With every move evaluated (no t* screen) ILS is still feasible and <= SMMA."""
    inst = study_instance("dag40", 4, seed=1, ratio=0.3)
    result = taopt.solve(inst, "ILS", seed=0, iterations=1, window=3, tstar_screen=None)
    assert taopt.evaluate(inst, result.plan) == pytest.approx(result.objective, rel=1e-12)
    assert result.objective <= taopt.solve(inst, "SMMA").objective


@pytest.mark.parametrize(
    "option",
    [
        {"tstar_screen": -1.0},
        {"iterations": -1},
        {"window": 0},
        {"max_block": 1.5},
        {"accept_worse": -0.1},
    ],
)
def test_ils_rejects_bad_options(option):
    """Bad search parameters raise InstanceError naming them."""
    inst = study_instance("small", 0, seed=1)
    with pytest.raises(InstanceError, match=next(iter(option))):
        taopt.solve(inst, "ILS", **option)


def test_forward_states_from_a_prefix_equal_a_full_run():
    """Re-running the DP from position a on stored prefix states equals the full DP, bit for bit."""
    inst = study_instance("dag40", 3, seed=1, ratio=0.45)
    order = list(taopt.solve(inst, "SMMA").plan.order)
    states, value = forward_states(inst, order)
    assert value == schedule(inst, order).info["dp_objective"]
    moved = order[:10] + order[10:20][::-1] + order[20:]
    if respects_precedences(inst, moved):  # else only the prefix identity is checked
        again, value2 = forward_states(inst, moved, 10, list(states))
        full, value3 = forward_states(inst, moved)
        assert value2 == value3
        assert all(np.array_equal(x, y) for x, y in zip(again, full, strict=True))


@settings(
    max_examples=25, derandomize=True, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
@given(
    index=st.integers(0, 4),
    ratio=st.sampled_from([0.15, 0.3, 0.6, 0.9]),
    setup=st.sampled_from(["small", "dag40"]),
    pick=st.randoms(use_true_random=False),
)
def test_incremental_move_evaluation_matches_full_schedule(index, ratio, setup, pick):
    """Every move from a random position: the incremental value is the full DP's (exact mode),
    a pruned move is no better, an early 'improves' answer bounds the true makespan above."""
    inst = study_instance(setup, index, seed=1, ratio=ratio)
    order = list(taopt.solve(inst, pick.choice(["NIA", "MMA", "SMMA"])).plan.order)
    states = ScheduleStates(inst, order)
    assert states.value == schedule(inst, order).info["dp_objective"]
    prec = _Precedence(range(inst.n), inst.precedences)
    moves = [m for i in range(inst.n) for m in _moves(states.order, i, prec, 6, 3)]
    assert moves  # at least the first customer can move (moves from every position)
    cost, depot, _, _ = delivery_cost_matrix(inst)
    screen = Screen(cost, depot, 0.0)
    for a, segment in pick.sample(moves, min(len(moves), 12)):
        moved = states.order.copy()
        moved[a : a + len(segment)] = segment
        assert respects_precedences(inst, moved.tolist())
        change = path_cost(cost, [depot, *moved]) - path_cost(cost, [depot, *states.order])
        assert screen.delta(states.order, a, segment) == pytest.approx(change, abs=1e-6)
        truth = schedule(inst, moved.tolist()).info["dp_objective"]
        exact = states.try_segment(a, segment, exact=True)
        quick = states.try_segment(a, segment)
        slack = TOLERANCE * states.value
        if exact is None:
            assert truth >= states.value - 2 * slack
            assert quick is None
        else:
            assert exact == truth
            assert exact < states.value
            assert quick is not None and quick >= truth - slack
    a, segment = pick.choice(moves)
    states.apply(a, segment)
    assert states.value == schedule(inst, states.order.tolist()).info["dp_objective"]
    assert all(
        np.array_equal(x, y)
        for x, y in zip(states.ready, forward_states(inst, states.order)[0], strict=True)
    )


@st.composite
def sop_problems(draw: st.DrawFn) -> SopProblem:
    """Random asymmetric integer costs (some arcs forbidden) and acyclic precedences."""
    n = draw(st.integers(4, 8))
    cost = np.array(draw(st.lists(st.integers(0, 9), min_size=n * n, max_size=n * n)), float)
    cost = cost.reshape(n, n)
    mask = np.array(draw(st.lists(st.booleans(), min_size=n * n, max_size=n * n))).reshape(n, n)
    cost[mask & (cost > 7)] = np.inf
    np.fill_diagonal(cost, 0.0)
    inner = draw(st.permutations(list(range(1, n - 1))))
    pairs = []
    for a, b in draw(st.lists(st.tuples(st.integers(0, n - 3), st.integers(0, n - 3)))):
        if a < b:
            pairs.append((inner[a], inner[b]))
    return SopProblem(cost, tuple(dict.fromkeys(pairs)), 0, n - 1, "random")


@settings(max_examples=40, derandomize=True, deadline=None)
@given(sop_problems())
def test_ils_sop_feasible_and_at_least_as_good_as_its_starts(problem):
    """On the SOP: a feasible order, never cheaper than brute force, never worse than its
    starts (SMMA's and MMA's paths); status no_solution only when no order exists."""
    import itertools

    inner = [v for v in range(problem.n) if v not in (problem.start, problem.end)]
    optimum = np.inf
    for perm in itertools.permutations(inner):
        order = [problem.start, *perm, problem.end]
        where = {v: k for k, v in enumerate(order)}
        if all(where[r] < where[j] for r, j in problem.precedences):
            optimum = min(optimum, float(problem.cost[order[:-1], order[1:]].sum()))
    starts = {}  # the ILS starts from SMMA's and MMA's paths (repaired at a dead end)
    for name in ("SMMA", "MMA"):
        start = taopt.solve(problem, name)
        if start.solution is not None:
            starts[name] = start.objective
    result = taopt.solve(problem, "ILS", seed=1, iterations=10)
    if result.solution is None:  # only when no order exists at all
        assert (
            str(result.status) == "no_solution"
            and "ILS found no start order" in (result.info["error"])
        )
        assert not starts and not np.isfinite(optimum)
        return
    assert starts, "ILS found an order although none of its start heuristics did"
    assert evaluate_order(problem, result.order) == pytest.approx(result.objective)
    assert result.objective >= optimum - 1e-9
    assert result.objective <= min(list(starts.values())[:2]) + 1e-9
