"""The DFJ loop's trace (``trace=True``): each round's point, its violated (2.5) sets and cuts."""

from __future__ import annotations

import numpy as np
import pytest

import taopt
from taopt.errors import InstanceError
from taopt.fields import thesis_field
from taopt.instance import Instance
from taopt.models.routing import solve_routing
from taopt.orchestration.solving import problem_from_instance
from taopt.result import Solution

TOLERANCE = 1e-6


@pytest.fixture(scope="module")
def traced() -> tuple[taopt.AssignmentProblem, Solution]:
    """A 12-target, 1-vehicle drift-field instance whose DFJ loop needs root and MIP rounds."""
    instance = Instance.random(12, 1, field=thesis_field(1e-3), seed=2)
    problem = problem_from_instance(instance, progress=False)
    return problem, taopt.solve(problem, "exact", time_limit=None, trace=True)


def _inside(arcs: list[list[float]], subset: list[int]) -> float:
    """Σ σ_ij over the arcs with both ends in ``subset`` (the left side of (2.5))."""
    members = set(subset)
    return sum(value for tail, head, value in arcs if tail in members and head in members)


def _cost(problem: taopt.AssignmentProblem, arcs: list[list[float]]) -> float:
    """(2.2) of a traced point."""
    return sum(problem.cost[int(t), int(h)] * value for t, h, value in arcs)


def test_trace_has_root_and_mip_rounds(traced):
    """The instance's trace has several root LPs (some fractional) and several MIP rounds."""
    _, solution = traced
    rounds = solution.info["trace"]["rounds"]
    stages = [r["stage"] for r in rounds]
    assert stages.count("root") >= 2 and stages.count("mip") >= 2
    assert [r["round"] for r in rounds] == list(range(1, len(rounds) + 1))
    assert any(value < 1 - TOLERANCE for r in rounds for _, _, value in r["arcs"])


def test_each_rounds_sets_are_violated_by_its_point(traced):
    """Every set a round reports violates (2.5) at its point, and the round adds its row."""
    _, solution = traced
    for record in solution.info["trace"]["rounds"]:
        for subset in record["subtours"]:
            assert _inside(record["arcs"], subset) > len(subset) - 1 + TOLERANCE
            assert subset in record["cuts"]


def test_later_points_satisfy_earlier_cuts(traced):
    """The (2.5) rows added in a round hold at every later round's point (they stay in)."""
    _, solution = traced
    rounds = solution.info["trace"]["rounds"]
    for k, record in enumerate(rounds):
        if record.get("discarded"):
            continue
        for later in rounds[k + 1 :]:
            for subset in record["cuts"]:
                assert _inside(later["arcs"], subset) <= len(subset) - 1 + TOLERANCE


def test_values_and_bounds_are_the_points_and_valid(traced):
    """A round's value is (2.2) of its point; every bound is at most the optimum."""
    problem, solution = traced
    for record in solution.info["trace"]["rounds"]:
        assert record["value"] == pytest.approx(_cost(problem, record["arcs"]), rel=1e-6)
        assert record["bound"] <= solution.objective * (1 + TOLERANCE)


def test_last_round_point_is_the_optimum(traced):
    """The last round's point is integral, has no subtour and its routes are the optimum."""
    problem, solution = traced
    last = solution.info["trace"]["rounds"][-1]
    assert solution.status.value == "optimal"
    assert last["subtours"] == []
    assert all(abs(value - 1.0) <= TOLERANCE for _, _, value in last["arcs"])
    assert _cost(problem, last["arcs"]) == pytest.approx(solution.objective, rel=1e-9)
    n = problem.n
    used = {(int(t), int(h)) for t, h, _ in last["arcs"]}
    for k, route in enumerate(solution.routes):
        points = [n + k, *route]
        assert all((a, b) in used for a, b in zip(points[:-1], points[1:], strict=False))


def test_trace_off_changes_nothing(traced):
    """Without trace the answer and the loop's counts are the same and nothing is kept."""
    problem, traced_solution = traced
    plain = taopt.solve(problem, "exact", time_limit=None)
    assert "trace" not in plain.info
    assert plain.objective == traced_solution.objective
    for key in ("rounds", "cuts", "root_rounds", "lifted_cuts", "core_arcs"):
        assert plain.info[key] == traced_solution.info[key]
    assert len(traced_solution.info["trace"]["rounds"]) == (
        plain.info["root_rounds"] + plain.info["rounds"]
    )


def test_trace_survives_solution_json(traced, tmp_path):
    """The trace is plain JSON data: saved and loaded with the solution, unchanged."""
    _, solution = traced
    path = tmp_path / "exact.json"
    solution.save(path)
    assert Solution.load(path).info["trace"] == solution.info["trace"]


def test_relaxation_traces_the_root():
    """relax=True keeps the root LPs; the last one violates no (2.5) and is the LP value."""
    cost = np.array([[0, 1, 9, 9], [1, 0, 9, 9], [9, 9, 0, 9], [5, 6, 4, 0.0]])
    relaxed = solve_routing(taopt.AssignmentProblem(cost, 3), relax=True, trace=True)
    rounds = relaxed.info["trace"]["rounds"]
    assert rounds[0]["subtours"] == [[0, 1]] and rounds[-1]["subtours"] == []
    assert rounds[-1]["value"] == pytest.approx(relaxed.objective)


def test_compact_models_and_other_methods_refuse_trace(traced):
    """MTZ / flow and a heuristic refuse trace=True naming themselves; trace=False is fine."""
    problem, _ = traced
    with pytest.raises(InstanceError, match="sec='mtz'"):
        solve_routing(problem, sec="mtz", trace=True)
    with pytest.raises(InstanceError, match="'MC' keeps no trace"):
        taopt.solve(problem, "MC", trace=True)
    assert "trace" not in taopt.solve(problem, "MC", trace=False).info
