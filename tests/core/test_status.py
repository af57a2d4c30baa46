"""The one status rule (taopt.status.decide), the one path from a stop to a Solution
(taopt.result.finish), the Solution builder (make_solution) and the per-class decomposition shared by chapter 3's corrected model and chapter 4's f_o."""

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
from taopt.result import FEASIBLE, Routes, Solution, finish, make_solution
from taopt.status import OPTIMALITY_TOLERANCE, RAW_OUTCOMES, STOPS, decide, relative_gap


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
def test_decide_closes_only_a_proven_gap(objective, bound, stopped_by, expected):
    """decide: optimal iff the relative gap is within the tolerance, else by the stop."""
    status, why = decide(stopped_by, objective, bound)
    assert status == expected
    assert why == ("optimal" if expected == "optimal" else stopped_by)


def test_relative_gap_edges():
    """The gap is inf without a bound or with an infinite value, 0 at 0/0."""
    assert relative_gap(5.0, None) == math.inf
    assert relative_gap(math.inf, 1.0) == math.inf
    assert relative_gap(0.0, -1.0) == math.inf
    assert relative_gap(4.0, 3.0) == pytest.approx(0.25)


@pytest.mark.parametrize("solver", sorted(RAW_OUTCOMES))
def test_decide_maps_every_raw_status_of_every_solver(solver):
    """Each solver's claimed optimum, limit and infeasibility map to the same taopt words."""
    for raw, kind in RAW_OUTCOMES[solver].items():
        closed = decide(raw, 10.0, 10.0, solver=solver, time_limited=True)
        open_ = decide(raw, 10.0, 9.0, solver=solver, time_limited=True)
        empty = decide(raw, None, 9.0, solver=solver, time_limited=False)
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


def test_decide_of_an_unknown_status_is_an_error():
    """An unlisted raw status (or solver) is an error, never a silent optimum."""
    assert decide("unbounded", 1.0, 1.0, solver="highs") == ("error", "error")
    assert decide("optimal", 1.0, 1.0, solver="nosuch") == ("error", "error")


@pytest.mark.parametrize("stop", STOPS)
def test_decide_reads_every_stop(stop):
    """Every stop word: a proof or error is itself; a closed gap is optimal; an open gap is
    time_limit after a limit or an interrupt and feasible after any other stopping rule."""
    closed, open_ = decide(stop, 10.0, 10.0), decide(stop, 10.0, 9.0)
    if stop in ("infeasible", "error"):
        assert closed == open_ == (stop, stop)
        return
    assert closed == ("optimal", "optimal")
    limited = stop in ("time_limit", "solver_limit", "max_states", "size", "interrupted")
    assert open_ == ("time_limit" if limited else "feasible", stop)
    assert decide(stop, None, 9.0)[0] == ("time_limit" if limited else "feasible")


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


def test_finish_decides_the_status_on_the_scored_objective():
    """finish: the status is decide's on the scored objective, the bound capped at it, and
    info["stopped_by"] says why; no incumbent is objective inf with the bound kept."""
    problem = small_routing(3)
    routes = Routes([[0, 1, 2, 3, 4], []])
    value = taopt.evaluate(problem, routes)
    closed = finish(problem, routes, method="x", stop="time_limit", bound=2 * value)
    opened = finish(problem, routes, method="x", stop="time_limit", bound=0.5 * value)
    assert (closed.status, closed.info["stopped_by"], closed.bound) == ("optimal", "optimal", value)
    assert (opened.status, opened.info["stopped_by"]) == ("time_limit", "time_limit")
    assert opened.gap == pytest.approx(0.5) and opened.is_scored_for(problem)
    empty = finish(problem, None, method="x", stop="interrupted", bound=3.0)
    assert (empty.status, empty.objective, empty.bound) == ("time_limit", math.inf, 3.0)
    proof = finish(problem, None, method="x", stop="infeasible", bound=math.inf)
    assert (proof.status, proof.info["stopped_by"]) == ("infeasible", "infeasible")
    raw = finish(problem, routes, method="x", stop="FEASIBLE", solver="cpsat", bound=value)
    assert raw.status == "optimal"  # a raw limit whose gap is closed proves the optimum


def test_make_solution_refuses_ambiguous_calls():
    """A status is required; no objective next to a payload; no payload: inf."""
    problem = small_routing(4)
    routes = Routes([[0, 1, 2, 3, 4], []])
    with pytest.raises(TypeError):
        make_solution(problem, routes, method="x")  # type: ignore[call-arg]
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
