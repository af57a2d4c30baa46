"""The remainder's assignment bound per order ideal (issue 33): never above the cheapest
completion of any state on random tiny SOPs, and the DP using it gives the brute-force optimum."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from taopt.models.sop_dp import _members, reversed_problem, solve_sop_dp
from taopt.models.sop_remainder import RemainderBound
from taopt.result import OPTIMAL
from taopt.runtime import Deadline
from taopt.sop.problem import SopProblem, evaluate_order
from tests.reference_exact import sop_brute_force, sop_instance, sop_orders
from tests.sop.test_sop_credit import _clustered, _prices


def _instance(seed: int) -> SopProblem:
    """Even seeds: the shared tiny SOPs; odd seeds: clustered ones with precedences."""
    return sop_instance(seed) if seed % 2 == 0 else _clustered(seed)


def _usable(problem: SopProblem) -> np.ndarray:
    """The usable arcs' costs (``inf`` elsewhere), as the DP reads them."""
    from taopt.models.sop import usable_arcs

    tails, heads = usable_arcs(problem.cost, problem.closure)
    usable = np.full((problem.n, problem.n), np.inf)
    usable[tails, heads] = problem.cost[tails, heads]
    return usable


def _completions(problem: SopProblem) -> dict[tuple[frozenset[int], int], float]:
    """Per state (ideal, last node) reached by a feasible order, its cheapest completion."""
    best: dict[tuple[frozenset[int], int], float] = {}
    for order in sop_orders(problem):
        for k in range(1, len(order)):
            rest = order[k - 1 :]
            cost = float(sum(problem.cost[a, b] for a, b in itertools.pairwise(rest)))
            key = (frozenset(order[:k]), order[k - 1])
            best[key] = min(best.get(key, math.inf), cost)
    return best


@pytest.mark.parametrize("seed", range(16))
def test_remainder_assignment_is_at_most_every_completion(seed):
    """For every state of every feasible order, in both directions, AP(I, s) over any set of
    last nodes holding v is at most the cheapest completion of (I, v)."""
    for problem in (_instance(seed), reversed_problem(_instance(seed))):
        completions = _completions(problem)
        bound = RemainderBound(_usable(problem), problem.end)
        by_ideal: dict[frozenset[int], list[int]] = {}
        for ideal, last in completions:
            by_ideal.setdefault(ideal, []).append(last)
        for (ideal, last), cheapest in completions.items():
            open_nodes = np.array(sorted(set(range(problem.n)) - ideal), dtype=np.int64)
            alone = bound.value(open_nodes, np.array([last]))
            shared = bound.value(open_nodes, np.array(sorted(by_ideal[ideal])))
            assert shared <= alone + 1e-9
            assert alone <= cheapest + 1e-6


def test_remainder_assignment_sees_no_completion():
    """A remainder whose node can be entered from nowhere has no assignment: the bound is inf."""
    cost = np.array([[0, 1, 1, 9], [1, 0, 1, 1], [np.inf, np.inf, 0, 1], [1, 1, 1, 0]], dtype=float)
    cost[:, 2] = np.inf  # node 2 cannot be entered
    bound = RemainderBound(cost, 3)
    assert bound.value(np.array([1, 2, 3]), np.array([0])) == math.inf
    assert bound.value(np.array([], dtype=np.int64), np.array([3])) == 0.0


def test_layer_bounds_each_state_by_its_ideal():
    """``layer`` gives each state f plus its ideal's assignment, evaluating closest-first."""
    problem = sop_instance(4)
    usable = _usable(problem)
    bound = RemainderBound(usable, problem.end)
    start = problem.start
    firsts = [w for w in range(problem.n) if np.isfinite(usable[start, w]) and w != problem.end]
    firsts = [w for w in firsts if not any(problem.closure.predecessors(w)) or w == start][:2]
    members = np.zeros((len(firsts), problem.n), dtype=bool)
    members[:, start] = True
    members[np.arange(len(firsts)), firsts] = True
    group = np.arange(len(firsts))
    last = np.array(firsts)
    value = usable[start, last]
    out = bound.layer(members, group, last, value, value, math.inf, Deadline(None))
    for i, w in enumerate(firsts):
        expected = value[i] + bound.value(np.flatnonzero(~members[i]), np.array([w]))
        assert out[i] == pytest.approx(expected)
    assert bound.ideals == len(firsts)


@pytest.mark.parametrize("seed", range(20))
def test_dp_with_remainder_bound_matches_brute_force(seed):
    """The DP dropping states by the remainder's assignment (with and without the root's row
    credit), from a middling order, gives the brute-force optimum and proves it."""
    problem = _instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    orders = sorted(sop_orders(problem), key=lambda o: evaluate_order(problem, o))
    start = orders[len(orders) // 2]
    lagrange, credit = _prices(problem)
    for kwargs in ({}, {"lagrange": lagrange, "credit": credit}):
        result = solve_sop_dp(problem, incumbent=start, beam_width=0, remainder=True, **kwargs)
        assert result.status == OPTIMAL
        assert result.objective == pytest.approx(optimum)
        assert result.bound == pytest.approx(optimum)
        assert evaluate_order(problem, result.order) == pytest.approx(optimum)


@pytest.mark.parametrize("seed", range(12))
def test_dp_with_remainder_bound_stopped_keeps_a_valid_bound(seed):
    """A run stopped by its state cap, given the optimum as incumbent, reports a bound at most
    the optimum."""
    problem = _instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    best = min(sop_orders(problem), key=lambda o: evaluate_order(problem, o))
    capped = solve_sop_dp(problem, incumbent=best, max_states=2, beam_width=0, remainder=True)
    assert capped.bound is not None and capped.bound <= optimum + 1e-6


def test_members_of_the_layer_match_the_bound_input():
    """``_members`` unpacks the ideals the DP hands to the bound (node v held iff bit v set)."""
    mask = np.array([0b1011], dtype=np.uint64)
    assert _members(mask, 5).tolist() == [[True, True, False, True, False]]


def _through(problem: SopProblem) -> tuple[dict, dict]:
    """Per forward state (ideal, last) and per backward state (filter, first), the cheapest
    feasible order through it."""
    forward: dict[tuple[frozenset[int], int], float] = {}
    backward: dict[tuple[frozenset[int], int], float] = {}
    for order in sop_orders(problem):
        cost = float(evaluate_order(problem, order))
        for k in range(1, len(order) + 1):
            key = (frozenset(order[:k]), order[k - 1])
            forward[key] = min(forward.get(key, math.inf), cost)
            key = (frozenset(order[-k:]), order[-k])
            backward[key] = min(backward.get(key, math.inf), cost)
    return forward, backward


@pytest.mark.parametrize("seed", range(16))
def test_state_lp_is_at_most_every_order_through_the_state(seed):
    """The root's LP with a state's ideal (or filter) fixed never exceeds the cheapest order
    through that state, forward and backward."""
    from taopt.models.sop_cuts import SopCutModel
    from taopt.models.sop_statelp import StateLp

    problem = _instance(seed)
    if not math.isfinite(sop_brute_force(problem)):
        return
    model = SopCutModel(problem)
    model.root()
    lp = StateLp(model)
    forward, backward = _through(problem)
    for reverse, table in ((False, forward), (True, backward)):
        for (held_set, last), cheapest in table.items():
            held = np.zeros(problem.n, dtype=bool)
            held[list(held_set)] = True
            assert lp.bound(held, last, reverse, Deadline(None)) <= cheapest + 1e-6
    lp.release()
    assert (np.asarray(model.highs.getLp().col_upper_) == 1.0).all()


@pytest.mark.parametrize("seed", range(20))
def test_dp_with_state_lp_matches_brute_force(seed):
    """The DP dropping states by the restricted LP (and the remainder's assignment), from a
    middling order, gives the brute-force optimum and proves it."""
    from taopt.models.sop_cuts import SopCutModel
    from taopt.models.sop_statelp import StateLp

    problem = _instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    orders = sorted(sop_orders(problem), key=lambda o: evaluate_order(problem, o))
    model = SopCutModel(problem)
    model.root()
    lagrange, credit = model.lagrangian_prices(), model.row_credit()
    for remainder in (False, True):
        result = solve_sop_dp(
            problem,
            incumbent=orders[len(orders) // 2],
            beam_width=0,
            lagrange=lagrange,
            credit=credit,
            remainder=remainder,
            state_lp=StateLp(model),
        )
        assert result.status == OPTIMAL
        assert result.objective == pytest.approx(optimum)
        assert result.bound == pytest.approx(optimum)
        assert evaluate_order(problem, result.order) == pytest.approx(optimum)


@pytest.mark.parametrize("seed", range(10))
def test_inherited_lp_prices_bound_every_order_through_the_state(seed):
    """With the restricted LP's prices of a state, ``B + Σ max(d_a, 0)`` over a whole order
    through that state (the bound its descendants inherit along their kept prefix) is at most
    that order's cost, forward and backward."""
    from taopt.models.sop_cuts import SopCutModel
    from taopt.models.sop_statelp import StateLp

    problem = _instance(seed)
    if not math.isfinite(sop_brute_force(problem)):
        return
    model = SopCutModel(problem)
    model.root()
    lp = StateLp(model)
    prices: dict[tuple[bool, frozenset[int], int], tuple[float, np.ndarray] | None] = {}
    for order in sop_orders(problem):
        cost = float(evaluate_order(problem, order))
        for reverse in (False, True):
            path = order[::-1] if reverse else order
            for k in range(1, len(order) + 1):
                key = (reverse, frozenset(path[:k]), path[k - 1])
                if key not in prices:
                    held = np.zeros(problem.n, dtype=bool)
                    held[list(key[1])] = True
                    lp.bound(held, key[2], reverse, Deadline(None))
                    last = lp.last_prices
                    prices[key] = None if last is None else (last[0], lp.positive(last[1], reverse))
                found = prices[key]
                if found is not None:
                    value, positive = found
                    assert value + positive[path[:-1], path[1:]].sum() <= cost + 1e-6
    lp.release()
