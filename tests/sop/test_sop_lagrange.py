"""The cut root's Lagrangian bound in the SOP DP and the portfolio's root stage (issue 33):
every bound at most the brute-force optimum, the same optima with the new rules on and off,
and CP-SAT stopped by the rule keeps a feasible order."""

from __future__ import annotations

import math

import numpy as np
import pytest

from taopt.models import sop as sop_model
from taopt.models import sop_cuts, sop_dp
from taopt.models.sop import solve_sop_problem
from taopt.models.sop_cuts import SopCutModel, solve_sop_cuts
from taopt.models.sop_dp import solve_sop_dp
from taopt.result import OPTIMAL
from taopt.sop.problem import SopProblem, evaluate_order
from tests.reference_exact import sop_brute_force, sop_instance, sop_orders


def _lagrange(problem: SopProblem) -> tuple[float, np.ndarray]:
    """The root loop's Lagrangian bound of ``problem``."""
    model = SopCutModel(problem)
    model.root()
    prices = model.lagrangian_prices()
    assert prices is not None
    return prices


@pytest.mark.parametrize("seed", range(20))
def test_lagrangian_bound_holds_on_every_order(seed):
    """``L + sum of max(d, 0)`` over an order's arcs is at most its cost, for every order."""
    problem = sop_instance(seed)
    constant, reduced = _lagrange(problem)
    for order in sop_orders(problem):
        arcs = reduced[order[:-1], order[1:]]
        assert np.isfinite(arcs).all()
        low = constant + np.maximum(arcs, 0.0).sum()
        assert low <= evaluate_order(problem, order) + 1e-6


@pytest.mark.parametrize("seed", range(20))
def test_dp_with_lagrange_matches_brute_force(seed):
    """The DP with the Lagrangian pruning, from a middling order, gives the brute-force
    optimum, as without it."""
    problem = sop_instance(seed)
    optimum = sop_brute_force(problem)
    lagrange = start = None
    if math.isfinite(optimum):
        lagrange = _lagrange(problem)
        orders = sorted(sop_orders(problem), key=lambda o: evaluate_order(problem, o))
        start = orders[len(orders) // 2]
    with_it = solve_sop_dp(problem, incumbent=start, lagrange=lagrange, beam_width=0)
    without = solve_sop_dp(problem, incumbent=start, beam_width=0)
    if not math.isfinite(optimum):
        assert with_it.status == without.status == "infeasible"
        return
    assert with_it.status == without.status == OPTIMAL
    assert with_it.objective == pytest.approx(optimum)
    assert without.objective == pytest.approx(optimum)
    assert evaluate_order(problem, with_it.order) == pytest.approx(optimum)


@pytest.mark.parametrize("seed", range(0, 20, 2))
def test_dp_with_lagrange_from_an_optimal_order(seed):
    """Given an optimal order, the DP with the Lagrangian pruning proves it (no false gap)."""
    problem = sop_instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    best = min(sop_orders(problem), key=lambda o: evaluate_order(problem, o))
    result = solve_sop_dp(problem, incumbent=best, lagrange=_lagrange(problem), beam_width=0)
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(optimum)
    assert result.bound == pytest.approx(optimum)


@pytest.mark.parametrize("seed", range(0, 20, 2))
def test_stopped_dp_with_lagrange_keeps_a_valid_bound(seed):
    """A DP stopped by its state cap reports a bound at most the optimum (L included)."""
    problem = sop_instance(seed)
    optimum = sop_brute_force(problem)
    if not math.isfinite(optimum):
        return
    result = solve_sop_dp(problem, max_states=1, lagrange=_lagrange(problem), beam_width=0)
    assert result.bound is not None and result.bound <= optimum + 1e-6


@pytest.mark.parametrize("seed", range(0, 30, 3))
@pytest.mark.parametrize("cuts_first", [0.0, 2.0])
@pytest.mark.parametrize("row_credit", [False, True])
def test_root_stage_either_way_matches_brute_force(monkeypatch, seed, cuts_first, row_credit):
    """The portfolio with its root stage, the cut engine first (share 0) or the DP first
    (share 2, never), with the DP's row credit on and off, gives the brute-force optimum with
    a feasible order."""
    monkeypatch.setattr(sop_model, "CUTS_FIRST_SHARE", cuts_first)
    monkeypatch.setattr(sop_model, "ROW_CREDIT", row_credit)
    problem = sop_instance(seed)
    optimum = sop_brute_force(problem)
    result = solve_sop_problem(problem, ideal_cap=1, max_states=2, cpsat=False)
    if not math.isfinite(optimum):
        assert result.status == "infeasible"
        return
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(optimum)
    assert evaluate_order(problem, result.order) == pytest.approx(optimum)
    assert result.info["root_stage"]["cuts_first"] is (cuts_first == 0.0)


@pytest.mark.parametrize("seed", range(0, 30, 5))
@pytest.mark.parametrize("heuristics", [False, True])
def test_cut_engine_with_and_without_sub_heuristics(monkeypatch, seed, heuristics):
    """The cut engine's optimum equals brute force with HiGHS's sub-MIP heuristics on or off."""
    monkeypatch.setattr(sop_cuts, "MIP_SUB_HEURISTICS", heuristics)
    problem = sop_instance(seed)
    optimum = sop_brute_force(problem)
    result = solve_sop_cuts(problem)
    if not math.isfinite(optimum):
        assert result.status == "infeasible"
        return
    assert result.status == OPTIMAL
    assert result.objective == pytest.approx(optimum)


def test_lagrange_rest_bound_keeps_the_optimum(monkeypatch):
    """With the rest-of-path bound on the reduced costs on, the DP still finds the optimum."""
    monkeypatch.setattr(sop_dp, "LAGRANGE_REST", True)
    for seed in range(0, 20, 4):
        problem = sop_instance(seed)
        optimum = sop_brute_force(problem)
        if not math.isfinite(optimum):
            continue
        result = solve_sop_dp(problem, lagrange=_lagrange(problem), beam_width=0)
        assert result.status == OPTIMAL
        assert result.objective == pytest.approx(optimum)


def test_lagrangian_pruning_fires():
    """From an optimal order the Lagrangian bound drops states on the small instances."""
    dropped = 0
    for seed in range(10):
        problem = sop_instance(seed)
        if not math.isfinite(sop_brute_force(problem)):
            continue
        best = min(sop_orders(problem), key=lambda o: evaluate_order(problem, o))
        result = solve_sop_dp(problem, incumbent=best, lagrange=_lagrange(problem), beam_width=0)
        dropped += result.info["lagrange_pruned"]
    assert dropped > 0
