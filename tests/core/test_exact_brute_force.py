"""Every family's exact methods against brute force on seeded random small instances.

docs/architecture.md, invariant 4: without a time limit an exact method ends "optimal" with
the brute-force value (every instance is feasible but the budgeted family's, whose limits
may admit no assignment: then "infeasible", proven). The default run checks a few hundred
instances; the ``slow`` run checks more than 2,000 (``pytest -m slow
tests/core/test_exact_brute_force.py``). Generators favour the cases that broke the DFJ loop:
asymmetric costs, zero and equal costs, 1–7 vehicles.
"""

from __future__ import annotations

import math

import networkx as nx
import numpy as np
import pytest
from reference import BRUTE_FORCE, brute_force_routing
from reference_budgeted import brute_force_budgeted
from reference_exact import (
    budgeted_instance,
    delivery_instance,
    dp_optimum,
    exact_failures,
    routing_instance,
    sop_instance,
)

import taopt

#: The file of issue 15: DFJ ended "feasible" 4 with bound 3 (HiGHS accepted its MIP start,
#: valued in the presolved space, as optimal); the optimum is 3.
ISSUE_15 = {
    "schema_version": 1,
    "kind": "assignment_problem",
    "n_targets": 4,
    "cost": [[0, 1, 2, 1, 2], [0, 0, 0, 2, 1], [2, 2, 0, 0, 3], [0, 3, 3, 0, 3], [3, 3, 3, 3, 0]],
}


CHECKS = {check.name: check for check in BRUTE_FORCE}


def test_issue_15_file_is_optimal_three(tmp_path):
    """The issue's 4-target file: exact (DFJ) ends optimal 3, as MTZ, flow and brute force."""
    path = tmp_path / "issue15.json"
    path.write_text(__import__("json").dumps(ISSUE_15))
    problem = taopt.AssignmentProblem.load(path)
    assert brute_force_routing(problem.cost, problem.n) == 3.0
    solution = taopt.solve(problem, "exact")
    assert solution.status == "optimal", solution.summary()
    assert solution.objective == pytest.approx(3.0) and solution.bound == pytest.approx(3.0)
    assert taopt.evaluate(problem, solution.solution) == pytest.approx(3.0)


def test_issue_15_stalled_loop_falls_back_to_compact_model(monkeypatch, tmp_path):
    """With HiGHS's answers no longer checked, the stalled DFJ loop still ends optimal 3 via flow."""
    from taopt.models.highs import HighsModel

    monkeypatch.setattr(HighsModel, "_consistent", lambda self, run: True)
    # nor the rounded root point, which is the optimum here: the MIP rounds must run
    monkeypatch.setattr("taopt.models.routing.dfj.rounded_routes", lambda *args: None)
    path = tmp_path / "issue15.json"
    path.write_text(__import__("json").dumps(ISSUE_15))
    problem = taopt.AssignmentProblem.load(path)
    # without the improver: it would polish MC's start (value 4) to the optimum at once,
    # and the loop would not stall
    solution = taopt.solve(problem, "exact", improve=None)
    assert solution.info["fallback"] == "flow"
    assert solution.status == "optimal" and solution.objective == pytest.approx(3.0)
    improved = taopt.solve(problem, "exact")
    assert improved.status == "optimal" and improved.objective == pytest.approx(3.0)


def test_highs_model_rejects_start_valued_in_presolved_space(tmp_path):
    """HighsModel re-solves when HiGHS's objective is not its point's value (issue 15's MIP)."""
    from taopt.models.routing import DfjModel

    path = tmp_path / "issue15.json"
    path.write_text(__import__("json").dumps(ISSUE_15))
    problem = taopt.AssignmentProblem.load(path)
    dfj = DfjModel(problem)
    root = dfj.root()
    routes = [[0, 1, 2, 3]]  # value 4; the optimum is [1, 2, 3, 0], value 3
    core = root.reduced_costs <= 1.0 + 1e-9
    core[dfj.route_arcs(routes)] = True
    dfj.model.set_upper(dfj.arcs[~core], 0.0)
    dfj.model.set_start(dfj.start_vector(routes))
    run = dfj.model.solve(mip_rel_gap=1e-6)
    assert run.status == "optimal"
    assert run.objective == pytest.approx(dfj.model.point_objective()) == pytest.approx(3.0)


def test_highs_model_solves_again_after_a_solve_error(monkeypatch, tmp_path):
    """A MIP run that ends in a HiGHS solve error (HiGHS 1.16 after presolving a budgeted
    model of zero costs to nothing, budgeted instance 593) is run again without presolve;
    a second solve error is a SolverError, never a status."""
    import dataclasses

    from taopt.errors import SolverError
    from taopt.models import highs
    from taopt.models.routing import DfjModel

    path = tmp_path / "issue15.json"
    path.write_text(__import__("json").dumps(ISSUE_15))
    dfj = DfjModel(taopt.AssignmentProblem.load(path))
    real = highs._highs_run
    failing = {"left": 1}

    def first_fails(highs_, is_mip, time_limit):
        run = real(highs_, is_mip, time_limit)
        if failing["left"] > 0:
            failing["left"] -= 1
            return dataclasses.replace(run, solver_status="solver_error", message="kSolveError")
        return run

    monkeypatch.setattr(highs, "_highs_run", first_fails)
    run = dfj.model.solve(mip_rel_gap=1e-6)
    assert dfj.model.reruns == 1 and run.solver_status == "optimal"
    failing["left"] = 2
    with pytest.raises(SolverError, match="also without presolve"):
        dfj.model.solve(mip_rel_gap=1e-6)


@pytest.mark.parametrize("family", sorted(CHECKS))
def test_exact_equals_brute_force(family):
    """Exact method of each family: optimal with the brute-force value on every instance."""
    check = CHECKS[family]
    failures = exact_failures(check.cases(range(check.fast)), check.method)
    assert not failures, f"{len(failures)} of {check.fast}:\n" + "\n".join(failures[:10])


@pytest.mark.slow
@pytest.mark.parametrize("family", sorted(CHECKS))
def test_exact_equals_brute_force_on_two_thousand(family):
    """The same on 2,670 more instances in all (seeds after the default run's)."""
    check = CHECKS[family]
    failures = exact_failures(check.cases(range(check.fast, check.fast + check.slow)), check.method)
    assert not failures, f"{len(failures)} of {check.slow}:\n" + "\n".join(failures[:10])


def test_generators_cover_the_hard_cases():
    """Routing instances include 1 and 7 vehicles, zero costs and ties; SOP has precedences."""
    problems = [routing_instance(s) for s in range(CHECKS["routing"].fast)]
    assert {1, 7} <= {p.m for p in problems}
    assert any((p.cost == 0).sum() > len(p.cost) for p in problems)
    assert any(len(np.unique(p.cost)) <= 4 for p in problems)
    assert any(sop_instance(s).precedences for s in range(10))
    assert nx.is_directed_acyclic_graph(delivery_instance(0, 5).precedence_graph)
    budgeted = [budgeted_instance(s) for s in range(CHECKS["budgeted"].fast)]
    optima = [brute_force_budgeted(p) for p in budgeted]
    assert any(math.isinf(o) for o in optima)  # no assignment within the limits
    assert any(  # a limit binds: the optimum is above the unlimited one
        math.isfinite(o) and o > dp_optimum(p.routing) + 1e-9
        for p, o in zip(budgeted, optima, strict=True)
    )


def test_study_flags_uncertified_exact_rows(caplog):
    """The study runner warns about an exact row neither optimal nor infeasible without a limit."""
    from taopt.orchestration.studies.drift import SPEC as spec
    from taopt.orchestration.study import _flag_uncertified

    key = {c: 1 for c in spec.key_columns}
    rows = [
        {**key, "method": "exact", "status": "feasible"},
        {**key, "method": "exact", "status": "optimal"},
        {**key, "method": "MC", "status": "feasible"},
    ]
    with caplog.at_level("WARNING", logger="taopt"):
        _flag_uncertified(spec, rows, {"exact"}, None)
    assert len(caplog.records) == 1 and "'feasible'" in caplog.records[0].getMessage()
    caplog.clear()
    with caplog.at_level("WARNING", logger="taopt"):
        _flag_uncertified(spec, rows, {"exact"}, 5.0)  # a limit may stop an exact method
    assert not caplog.records
