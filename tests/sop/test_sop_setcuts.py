"""The set path cuts and alternation rows of the SOP cut loop (issue 33): every row found,
at LP points and at random points, holds on every feasible order of random small SOPs with
dense precedence, and the root bound with them stays at most the brute-force optimum."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from taopt.models import sop_cuts
from taopt.models.sop_cuts import SopCutModel, cut_bound
from taopt.sop.problem import SopProblem
from tests.reference_exact import sop_brute_force, sop_orders


def _ordered(seed: int, n: int = 8) -> SopProblem:
    """``n`` nodes, random integer costs, a third of the inner pairs ordered (chains
    ``i ≺ t ≺ s ≺ j`` and incomparable predecessors for the rows to use)."""
    rng = np.random.default_rng([35, seed])
    cost = rng.integers(1, 60, (n, n)).astype(float)
    np.fill_diagonal(cost, 0.0)
    pairs = [(a, b) for a, b in itertools.combinations(range(1, n - 1), 2) if rng.random() < 0.33]
    return SopProblem(cost, pairs, 0, n - 1, name=f"ordered-{seed}")


def _holds(model: SopCutModel, orders: list[list[int]]) -> None:
    """Every row of ``model`` holds on every order of ``orders``."""
    for order in orders:
        used = np.zeros(model.n_arcs)
        used[model.arc_index[order[:-1], order[1:]]] = 1.0
        for row, side in zip(model.cut_rows, model.cut_sides, strict=True):
            assert used[row].sum() >= side - 1e-9, (order, row, side)


@pytest.mark.parametrize("seed", range(16))
def test_set_rows_hold_on_every_order(seed):
    """The set path cuts and alternation rows separated at the LP points of the root loop and
    at random points hold on every feasible order."""
    problem = _ordered(seed)
    orders = list(sop_orders(problem))
    model = SopCutModel(problem)
    model.root()
    rng = np.random.default_rng(seed)
    for _ in range(6):
        point = rng.random(model.n_arcs) * rng.random()
        model.separate(point, every=True)  # the pairs' flows at the point
        model.add_cuts(*model.separate_sets(point))
    _holds(model, orders)


def test_set_rows_are_found():
    """Over the small instances, random points violate both kinds of rows (side 1 and 2)."""
    sides: set[float] = set()
    for seed in range(16):
        model = SopCutModel(_ordered(seed))
        rng = np.random.default_rng(seed)
        for _ in range(3):
            point = 0.3 * rng.random(model.n_arcs)
            model.separate(point, every=True)  # the pairs' flows at the point
            sides |= set(model.separate_sets(point)[1])
    assert sides == {1.0, 2.0}


@pytest.mark.parametrize("seed", range(16))
@pytest.mark.parametrize("set_cuts", [False, True])
def test_root_bound_with_set_rows_at_most_brute_force(monkeypatch, seed, set_cuts):
    """The root bound with and without the set rows never exceeds the brute-force optimum."""
    monkeypatch.setattr(sop_cuts, "SET_CUTS", set_cuts)
    problem = _ordered(seed)
    assert cut_bound(problem).bound <= sop_brute_force(problem) + 1e-6
