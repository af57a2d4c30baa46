"""Stretch-partition rows (taopt.models.sop_stretch): every row holds on every feasible order
of small random SOPs (sparse and dense precedence, rows found at LP points of random costs),
and the root bound with them never exceeds the brute-force optimum."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from taopt.models import sop_cuts
from taopt.models.sop_cuts import SopCutModel, solve_sop_cuts
from taopt.models.sop_stretch import stretch_domains, stretch_rows
from taopt.result import OPTIMAL
from taopt.sop.problem import SopProblem, evaluate_order
from tests.reference_exact import sop_brute_force, sop_orders


def _instance(seed: int, density: float) -> SopProblem:
    """6-8 nodes, start 0, end n - 1, integral or real costs, inner precedence pairs drawn
    with probability ``density`` (at least one)."""
    rng = np.random.default_rng([40, seed, int(density * 100)])
    n = int(rng.integers(6, 9))
    cost = rng.uniform(0.0, 100.0, (n, n))
    if seed % 2:
        cost = np.round(cost / 10.0)
    inner = range(1, n - 1)
    pairs = [(a, b) for a, b in itertools.combinations(inner, 2) if rng.random() < density]
    if not pairs:
        pairs = [(1, n - 2)]
    order = rng.permutation(n - 2) + 1  # precedences along a random order of the inner nodes
    rank = {int(v): k for k, v in enumerate(order)}
    pairs = [(a, b) if rank[a] < rank[b] else (b, a) for a, b in pairs]
    return SopProblem(cost, pairs, 0, n - 1, name=f"stretch-{seed}")


def _used(model: SopCutModel, order: list[int]) -> np.ndarray:
    used = np.zeros(model.n_arcs)
    used[model.arc_index[order[:-1], order[1:]]] = 1.0
    return used


@pytest.mark.parametrize("density", [0.15, 0.5])
@pytest.mark.parametrize("seed", range(12))
def test_stretch_rows_hold_on_every_feasible_order(seed, density):
    """Rows of the extended LP at the LP points of several random objectives hold on every
    feasible order (their proof: each order splits into the three stretches of a pair)."""
    problem = _instance(seed, density)
    model = SopCutModel(problem)
    rng = np.random.default_rng(seed)
    orders = list(sop_orders(problem))
    rows = []
    for _ in range(4):
        costs = rng.uniform(0.0, 10.0, model.n_arcs)
        model.costs = costs
        model.highs.changeColsCost(model.n_arcs, np.arange(model.n_arcs, dtype=np.int32), costs)
        model.highs.run()
        rows += stretch_rows(model, model.highs.getInfo().objective_function_value) or []
    for order in orders:
        used = _used(model, order)
        for arcs, weights, side in rows:
            assert used[arcs] @ weights >= side - 1e-9, (order, arcs, weights, side)


def test_stretch_rows_are_found():
    """Over the random instances above some stretch rows are violated (the test above is not
    empty), and each separated row is violated at the point it was found at."""
    found = 0
    for seed in range(12):
        problem = _instance(seed, 0.15)
        model = SopCutModel(problem)
        model.highs.run()
        x = model.lp_values()
        rows = stretch_rows(model, model.highs.getInfo().objective_function_value) or []
        for arcs, weights, side in rows:
            assert x[arcs] @ weights < side
            found += 1
    assert found > 0


@pytest.mark.parametrize("density", [0.15, 0.5])
@pytest.mark.parametrize("seed", range(15))
def test_root_with_stretch_rows_at_most_brute_force(seed, density):
    """The root bound with the stretch rows never exceeds the brute-force optimum, nor falls
    below the bound without them."""
    problem = _instance(seed, density)
    optimum = sop_brute_force(problem)
    model = SopCutModel(problem)
    root = model.root(stretch=True)
    assert root.bound <= optimum + 1e-6
    plain = SopCutModel(problem).root()
    assert root.value >= plain.value - 1e-6


def test_every_order_lies_in_its_stretches():
    """Each arc of each feasible order lies in the domain of the stretch it belongs to."""
    problem = _instance(3, 0.5)
    model = SopCutModel(problem)
    inner = [(int(i), int(j)) for i, j in model.pairs if i != 0 and j != problem.end]
    for order in sop_orders(problem):
        where = {v: k for k, v in enumerate(order)}
        for i, j in inner:
            domains = stretch_domains(model, i, j)
            for u, v in itertools.pairwise(order):
                arc = model.arc_index[u, v]
                k = 0 if where[v] <= where[i] else (1 if where[v] <= where[j] else 2)
                assert domains[k][0][arc], (order, i, j, u, v)


@pytest.mark.parametrize("density", [0.15, 0.5])
@pytest.mark.parametrize("seed", range(10))
def test_cut_engine_with_stretch_rows_matches_brute_force(seed, density):
    """The cut engine (stretch rows on) returns the brute-force optimum, proven, with an order
    of that cost."""
    problem = _instance(seed, density)
    optimum = sop_brute_force(problem)
    result = solve_sop_cuts(problem)
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(optimum)
    assert evaluate_order(problem, result.order) == pytest.approx(optimum)


@pytest.mark.parametrize("back_to_back", [False, True])
def test_extended_lps_per_root_loop(back_to_back, monkeypatch):
    """``STRETCH_BACK_TO_BACK`` off: a root loop starts one extended LP at most, the model's
    second waits for the next loop; on: both in the first loop (an extended LP that always
    finds rows stands in for the real one, whose rows the tiny SOPs' cut loop leaves none)."""
    monkeypatch.setattr(sop_cuts, "STRETCH_BACK_TO_BACK", back_to_back)

    def always(self, value, deadline):
        if self.stretch_solves >= sop_cuts.STRETCH_ROUNDS:
            return False
        self.stretch_solves += 1
        return True

    monkeypatch.setattr(SopCutModel, "_stretch", always)
    model = SopCutModel(_instance(1, 0.5))
    model.root(stretch=True)
    assert model.stretch_solves == (2 if back_to_back else 1)
    model.root(stretch=True)
    assert model.stretch_solves == 2
