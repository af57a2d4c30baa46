"""Every family's exact methods against brute force on seeded random small instances.

docs/architecture.md, invariant 4: without a time limit an exact method ends "optimal" with
the brute-force value (every instance is feasible but the budgeted family's, whose limits
may admit no assignment: then "infeasible", proven). The default run checks a few hundred
instances; the ``slow`` run checks more than 2,000 (``pytest -m slow
tests/test_exact_brute_force.py``). Generators favour the cases that broke the DFJ loop:
asymmetric costs, zero and equal costs, 1–7 vehicles.
"""

from __future__ import annotations

import itertools
import math

import networkx as nx
import numpy as np
import pytest
from reference import BRUTE_FORCE, brute_force, brute_force_delivery, brute_force_routing
from reference_budgeted import brute_force_budgeted
from test_models_routing import dp_optimum

import taopt
from taopt.budgeted import BudgetedProblem
from taopt.comm.problem import random_problem

REL = 1e-6

#: The file of issue 15: DFJ ended "feasible" 4 with bound 3 (HiGHS accepted its MIP start,
#: valued in the presolved space, as optimal); the optimum is 3.
ISSUE_15 = {
    "schema_version": 1,
    "kind": "assignment_problem",
    "n_targets": 4,
    "cost": [[0, 1, 2, 1, 2], [0, 0, 0, 2, 1], [2, 2, 0, 0, 3], [0, 3, 3, 0, 3], [3, 3, 3, 3, 0]],
}


# ----------------------------------------------------------------------- generators
def _costs(rng: np.random.Generator, size: int, kind: int) -> np.ndarray:
    """Asymmetric costs: uniform reals, small integers (many ties), or 0/1 (many zeros)."""
    if kind == 0:
        return rng.uniform(0.0, 100.0, size=(size, size))
    if kind == 1:
        return rng.integers(0, 4, size=(size, size)).astype(float)
    return np.where(rng.random((size, size)) < 0.5, 0.0, 1.0)


def routing_instance(seed: int) -> taopt.AssignmentProblem:
    """1–7 targets, 1–7 vehicles (fewer vehicles for more targets), three cost kinds."""
    rng = np.random.default_rng([15, seed])
    n = int(rng.integers(1, 8))
    m = int(rng.integers(1, 8 if n <= 5 else 4))
    return taopt.AssignmentProblem(_costs(rng, n + m, seed % 3), n, name=f"rand-{seed}")


def delivery_instance(seed: int, customers: int) -> taopt.DeliveryInstance:
    """Customers on a 3×3 street grid with random precedences (a DAG by index order)."""
    rng = np.random.default_rng([16, seed])
    pairs = [(a, b) for a, b in itertools.combinations(range(customers), 2) if rng.random() < 0.3]
    return taopt.DeliveryInstance.grid(
        rng.uniform(0, 600, size=(customers, 2)),
        3,
        600.0,
        float(rng.uniform(1.0, 3.0)),
        1.0,
        float(rng.uniform(450.0, 1200.0)),  # every sortie to a nearest stop fits
        precedences=pairs,
    )


def sop_instance(seed: int) -> taopt.SopProblem:
    """4–7 nodes, start 0 and end n-1, random precedences among the inner nodes."""
    rng = np.random.default_rng([17, seed])
    n = int(rng.integers(4, 8))
    cost = _costs(rng, n, seed % 3)
    inner = range(1, n - 1)
    pairs = [(a, b) for a, b in itertools.combinations(inner, 2) if rng.random() < 0.25]
    return taopt.SopProblem(cost, pairs, 0, n - 1, name=f"sop-{seed}")


def sop_brute_force(problem: taopt.SopProblem) -> float:
    """Cheapest precedence-respecting path from start to end over every order of the rest."""
    inner = [v for v in range(problem.n) if v not in (problem.start, problem.end)]
    best = math.inf
    for order in itertools.permutations(inner):
        position = {v: i for i, v in enumerate(order)}
        if all(position[a] < position[b] for a, b in problem.precedences):
            path = [problem.start, *order, problem.end]
            best = min(best, sum(problem.cost[a, b] for a, b in itertools.pairwise(path)))
    return best


def capability_instance(seed: int) -> taopt.CapabilityProblem:
    """2–5 targets demanding one or both of {a, b}, 2–4 vehicles holding each at least once."""
    rng = np.random.default_rng([18, seed])
    n, m = int(rng.integers(2, 6)), int(rng.integers(2, 5))
    kinds = ["a", "b"] + [str(rng.choice(["a", "b"])) for _ in range(m - 2)]
    rng.shuffle(kinds)
    options = [{"a"}, {"b"}, {"a", "b"}]
    demands = [options[int(rng.integers(0, 3))] for _ in range(n)]
    return taopt.CapabilityProblem(_costs(rng, n + m, seed % 3), n, kinds, demands)


def capability_brute_force(problem: taopt.CapabilityProblem) -> float:
    """Sum of per-class brute-force optima (the §3.6 split)."""
    return sum(
        brute_force_routing(c.problem.cost, c.problem.n) for c in problem.classes if c.problem
    )


def comm_instance(seed: int) -> taopt.CommProblem:
    """Chapter 4: 2–6 targets, 2–4 vehicles, 1–2 attributes, random range."""
    rng = np.random.default_rng([19, seed])
    n, m = int(rng.integers(2, 7)), int(rng.integers(2, 5))
    attributes = int(rng.integers(1, 3))
    return random_problem(n, m, attributes, float(rng.uniform(50, 500)), seed=rng, side=1000.0)


def comm_brute_force(problem: taopt.CommProblem) -> float:
    """f_o: brute force per attribute class of the full-information problem."""
    full = problem.full_information()
    classes = getattr(full, "classes", None)
    if classes is None:
        return dp_optimum(full)
    return sum(dp_optimum(c.problem) for c in classes if c.problem)


def budgeted_instance(seed: int) -> BudgetedProblem:
    """§6.2: 2–6 targets, 1–3 vehicles, the three cost kinds; per vehicle a capacity and a
    time limit around its share of the targets (or none), so that on some instances a limit
    binds and on some no assignment meets the limits."""
    rng = np.random.default_rng([20, seed])
    n, m = int(rng.integers(2, 7)), int(rng.integers(1, 4))
    cost = _costs(rng, n + m, seed % 3)
    leg = float(np.median(cost)) + 1.0
    share = n / m
    capacity = [
        max(1, math.ceil(share * rng.uniform(0.5, 1.5))) if rng.random() < 0.8 else None
        for _ in range(m)
    ]
    max_time = [
        float(leg * share * rng.uniform(0.3, 1.2)) if rng.random() < 0.7 else None for _ in range(m)
    ]
    return BudgetedProblem(cost, n, capacity, max_time, name=f"budgeted-{seed}")


# -------------------------------------------------------------------------- checking
def _failures(cases, method: str) -> list[str]:
    """Run ``method`` without a time limit on each (problem, optimum); describe every miss.
    An infinite optimum (no assignment within a family's limits) must be status
    "infeasible" with no answer."""
    failures = []
    for problem, optimum in cases:
        solution = taopt.solve(problem, method)
        if math.isinf(optimum):
            if solution.status != "infeasible" or solution.solution is not None:
                failures.append(
                    f"{problem.name}: {solution.status} {solution.objective}, brute force: "
                    "no assignment within the limits"
                )
            continue
        value = taopt.evaluate(problem, solution.solution)
        tolerance = REL * max(1.0, abs(optimum))
        if (
            solution.status != "optimal"
            or abs(solution.objective - optimum) > tolerance
            or abs(value - optimum) > tolerance
            or solution.bound is None
            or solution.bound > optimum + tolerance
        ):
            failures.append(
                f"{getattr(problem, 'name', '') or problem!r}: {solution.status} "
                f"{solution.objective} (bound {solution.bound}), brute force {optimum}"
            )
    return failures


# the checks (reference.brute_force registers each; a family added later lists its own as
# BRUTE_FORCE in tests/reference_<family>.py). Default run: 270 instances; slow run: 2,670
# more (seeds after the default run's).
@brute_force("routing", "exact", fast=100, slow=1200)
def _routing_cases(seeds):
    return [(p, dp_optimum(p)) for p in map(routing_instance, seeds)]


def _delivery_cases(seeds, customers):
    cases = []
    for seed in seeds:
        instance = delivery_instance(seed, customers(seed))
        cases.append((instance, brute_force_delivery(instance)))
    return cases


@brute_force("dp", "exact", fast=30, slow=250)
def _dp_cases(seeds):
    return _delivery_cases(seeds, lambda s: 3 + s % 4)


@brute_force("milp", "milp", fast=10, slow=60)
def _milp_cases(seeds):
    return _delivery_cases(seeds, lambda s: 2 + s % 2)


@brute_force("sop", "exact", fast=40, slow=250)
def _sop_cases(seeds):
    return [(p, sop_brute_force(p)) for p in map(sop_instance, seeds)]


@brute_force("capability", "exact", fast=20, slow=150)
def _capability_cases(seeds):
    return [(p, capability_brute_force(p)) for p in map(capability_instance, seeds)]


@brute_force("joint", "joint", fast=10, slow=60)
def _joint_cases(seeds):
    return _capability_cases(seeds)


@brute_force("comm", "exact", fast=20, slow=100)
def _comm_cases(seeds):
    return [(p, comm_brute_force(p)) for p in map(comm_instance, seeds)]


@brute_force("budgeted", "exact", fast=40, slow=600)
def _budgeted_cases(seeds):
    return [(p, brute_force_budgeted(p)) for p in map(budgeted_instance, seeds)]


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
    failures = _failures(check.cases(range(check.fast)), check.method)
    assert not failures, f"{len(failures)} of {check.fast}:\n" + "\n".join(failures[:10])


@pytest.mark.slow
@pytest.mark.parametrize("family", sorted(CHECKS))
def test_exact_equals_brute_force_on_two_thousand(family):
    """The same on 2,670 more instances in all (seeds after the default run's)."""
    check = CHECKS[family]
    failures = _failures(check.cases(range(check.fast, check.fast + check.slow)), check.method)
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
