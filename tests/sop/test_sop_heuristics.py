"""The ordering heuristics (NIA, MMA, SMMA, GA) on instances with forbidden arcs.

Each heuristic must return a feasible order (re-checked by the SOP's one scorer, never
cheaper than the brute-force optimum) whenever one exists (a greedy dead end is repaired by
backtracking), and status "no_solution" with the reason in ``info["error"]`` when none
exists; never an exception. The exact method
is checked against brute force on the same instances. ``taopt solve`` on the issue's
five-node file prints the exact row 16 and a feasible NIA row.
"""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import taopt
from taopt.errors import SolverError
from taopt.heuristics.ga_delivery import ga_order
from taopt.heuristics.sequencing import NoOrderError, mma_order, nia_order, smma_order
from taopt.orchestration.cli import main
from taopt.sop.problem import SopProblem, evaluate_order

HEURISTICS = ("NIA", "MMA", "SMMA", "GA")
OPTIONS = {"GA": {"generations": 20}}

#: The file of issue 15: arc 1 -> 4 is forbidden (-1), the optimum is 16.
FIVE_NODES = {
    "schema_version": 1,
    "kind": "sop_problem",
    "name": "five-nodes",
    "cost": [
        [0, 3, 5, 9, -1],
        [-1, 0, 4, 6, -1],
        [-1, 2, 0, 3, 7],
        [-1, 4, 1, 0, 3],
        [2, -1, -1, -1, 0],
    ],
    "precedences": [[2, 1]],
    "start": 0,
    "end": 4,
}


def brute_force(problem: SopProblem) -> float:
    """Cheapest feasible order by enumerating every permutation of the inner nodes."""
    inner = [v for v in range(problem.n) if v not in (problem.start, problem.end)]
    best = np.inf
    for perm in itertools.permutations(inner):
        order = [problem.start, *perm, problem.end]
        where = {v: k for k, v in enumerate(order)}
        if any(where[r] > where[j] for r, j in problem.precedences):
            continue
        best = min(best, float(problem.cost[order[:-1], order[1:]].sum()))
    return best


@st.composite
def sop_with_forbidden_arcs(draw: st.DrawFn) -> SopProblem:
    """Random asymmetric integer costs, 0-60 % forbidden arcs, random acyclic precedences."""
    n = draw(st.integers(3, 7))
    costs = draw(st.lists(st.integers(0, 9), min_size=n * n, max_size=n * n))
    forbidden_share = draw(st.sampled_from([0.0, 0.1, 0.3, 0.45, 0.6]))
    mask = draw(st.lists(st.floats(0, 1), min_size=n * n, max_size=n * n))
    cost = np.array(costs, dtype=float).reshape(n, n)
    cost[np.array(mask).reshape(n, n) < forbidden_share] = np.inf
    np.fill_diagonal(cost, 0.0)
    inner = draw(st.permutations(list(range(1, n - 1))))
    pairs = []
    if len(inner) >= 2:
        chosen = draw(st.lists(st.tuples(st.integers(0, len(inner) - 1), st.integers(0, 2))))
        for a, step in chosen:
            b = a + 1 + step
            if b < len(inner):
                pairs.append((inner[a], inner[b]))
    return SopProblem(cost, tuple(dict.fromkeys(pairs)), 0, n - 1, "random")


@settings(
    max_examples=60,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(sop_with_forbidden_arcs())
def test_heuristics_feasible_or_report(problem):
    """Every heuristic returns a feasible order (>= the optimum) when one exists, else
    status no_solution naming the reason; it never raises."""
    optimum = brute_force(problem)
    for method in HEURISTICS:
        result = taopt.solve(problem, method, seed=0, **OPTIONS.get(method, {}))
        if not np.isfinite(optimum):
            assert str(result.status) == "no_solution" and result.solution is None
            assert "no feasible order exists" in result.info["error"]
            continue
        assert str(result.status) == "feasible", (method, result.info)
        assert evaluate_order(problem, result.order) == pytest.approx(result.objective)
        assert result.objective >= optimum - 1e-9


@settings(max_examples=15, derandomize=True, deadline=None)
@given(sop_with_forbidden_arcs())
def test_exact_matches_brute_force_with_forbidden_arcs(problem):
    """The exact SOP method proves the brute-force optimum (or infeasibility) on small instances."""
    optimum = brute_force(problem)
    result = taopt.solve(problem, "exact")  # never an error: no path is status "infeasible"
    if np.isfinite(optimum):
        assert result.status == "optimal"
        assert result.objective == pytest.approx(optimum)
        assert evaluate_order(problem, result.order) == pytest.approx(optimum)
    else:
        assert result.status == "infeasible" and result.solution is None


@pytest.mark.parametrize("rule", [nia_order, mma_order, smma_order])
def test_insertion_never_creates_a_forbidden_arc(rule):
    """An insertion before the end node is refused when its new arc into the end is forbidden."""
    problem = SopProblem.from_dict(FIVE_NODES)
    order = rule(problem.cost, problem.precedences, problem.start, problem.end)
    assert np.isfinite(problem.cost[order[:-1], order[1:]]).all()
    assert evaluate_order(problem, order) == 16.0


def test_heuristics_report_dead_end():
    """With no usable arc into the end node from any inner node, every rule says it found
    none: a dead end without the repair, a proof of no order with it."""
    cost = np.ones((4, 4))
    cost[1:3, 3] = np.inf
    for rule in (nia_order, mma_order, smma_order):
        with pytest.raises(SolverError, match="found no feasible order"):
            rule(cost, [], 0, 3, repair=False)
        with pytest.raises(NoOrderError, match="no feasible order exists") as caught:
            rule(cost, [], 0, 3)
        assert caught.value.proved
    with pytest.raises(SolverError, match="GA found no feasible order"):
        ga_order(cost, [], 0, 3, generations=5)


def test_ga_unchanged_without_forbidden_arcs():
    """On a complete matrix the GA's decoder takes no forbidden-arc branch: the doc example holds."""
    cost = [[0, 6, 1, 9], [5, 0, 7, 3], [3, 6, 0, 9], [5, 1, 9, 0]]
    assert ga_order(cost, [(1, 2)], start=0, generations=50, seed=1) == [0, 3, 1, 2]


def test_solve_five_nodes_file(tmp_path, capsys):
    """`taopt solve` on the issue's five-node file: exact row 16, NIA feasible, exit code 0."""
    path = tmp_path / "five.json"
    path.write_text(json.dumps(FIVE_NODES))
    code = main(["solve", str(path), "--methods", "exact,NIA", "--quiet"])
    out = capsys.readouterr().out
    assert code == 0
    rows = {line.split()[0]: line.split() for line in out.splitlines()[2:4]}
    assert rows["exact"][1:3] == ["optimal", "16"]
    assert rows["NIA"][1] == "feasible"


#: Only 0 -> 1 -> 2 -> 3 -> 4 is usable (22); the greedy rules insert 3 first and dead-end.
DEAD_END = {
    **FIVE_NODES,
    "name": "greedy-dead-end",
    "cost": [
        [0, 2, -1, -1, -1],
        [1, 0, 8, 8, -1],
        [0, 4, 0, 5, -1],
        [5, 3, 2, 0, 7],
        [8, -1, 5, 6, 0],
    ],
    "precedences": [],
}


def test_greedy_dead_end_is_repaired(tmp_path, capsys):
    """The greedy rules dead-end on this file; the backtracking repair gives the only order
    (22, the optimum) and the table says so; exit 0."""
    path = tmp_path / "dead_end.json"
    path.write_text(json.dumps(DEAD_END))
    code = main(["solve", str(path), "--methods", "exact,NIA,MMA,SMMA,ILS", "--quiet"])
    out = capsys.readouterr().out
    assert code == 0
    lines = {line.split()[0]: line for line in out.splitlines()[2:7]}
    assert lines["exact"].split()[1:3] == ["optimal", "22"]
    problem = SopProblem.from_dict(DEAD_END)
    for method in ("NIA", "MMA", "SMMA", "ILS"):
        assert lines[method].split()[1:3] == ["feasible", "22"]
        result = taopt.solve(problem, method, seed=0)
        assert evaluate_order(problem, result.order) == result.objective == 22
    for method in ("NIA", "MMA", "SMMA"):
        with pytest.raises(SolverError, match=f"{method} found no feasible order"):
            taopt.heuristics.sequencing._RULES[method](
                problem.cost, problem.precedences, problem.start, problem.end, repair=False
            )


#: Nodes 1 and 2 cannot reach the end node 3: no feasible order exists.
NO_ORDER = {
    **FIVE_NODES,
    "name": "no-order",
    "cost": [[0, 1, 1, 1], [1, 0, 1, -1], [1, 1, 0, -1], [1, 1, 1, 0]],
    "precedences": [],
    "start": 0,
    "end": 3,
}


def test_no_order_is_a_no_solution_row(tmp_path, capsys):
    """On an SOP with no feasible order every heuristic row is no_solution with its reason
    and exact's is infeasible; nothing raises, exit 0."""
    path = tmp_path / "no_order.json"
    path.write_text(json.dumps(NO_ORDER))
    code = main(["solve", str(path), "--methods", "exact,NIA,MMA,SMMA,GA,ILS", "--quiet"])
    out = capsys.readouterr().out
    assert code == 0
    lines = {line.split()[0]: line for line in out.splitlines()[2:8]}
    assert lines["exact"].split()[1] == "infeasible"
    for method in ("NIA", "MMA", "SMMA", "GA", "ILS"):
        assert lines[method].split()[1] == "no_solution"
        note = lines[method].split()[-1]  # the reason is a numbered note under the table
        assert f"{note} {method}:" in out
        assert "no feasible order exists" in out.split(f"{note} {method}:")[1].splitlines()[0]
