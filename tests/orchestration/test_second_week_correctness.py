"""Issue 30, defects 1-3: no false "optimal", heuristics that answer instead of raising.

Reproducers of the defects, then an adversarial round on tiny instances: every method's
answer re-scored by ``taopt.evaluate`` and compared with brute force (budgeted) or the
exact method (SOP). The larger sweeps are ``@pytest.mark.slow``.
"""

from __future__ import annotations

import itertools
import json
import math
import re

import numpy as np
import pytest
from reference_budgeted import brute_force_budgeted

import taopt
from taopt.budgeted import BudgetedProblem
from taopt.errors import FeasibilityError, InstanceError
from taopt.heuristics import budgeted, peers
from taopt.heuristics.budgeted import genetic_algorithm
from taopt.runtime import Deadline
from taopt.sop.problem import SopProblem, evaluate_order

# -- defect 2: the budgeted GA -------------------------------------------------------------------


def test_budgeted_ga_with_zero_travel_times_keeps_the_capacity():
    """All travel times 0, capacity [None, 1]: every seed answers a feasible optimum 0."""
    problem = BudgetedProblem(np.zeros((5, 5)), 3, capacity=[None, 1])
    for seed in range(10):
        answer = genetic_algorithm(problem, seed=seed, population=20, generations=20)
        assert str(answer.status) == "feasible"
        assert taopt.evaluate(problem, answer.solution) == answer.objective == 0.0


def test_budgeted_ga_on_an_infeasible_zero_cost_instance_gives_no_solution():
    """Three targets, capacities 0 and 1, travel times 0: no_solution with the reason."""
    problem = BudgetedProblem(np.zeros((5, 5)), 3, capacity=[0, 1])
    assert math.isinf(brute_force_budgeted(problem))
    for seed in range(3):
        answer = genetic_algorithm(problem, seed=seed, population=10, generations=10)
        assert str(answer.status) == "no_solution" and answer.solution is None
        assert "GA met no chromosome" in answer.info["error"]


def test_capacity_unit_is_positive():
    """The price of a target over a capacity is never 0, whatever the travel times."""
    assert budgeted.capacity_unit(BudgetedProblem(np.zeros((4, 4)), 2, capacity=[1, 1])) == 1.0
    cost = np.zeros((4, 4))
    cost[2, 0] = 6.0
    assert budgeted.capacity_unit(BudgetedProblem(cost, 2, capacity=[1, 1])) == 6.0


# -- defect 1: negative SOP costs, CP-SAT's forbidden arcs ---------------------------------------

#: The one message for a negative cost on arc (1, 2) of value -3.
NEGATIVE = r"arc \(1, 2\) has cost -3 < 0: SOP costs must be >= 0"


def _four_nodes(value: float) -> list[list[float]]:
    """A 4-node matrix, all arcs 5 except ``cost[1][2] = value``."""
    cost = [[0.0 if i == j else 5.0 for j in range(4)] for i in range(4)]
    cost[1][2] = value
    return cost


def test_negative_cost_refused_in_python():
    """SopProblem refuses a negative cost (-1 included) naming the arc and the value."""
    with pytest.raises(InstanceError, match=NEGATIVE):
        SopProblem(np.array(_four_nodes(-3.0)), (), 0, 3)
    with pytest.raises(InstanceError, match=r"arc \(1, 2\) has cost -1 < 0"):
        SopProblem(np.array(_four_nodes(-1.0)), (), 0, 3)
    assert SopProblem(np.array(_four_nodes(np.inf)), (), 0, 3).n == 4  # inf forbids


@pytest.mark.parametrize("value", [-3, -0.5])
def test_negative_cost_refused_in_json_files(tmp_path, value):
    """A JSON file with a negative cost other than -1: the same message, after the path."""
    path = tmp_path / "negative.json"
    data = {"schema_version": 1, "kind": "sop_problem", "start": 0, "end": 3}
    path.write_text(json.dumps({**data, "cost": _four_nodes(value)}))
    text = f"arc (1, 2) has cost {value:g} < 0: SOP costs must be >= 0"
    with pytest.raises(InstanceError) as caught:
        SopProblem.load(path)
    assert str(caught.value).startswith(f"{path}: {text}")
    path.write_text(json.dumps({**data, "cost": _four_nodes(-1)}))  # TSPLIB's marker
    assert not np.isfinite(SopProblem.load(path).cost[1, 2])


def test_negative_cost_refused_by_the_schema():
    """The schema alone refuses -3 and -0.5 and accepts -1 (for other tools reading it)."""
    import jsonschema

    from taopt import schemas

    data = {"schema_version": 1, "kind": "sop_problem", "start": 0, "end": 3}
    validator = jsonschema.Draft202012Validator(schemas.schema("sop_problem"))
    assert validator.is_valid({**data, "cost": _four_nodes(-1)})
    for value in (-3, -0.5):
        assert not validator.is_valid({**data, "cost": _four_nodes(value)})


def test_negative_cost_refused_in_tsplib_files(tmp_path):
    """A TSPLIB .sop file with a weight below 0 other than -1: the same message."""
    rows = [[0, 0, 0, 1000000], [-1, 0, -3, 0], [-1, 7, 0, 0], [-1, -1, -1, 0]]
    body = "\n".join(" ".join(str(v) for v in row) for row in rows)
    path = tmp_path / "negative.sop"
    path.write_text(
        "NAME: negative\nTYPE: SOP\nDIMENSION: 4\nEDGE_WEIGHT_TYPE: EXPLICIT\n"
        f"EDGE_WEIGHT_FORMAT: FULL_MATRIX\nEDGE_WEIGHT_SECTION\n4\n{body}\nEOF\n"
    )
    with pytest.raises(InstanceError, match=f"^{re.escape(str(path))}: {NEGATIVE}"):
        SopProblem.load(path)
    path.write_text(path.read_text().replace("-1 0 -3 0", "-1 0 3 0"))
    problem = SopProblem.load(path)  # the -1 markers still read as TSPLIB means them
    assert np.isinf(problem.cost[[1, 2, 3, 3], [0, 0, 1, 2]]).all()
    assert brute_force_sop(problem) == 0 + 3 + 0


def brute_force_sop(problem: SopProblem) -> float:
    """The cheapest feasible order over every permutation of the inner nodes (inf if none)."""
    inner = [v for v in range(problem.n) if v not in (problem.start, problem.end)]
    best = math.inf
    for perm in itertools.permutations(inner):
        try:
            best = min(best, evaluate_order(problem, [problem.start, *perm, problem.end]))
        except FeasibilityError:
            continue
    return best


def test_cpsat_worker_takes_forbidden_arcs_explicitly():
    """The CP-SAT worker reads forbidden arcs from their own array, never from a cost's sign:
    negative costs are used (the brute-force optimum -6), marked arcs are not."""
    cost = np.array([[0, 4, 9, 9], [9, 0, -8, 9], [9, 9, 0, -2], [0, 0, 0, 0]])
    options = {"time_limit": 20, "seed": 0, "num_workers": 1, "kind": "sop"}
    options.update(start=0, end=3, precedences=[])
    request = {"cost": cost, "n": 4, "m": 0, "options": options}
    request["options"]["forbidden"] = np.zeros((4, 4), dtype=bool).tolist()
    reply = peers._call("cpsat", request, Deadline(20)).reply
    assert reply is not None
    assert reply["cpsat_status"] == "OPTIMAL" and reply["order"] == [0, 1, 2, 3]
    assert reply["objective"] == 4 - 8 - 2 == -6
    forbidden = np.zeros((4, 4), dtype=bool)
    forbidden[1, 2] = True
    request["options"]["forbidden"] = forbidden.tolist()
    reply = peers._call("cpsat", request, Deadline(20)).reply
    assert reply is not None
    assert reply["order"] == [0, 2, 1, 3] and reply["objective"] == 9 + 9 + 9


def random_sop(rng: np.random.Generator, largest: int = 7) -> SopProblem:
    """A tiny SOP (3..largest nodes): costs 0..19, a random share of forbidden arcs, random
    precedences between inner nodes; feasible or not."""
    n = int(rng.integers(3, largest + 1))
    cost = rng.integers(0, 20, size=(n, n)).astype(float)
    cost[rng.random((n, n)) < rng.uniform(0, 0.6)] = np.inf
    pairs = set()
    if n > 3:
        for _ in range(int(rng.integers(0, n))):
            r, j = sorted(int(v) for v in rng.choice(np.arange(1, n - 1), 2, replace=False))
            pairs.add((r, j))
    return SopProblem(cost, tuple(sorted(pairs)), 0, n - 1)


# -- defect 3 and the adversarial round: SOP ----------------------------------------------------

#: The SOP heuristics with iteration-bounded options (no wall-clock stop in tests).
SOP_HEURISTICS = {
    "NIA": {},
    "MMA": {},
    "SMMA": {},
    "GA": {"population": 10, "generations": 10},
    "ILS": {"iterations": 3},
}


def check_sop_answer(problem: SopProblem, method: str, result: taopt.Solution, optimum: float):
    """A heuristic's answer: feasible and re-scored when an order exists (never below the
    optimum), status no_solution with the reason when none does; never "optimal"."""
    assert str(result.status) in ("feasible", "no_solution"), (method, result.status)
    if math.isfinite(optimum):
        assert result.solution is not None, (method, result.info)
        assert evaluate_order(problem, result.order) == result.objective >= optimum
    else:
        assert result.solution is None and "no feasible order exists" in result.info["error"]


def test_sop_heuristics_answer_on_random_tiny_sops():
    """25 random tiny SOPs with forbidden arcs and precedences (some infeasible): every
    heuristic answers (repaired at a dead end), re-scored, never below brute force."""
    rng = np.random.default_rng(30)
    repaired = 0
    for k in range(25):
        problem = random_sop(rng)
        optimum = brute_force_sop(problem)
        for method, options in SOP_HEURISTICS.items():
            result = taopt.solve(problem, method, seed=k, **options)
            check_sop_answer(problem, method, result, optimum)
            repaired += bool(result.info.get("repaired"))
    assert repaired > 0  # the sample does reach greedy dead ends


def test_backtracking_repair_proves_or_gives_up():
    """backtrack_order finds the only order, proves there is none, or says its budget ran out."""
    from taopt.heuristics.sequencing import backtrack_order

    inf = np.inf
    only = [[0, 2, inf, inf], [1, 0, 8, inf], [0, 4, 0, 5], [5, 3, 2, 0]]
    assert backtrack_order(only, [], 0, 3) == ([0, 1, 2, 3], False)
    none = [[0, 1, 1, 1], [1, 0, 1, inf], [1, 1, 0, inf], [1, 1, 1, 0]]
    assert backtrack_order(none, [], 0, 3) == (None, True)
    assert backtrack_order(np.ones((6, 6)), [], 0, 5, budget=2) == (None, False)


def test_cpsat_never_optimal_for_a_wrong_value():
    """cpsat on random tiny SOPs with forbidden arcs and precedences: "optimal" only at the
    brute-force optimum, "infeasible" only when no order exists; its order re-scored."""
    rng = np.random.default_rng(31)
    for k in range(6):
        problem = random_sop(rng)
        optimum = brute_force_sop(problem)
        result = taopt.solve(problem, "cpsat", time_limit=20, seed=k, num_workers=1)
        if math.isfinite(optimum):
            assert str(result.status) == "optimal" and result.objective == optimum
            assert evaluate_order(problem, result.order) == optimum
        else:
            assert str(result.status) == "infeasible" and result.solution is None


@pytest.mark.slow
def test_sop_sweep_every_method_against_brute_force():
    """300 random tiny SOPs: exact and cpsat prove the brute-force optimum (or infeasible);
    every heuristic answers as :func:`check_sop_answer` requires."""
    rng = np.random.default_rng(32)
    for k in range(300):
        problem = random_sop(rng)
        optimum = brute_force_sop(problem)
        for method in ("exact", "cpsat"):
            result = taopt.solve(problem, method, seed=k)
            if math.isfinite(optimum):
                assert str(result.status) == "optimal" and result.objective == optimum
                assert evaluate_order(problem, result.order) == optimum
            else:
                assert str(result.status) == "infeasible", (k, method)
        for method, options in SOP_HEURISTICS.items():
            check_sop_answer(
                problem, method, taopt.solve(problem, method, seed=k, **options), optimum
            )


# -- the adversarial round: budgeted -------------------------------------------------------------


def random_budgeted(rng: np.random.Generator) -> BudgetedProblem:
    """A tiny budgeted problem: 1-5 targets, 1-3 vehicles, whole travel times with many
    zeros (largest 1, 3 or 10), random capacities and maximum travel times; feasible or not."""
    n, m = int(rng.integers(1, 6)), int(rng.integers(1, 4))
    high = int(rng.choice([1, 3, 10]))
    cost = rng.integers(0, high, size=(n + m, n + m)).astype(float)
    capacity = [None if rng.random() < 0.4 else int(rng.integers(0, 3)) for _ in range(m)]
    max_time = [
        None if rng.random() < 0.5 else float(rng.integers(0, 3 * high + 1)) for _ in range(m)
    ]
    return BudgetedProblem(cost, n, capacity=capacity, max_time=max_time)


#: The budgeted heuristics with iteration-bounded options.
BUDGETED_HEURISTICS = {"MC": {}, "EVM": {}, "GA": {"population": 10, "generations": 15}}


def check_budgeted_answer(problem, method, result, optimum):
    """A heuristic's answer: feasible (re-scored, never below the optimum) or no_solution
    with the reason (always when no solution exists); never "optimal"."""
    assert str(result.status) in ("feasible", "no_solution"), (method, result.status)
    if result.solution is None:
        assert "error" in result.info and math.isinf(result.objective)
        return
    assert math.isfinite(optimum), f"{method} answered on an infeasible instance"
    assert taopt.evaluate(problem, result.solution) == pytest.approx(result.objective)
    assert result.objective >= optimum - 1e-9


def test_budgeted_heuristics_answer_on_random_tiny_problems():
    """25 random tiny budgeted problems (zero travel times, tight limits, some infeasible):
    MC, EVM and GA never raise; answers feasible and never below brute force."""
    rng = np.random.default_rng(33)
    for k in range(25):
        problem = random_budgeted(rng)
        optimum = brute_force_budgeted(problem)
        for method, options in BUDGETED_HEURISTICS.items():
            result = taopt.solve(problem, method, seed=k, **options)
            check_budgeted_answer(problem, method, result, optimum)


@pytest.mark.slow
def test_budgeted_sweep_every_method_against_brute_force():
    """300 random tiny budgeted problems: exact proves the brute-force optimum (or
    infeasible); MC, EVM and GA answer as :func:`check_budgeted_answer` requires."""
    rng = np.random.default_rng(34)
    for k in range(300):
        problem = random_budgeted(rng)
        optimum = brute_force_budgeted(problem)
        exact = taopt.solve(problem, "exact")
        if math.isfinite(optimum):
            assert str(exact.status) == "optimal"
            assert exact.objective == pytest.approx(optimum, rel=1e-6, abs=1e-9)
        else:
            assert str(exact.status) == "infeasible"
        for method, options in BUDGETED_HEURISTICS.items():
            result = taopt.solve(problem, method, seed=k, **options)
            check_budgeted_answer(problem, method, result, optimum)
