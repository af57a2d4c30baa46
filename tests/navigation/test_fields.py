"""Drift fields (2.1): vectorised velocity and Jacobian, validation, JSON round trip."""

from __future__ import annotations

import json

import casadi as ca
import numpy as np
import pytest

from taopt.errors import InstanceError
from taopt.fields import GriddedField, LinearField, UniformField, field_from_dict, thesis_field


def gridded_example() -> GriddedField:
    x = np.linspace(0, 100, 11)
    y = np.linspace(0, 80, 9)
    gx, gy = np.meshgrid(x, y, indexing="ij")
    return GriddedField(x, y, 0.2 * np.sin(gx / 30) + 0.001 * gy, 0.1 * np.cos(gy / 25))


FIELDS = {
    "uniform": UniformField(0.3, -0.1),
    "linear": LinearField([[0.003, 0.002], [-0.002, 0.003]], b=[0.1, -0.05]),
    "thesis": thesis_field(),
    "gridded": gridded_example(),
}


@pytest.fixture(params=sorted(FIELDS))
def field(request):
    """Each kind of field."""
    return FIELDS[request.param]


def sample_points(n: int = 25) -> np.ndarray:
    return np.random.default_rng(0).uniform([10, 10], [90, 70], size=(n, 2))


def test_velocity_is_vectorised(field):
    pts = sample_points()
    batch = field.velocity(pts)
    assert batch.shape == (len(pts), 2)
    one_by_one = np.vstack([field.velocity(p) for p in pts])
    np.testing.assert_allclose(batch, one_by_one, rtol=1e-12, atol=1e-15)


def test_jacobian_matches_finite_differences(field):
    pts = sample_points()
    jac = field.jacobian(pts)
    assert jac.shape == (len(pts), 2, 2)
    h = 1e-4
    for b in range(2):
        step = np.zeros(2)
        step[b] = h
        fd = (field.velocity(pts + step) - field.velocity(pts - step)) / (2 * h)
        np.testing.assert_allclose(jac[:, :, b], fd, rtol=1e-5, atol=1e-8)


def test_casadi_velocity_matches_numeric(field):
    sym = ca.MX if field.kind == "gridded" else ca.SX
    x, y = sym.sym("x"), sym.sym("y")
    vx, vy = field.casadi(x, y)
    fun = ca.Function("v", [x, y], [ca.vertcat(vx, vy)])
    for p in sample_points(5):
        np.testing.assert_allclose(
            np.asarray(fun(p[0], p[1])).ravel(), field.velocity(p)[0], rtol=1e-10, atol=1e-14
        )


def test_max_speed_bounds_samples(field):
    region = (0.0, 100.0, 0.0, 80.0)
    gx, gy = np.meshgrid(np.linspace(0, 100, 41), np.linspace(0, 80, 41))
    pts = np.column_stack([gx.ravel(), gy.ravel()])
    assert field.max_speed(region) >= field.speed(pts).max() - 1e-9
    where = field.argmax_speed(region)
    assert field.speed(where)[0] == pytest.approx(field.max_speed(region), rel=1e-6)


def test_json_round_trip(field):
    data = json.loads(json.dumps(field.to_dict()))
    again = field_from_dict(data)
    assert again == field and hash(again) == hash(field)
    np.testing.assert_allclose(again.velocity(sample_points()), field.velocity(sample_points()))


def test_thesis_field_values():
    # 1e-3 [0.3x + 0.2y, -0.2x + 0.3y] at (1000, 1000) is (0.5, 0.1): the square's strongest
    field = thesis_field()
    np.testing.assert_allclose(field.velocity([1000, 1000]), [[0.5, 0.1]])
    assert field.max_speed((0, 1000, 0, 1000)) == pytest.approx(np.hypot(0.5, 0.1))
    assert not field.is_uniform and LinearField(np.zeros((2, 2)), [1, 2]).is_uniform


@pytest.mark.parametrize(
    ("data", "match"),
    [
        ({"kind": "vortex"}, "unknown field kind 'vortex'"),
        ({"kind": "linear"}, "missing 'A'"),
        ({"kind": "uniform", "vx": 1.0}, "missing 'vy'"),
        ({"vx": 1.0}, "'kind'"),
        ({"kind": "linear", "A": [[1, 2, 3]]}, r"A: expected 2 rows of 2 numbers, got 1"),
        ({"kind": "uniform", "vx": float("nan"), "vy": 0}, "finite"),
    ],
)
def test_bad_field_data(data, match):
    with pytest.raises(InstanceError, match=match):
        field_from_dict(data)


def test_gridded_validation_names_the_problem():
    x, y = np.linspace(0, 1, 5), np.linspace(0, 1, 5)
    ok = np.zeros((5, 5))
    with pytest.raises(InstanceError, match="x must be strictly increasing"):
        GriddedField(x[::-1], y, ok, ok)
    with pytest.raises(InstanceError, match="vy must have shape"):
        GriddedField(x, y, ok, np.zeros((4, 5)))
    bad = ok.copy()
    bad[2, 3] = np.nan
    with pytest.raises(InstanceError, match=r"vx\[2, 3\]"):
        GriddedField(x, y, bad, ok)
    with pytest.raises(InstanceError, match="method"):
        GriddedField(x, y, ok, ok, method="cubic")
    with pytest.raises(InstanceError, match="shape"):
        UniformField(0, 0).velocity([1, 2, 3])
