"""Chapter 3 problem data: instances, the §3.7 generator, JSON, bounds and bad input."""

from __future__ import annotations

import numpy as np
import pytest

import taopt
from taopt import Instance, Obstacle, Target, Vehicle
from taopt.bounds import arborescence, doubled_arborescence, thesis_mcga
from taopt.capability import CapabilityProblem
from taopt.capability.instances import (
    THESIS_OBSTACLES,
    capability_problem_from_instance,
    random_demands,
    thesis_scenario,
)
from taopt.errors import FeasibilityError, InstanceError
from taopt.fields import thesis_field

RING = (
    Obstacle(((30, 30), (70, 30), (70, 40), (30, 40)), "south"),
    Obstacle(((30, 60), (70, 60), (70, 70), (30, 70)), "north"),
    Obstacle(((30, 40), (40, 40), (40, 60), (30, 60)), "west"),
    Obstacle(((60, 40), (70, 40), (70, 60), (60, 60)), "east"),
)


def small_instance(**changes) -> Instance:
    """Two capabilities in a 100 m square with the ring obstacle; target t0 demands both."""
    base = Instance(
        vehicles=(
            Vehicle("sonar1", (5.0, 5.0), capability="sonar"),
            Vehicle("camera1", (95.0, 5.0), capability="camera"),
            Vehicle("sonar2", (95.0, 95.0), capability="sonar"),
        ),
        targets=(
            Target("t0", (20.0, 80.0), ("sonar", "camera")),
            Target("t1", (80.0, 20.0), ("camera",)),
            Target("t2", (15.0, 50.0), ("sonar",)),
        ),
        region=(0.0, 100.0, 0.0, 100.0),
        field=thesis_field(1e-3),
        obstacles=(RING[0],),
    )
    return base.replace(**changes)


def test_converter_uses_the_grid_with_obstacles():
    """With obstacles the matrix is the grid planner's (10 m cells, 16 moves by default)."""
    from taopt.navigation import grid_travel_time_matrix

    inst = small_instance()
    problem = capability_problem_from_instance(inst, cell=5.0)
    grid = grid_travel_time_matrix(
        inst.field, inst.points, inst.region, 5.0, inst.obstacles, neighbours=16
    )
    np.testing.assert_allclose(problem.cost, grid)
    assert problem.vehicle_capability == ("sonar", "camera", "sonar")
    assert problem.demands[0] == frozenset({"sonar", "camera"})
    assert [len(c.targets) for c in problem.classes] == [2, 2]


def test_converter_without_obstacles_uses_navigation():
    """Without obstacles, still water: the matrix is the straight-line time (closed form)."""
    inst = small_instance(obstacles=(), field=None)
    problem = capability_problem_from_instance(inst)
    pts = inst.points
    np.testing.assert_allclose(problem.cost, np.linalg.norm(pts[:, None] - pts[None], axis=2))


def test_speeds_per_capability_give_one_matrix_each():
    """Vehicle kinds of different speeds get their own matrix; one kind, one speed."""
    inst = small_instance(
        vehicles=(
            Vehicle("sonar1", (5.0, 5.0), 1.0, "sonar"),
            Vehicle("camera1", (95.0, 5.0), 2.0, "camera"),
            Vehicle("sonar2", (95.0, 95.0), 1.0, "sonar"),
        ),
        obstacles=(),
        field=None,
    )
    problem = capability_problem_from_instance(inst)
    np.testing.assert_allclose(problem.cost_for("camera"), problem.cost_for("sonar") / 2)
    mixed = inst.replace(
        vehicles=(*inst.vehicles[:2], Vehicle("sonar2", (95.0, 95.0), 3.0, "sonar"))
    )
    with pytest.raises(InstanceError, match="capability 'sonar' have different speeds"):
        capability_problem_from_instance(mixed)


def test_bad_input_is_named_before_solving():
    """A demand no vehicle serves, a target in an obstacle, an unreachable demanded target."""
    with pytest.raises(InstanceError, match="demands capability 'lidar', which no vehicle has"):
        small_instance(targets=(Target("t0", (20.0, 80.0), ("lidar",)),))
    with pytest.raises(InstanceError, match="demands capability 'lidar', which no vehicle has"):
        CapabilityProblem(np.ones((2, 2)), 1, ["sonar"], [{"lidar"}])
    inside = small_instance(targets=(Target("t9", (50.0, 35.0), ("sonar",)),))
    with pytest.raises(InstanceError, match="target 't9' .* inside obstacle 'south'"):
        capability_problem_from_instance(inside)
    walled = small_instance(targets=(Target("t0", (50.0, 50.0), ("camera",)),), obstacles=RING)
    with pytest.raises(InstanceError, match="target 0 demands capability 'camera' but no vehicle"):
        capability_problem_from_instance(walled, cell=5.0)


def test_evaluate_names_target_and_capability():
    """The scorer checks (3.2) and capabilities, naming the target and the capability."""
    x = np.array([1.0, 2.0, 0.0, 3.0])
    p = CapabilityProblem(abs(x[:, None] - x[None, :]), 2, ["a", "b"], [{"a"}, {"a", "b"}])
    assert taopt.evaluate(p, [[0, 1], [1]]) == 3.0
    with pytest.raises(FeasibilityError, match="target 1 is never served for capability 'b'"):
        taopt.evaluate(p, [[0, 1], []])
    with pytest.raises(FeasibilityError, match="vehicle 1 .* visits target 0, which does not"):
        taopt.evaluate(p, [[0, 1], [0, 1]])
    with pytest.raises(FeasibilityError, match="target 0 is served twice for capability 'a'"):
        taopt.evaluate(p, [[0, 1, 0], [1]])


def test_thesis_scenario_is_deterministic_and_valid():
    """Same seed, same scenario; points avoid the obstacles; every capability has a vehicle."""
    a = thesis_scenario(20, 6, 3, seed=7)
    b = thesis_scenario(20, 6, 3, seed=7)
    np.testing.assert_array_equal(a.problem.cost, b.problem.cost)
    assert a.problem.demands == b.problem.demands
    assert a.problem.vehicle_capability == b.problem.vehicle_capability
    pts = a.instance.points
    for obstacle in THESIS_OBSTACLES:
        assert not obstacle.contains(pts).any()
    assert set(a.problem.vehicle_capability) == {"c0", "c1", "c2"}
    assert np.isfinite(a.problem.cost).all()
    c = thesis_scenario(20, 6, 3, seed=8)
    assert not np.array_equal(a.problem.cost, c.problem.cost)


def test_random_demands_are_non_empty_subsets():
    """Each target demands a non-empty subset, about half the capabilities on average."""
    rng = np.random.default_rng(0)
    demands = random_demands(rng, 4000, ["a", "b", "c", "d"])
    sizes = np.array([len(d) for d in demands])
    assert sizes.min() >= 1 and sizes.max() <= 4
    assert sizes.mean() == pytest.approx(4 * 0.5 / (1 - 0.5**4), rel=0.03)


def test_json_round_trip_and_schema():
    """to_dict/from_dict round-trips (inf as null); the schema rejects a bad file by path."""
    cost = np.array([[0, np.inf, 2, 5], [1, 0, 2, 4], [3, 4, 0, 1], [3, 4, 1, 0.0]])
    p = CapabilityProblem(cost, 2, ["a", "b"], [{"a"}, {"b"}], name="tiny")  # 0 -> 1 unused
    data = p.to_dict()
    assert data["cost"][0][1] is None
    q = CapabilityProblem.from_dict(data)
    np.testing.assert_array_equal(q.cost, p.cost)
    assert q.demands == p.demands and q.name == "tiny"
    data["demands"][1] = []
    with pytest.raises(InstanceError, match=r"demands\[1\]"):
        CapabilityProblem.from_dict(data)
    from taopt.orchestration.pipeline import load_problem

    assert load_problem(p.to_dict()).n == 2


def test_bounds_order_on_a_metric_instance():
    """arborescence <= optimum <= f^da; f^da = 2 f^a on symmetric costs."""
    from taopt.orchestration.studies.capability_claims import exact_optimum

    x = np.random.default_rng(3).uniform(0, 100, (9, 2))
    cost = np.linalg.norm(x[:, None] - x[None], axis=2)
    p = CapabilityProblem(cost, 6, ["a", "b", "a"], [{"a"}, {"b"}, {"a", "b"}, {"a"}, {"b"}, {"a"}])
    optimum = exact_optimum(p)[0]
    assert arborescence(p) <= optimum + 1e-9
    assert thesis_mcga(p) <= optimum + 1e-9  # symmetric: Theorem 3.4 holds
    assert optimum <= doubled_arborescence(p) + 1e-9
    assert doubled_arborescence(p) == pytest.approx(2 * thesis_mcga(p))
