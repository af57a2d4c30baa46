"""The polish of :func:`~taopt.models.sop_cuts.round_point` (issue 33): the vectorised or-opt
search makes the very moves of the run-at-a-time search it replaced (kept here as the
reference), so its order and cost are the same on random SOPs and random orders."""

from __future__ import annotations

import numpy as np
import pytest

from taopt.models import sop_cuts
from taopt.models.sop_cuts import POLISH_PASSES, SopCutModel, polish, round_point
from taopt.sop.generate import random_sop
from taopt.sop.problem import SopProblem, evaluate_order


def _reference_polish(
    cost: np.ndarray, before: np.ndarray, order: list[int]
) -> tuple[float, list[int]]:
    """The or-opt search one run at a time (the code before the vectorised one)."""
    order = list(order)
    n = len(order)
    for _ in range(POLISH_PASSES):
        improved = False
        for length in (1, 2, 3):
            p = 1
            while p + length <= n - 1:
                run = order[p : p + length]
                rest = order[:p] + order[p + length :]
                with np.errstate(invalid="ignore"):
                    removed = (
                        cost[order[p - 1], run[0]]
                        + cost[run[-1], order[p + length]]
                        - cost[order[p - 1], order[p + length]]
                    )
                place = _reference_place(cost, before, rest, run, removed)
                if place is not None:
                    order = rest[:place] + run + rest[place:]
                    improved = True
                p += 1
        if not improved:
            break
    return float(cost[order[:-1], order[1:]].sum()), order


def _reference_place(
    cost: np.ndarray, before: np.ndarray, rest: list[int], run: list[int], removed: float
) -> int | None:
    rest_arr, run_arr = np.array(rest), np.array(run)
    preds = before[np.ix_(rest_arr, run_arr)].any(axis=1)
    succs = before[np.ix_(run_arr, rest_arr)].any(axis=0)
    lo = int(np.flatnonzero(preds).max()) + 1 if preds.any() else 1
    hi = int(np.flatnonzero(succs).min()) if succs.any() else len(rest) - 1
    if lo > hi:
        return None
    q = np.arange(max(lo, 1), hi + 1)
    added = cost[rest_arr[q - 1], run[0]] + cost[run[-1], rest_arr[q]]
    with np.errstate(invalid="ignore"):
        delta = added - cost[rest_arr[q - 1], rest_arr[q]] - removed
    delta[np.isnan(delta)] = np.inf
    best = int(np.argmin(delta))
    return int(q[best]) if delta[best] < -1e-9 else None


def _problem(seed: int) -> SopProblem:
    """A random SOP of 5-40 nodes, small integral costs (ties), some arcs forbidden."""
    rng = np.random.default_rng([44, seed])
    n = int(rng.integers(5, 41))
    base = random_sop(
        n, float(rng.choice([0.0, 0.1, 0.3, 0.6])), seed, high=int(rng.integers(3, 50))
    )
    cost = base.cost.copy()
    cost[rng.random((n, n)) < rng.choice([0.0, 0.1, 0.3])] = np.inf
    np.fill_diagonal(cost, 0.0)
    return SopProblem(cost, base.precedences, 0, n - 1)


def _random_order(model: SopCutModel, rng: np.random.Generator) -> list[int]:
    """A random order keeping the precedences (forbidden arcs allowed)."""
    problem, before = model.problem, model.before
    order, left = [problem.start], set(range(model.n)) - {problem.start, problem.end}
    while left:
        ready = [v for v in left if not any(before[u, v] for u in left)]
        order.append(int(rng.choice(ready)))
        left.remove(order[-1])
    return [*order, problem.end]


@pytest.mark.parametrize("seed", range(40))
@pytest.mark.parametrize("block", [32, 3])
def test_polish_makes_the_reference_moves(seed, block, monkeypatch):
    """From random orders, the polish returns the reference search's cost and order (a
    small block: many block ends)."""
    monkeypatch.setattr(sop_cuts, "POLISH_BLOCK", block)
    problem = _problem(seed)
    model = SopCutModel(problem)
    rng = np.random.default_rng(seed)
    for _ in range(3):
        order = _random_order(model, rng)
        value, polished = polish(model, order)
        expected, reference = _reference_polish(problem.cost, model.before, order)
        assert polished == reference
        assert value == expected or (np.isinf(value) and np.isinf(expected))


@pytest.mark.parametrize("seed", range(20))
def test_round_point_polish_matches_the_reference(seed, monkeypatch):
    """At random points, round_point's order is the reference polish of its greedy order,
    feasible and costed right."""
    problem = _problem(seed)
    model = SopCutModel(problem)
    greedy: list[list[int]] = []

    def spy(model, order, deadline=None):
        greedy.append(list(order))
        return polish(model, order, deadline)

    monkeypatch.setattr(sop_cuts, "polish", spy)
    rng = np.random.default_rng([7, seed])
    for _ in range(3):
        greedy.clear()
        rounded = round_point(model, rng.random(model.n_arcs))
        if rounded is None:
            continue
        value, order = rounded
        expected, reference = _reference_polish(problem.cost, model.before, greedy[0])
        assert order == reference
        assert value == expected or (np.isinf(value) and np.isinf(expected))
        if np.isfinite(value):
            assert evaluate_order(problem, order) == pytest.approx(value)
