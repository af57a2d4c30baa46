"""The SOP portfolio's resources: the memory ladder (degrade, never refuse) and the time left
used (issue 33, item 3)."""

from __future__ import annotations

import numpy as np
import pytest
from reference_exact import sop_brute_force

import taopt
from taopt.models.sop import BASE_BYTES, beam_bytes, dp_bytes, solve_sop_problem
from taopt.models.sop_dp import solve_sop_dp
from taopt.models.sop_stages import (
    MIN_BEAM_WIDTH,
    MIN_DP_STATES,
    beam_width_cap,
    memory_plan,
    use_the_rest,
)
from taopt.result import TIME_LIMIT
from taopt.runtime import Deadline
from taopt.sop.generate import random_sop
from taopt.sop.problem import evaluate_order


def limit_for(plan: str, n: int) -> float:
    """A memory limit (GB) at which :func:`memory_plan` picks ``plan`` on ``n`` nodes."""
    if plan == "dp":
        return (BASE_BYTES + dp_bytes(n, MIN_DP_STATES)) / 1e9
    if plan == "beam":
        return (BASE_BYTES + beam_bytes(n, 4 * MIN_BEAM_WIDTH)) / 1e9
    return BASE_BYTES / 2e9


@pytest.mark.parametrize("plan", ["dp", "beam", "bound"])
def test_memory_plan_picks_the_strongest_stage_that_fits(plan):
    """Lowering the limit walks the ladder DP -> beam -> bound, never an error."""
    assert memory_plan(30, limit_for(plan, 30)) == plan
    assert memory_plan(300, 4.0) == "dp"


@pytest.mark.parametrize("plan", ["dp", "beam", "bound"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_each_degraded_stage_returns_a_feasible_order_and_a_valid_bound(plan, seed):
    """At a memory limit too low for the stronger stages, taopt.solve returns a feasible
    order and a bound <= the brute-force optimum (no InstanceError for size)."""
    problem = random_sop(9, 0.15, seed)
    optimum = sop_brute_force(problem)
    result = taopt.solve(problem, "exact", time_limit=20.0, max_memory_gb=limit_for(plan, 9))
    assert result.info["memory_plan"] == plan
    assert str(result.status) in ("time_limit", "optimal")
    assert evaluate_order(problem, result.order) == result.objective >= optimum - 1e-9
    assert result.bound <= optimum + 1e-9
    if str(result.status) == "optimal":
        assert result.objective == pytest.approx(optimum)


def test_the_memory_limit_is_read_from_the_environment(monkeypatch):
    """TAOPT_MAX_MEMORY_GB sets the guard's limit: below the process's base only the bound
    stage runs, and the answer is still a feasible order with a valid bound."""
    problem = random_sop(9, 0.1, 4)
    monkeypatch.setenv("TAOPT_MAX_MEMORY_GB", f"{BASE_BYTES / 2e9:g}")
    result = taopt.solve(problem, "exact", time_limit=20.0)
    assert result.info["memory_plan"] == "bound"
    assert evaluate_order(problem, result.order) == result.objective
    assert result.bound <= sop_brute_force(problem) + 1e-9


@pytest.mark.slow
def test_the_rest_of_the_limit_grows_the_dp_then_widens_the_beam():
    """A run whose DP stopped at its state cap goes on with larger caps while they fit the
    memory, then wider beams up to the widest that fits: never a worse order, never a
    lower bound, and the stages stop at the memory caps (the deadline is not reached)."""
    problem = random_sop(30, 0.05, 1)
    gb = (BASE_BYTES + dp_bytes(30, 12_000)) / 1e9
    first = solve_sop_dp(problem, max_states=3_000, beam_width=64)
    assert first.status == TIME_LIMIT and first.info["stopped_by"] == "max_states"
    rest = use_the_rest(problem, first, Deadline(600.0), 3_000, gb, 0.0)
    steps = rest.info["rest"]
    assert steps[:2] == ["dp 6,000 states", "dp 12,000 states"]
    assert steps[-1] == f"beam {beam_width_cap(30, gb):,}"
    assert rest.objective <= first.objective and rest.bound >= first.bound
    assert evaluate_order(problem, rest.order) == rest.objective
    assert rest.bound <= rest.objective


def test_the_estimate_of_the_stages_run_is_recorded():
    """The portfolio records the estimated peak of the stages it ran (at least the base)."""
    result = solve_sop_problem(random_sop(12, 0.2, 0), time_limit=30.0)
    assert result.info["memory_estimate"] >= BASE_BYTES
    assert np.isfinite(result.info["memory_estimate"])
