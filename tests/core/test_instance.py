"""Instances: validation errors that name the item, Assumption 2.1, JSON with a schema version."""

from __future__ import annotations

import json

import numpy as np
import pytest

from taopt.errors import InstanceError
from taopt.fields import LinearField, thesis_field
from taopt.instance import Instance, Obstacle, Target, Vehicle, check_schema, load_json


def small(**changes) -> Instance:
    base = {
        "vehicles": (
            Vehicle("a", (0.0, 0.0)),
            Vehicle("b", (10.0, 10.0), speed=2.0, capability="camera"),
        ),
        "targets": (Target("t1", (5.0, 5.0)), Target("t2", (1.0, 9.0), demands=("any", "camera"))),
        "region": (0.0, 10.0, 0.0, 10.0),
        "field": thesis_field(1e-2),
        "obstacles": (Obstacle(((2.0, 2.0), (3.0, 2.0), (3.0, 3.0)), id="rock"),),
        "name": "small",
    }
    base.update(changes)
    return Instance(**base)


def test_points_order_targets_then_vehicles():
    inst = small()
    np.testing.assert_array_equal(inst.points, [[5, 5], [1, 9], [0, 0], [10, 10]])
    assert inst.n_targets == 2 and inst.n_vehicles == 2
    np.testing.assert_array_equal(inst.speeds, [1.0, 2.0])


def test_json_round_trip(tmp_path):
    inst = small(metadata={"seed": 3})
    path = tmp_path / "inst.json"
    inst.save(path)
    again = Instance.load(path)
    assert again == inst
    assert again.to_dict() == inst.to_dict()
    assert json.loads(path.read_text())["schema_version"] == 1


def test_random_is_reproducible():
    a = Instance.random(8, 3, side=1000.0, field=thesis_field(), seed=11)
    b = Instance.random(8, 3, side=1000.0, field=thesis_field(), seed=11)
    c = Instance.random(8, 3, side=1000.0, field=thesis_field(), seed=12)
    assert a == b and a != c
    assert a.points.shape == (11, 2)
    assert np.all((a.points >= 0) & (a.points <= 1000))


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"vehicles": ()}, "at least one vehicle"),
        ({"targets": ()}, "at least one target"),
        ({"region": (0, -1, 0, 10)}, "xmin < xmax"),
        ({"vehicles": (Vehicle("a", (0, 0)), Vehicle("a", (1, 1)))}, "duplicate id 'a'"),
        ({"targets": (Target("a", (1, 1)),)}, "duplicate id 'a' \\(target\\)"),
        ({"vehicles": (Vehicle("a", (0, 0), speed=0.0),)}, "vehicle 'a': speed must be positive"),
        ({"vehicles": (Vehicle("a", (20, 0)),)}, "vehicle 'a': start .* outside the region"),
        ({"targets": (Target("t9", (5, 50)),)}, "target 't9': position .* outside"),
        ({"targets": (Target("t9", (5, float("nan"))),)}, "target 't9': position .* not finite"),
        (
            {"targets": (Target("t9", (1, 1), demands=("sonar",)),)},
            "target 't9' demands capability 'sonar'",
        ),
        ({"targets": (Target("t9", (1, 1), demands=()),)}, "target 't9' demands no capability"),
        ({"obstacles": (Obstacle(((0, 0), (1, 1))),)}, "obstacle 0 needs at least 3 vertices"),
        ({"field": "strong"}, "field must be a taopt.fields.Field"),
    ],
)
def test_validation_names_the_item(changes, match):
    with pytest.raises(InstanceError, match=match):
        small(**changes)


def test_assumption_2_1_message_names_location_and_speeds():
    # drift 0.1 * [x, y] reaches |v_c| = 0.1 * sqrt(200) ~ 1.414 at the corner (10, 10)
    field = LinearField([[0.1, 0.0], [0.0, 0.1]])
    with pytest.raises(InstanceError) as info:
        small(field=field)
    message = str(info.value)
    assert "vehicle 'a'" in message and "Assumption 2.1" in message
    assert "speed 1 " in message and "1.41421" in message
    assert "(10.0, 10.0)" in message


def test_unknown_schema_version(tmp_path):
    data = small().to_dict()
    data["schema_version"] = 99
    with pytest.raises(InstanceError, match="unknown schema_version 99"):
        Instance.from_dict(data)
    with pytest.raises(InstanceError, match="expected a 'instance' file"):
        check_schema({"schema_version": 1, "kind": "problem"}, "instance")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(InstanceError, match="not valid JSON"):
        load_json(bad)
    missing = small().to_dict()
    del missing["vehicles"]
    with pytest.raises(InstanceError, match="missing 'vehicles'"):
        Instance.from_dict(missing)


def test_replace_revalidates():
    inst = small()
    with pytest.raises(InstanceError, match="outside"):
        inst.replace(region=(0.0, 5.0, 0.0, 5.0))


def test_obstacle_contains():
    obs = Obstacle(((0, 0), (2, 0), (2, 2), (0, 2)))
    np.testing.assert_array_equal(obs.contains([[1, 1], [3, 1]]), [True, False])


def test_load_errors_name_the_file(tmp_path):
    """Schema and constructor errors of Instance.load both start with the file's path."""
    data = small().to_dict()
    data["vehicles"][0]["start"] = ["0", 0]
    path = tmp_path / "bad-start.json"
    path.write_text(json.dumps(data))
    with pytest.raises(
        InstanceError, match=r"bad-start\.json: vehicles\[0\]\.start\[0\]: expected"
    ):
        Instance.load(path)
    data = small().to_dict()
    data["targets"][0]["position"] = [50.0, 5.0]
    path = tmp_path / "outside.json"
    path.write_text(json.dumps(data))
    with pytest.raises(InstanceError, match=r"outside\.json: target 't1': position .* outside"):
        Instance.load(path)
