"""Lifted precedence path cuts and reduced-cost fixing in the SOP cut engine (issue 33):
each lifted row holds on every feasible order, fixing keeps every order better than the
incumbent, and the engine still equals brute force on denser precedences."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest

from taopt.models.sop_cuts import SopCutModel, solve_sop_cuts
from taopt.result import OPTIMAL
from taopt.sop.generate import random_sop
from taopt.sop.problem import SopProblem, evaluate_order


def _problem(seed: int, scale: float = 1.0) -> SopProblem:
    """A random SOP of 6-9 nodes with dense precedences (liftings have work to do)."""
    n = 6 + seed % 4
    problem = random_sop(n, 0.3 + 0.1 * (seed % 3), seed)
    if scale != 1.0:
        problem = SopProblem(problem.cost * scale, problem.precedences, 0, n - 1)
    return problem


def _orders(problem: SopProblem) -> list[list[int]]:
    """Every feasible order (start and end fixed, usable arcs)."""
    inner = [v for v in range(problem.n) if v not in (problem.start, problem.end)]
    found = []
    for perm in itertools.permutations(inner):
        order = [problem.start, *perm, problem.end]
        where = {v: k for k, v in enumerate(order)}
        if (
            all(where[a] < where[b] for a, b in problem.closure.edges())
            and np.isfinite(problem.cost[order[:-1], order[1:]]).all()
        ):
            found.append(order)
    return found


def _incidence(model: SopCutModel, orders: list[list[int]]) -> np.ndarray:
    """One row per order: its arcs' indicator."""
    used = np.zeros((len(orders), model.n_arcs))
    for k, order in enumerate(orders):
        used[k, model.arc_index[order[:-1], order[1:]]] = 1.0
    return used


@pytest.mark.parametrize("seed", range(10))
def test_lifted_rows_hold_on_every_feasible_order(seed):
    """Both liftings of every pair's path cut, on random sides of W(i, j), hold on every order."""
    problem = _problem(seed)
    model = SopCutModel(problem)
    used = _incidence(model, _orders(problem))
    rng = np.random.default_rng(seed)
    before = model.before
    for i, j in model.pairs:
        inside = ~before[:, i] & ~before[j, :]
        for _ in range(6):
            source = inside & (rng.random(model.n) < 0.5)
            source[i], source[j] = True, False
            sink = inside & ~source
            for tails, heads in model.lifted(int(i), int(j), source, sink):
                row = np.flatnonzero(tails[model.tails] & heads[model.heads])
                assert (used[:, row].sum(axis=1) >= 1).all(), (i, j, source, tails, heads)


@pytest.mark.parametrize("seed", range(10))
def test_separated_rows_hold_at_random_points(seed):
    """Rows separated (lifted) at random fractional points hold on every feasible order."""
    problem = _problem(seed)
    model = SopCutModel(problem)
    used = _incidence(model, _orders(problem))
    rng = np.random.default_rng(seed)
    for _ in range(8):
        for row in model.separate(rng.random(model.n_arcs) * 0.6, every=True):
            assert (used[:, row].sum(axis=1) >= 1).all()


@pytest.mark.parametrize(
    ("seed", "scale"), [(s, 1.0) for s in range(6)] + [(6, 0.37), (7, 0.37), (8, 5.0), (9, 5.0)]
)
def test_fixing_keeps_every_better_order(seed, scale):
    """After reduced-cost fixing against optimum + slack, no order cheaper than the
    incumbent (integral costs: by 1 at least) uses a fixed arc."""
    problem = _problem(seed, scale)
    orders = _orders(problem)
    values = np.array([problem.cost[o[:-1], o[1:]].sum() for o in orders])
    model = SopCutModel(problem)
    model.root()
    incumbent = float(values.min()) + 3 * scale
    model.fix_by_reduced_cost(incumbent)
    used = _incidence(model, orders)
    better = values <= (incumbent - 1 if model.integral_costs else incumbent)
    assert not used[better][:, model.fixed].any()


@pytest.mark.parametrize(
    ("seed", "scale"), [(s, 1.0) for s in range(12)] + [(s, 5.0) for s in range(4)] + [(4, 0.37)]
)
def test_engine_matches_brute_force_dense(seed, scale):
    """The engine (lifting, fixing, bounds rounded to the costs' gcd) proves the brute-force
    optimum, its order feasible."""
    problem = _problem(seed, scale)
    orders = _orders(problem)
    optimum = min((float(problem.cost[o[:-1], o[1:]].sum()) for o in orders), default=math.inf)
    result = solve_sop_cuts(problem)
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(optimum)
    assert evaluate_order(problem, result.order) == pytest.approx(optimum)
    assert result.bound <= optimum + 1e-6


def test_cost_step_is_the_gcd():
    """Costs all multiples of 5 give bounds rounded up to multiples of 5; fractional costs none."""
    problem = _problem(1, 5.0)
    model = SopCutModel(problem)
    assert model.step == 5
    assert model.round_up(12.3) == 15.0
    assert SopCutModel(_problem(1, 0.37)).round_up(12.3) == 12.3


@pytest.mark.parametrize("seed", range(8))
def test_pool_rows_keep_the_dual_bound_a_bound(seed):
    """General rows (2-cycle rows ``x_uv + x_vu <= 1``, as HiGHS's pool gives them) in the
    model: the Lagrangian bound prices their upper side, equals the LP value rounded up, and
    stays at most the brute-force optimum."""
    problem = _problem(seed)
    orders = _orders(problem)
    optimum = min(float(problem.cost[o[:-1], o[1:]].sum()) for o in orders)
    model = SopCutModel(problem)
    model.root()
    pairs = [
        (model.arc_index[u, v], model.arc_index[v, u])
        for u in range(model.n)
        for v in range(u + 1, model.n)
        if model.arc_index[u, v] >= 0 and model.arc_index[v, u] >= 0
    ]
    index = np.array(pairs, dtype=np.int32).ravel()
    starts = np.arange(0, len(index) + 1, 2, dtype=np.int32)
    added = model.add_pool_rows(
        starts, index, np.ones(len(index)), np.full(len(pairs), -np.inf), np.ones(len(pairs))
    )
    assert added == len(pairs)
    assert (
        model.add_pool_rows(
            starts, index, np.ones(len(index)), np.full(len(pairs), -np.inf), np.ones(len(pairs))
        )
        == 0
    )  # kept once
    root = model.root()
    assert root.bound <= optimum + 1e-6
    assert root.bound == pytest.approx(model.round_up(root.value))


def _shared_file(name: str) -> Path | None:
    """A TSPLIB file of ``shared/benchmarks/tsplib`` beside or above the checkout, if any."""
    for up in Path(__file__).resolve().parents:
        path = up / "shared" / "benchmarks" / "tsplib" / name
        if path.is_file():
            return path
    return None


@pytest.mark.slow
def test_p43_1_closed():
    """p43.1 (TSPLIB, optimum 28140) is proven optimal by the cut engine."""
    path = _shared_file("p43.1.sop")
    if path is None:
        pytest.skip("p43.1.sop is not beside the checkout (shared/benchmarks/tsplib)")
    problem = SopProblem.load(path)
    result = solve_sop_cuts(problem, time_limit=300)
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(28140)
    assert evaluate_order(problem, result.order) == pytest.approx(28140)
