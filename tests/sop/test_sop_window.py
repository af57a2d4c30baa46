"""The position-window Lagrangian bound (issue 33, :mod:`taopt.models.sop_window`): the root
bound and every completion bound never above brute force on tiny random SOPs (dense and
sparse precedence, forbidden arcs), and the DP with it still equals brute force."""

from __future__ import annotations

import math

import numpy as np
import pytest

from taopt.ideals import bits
from taopt.models import sop_window
from taopt.models.sop_dp import assignment_potentials, reversed_problem, solve_sop_dp
from taopt.models.sop_window import (
    ITERATIONS,
    STALL_STEPS,
    TRIAL,
    WindowCompletion,
    _popcount,
    _stalled,
    _usable,
    start_prices,
    window_bound,
    window_prices,
    windows,
)
from taopt.result import OPTIMAL
from taopt.sop.problem import SopProblem, evaluate_order, path_cost
from tests.reference_exact import sop_instance, sop_orders


def _problem(seed: int) -> SopProblem:
    """Odd seeds: :func:`sop_instance` (4-7 nodes, sparse); even: 6-8 nodes, a random share of
    forbidden arcs and precedence of density 0.1-0.7 (dense ones included)."""
    if seed % 2:
        return sop_instance(seed)
    rng = np.random.default_rng([33, seed])
    n = int(rng.integers(6, 9))
    cost = rng.integers(1, 60, size=(n, n)).astype(float)
    cost[rng.random((n, n)) < 0.15] = np.inf
    density = [0.1, 0.4, 0.7][seed % 3]
    pairs = [(a, b) for a in range(1, n - 1) for b in range(a + 1, n - 1) if rng.random() < density]
    order = rng.permutation(np.arange(1, n - 1))  # relabel: precedence not along the labels
    pairs = [(int(order[a - 1]), int(order[b - 1])) for a, b in pairs]
    return SopProblem(cost, pairs, 0, n - 1, name=f"window-{seed}")


def _completions(problem: SopProblem, orders: list[list[int]]) -> dict:
    """The cheapest completion of every state ``(ideal, last)`` some order passes through."""
    best: dict = {}
    for order in orders:
        for k in range(1, problem.n):
            key = (frozenset(order[:k]), order[k - 1])
            rest = path_cost(problem.cost, order[k - 1 :])
            best[key] = min(best.get(key, math.inf), rest)
    return best


def _masks(problem: SopProblem, keys: list) -> tuple[np.ndarray, np.ndarray]:
    node = bits(problem.n)
    mask = np.array([np.bitwise_or.reduce(node[sorted(ideal)]) for ideal, _ in keys])
    return mask.astype(np.uint64), np.array([last for _, last in keys], dtype=np.int64)


def test_windows_hold_every_feasible_order():
    """Every node of every feasible order sits inside its window."""
    for seed in range(30):
        problem = _problem(seed)
        low, high = windows(problem)
        for order in sop_orders(problem):
            where = np.argsort(order)
            assert (low <= where).all() and (where <= high).all()


@pytest.mark.parametrize("seed", range(40))
def test_root_bound_never_above_the_optimum(seed):
    """``L(lam)`` for random prices, for zero prices and for the subgradient's are at most
    the brute-force optimum (``inf`` only when no order exists)."""
    problem = _problem(seed)
    orders = list(sop_orders(problem))
    optimum = min((evaluate_order(problem, o) for o in orders), default=math.inf)
    rng = np.random.default_rng(seed)
    for lam in (np.zeros(problem.n), rng.normal(0, 30, problem.n)):
        assert window_bound(problem, lam) <= optimum + 1e-6
    if math.isfinite(optimum):
        found = window_prices(problem, optimum + 1)
        assert found.bound <= optimum + 1e-6
        assert found.bound == pytest.approx(window_bound(problem, found.lam))


@pytest.mark.parametrize("seed", range(40))
def test_completion_bound_never_above_the_cheapest_completion(seed):
    """For every state some order passes through, forward and on the reversed problem, the
    window completion bound is at most the brute-force cheapest completion."""
    problem = _problem(seed)
    rng = np.random.default_rng(seed)
    for data in (problem, reversed_problem(problem)):
        orders = list(sop_orders(data))
        if not orders:
            return
        best = _completions(data, orders)
        keys = list(best)
        mask, last = _masks(data, keys)
        optimum = min(evaluate_order(data, o) for o in orders)
        for lam in (rng.normal(0, 30, data.n), window_prices(data, optimum + 1).lam):
            bound = WindowCompletion(data, lam)(mask, last)
            truth = np.array([best[key] for key in keys])
            assert (bound <= truth + 1e-6).all()


def test_completion_bound_is_tight_somewhere():
    """The completion bound is not vacuous: on some tiny instance with the subgradient's
    prices it equals the cheapest completion for some state past the start."""
    tight = 0
    for seed in range(20):
        problem = _problem(seed)
        orders = list(sop_orders(problem))
        if not orders:
            continue
        best = _completions(problem, orders)
        keys = [key for key in best if len(key[0]) > 1]
        mask, last = _masks(problem, keys)
        optimum = min(evaluate_order(problem, o) for o in orders)
        bound = WindowCompletion(problem, window_prices(problem, optimum + 1).lam)(mask, last)
        truth = np.array([best[key] for key in keys])
        tight += int((np.abs(bound - truth) < 1e-6).sum())
    assert tight > 0


def test_wide_masks_and_chunks_give_the_same_bound(monkeypatch):
    """Masks of several words (70 nodes) and chunked calls: the held prices by byte table
    equal the membership sum, the popcount the set size."""
    from taopt.models import sop_window

    rng = np.random.default_rng(5)
    n = 70
    cost = rng.integers(1, 50, size=(n, n)).astype(float)
    problem = SopProblem(cost, [(1, 2), (2, 3)], 0, n - 1)
    lam = rng.normal(0, 10, n)
    table = WindowCompletion(problem, lam)
    node = bits(n)
    sets = [rng.choice(np.arange(n), size=int(rng.integers(1, n)), replace=False) for _ in range(9)]
    mask = np.array([np.bitwise_or.reduce(node[s], axis=0) for s in sets])
    held = table._held_prices(mask)
    assert held == pytest.approx([lam[s].sum() for s in sets])
    assert (_popcount(mask) == [len(s) for s in sets]).all()
    last = np.array([int(s[0]) for s in sets])
    whole = table(mask, last)
    monkeypatch.setattr(sop_window, "CHUNK", 2)
    assert np.array_equal(table(mask, last), whole, equal_nan=True)


@pytest.mark.parametrize("seed", range(30))
def test_dp_with_the_window_bound_equals_brute_force(seed):
    """The DP with the window prices, from a middling order and from an optimal one, proves
    the brute-force optimum (no false gap, no false optimal)."""
    problem = _problem(seed)
    orders = sorted(sop_orders(problem), key=lambda o: evaluate_order(problem, o))
    if not orders:
        result = solve_sop_dp(problem, window=np.zeros(problem.n), beam_width=0)
        assert result.status == "infeasible"
        return
    optimum = evaluate_order(problem, orders[0])
    lam = window_prices(problem, optimum + 1).lam
    for start in (orders[len(orders) // 2], orders[0]):
        result = solve_sop_dp(problem, incumbent=start, window=lam, beam_width=0)
        assert result.status == OPTIMAL
        assert result.objective == pytest.approx(optimum)
        assert result.bound == pytest.approx(optimum)
        assert evaluate_order(problem, result.order) == pytest.approx(optimum)


@pytest.mark.parametrize("seed", range(20))
def test_from_the_assignment_prices_the_bound_is_at_least_the_assignment_bound(seed):
    """Started from the assignment's dual prices, ``L(lam)`` is at least the assignment bound
    (and at most the optimum), and the subgradient from there keeps at least that."""
    problem = _problem(seed)
    usable = _usable(problem)
    alpha, beta = assignment_potentials(usable, problem.start, problem.end)
    inner = [v for v in range(problem.n) if v not in (problem.start, problem.end)]
    assignment = alpha[problem.start] + alpha[inner].sum() + np.delete(beta, problem.start).sum()
    lam = start_prices(alpha, beta, problem.start, problem.end)
    optimum = min((evaluate_order(problem, o) for o in sop_orders(problem)), default=math.inf)
    if not math.isfinite(assignment):
        return
    assert window_bound(problem, lam) >= assignment - 1e-6
    assert window_bound(problem, lam) <= optimum + 1e-6
    if math.isfinite(optimum):
        assert window_prices(problem, optimum + 1, lam=lam).bound >= assignment - 1e-6


def test_a_bound_kept_at_the_floor_stops_after_the_trial():
    """With a floor no bound reaches, the subgradient stops after its trial (TRIAL steps), its
    bound still at most an order's cost; without one it goes on."""
    rng = np.random.default_rng(7)
    n = 30
    cost = rng.integers(1, 100, size=(n, n)).astype(float)
    pairs = [(a, b) for a in range(1, n - 1) for b in range(a + 1, n - 1) if rng.random() < 0.3]
    problem = SopProblem(cost, pairs, 0, n - 1)
    order = list(range(n))  # every pair (a, b) has a < b
    target = evaluate_order(problem, order)
    stopped = window_prices(problem, target, iterations=4 * TRIAL, floor=np.inf)
    assert stopped.iterations == TRIAL
    assert stopped.bound <= target
    free = window_prices(problem, target, iterations=4 * TRIAL)
    assert free.iterations > TRIAL
    assert stopped.bound <= free.bound <= target


def _dense_30() -> tuple[SopProblem, float]:
    """A 30-node SOP of precedence density 0.3 and the cost of an order of it (a bound that
    creeps up after its first steps: 477 steps with the plateau rule, 597 without)."""
    rng = np.random.default_rng(1)
    n = 30
    cost = rng.integers(1, 100, size=(n, n)).astype(float)
    pairs = [(a, b) for a in range(1, n - 1) for b in range(a + 1, n - 1) if rng.random() < 0.3]
    problem = SopProblem(cost, pairs, 0, n - 1)
    return problem, evaluate_order(problem, list(range(n)))  # every pair (a, b) has a < b


def test_stalled_reads_the_rise_over_the_last_steps():
    """``_stalled``: not within ``2 * STALL_STEPS`` steps; then a flat history stalls, a rise
    of a tenth of the gap over the window does not, one of a thousandth does."""
    flat = [10.0] * (2 * STALL_STEPS + 1)
    assert not _stalled(flat[:-1], 110.0)
    assert _stalled(flat, 110.0)
    assert not _stalled(flat[:-1] + [20.0], 110.0)
    assert _stalled(flat[:-1] + [10.1], 110.0)
    assert not _stalled(flat[:STALL_STEPS] + [-np.inf] + flat[STALL_STEPS + 1 :], 110.0)


def test_stall_rule_ends_the_run_and_only_truncates_it(monkeypatch):
    """Without a time limit the plateau rule ends the subgradient before ``ITERATIONS`` steps
    on a 30-node SOP aimed at an order's cost (its bound stays below it), and it only cuts
    the run short: the same subgradient without the rule (``STALL_SHARE`` 0) stopped at the
    same step returns the same prices and bound, at most the order's cost, and going on
    without the rule never lowers the bound."""
    problem, target = _dense_30()
    ruled = window_prices(problem, target)
    assert ruled.iterations < ITERATIONS
    assert ruled.bound <= target
    monkeypatch.setattr(sop_window, "STALL_SHARE", 0.0)
    same = window_prices(problem, target, iterations=ruled.iterations)
    assert same.bound == ruled.bound
    assert np.array_equal(same.lam, ruled.lam)
    free = window_prices(problem, target)
    assert free.iterations > ruled.iterations
    assert ruled.bound <= free.bound <= target


@pytest.mark.parametrize("n", [20, 70, 130])
def test_window_bound_per_run_of_masks_equals_the_bound_per_state(n):
    """States sharing an ideal, in runs and shuffled (equal masks apart), and first steps in
    and out of the ideal: the bound per run of masks equals ``H`` (or ``H2`` when the
    cheapest walk's first step is held) plus the prices of the nodes not held, per state."""
    rng = np.random.default_rng(n)
    cost = rng.integers(1, 50, size=(n, n)).astype(float)
    problem = SopProblem(cost, [(1, 2), (2, 3)], 0, n - 1)
    lam = rng.normal(0, 10, n)
    table = WindowCompletion(problem, lam)
    node = bits(n)
    sets, last = [], []
    for _ in range(12):
        held = rng.choice(np.arange(1, n - 1), size=int(rng.integers(1, n - 2)), replace=False)
        held = np.append(held, 0)
        for v in rng.choice(held, size=int(rng.integers(1, 4))):  # a run of last nodes
            sets.append(held)
            last.append(int(v))
    for order in (np.arange(len(sets)), rng.permutation(len(sets))):
        mask = np.array([np.bitwise_or.reduce(node[sets[i]], axis=0) for i in order])
        ends = np.array([last[i] for i in order])
        got = table(mask, ends)
        for i, at in enumerate(order):
            k = len(sets[at]) - 1
            step = table.step[k, last[at]]
            head = table.spare if step >= 0 and step in sets[at] else table.table
            want = head[k, last[at]] + lam.sum() - lam[sets[at]].sum()
            assert got[i] == pytest.approx(want) or (np.isinf(want) and got[i] == want)
