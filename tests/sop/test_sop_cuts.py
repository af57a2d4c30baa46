"""Precedence path cuts and the cut engine (issue 33 items 2 and 4): every bound below the
brute-force optimum, every row valid on every feasible order, every order feasible, and an
optimum claimed only when it is the brute-force one."""

from __future__ import annotations

import math

import numpy as np
import pytest

from taopt.models.sop import solve_sop_problem
from taopt.models.sop_cuts import SopCutModel, cut_bound, polish, round_point, solve_sop_cuts
from taopt.result import OPTIMAL, TIME_LIMIT
from taopt.sop.problem import SopProblem, evaluate_order, load_sop
from tests.reference_exact import assert_rows_hold, sop_brute_force, sop_instance


@pytest.mark.parametrize("seed", range(30))
def test_root_bound_at_most_brute_force(seed):
    """The root bound of the cut loop never exceeds the brute-force optimum."""
    problem = sop_instance(seed)
    optimum = sop_brute_force(problem)
    root = cut_bound(problem)
    assert root.bound <= optimum + 1e-6


@pytest.mark.parametrize("seed", range(30))
def test_cut_engine_matches_brute_force(seed):
    """The cut engine's optimum equals brute force; its order is feasible and so scored."""
    problem = sop_instance(seed)
    optimum = sop_brute_force(problem)
    result = solve_sop_cuts(problem)
    if not math.isfinite(optimum):
        assert result.status == "infeasible"
        return
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(optimum)
    assert evaluate_order(problem, result.order) == pytest.approx(optimum)


@pytest.mark.parametrize("seed", range(12))
def test_every_row_holds_on_every_feasible_order(seed):
    """Each separated row (sum of its arcs >= its side) holds on every feasible order."""
    problem = sop_instance(seed)
    model = SopCutModel(problem)
    model.root()
    rng = np.random.default_rng(seed)
    for _ in range(5):  # rows separated at random points too, not only LP optima
        point = rng.random(model.n_arcs)
        model.add_cuts(model.separate(point))
    assert_rows_hold(model, problem)


def test_integral_non_order_is_cut():
    """An integral point of two subpaths (no order) violates a separated row."""
    cost = np.ones((5, 5))
    problem = SopProblem(cost, [], 0, 4)
    model = SopCutModel(problem)
    point = np.zeros(model.n_arcs)
    assert (model.arc_index[[0, 1, 2, 3], [1, 4, 3, 2]] >= 0).all()
    for i, j in [(0, 1), (1, 4), (2, 3), (3, 2)]:  # start -> 1 -> end plus a cycle 2-3
        point[model.arc_index[i, j]] = 1.0
    cuts = model.separate(point)
    assert cuts and all(point[cut].sum() < 1 for cut in cuts)


def test_rounding_gives_a_feasible_order():
    """An order rounded from the root LP and polished is feasible and costed right."""
    problem = _esc12()
    model = SopCutModel(problem)
    root = model.root()
    value, order = round_point(model, root.values)
    assert evaluate_order(problem, order) == pytest.approx(value)
    again, _ = polish(model, order)
    assert again <= value


def _esc12() -> SopProblem:
    cost, precedences, start, end, name = load_sop("ESC12")
    return SopProblem(cost, precedences, start, end, name=name)


def test_esc12_closed_by_cuts():
    """ESC12 (optimum 1675, TSPLIB) is proven optimal by the cut engine."""
    result = solve_sop_cuts(_esc12())
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(1675)


def test_time_limited_run_keeps_a_proven_bound():
    """A run out of time reports time_limit (or optimal), an order if any, a bound <= 1675."""
    result = solve_sop_cuts(_esc12(), time_limit=1e-3)
    assert result.status in (TIME_LIMIT, OPTIMAL)
    assert result.bound is None or result.bound <= 1675 + 1e-6


@pytest.mark.parametrize("seed", range(0, 30, 3))
def test_portfolio_cut_stage_matches_brute_force(seed):
    """The portfolio's MILP stage (now the cut engine), forced and after a capped DP, gives
    the brute-force optimum and never a false optimal."""
    problem = sop_instance(seed)
    optimum = sop_brute_force(problem)
    for options in ({"engine": "milp"}, {"ideal_cap": 1, "max_states": 1}):
        result = solve_sop_problem(problem, **options)
        if not math.isfinite(optimum):
            assert result.status == "infeasible"
            continue
        assert result.status == OPTIMAL, options
        assert result.objective == pytest.approx(optimum)
        assert evaluate_order(problem, result.order) == pytest.approx(optimum)


def test_optimal_incumbent_is_certified_by_the_cutoff():
    """Given an optimal order of ESC12 (integral costs), the cut engine proves it optimal."""
    problem = _esc12()
    first = solve_sop_cuts(problem)
    again = solve_sop_cuts(problem, incumbent=first.order)
    assert again.status == OPTIMAL
    assert again.objective == pytest.approx(1675)
    assert again.bound == pytest.approx(1675)


def _reached(graph, flow, source):
    """The nodes reached from ``source`` in the residual graph of ``flow`` (the reference)."""
    residual = graph.toarray() - flow.toarray() > 0
    reached = np.zeros(graph.shape[0], dtype=bool)
    reached[source] = True
    frontier = reached.copy()
    while frontier.any():
        frontier = residual[frontier].any(axis=0) & ~reached
        reached |= frontier
    return reached


@pytest.mark.parametrize("seed", range(8))
def test_copy_flows_equal_one_flow_per_copy(seed):
    """The batched maximum flows of ``copy_flows`` (``pair_flows``: one source and one sink)
    equal scipy's maximum flow of each copy's own subgraph, from a super source to a super
    sink joined to its 1-2 sources and sinks (capped at FLOW_CAP units), and where below the
    cap the source sides equal the nodes reached from the sources in that flow's residual
    graph, on random fractional points of random SOPs (some copies without arcs)."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import maximum_flow

    from taopt.models.sop_cuts import FLOW_CAP, FLOW_SCALE, copy_flows, pair_flows

    rng = np.random.default_rng([42, seed])
    model = SopCutModel(sop_instance(seed))
    n = model.n
    values = rng.random(model.n_arcs) * (rng.random(model.n_arcs) < 0.4)
    support = values > 1e-9
    tails, heads = model.tails[support], model.heads[support]
    caps = np.floor(values[support] * FLOW_SCALE * rng.integers(1, 5)).astype(np.int32)
    count = 30
    ends = [[rng.choice(n, size=rng.integers(1, 3), replace=False) for _ in range(count)]]
    ends.append([rng.choice(np.setdiff1d(range(n), xs), size=len(xs) % 2 + 1) for xs in ends[0]])
    inside = rng.random((count, n)) < 0.8
    for k in range(count):
        inside[k, np.concatenate([ends[0][k], ends[1][k]])] = True
    single = np.array([len(xs) == 1 == len(ys) for xs, ys in zip(*ends, strict=True)])
    pairs = np.array([[xs[0], ys[0]] for xs, ys in zip(*ends, strict=True)])[single]
    runs = [
        (pair_flows(n, tails, heads, caps, pairs, inside[single]), np.flatnonzero(single)),
        (
            copy_flows(
                n,
                tails,
                heads,
                caps,
                inside,
                *[
                    (np.repeat(np.arange(count), [len(e) for e in side]), np.concatenate(side))
                    for side in ends
                ],
            ),
            np.arange(count),
        ),
    ]
    for (flows, sides), copies in runs:
        for at, k in enumerate(copies):
            keep = inside[k][tails] & inside[k][heads]
            xs, ys = ends[0][k], ends[1][k]
            big = np.full(len(xs) + len(ys), 10 * FLOW_SCALE)
            graph = sp.csr_matrix(
                (
                    np.concatenate([caps[keep], big]),
                    (
                        np.concatenate([tails[keep], np.full(len(xs), n), ys]),
                        np.concatenate([heads[keep], xs, np.full(len(ys), n + 1)]),
                    ),
                ),
                shape=(n + 2, n + 2),
            )
            graph.sum_duplicates()
            result = maximum_flow(graph, n, n + 1)
            assert min(flows[at], FLOW_CAP * FLOW_SCALE) == min(
                result.flow_value, FLOW_CAP * FLOW_SCALE
            )
            if flows[at] < FLOW_CAP * FLOW_SCALE:
                assert np.array_equal(sides[at], _reached(graph, result.flow, n)[:n])
