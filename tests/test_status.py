"""The one status rule (taopt.status), the one Solution builder (make_solution) and the
per-class decomposition shared by chapter 3's corrected model and chapter 4's f_o."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

import taopt
import taopt.orchestration.pipeline as pipeline
from taopt.comm.problem import random_problem as comm_problem
from taopt.errors import SolverError
from taopt.models.capability import solve_capability, solve_classes
from taopt.orchestration.studies.capability_claims import random_problem as capability_problem
from taopt.result import FEASIBLE, Routes, Solution, make_solution
from taopt.status import OPTIMALITY_TOLERANCE, RAW_OUTCOMES, certify, outcome, relative_gap


def brute_force(problem: taopt.AssignmentProblem) -> float:
    """Optimum of a tiny open-routing problem by enumerating every assignment and order."""
    best = math.inf
    for owner in itertools.product(range(problem.m), repeat=problem.n):
        for order in itertools.permutations(range(problem.n)):
            routes = [[t for t in order if owner[t] == j] for j in range(problem.m)]
            best = min(best, taopt.evaluate(problem, routes))
    return best


def small_routing(seed: int, n: int = 5, m: int = 2) -> taopt.AssignmentProblem:
    """Random Euclidean open routing: n targets, m vehicles."""
    points = np.random.default_rng(seed).uniform(0, 100, size=(n + m, 2))
    cost = np.hypot(*(points[:, None, :] - points[None, :, :]).transpose(2, 0, 1))
    return taopt.AssignmentProblem(cost, n_targets=n)


# -- the status rule ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("objective", "bound", "stopped_by", "expected"),
    [
        (10.0, 10.0, "time_limit", "optimal"),
        (10.0, 10.0 * (1 - 0.5 * OPTIMALITY_TOLERANCE), "mip_gap", "optimal"),
        (10.0, 9.0, "time_limit", "time_limit"),
        (10.0, 9.0, "solver_limit", "time_limit"),
        (10.0, 9.0, "mip_gap", "feasible"),
        (10.0, None, "max_rounds", "feasible"),
        (0.0, 0.0, "mip_gap", "optimal"),
        (10.0, 11.0, "mip_gap", "optimal"),  # a bound above the objective closes the gap
    ],
)
def test_certify_closes_only_a_proven_gap(objective, bound, stopped_by, expected):
    """certify: optimal iff the relative gap is within the tolerance, else by stopped_by."""
    status, why = certify(objective, bound, stopped_by)
    assert status == expected
    assert why == ("optimal" if expected == "optimal" else stopped_by)


def test_relative_gap_edges():
    """The gap is inf without a bound or with an infinite value, 0 at 0/0."""
    assert relative_gap(5.0, None) == math.inf
    assert relative_gap(math.inf, 1.0) == math.inf
    assert relative_gap(0.0, -1.0) == math.inf
    assert relative_gap(4.0, 3.0) == pytest.approx(0.25)


@pytest.mark.parametrize("solver", sorted(RAW_OUTCOMES))
def test_outcome_maps_every_raw_status_of_every_solver(solver):
    """Each solver's claimed optimum, limit and infeasibility map to the same taopt words."""
    for raw, kind in RAW_OUTCOMES[solver].items():
        closed = outcome(solver, raw, objective=10.0, bound=10.0, time_limited=True)
        open_ = outcome(solver, raw, objective=10.0, bound=9.0, time_limited=True)
        empty = outcome(solver, raw, objective=None, bound=9.0, time_limited=False)
        if kind == "infeasible":
            assert closed == open_ == empty == ("infeasible", "infeasible")
        elif kind == "optimal":
            assert closed == ("optimal", "optimal")
            assert open_ == ("feasible", "mip_gap")  # a solver's word is not a proof
            assert empty == ("error", "error")  # an optimum without a point
        else:
            assert closed == ("optimal", "optimal")  # a limit with a closed gap proves it
            assert open_ == ("time_limit", "time_limit")
            assert empty == ("time_limit", "solver_limit")


def test_outcome_of_an_unknown_status_is_an_error():
    """An unlisted raw status (or solver) is an error, never a silent optimum."""
    assert outcome("highs", "unbounded", objective=1.0, bound=1.0) == ("error", "error")
    assert outcome("nosuch", "optimal", objective=1.0, bound=1.0) == ("error", "error")


def test_highs_model_and_cvxpy_runs_use_the_rule():
    """Both HiGHS paths give the certified optimum of a tiny MIP with a closed gap."""
    import cvxpy as cp

    from taopt.models.highs import HighsModel, solve_highs

    x = cp.Variable(2, integer=True)
    problem = cp.Problem(cp.Minimize(x.sum()), [x >= 0.5, x <= 4])
    run = solve_highs(problem)
    assert (run.status, run.objective, run.bound) == ("optimal", 2.0, 2.0)
    model_run = HighsModel(problem).solve()
    assert (model_run.status, model_run.objective) == ("optimal", 2.0)


# -- make_solution ------------------------------------------------------------------------------


def test_make_solution_scores_the_payload_once_and_marks_it():
    """The objective is evaluate(payload); the mark names this problem, not another."""
    problem, other = small_routing(1), small_routing(2)
    routes = Routes([[0, 1, 2], [3, 4]])
    solution = make_solution(problem, routes, method="x", status=FEASIBLE)
    assert solution.objective == pytest.approx(taopt.evaluate(problem, routes), rel=1e-12)
    assert solution.is_scored_for(problem) and not solution.is_scored_for(other)
    assert solution.replace(info={"a": 1}).is_scored_for(problem)  # same payload: still scored
    assert not solution.replace(objective=0.0).is_scored_for(problem)
    assert not Solution.from_dict(solution.to_dict()).is_scored_for(problem)
    assert Solution.from_dict(solution.to_dict()) == solution  # the mark is not data


def test_make_solution_certifies_from_stopped_by():
    """With stopped_by, the status is certify's on the scored objective."""
    problem = small_routing(3)
    routes = Routes([[0, 1, 2, 3, 4], []])
    value = taopt.evaluate(problem, routes)
    closed = make_solution(problem, routes, method="x", stopped_by="time_limit", bound=value)
    opened = make_solution(problem, routes, method="x", stopped_by="time_limit", bound=0.5 * value)
    assert (closed.status, closed.info["stopped_by"]) == ("optimal", "optimal")
    assert (opened.status, opened.info["stopped_by"]) == ("time_limit", "time_limit")
    assert opened.gap == pytest.approx(0.5)


def test_make_solution_refuses_ambiguous_calls():
    """Exactly one of status/stopped_by; no objective next to a payload; no payload: inf."""
    problem = small_routing(4)
    routes = Routes([[0, 1, 2, 3, 4], []])
    with pytest.raises(TypeError):
        make_solution(problem, routes, method="x")
    with pytest.raises(TypeError):
        make_solution(problem, routes, method="x", status=FEASIBLE, stopped_by="mip_gap")
    with pytest.raises(TypeError):
        make_solution(problem, routes, method="x", status=FEASIBLE, objective=1.0)
    empty = make_solution(problem, None, method="x", status="time_limit", bound=3.0)
    assert empty.objective == math.inf and empty.solution is None


def test_solve_scores_once_and_still_checks_a_hand_built_solution(monkeypatch):
    """taopt.solve skips evaluate for make_solution's result; a hand-built lie is caught."""
    problem = small_routing(5)
    calls = []
    scorer = pipeline.evaluate
    monkeypatch.setattr(pipeline, "evaluate", lambda p, s: calls.append(1) or scorer(p, s))
    result = taopt.solve(problem, "MC")
    assert calls == [] and result.objective == pytest.approx(taopt.evaluate(problem, result.routes))
    spec = pipeline.get_method(problem, "MC")
    routes = Routes([[0, 1, 2, 3, 4], []])

    def lying(p, **options):
        return Solution(objective=1.0, status=FEASIBLE, solution=routes, method="MC")

    monkeypatch.setattr(
        pipeline, "get_method", lambda p, name: dataclasses.replace(spec, func=lying)
    )
    with pytest.raises(SolverError, match="reported objective"):
        taopt.solve(problem, "MC")
    assert calls == [1]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_exact_routing_through_make_solution_equals_brute_force(seed):
    """The exact model (built by make_solution) is optimal and equals enumeration."""
    problem = small_routing(seed, n=5, m=2)
    result = taopt.solve(problem, "exact")
    assert result.status == "optimal"
    assert result.objective == pytest.approx(brute_force(problem), rel=1e-9)
    assert result.bound <= result.objective + 1e-9


# -- the shared per-class decomposition ---------------------------------------------------------


@pytest.mark.parametrize("seed", [1, 2])
def test_comm_exact_equals_the_corrected_capability_optimum(seed):
    """f_o (comm's exact) and chapter 3's corrected model agree: one decomposition."""
    problem = comm_problem(9, 4, 2, 300.0, seed=seed)
    comm = taopt.solve(problem, "exact", incumbent=None)
    corrected = solve_capability(problem.full_information(), "corrected", workers=1)
    assert comm.status == corrected.status == "optimal"
    assert comm.objective == pytest.approx(corrected.objective, rel=1e-9)
    assert comm.info["routes"] == corrected.routes
    assert comm.bound <= comm.objective + 1e-9


def test_comm_exact_with_one_attribute_equals_brute_force():
    """With one attribute f_o is chapter 2's optimum on the distances (one class)."""
    problem = comm_problem(5, 2, 1, 300.0, seed=3)
    comm = taopt.solve(problem, "exact")
    assert comm.status == "optimal" and comm.info["classes"] == 1
    assert comm.objective == pytest.approx(brute_force(problem.full_information()), rel=1e-9)


def test_solve_classes_shares_one_time_limit():
    """Under a tiny limit every class stops and the bound stays below the optimum."""
    problem = capability_problem("euclidean", 30, 6, 3, np.random.default_rng(7))
    optimum = solve_capability(problem, "corrected", workers=1)
    split = solve_classes(
        problem.classes, time_limit=0.05, start=__import__("time").perf_counter(), workers=1
    )
    assert split.bound <= optimum.objective + 1e-6
    assert len(split.per_class) == len(problem.classes)
    for row in split.per_class:
        if row["targets"]:
            assert row["status"] in ("optimal", "time_limit", "feasible")
