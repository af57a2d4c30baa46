"""The ideal DP for the SOP and the "exact" portfolio (issue 16 item 3).

Checked without trusting either engine: optima against brute force over permutations and
against the flow MILP, the completion bound against the true cheapest completion of
every state of small instances, the ideal count against a subset enumeration, and the
portfolio against TSPLIB's proven optima.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import taopt
from taopt.models.sop import solve_sop, solve_sop_problem
from taopt.models.sop_dp import (
    beam_order,
    completion_bound,
    count_ideals,
    reversed_problem,
    solve_sop_dp,
)
from taopt.result import INFEASIBLE, OPTIMAL, TIME_LIMIT
from taopt.sop.problem import KNOWN_OPTIMA, SopProblem, evaluate_order, shipped_sop


def random_problem(seed: int, n: int, forbidden: float, density: float) -> SopProblem:
    """Random integer costs, a share of forbidden arcs, random acyclic precedences."""
    rng = np.random.default_rng([16, seed])
    cost = rng.integers(0, 60, size=(n, n)).astype(float)
    cost[rng.random((n, n)) < forbidden] = np.inf
    np.fill_diagonal(cost, 0.0)
    inner = rng.permutation(np.arange(1, n - 1))
    pairs = [
        (int(inner[a]), int(inner[b]))
        for a, b in itertools.combinations(range(n - 2), 2)
        if rng.random() < density
    ]
    return SopProblem(cost, tuple(pairs), 0, n - 1, f"random-{seed}")


def feasible_orders(problem: SopProblem, visited: tuple[int, ...] = ()):
    """Every feasible order that starts with ``visited`` (default: with start)."""
    prefix = list(visited) or [problem.start]
    rest = [v for v in range(problem.n) if v not in prefix and v != problem.end]
    for perm in itertools.permutations(rest):
        order = [*prefix, *perm, problem.end]
        where = {v: k for k, v in enumerate(order)}
        if all(where[r] < where[j] for r, j in problem.precedences):
            if np.isfinite(problem.cost[order[:-1], order[1:]]).all():
                yield order


def brute_force(problem: SopProblem) -> float:
    """Cheapest feasible order by enumeration (inf when none)."""
    costs = [float(problem.cost[o[:-1], o[1:]].sum()) for o in feasible_orders(problem)]
    return min(costs, default=np.inf)


CASES = [
    (seed, n, forbidden, density)
    for seed, (n, forbidden, density) in enumerate(
        [(5, 0.0, 0.0), (6, 0.2, 0.0), (7, 0.0, 0.3), (7, 0.3, 0.3), (8, 0.15, 0.2)] * 4
    )
]


@pytest.mark.parametrize("seed, n, forbidden, density", CASES)
def test_dp_equals_brute_force_and_the_milp(seed, n, forbidden, density):
    """Small random SOPs (with/without precedences, missing arcs): DP = brute force = MILP."""
    problem = random_problem(seed, n, forbidden, density)
    optimum = brute_force(problem)
    dp = solve_sop_dp(problem)
    milp = solve_sop(problem.cost, problem.precedences, problem.start, problem.end)
    if not np.isfinite(optimum):
        assert dp.status == INFEASIBLE and milp.status == INFEASIBLE
        assert dp.solution is None and dp.objective == np.inf
        return
    assert dp.status == OPTIMAL and milp.status == OPTIMAL
    assert dp.objective == pytest.approx(optimum) == milp.objective
    assert evaluate_order(problem, dp.order) == pytest.approx(dp.objective)
    assert dp.bound == pytest.approx(optimum)


@pytest.mark.parametrize("seed", range(8))
def test_dp_with_a_good_incumbent_still_proves_the_optimum(seed):
    """Given the optimal order as incumbent (everything prunes), the DP returns it, optimal."""
    problem = random_problem(100 + seed, 7, 0.0, 0.3)  # complete: always feasible
    optimum = brute_force(problem)
    best = min(feasible_orders(problem), key=lambda o: problem.cost[o[:-1], o[1:]].sum())
    result = solve_sop_dp(problem, incumbent=best, beam_width=0)
    assert result.status == OPTIMAL and result.objective == pytest.approx(optimum)
    assert result.bound <= optimum + 1e-9


@pytest.mark.parametrize("seed", range(6))
def test_completion_bound_never_exceeds_the_true_completion(seed):
    """For every reachable state (ideal, last) of a small SOP, g <= the cheapest completion."""
    problem = random_problem(200 + seed, 7, 0.15, 0.25)
    checked = 0
    for order in feasible_orders(problem):
        for k in range(1, problem.n):
            prefix = tuple(order[:k])
            completions = [
                float(problem.cost[o[k - 1 :][:-1], o[k - 1 :][1:]].sum())
                for o in feasible_orders(problem, prefix)
            ]
            true = min(completions, default=np.inf)
            assert completion_bound(problem, set(prefix), prefix[-1]) <= true + 1e-9
            checked += 1
        if checked > 150:
            break


def test_completion_bound_is_positive_somewhere():
    """The bound is not trivially zero: at the start of ESC12 it is at least the assignment
    relaxation's half of the optimum (a check that the test above can fail)."""
    problem = SopProblem.load("ESC12")
    assert completion_bound(problem, {problem.start}, problem.start) > 0.5 * KNOWN_OPTIMA["ESC12"]


@pytest.mark.parametrize("seed", range(5))
def test_count_ideals_equals_a_subset_enumeration(seed):
    """The capped BFS count equals the number of predecessor-closed sets holding start."""
    problem = random_problem(300 + seed, 9, 0.0, 0.3)
    inner = [v for v in range(problem.n) if v != problem.start]
    closed = 0
    for size in range(len(inner) + 1):
        for subset in itertools.combinations(inner, size):
            chosen = {problem.start, *subset}
            if all(r in chosen for r, j in problem.closure.edges if j in chosen):
                closed += 1
    assert count_ideals(problem) == (closed, False)
    assert count_ideals(problem, cap=closed // 2)[1] is True


#: The shipped files of issue 16's certification set: certified by the slow test below.
LARGER = {"ESC47", "p43.4", "ry48p.4", "ft53.4", "rbg048a", "rbg050c"}


@pytest.mark.parametrize("name", sorted(set(shipped_sop()) - LARGER))
def test_portfolio_certifies_the_shipped_tsplib_optima(name):
    """taopt.solve(SopProblem, "exact") proves TSPLIB's optimum on the small shipped files."""
    problem = SopProblem.load(name)
    result = taopt.solve(problem, "exact")
    assert result.status == OPTIMAL and result.objective == KNOWN_OPTIMA[name]
    assert result.bound == pytest.approx(KNOWN_OPTIMA[name])
    assert evaluate_order(problem, result.order) == KNOWN_OPTIMA[name]


def test_esc47_with_one_second_returns_a_bound_not_an_error(sop_esc47):
    """ESC47 at time_limit=1 s: time_limit (or optimal) with a feasible order and a bound <= 1288."""
    problem = sop_esc47
    result = taopt.solve(problem, "exact", time_limit=1.0)
    assert result.status in (TIME_LIMIT, OPTIMAL)
    assert 0 < result.bound <= KNOWN_OPTIMA["ESC47"] <= result.objective
    assert evaluate_order(problem, result.order) == result.objective


def test_a_stopped_dp_returns_the_incumbent_and_a_valid_bound(sop_esc25):
    """The DP stopped by max_states keeps NIA's order and proves a bound <= the optimum."""
    problem = sop_esc25
    nia = taopt.solve(problem, "NIA")
    result = solve_sop_dp(problem, incumbent=nia, max_states=200, beam_width=0)
    assert result.status == TIME_LIMIT and result.info["stopped_by"] == "max_states"
    assert result.order == nia.order and result.objective == nia.objective
    assert 0 < result.bound <= KNOWN_OPTIMA["ESC25"]


def test_a_stopped_dp_without_incumbent_has_no_path_but_a_bound(sop_esc25):
    """Stopped with no incumbent and no beam: objective inf, no order, a positive valid bound."""
    problem = sop_esc25
    result = solve_sop_dp(problem, max_states=200, beam_width=0)
    assert result.status == TIME_LIMIT and result.solution is None
    assert result.objective == np.inf and 0 < result.bound <= KNOWN_OPTIMA["ESC25"]


def test_infeasible_sop_is_reported_with_a_proof():
    """Precedences 1 before 2 and 2 before 3 with arc 1 -> 2 the only way into 2 ... and no
    arc 2 -> 3 nor 1 -> 3 usable: no path exists; every engine says "infeasible"."""
    cost = np.ones((5, 5))
    cost[:, 2] = np.inf
    cost[1, 2] = 1.0  # 2 can only be entered from 1
    cost[2, 3] = np.inf  # ... and 3 never directly after 2
    cost[0, 3] = cost[1, 3] = np.inf
    problem = SopProblem(cost, ((1, 2), (2, 3)), 0, 4)
    assert brute_force(problem) == np.inf
    dp = solve_sop_dp(problem)
    assert dp.status == INFEASIBLE and "proof" in dp.info
    for engine in ("dp", "milp", "auto"):
        assert solve_sop_problem(problem, engine=engine).status == INFEASIBLE
    assert taopt.solve(problem, "exact").status == INFEASIBLE


def test_unreachable_node_is_infeasible_not_an_error():
    """A node no usable arc enters: status infeasible with the node named, no InstanceError."""
    cost = np.ones((4, 4))
    cost[:, 2] = np.inf
    result = taopt.solve(SopProblem(cost, (), 0, 3), "exact")
    assert result.status == INFEASIBLE and "node 2" in result.info["proof"]


def test_beam_order_is_feasible_and_deterministic():
    """The beam's order is feasible, scored as claimed, never below the optimum, repeatable."""
    problem = SopProblem.load("ESC12")
    cost, order = beam_order(problem, width=16)
    assert evaluate_order(problem, order) == cost >= KNOWN_OPTIMA["ESC12"]
    assert beam_order(problem, width=16) == (cost, order)


@pytest.mark.parametrize("engine", ["dp", "milp"])
def test_each_engine_alone_agrees(engine):
    """engine="dp" and engine="milp" both certify ESC11."""
    result = solve_sop_problem(SopProblem.load("ESC11"), engine=engine)
    assert result.status == OPTIMAL and result.objective == KNOWN_OPTIMA["ESC11"]
    assert result.info["engine"] == engine


@pytest.mark.parametrize("seed", range(4))
def test_assignment_prices_leave_no_negative_reduced_cost(seed):
    """Reduced costs c - alpha - beta are >= 0 on every usable arc, and the prices' sum (the
    bound f + P at the start) is not above the brute-force optimum."""
    from taopt.models.sop import usable_arcs
    from taopt.models.sop_dp import assignment_potentials

    problem = random_problem(400 + seed, 7, 0.1, 0.2)
    tails, heads = usable_arcs(problem.cost, problem.closure)
    usable = np.full((problem.n, problem.n), np.inf)
    usable[tails, heads] = problem.cost[tails, heads]
    alpha, beta = assignment_potentials(usable, problem.start, problem.end)
    reduced = usable[tails, heads] - alpha[tails] - beta[heads]
    assert (reduced >= 0).all()
    optimum = brute_force(problem)
    total = alpha[np.arange(problem.n) != problem.end].sum() + beta.sum()
    assert total <= optimum + 1e-9


@pytest.mark.parametrize("seed", range(12))
def test_each_direction_and_the_meeting_equal_brute_force(seed):
    """Forward alone, the reversed problem alone and the two meeting all give the optimum."""
    problem = random_problem(300 + seed, 8, 0.1 * (seed % 3), 0.1 * (seed % 4))
    optimum = brute_force(problem)
    met = solve_sop_dp(problem, beam_width=0)
    forward = solve_sop_dp(problem, beam_width=0, both=False)
    backward = solve_sop_dp(reversed_problem(problem), beam_width=0, both=False)
    if not np.isfinite(optimum):
        assert met.status == forward.status == backward.status == INFEASIBLE
        return
    for result in (met, forward, backward):
        assert result.status == OPTIMAL and result.objective == pytest.approx(optimum)
        assert result.bound == pytest.approx(optimum)
    assert evaluate_order(problem, met.order) == pytest.approx(optimum)
    assert met.order[0] == problem.start and met.order[-1] == problem.end


def test_the_two_directions_meet_on_a_search_without_pruning():
    """With no incumbent and no beam nothing prunes: the search ends by the meeting join."""
    problem = random_problem(400, 8, 0.0, 0.2)
    result = solve_sop_dp(problem, beam_width=0)
    assert result.info["direction"] == "both"
    assert result.objective == pytest.approx(brute_force(problem))


@pytest.mark.parametrize("seed", range(4))
def test_completion_bound_of_the_reversed_problem_is_valid(seed):
    """The backward search's bound (the bound on the reversed SOP) never exceeds the truth."""
    problem = reversed_problem(random_problem(500 + seed, 7, 0.15, 0.3))
    for order in itertools.islice(feasible_orders(problem), 20):
        for k in range(1, problem.n):
            prefix = tuple(order[:k])
            true = min(
                (
                    float(problem.cost[o[k - 1 :][:-1], o[k - 1 :][1:]].sum())
                    for o in feasible_orders(problem, prefix)
                ),
                default=np.inf,
            )
            assert completion_bound(problem, set(prefix), prefix[-1]) <= true + 1e-9


def test_portfolio_certifies_rbg048a():
    """rbg048a (TSPLIB optimum 351): the portfolio proves it (the backward search closes it)."""
    problem = SopProblem.load("rbg048a")
    result = taopt.solve(problem, "exact", time_limit=60)
    assert result.status == OPTIMAL and result.objective == KNOWN_OPTIMA["rbg048a"]
    assert evaluate_order(problem, result.order) == result.objective


@pytest.mark.slow
@pytest.mark.parametrize(
    "name", ["ESC25", "ESC47", "rbg048a", "rbg050c", "p43.4", "ry48p.4", "ft53.4"]
)
def test_portfolio_certifies_the_issue_16_set(name):
    """The certification set of issue 16 at its known optima within 120 s (rbg050c needs the
    second DP stage, about 40 s)."""
    problem = SopProblem.load(name)
    result = taopt.solve(problem, "exact", time_limit=120)
    assert result.status == OPTIMAL and result.objective == KNOWN_OPTIMA[name]
    assert evaluate_order(problem, result.order) == result.objective


@pytest.mark.parametrize("seed", range(6))
def test_both_price_sets_still_equal_brute_force(seed):
    """The bound on both directions' prices (the larger of two valid bounds) stays exact."""
    problem = random_problem(600 + seed, 8, 0.1 * (seed % 3), 0.15)
    optimum = brute_force(problem)
    result = solve_sop_dp(problem, beam_width=0, both_prices=True)
    if not np.isfinite(optimum):
        assert result.status == INFEASIBLE
        return
    assert result.status == OPTIMAL and result.objective == pytest.approx(optimum)
    assert result.bound == pytest.approx(optimum)


@pytest.mark.parametrize(("n", "words"), [(20, 1), (58, 1), (130, 3)])
def test_cheapest_extension_per_state_equals_a_full_sort(n, words):
    """The merge keeps, per (mask, last), the extension a stable sort by (mask, last, value)
    puts first: the same states, values and parents, ties included."""
    from taopt.ideals import differs, lex_keys
    from taopt.models.sop_dp import _cheapest_per_state

    rng = np.random.default_rng(n)
    size = 5_000
    pool = rng.integers(0, 2 ** min(n, 63), (200, words), dtype=np.uint64)
    mask = pool[rng.integers(0, 200, size)]
    mask = mask[:, 0] if words == 1 else mask
    last = rng.integers(0, n, size)
    value = rng.integers(0, 20, size).astype(float)  # many ties
    order = np.lexsort((value, last, *lex_keys(mask)))
    first = np.ones(size, dtype=bool)
    first[1:] = differs(mask[order]) | (last[order][1:] != last[order][:-1])
    assert np.array_equal(_cheapest_per_state(mask, last, value, n), order[first])


def test_beam_passes_run_to_their_end_are_reused(sop_esc25):
    """A beam pass that ran to its end is remembered per problem and width and reused by a
    later call (a second DP stage), which proves the same optimum."""
    from taopt.models import sop_dp

    sop_dp._BEAMS.clear()
    first = sop_dp.solve_sop_dp(sop_esc25, beam_width=256)
    keys = {sop_dp._problem_key(sop_esc25, w) for w in (64, 256)}
    assert keys <= set(sop_dp._BEAMS)
    again = sop_dp.solve_sop_dp(sop_esc25, beam_width=256)
    assert again.status == first.status == OPTIMAL and again.objective == first.objective
    assert again.info["beam"] == first.info["beam"]


def _grown_at_once(search, mask, last, value):
    """Every extension of a layer, then one merge of them all (the reference of ``grow``)."""
    from taopt.ideals import has, holds
    from taopt.models.sop_dp import _cheapest_per_state

    parts = []
    for w in range(search.problem.n):
        if w == search.problem.start:
            continue
        ok = np.flatnonzero(~has(mask, w) & holds(mask, search.pred[w]))
        step = search.usable[last[ok], w]
        ok, step = ok[np.isfinite(step)], step[np.isfinite(step)]
        parts.append((mask[ok] | search.bits[w], np.full(len(ok), w), value[ok] + step, ok))
    c_mask, c_last, c_value, c_parent = (np.concatenate(a) for a in zip(*parts, strict=True))
    chosen = _cheapest_per_state(c_mask, c_last, c_value, search.problem.n)
    return c_mask[chosen], c_last[chosen], c_value[chosen], c_parent[chosen]


@pytest.mark.parametrize(("n", "shuffled"), [(14, False), (14, True), (70, False), (70, True)])
def test_layer_merged_per_node_equals_one_merge_of_all_extensions(n, shuffled):
    """``grow`` (each node's extensions merged as they are made, then one sort) keeps the
    same states, values and parents, in the same order, as one merge of every extension;
    also from a layer not in mask order (a beam's) and with two-word masks."""
    from taopt.models.sop_dp import Deadline, _Search
    from taopt.sop.generate import random_sop

    problem = random_sop(n, 0.05, 3, high=5)  # costs 0-5: many equal values
    search = _Search(problem)
    layer = search.first()[:3]
    rng = np.random.default_rng(n)
    for _ in range(4):
        if shuffled:
            layer = tuple(a[rng.permutation(len(layer[0]))] for a in layer)
        got = search.grow(*layer, Deadline(None))
        want = _grown_at_once(search, *layer)
        assert got is not None and len(got[0]) > 0
        for a, b in zip(got, want, strict=True):
            assert np.array_equal(a, b)
        layer = got[:3]


@pytest.mark.parametrize("n", [20, 64, 130])
def test_open_prices_by_byte_table_equal_the_membership_product(n):
    """The completion bound's open prices read from its byte table equal the prices summed
    over the nodes each mask does not hold (one- and multi-word masks)."""
    from taopt.ideals import full, words
    from taopt.models.sop_dp import _Bound, _members

    rng = np.random.default_rng(n)
    usable = rng.integers(1, 50, (n, n)).astype(float)
    bound = _Bound(usable, 0, n - 1, (rng.normal(size=n), rng.normal(size=n)))
    mask = rng.integers(0, 2**63, (500, words(n)), dtype=np.uint64)
    mask = mask[:, 0] if words(n) == 1 else mask
    mask &= full(n)
    price = bound.beta + np.where(np.arange(n) != n - 1, bound.alpha, 0.0)
    price[0] = 0.0
    want = price.sum() - _members(mask, n).astype(float) @ price
    assert np.allclose(bound._open_prices(mask), want, rtol=0, atol=1e-9)


def test_narrow_beam_pass_runs_past_a_spent_beam_budget(monkeypatch, sop_esc25):
    """With the beam's budget spent before it starts, the first (narrowest) pass still runs
    on its share of the stage and gives the DP its order; the DP proves ESC25's optimum."""
    from taopt.models import sop_dp

    monkeypatch.setattr(sop_dp, "BEAM_SHARE", 0.0)
    monkeypatch.setattr(sop_dp, "_BEAMS", {})
    result = sop_dp.solve_sop_dp(sop_esc25, 60, beam_width=64)
    assert result.info["beam"] is not None
    assert str(result.status) == "optimal" and result.objective == 1681


@pytest.mark.parametrize(("n", "words"), [(20, 1), (62, 1), (130, 3)])
def test_block_of_a_layer_in_mask_order_merged_without_a_sort(n, words):
    """From masks in mask order (runs of equal masks, several last nodes each), the extensions
    by one node merged by their runs keep the same states and parents as the sort; the order
    check accepts sorted layers and rejects a swapped pair."""
    from taopt.ideals import bits, differs, has
    from taopt.models.sop_dp import (
        _cheapest_per_block,
        _cheapest_per_state,
        _in_mask_order,
        _state_order,
    )

    rng = np.random.default_rng(n)
    pool = rng.integers(0, 2 ** min(n, 62), (300, words), dtype=np.uint64)
    pool = pool[:, 0] if words == 1 else pool
    mask = pool[rng.integers(0, 300, 3_000)]
    last = rng.integers(0, n, 3_000)
    layer = _state_order(mask, last, n)
    mask = mask[layer]
    assert _in_mask_order(mask)
    w = n - 1
    keep = ~has(mask, w)
    block = mask[keep] | bits(n)[w]
    value = rng.integers(0, 5, len(block)).astype(float)  # many ties
    merged = _cheapest_per_block(block, value, True, n, w)
    assert np.array_equal(merged, _cheapest_per_state(block, np.full(len(block), w), value, n))
    distinct = np.flatnonzero(differs(mask))  # a pair of different masks, swapped
    swapped = mask.copy()
    i = int(distinct[len(distinct) // 2])
    swapped[[i, i + 1]] = swapped[[i + 1, i]]
    assert not _in_mask_order(swapped)


def test_completion_bound_does_not_depend_on_the_order_of_the_states():
    """The beam bounds its cut layer in mask order and puts the values back: ``totals`` of a
    shuffled layer (the states of one ideal apart) equals the layer's, shuffled."""
    from taopt.ideals import row_keys
    from taopt.models.sop_dp import Deadline, _Search
    from taopt.sop.generate import random_sop

    problem = random_sop(70, 0.3, 3)
    search = _Search(problem)
    mask, last, value, _ = search.first()
    for _ in range(6):  # a few layers deep: several last nodes per ideal
        mask, last, value, _ = search.grow(mask, last, value, Deadline(None))
    assert len(np.unique(row_keys(mask))) < len(mask)
    whole = search.totals(mask, last, value, Deadline(None))
    shuffle = np.random.default_rng(0).permutation(len(mask))
    part = search.totals(mask[shuffle], last[shuffle], value[shuffle], Deadline(None))
    assert np.array_equal(part, whole[shuffle])
