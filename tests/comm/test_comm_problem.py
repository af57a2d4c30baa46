"""Chapter 4 data: CommProblem validation and JSON, full information, the scorer, the MST bound."""

from __future__ import annotations

import json
import math

import networkx as nx
import numpy as np
import pytest

import taopt
from taopt.comm import CommProblem, Trajectories, evaluate_trajectories, random_problem
from taopt.comm.bounds import mst_bound
from taopt.errors import FeasibilityError, InstanceError
from taopt.result import Solution


def line_problem(r: float = 5.0) -> CommProblem:
    """Two targets on the x axis at 1 and 3, one vehicle at the origin, one attribute."""
    return CommProblem([[1, 0], [3, 0]], [[0, 0]], ["a", "a"], ["a"], comm_range=r)


# -- validation ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "needle"),
    [
        ({"target_attribute": ["a", "z"]}, "target 1 has attribute 'z'"),
        ({"targets": [[1, 0], [np.nan, 0]]}, "targets[1]"),
        ({"vehicles": [[0, np.inf]]}, "vehicles[0]"),
        ({"comm_range": -1.0}, "comm_range"),
        ({"comm_range": math.inf}, "comm_range"),
        ({"targets": np.zeros((0, 2)), "target_attribute": []}, "targets is empty"),
        ({"vehicles": np.zeros((0, 2)), "vehicle_ability": []}, "vehicles is empty"),
        ({"vehicle_ability": ["a", "a"]}, "vehicle_ability has 2 labels"),
        ({"target_attribute": ["a", 1.5]}, "target_attribute[1]"),
    ],
)
def test_validation_names_the_item(kwargs: dict, needle: str) -> None:
    """Bad data raises InstanceError naming the offending target, vehicle or field."""
    base = {
        "targets": [[1, 0], [3, 0]],
        "vehicles": [[0, 0]],
        "target_attribute": ["a", "a"],
        "vehicle_ability": ["a"],
        "comm_range": 5.0,
    }
    base.update(kwargs)
    with pytest.raises(InstanceError, match=needle.replace("[", r"\[").replace("]", r"\]")):
        CommProblem(**base)


def test_zero_range_is_allowed() -> None:
    """r = 0 is a valid (if useless) range: vehicles only talk when they meet."""
    assert line_problem(0.0).comm_range == 0.0


def test_json_round_trip_and_schema(tmp_path) -> None:
    """save/load keeps every field; a file with a bad field is refused naming the path."""
    p = random_problem(7, 3, 2, 150.0, seed=4, name="x")
    path = tmp_path / "p.json"
    p.save(path)
    q = CommProblem.load(path)
    assert q.name == "x" and q.comm_range == 150.0
    assert np.array_equal(q.targets, p.targets) and np.array_equal(q.vehicles, p.vehicles)
    assert q.target_attribute == p.target_attribute and q.vehicle_ability == p.vehicle_ability
    data = json.loads(path.read_text())
    data["comm_range"] = -3
    with pytest.raises(InstanceError, match="comm_range"):
        CommProblem.from_dict(data)
    assert taopt.registry.family_for_kind("comm_problem").problem_type is CommProblem


def test_random_problem_labels_and_seed() -> None:
    """Every label 0..|A|-1 is some vehicle's and some target's; same seed, same scenario."""
    for k in range(1, 7):
        p = random_problem(30, 6, k, 100.0, seed=k)
        assert set(p.vehicle_ability) == set(range(k)) == set(p.target_attribute)
    a, b = random_problem(10, 4, 2, 9.0, seed=3), random_problem(10, 4, 2, 9.0, seed=3)
    assert np.array_equal(a.targets, b.targets) and a.vehicle_ability == b.vehicle_ability
    with pytest.raises(InstanceError, match="must lie in"):
        random_problem(3, 2, 3, 1.0)


def test_full_information_costs_are_euclidean() -> None:
    """full_information: AssignmentProblem for one attribute, else a CapabilityProblem split
    into one class per attribute, both on the Euclidean distances."""
    one = random_problem(6, 2, 1, 10.0, seed=1)
    full = one.full_information()
    assert isinstance(full, taopt.AssignmentProblem)
    gap = one.points[:, None, :] - one.points[None, :, :]
    assert np.allclose(full.cost, np.hypot(gap[..., 0], gap[..., 1]))
    two = random_problem(8, 3, 2, 10.0, seed=2)
    cap = two.full_information()
    assert isinstance(cap, taopt.CapabilityProblem)
    assert sorted(t for c in cap.classes for t in c.targets) == list(range(8))
    for c in cap.classes:
        assert all(two.target_attribute[t] == c.capability for t in c.targets)
        assert all(two.vehicle_ability[v] == c.capability for v in c.vehicles)


# -- the scorer ------------------------------------------------------------------------------


def test_scorer_sums_the_driven_lengths() -> None:
    """(4.1) is the polyline length; waiting adds nothing; the payload survives JSON."""
    p = line_problem()
    tr = Trajectories([[[0, 0, 0], [1, 1, 0], [5, 1, 0], [7, 3, 0]]], [[(0, 1), (1, 3)]])
    assert evaluate_trajectories(p, tr) == pytest.approx(3.0)
    assert taopt.evaluate(p, tr) == pytest.approx(3.0)
    s = Solution(objective=3.0, status="feasible", solution=tr, method="DAA")
    assert Solution.from_dict(json.loads(json.dumps(s.to_dict()))) == s


@pytest.mark.parametrize(
    ("paths", "visits", "needle"),
    [
        ([[[0, 0, 0], [1, 1, 0]]], [[(0, 1)]], "target 1 .* never visited"),
        ([[[0, 0, 0], [0.5, 1, 0], [2.5, 3, 0]]], [[(0, 1), (1, 2)]], "faster than unit"),
        ([[[0, 0, 0], [2, 1, 0.5], [5, 3, 0]]], [[(0, 1), (1, 2)]], "not at the target"),
        ([[[0, 1, 1], [1, 1, 0], [3, 3, 0]]], [[(0, 1), (1, 2)]], "starts at"),
        ([[[0, 0, 0], [1, 1, 0], [3, 3, 0]]], [[(0, 1), (2, 2)]], "2, which is not a target"),
        ([[[0, 0, 0], [1, 1, 0], [0.5, 3, 0]]], [[(0, 1), (1, 2)]], "back in time"),
    ],
)
def test_scorer_rejects_infeasible(paths, visits, needle: str) -> None:
    """The scorer names what is wrong: unvisited target, speed, position, start, index, time."""
    with pytest.raises(FeasibilityError, match=needle):
        evaluate_trajectories(line_problem(), Trajectories(paths, visits))


def test_scorer_checks_the_attribute() -> None:
    """A vehicle may only visit targets whose attribute is its ability ((4.2))."""
    p = CommProblem([[1, 0]], [[0, 0], [0, 0]], ["b"], ["a", "b"], comm_range=1.0)
    tr = Trajectories([[[0, 0, 0], [1, 1, 0]], [[0, 0, 0]]], [[(0, 1)], []])
    with pytest.raises(FeasibilityError, match="ability 'a'"):
        evaluate_trajectories(p, tr)


# -- the MST bound ---------------------------------------------------------------------------


def networkx_mst(problem: CommProblem) -> float:
    """Lemma 4.8's graph built literally: per class, vehicles and targets, zero vehicle edges."""
    total = 0.0
    for code in range(len(problem.attributes)):
        vehicles = [f"v{j}" for j in np.flatnonzero(problem.vehicle_code == code)]
        targets = list(np.flatnonzero(problem.target_code == code))
        if not targets:
            continue
        g = nx.Graph()
        for a in range(len(vehicles)):
            for b in range(a + 1, len(vehicles)):
                g.add_edge(vehicles[a], vehicles[b], weight=0.0)
        points = {
            f"v{j}": problem.vehicles[j] for j in np.flatnonzero(problem.vehicle_code == code)
        }
        points.update({f"t{q}": problem.targets[q] for q in targets})
        names = list(points)
        for a in range(len(names)):
            for b in range(a + 1, len(names)):
                if names[a][0] == "v" and names[b][0] == "v":
                    continue
                w = float(np.hypot(*(points[names[a]] - points[names[b]])))
                g.add_edge(names[a], names[b], weight=w)
        total += nx.minimum_spanning_tree(g).size(weight="weight")
    return total


def test_mst_bound_matches_the_literal_graph() -> None:
    """mst_bound (contracted vehicles, scipy) equals networkx on the literal graph of Lemma 4.8."""
    for seed in range(15):
        p = random_problem(3 + seed, 1 + seed % 4, 1 + seed % 3 if seed % 4 >= 2 else 1, 5.0, seed)
        assert mst_bound(p) == pytest.approx(networkx_mst(p), rel=1e-12)
    assert taopt.bounds.mst(line_problem()) == pytest.approx(3.0)


def test_mst_bound_with_coincident_points() -> None:
    """Targets on top of each other or of a vehicle add zero, not a broken tree."""
    p = CommProblem([[0, 0], [0, 0], [2, 0]], [[0, 0]], [0, 0, 0], [0], comm_range=1.0)
    assert mst_bound(p) == pytest.approx(2.0)


def test_mst_bound_below_the_dp_optimum() -> None:
    """Lemma 4.8: f_MST <= f_o, f_o from an independent dynamic programme (n <= 7)."""
    from taopt.orchestration.studies.routing_claims import exact_optimum

    for seed in range(20):
        p = random_problem(3 + seed % 5, 1 + seed % 3, 1 + (seed % 2 if seed % 3 else 0), 1.0, seed)
        full = p.full_information()
        parts = [c.problem for c in full.classes] if hasattr(full, "classes") else [full]
        f_o = sum(exact_optimum(sub)[0] for sub in parts if sub is not None)
        assert mst_bound(p) <= f_o + 1e-9
