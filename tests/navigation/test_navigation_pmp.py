"""Vectorised Pontryagin shooting (taopt.navigation.pmp) against collocation, closed forms and
an independent integrator; its guards, fallback and reporting."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from taopt.errors import InstanceError
from taopt.fields import Field, GriddedField, LinearField, UniformField, thesis_field
from taopt.navigation import min_time_path, navigation_law, pmp, travel_time_matrix
from taopt.navigation.checks import matrix_report
from taopt.navigation.collocation import CollocationSolver
from taopt.navigation.pmp import pmp_travel_times, triangle_violations
from taopt.navigation.uniform import uniform_travel_times


def thesis_points(n_targets: int, n_vehicles: int, seed: int) -> np.ndarray:
    """Targets then vehicle starts, uniform in the thesis's 1000 m square (§2.5)."""
    rng = np.random.default_rng(seed)
    return np.vstack([rng.uniform(0, 1000, (n_targets, 2)), rng.uniform(0, 1000, (n_vehicles, 2))])


def all_pairs(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.nonzero(~np.eye(n, dtype=bool))


def reintegrate(field: Field, start, heading: float, duration: float, speed: float = 1.0):
    """End point of (2.1)+(2.6) by scipy's adaptive DOP853 (independent of pmp's fixed steps)."""

    def rhs(t, z):
        psi = z[2]
        law = navigation_law(field, z[None, :2], np.array([psi]))[0]
        drift = field.velocity(z[:2])[0]
        return [speed * np.cos(psi) + drift[0], speed * np.sin(psi) + drift[1], law]

    sol = solve_ivp(rhs, (0.0, duration), [*start, heading], "DOP853", rtol=1e-12, atol=1e-10)
    return sol.y[:2, -1]


class JetField(Field):
    """A current ``(U cos(y / L), 0)`` along x; going upstream on the axis y = 0 meets the
    strongest headwind, and the extremals leaving ``a`` against it focus (conjugate points)."""

    kind = "jet"

    def __init__(self, U: float = 0.6, L: float = 20.0) -> None:
        self.U, self.L = U, L

    def velocity(self, xy):
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        return np.column_stack([self.U * np.cos(xy[:, 1] / self.L), np.zeros(len(xy))])

    def jacobian(self, xy):
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        jac = np.zeros((len(xy), 2, 2))
        jac[:, 0, 1] = -self.U / self.L * np.sin(xy[:, 1] / self.L)
        return jac

    def casadi(self, x, y):
        return self.U * ca.cos(y / self.L), 0 * x

    def max_speed(self, region):
        return self.U

    def to_dict(self):
        return {"kind": self.kind, "U": self.U, "L": self.L}


pmp.is_smooth.register(JetField, lambda field: True)


# -- the thesis's field: accuracy, Lemma 2.3 -------------------------------------------------------


def check_against_refined_collocation(samples: int, seed: int) -> None:
    points = thesis_points(120, 20, seed=0)
    field = thesis_field(1e-3)
    matrix, info = travel_time_matrix(field, points, return_info=True)
    assert info["method"] == "pmp" and info["fallback"] == [] and info["suspect"] == []
    rows, cols = all_pairs(len(points))
    pick = np.random.default_rng(seed).choice(rows.size, samples, replace=False)
    fine = CollocationSolver(field, intervals=16)
    worst = 0.0
    for r in pick:
        i, j = rows[r], cols[r]
        ref = fine.solve(points[i], points[j])
        assert ref.success
        worst = max(worst, abs(matrix[i, j] - ref.time) / ref.time)
    assert worst < 1e-8


def test_thesis_140_matrix_matches_refined_collocation_on_a_sample():
    """120 + 20 points: every sampled entry within 1e-8 of collocation on 16 intervals."""
    check_against_refined_collocation(samples=120, seed=1)


@pytest.mark.slow
def test_thesis_140_matrix_matches_refined_collocation_on_500_pairs():
    """The same on 500 sampled pairs."""
    check_against_refined_collocation(samples=500, seed=2)


def test_triangle_inequality_on_all_triples_of_60_points():
    """Lemma 2.3 within 1e-8 relative on every triple of a 50 + 10 point matrix."""
    matrix = travel_time_matrix(thesis_field(1e-3), thesis_points(50, 10, seed=3))
    report = matrix_report(matrix)
    assert report.triangle_holds(1e-8), report.summary()
    assert report.max_relative_asymmetry > 0.05  # and asymmetric
    assert triangle_violations(matrix, 1e-8) == []


def test_pmp_agrees_with_shooting_and_an_independent_integrator_fig21():
    """Fig. 2.1's field: pmp equals CVODES shooting, and re-integrating its extremal by scipy
    from (psi(0), T) lands on the goal."""
    field = thesis_field(1e-2)
    pairs = np.random.default_rng(4).uniform(0, 100, (12, 2, 2))
    out = pmp_travel_times(field, pairs[:, 0], pairs[:, 1])
    assert out.accepted.all()
    for k, (a, b) in enumerate(pairs):
        shoot = min_time_path(field, a, b, method="shooting").time
        assert out.time[k] == pytest.approx(shoot, rel=1e-9)
        end = reintegrate(field, a, out.heading[k], out.time[k])
        assert np.linalg.norm(end - b) < 1e-7 * np.linalg.norm(b - a)
    assert np.all(out.time <= out.line_time)  # never slower than the straight line


def test_min_time_path_pmp_ends_at_the_goal_and_matches_collocation():
    """The decoded pmp path starts at a, ends at b, and its time is collocation's."""
    field = thesis_field(1e-2)
    a, b = np.array([10.0, 80.0]), np.array([90.0, 15.0])
    path = min_time_path(field, a, b, method="pmp")
    np.testing.assert_allclose(path.xy[0], a, atol=1e-12)
    np.testing.assert_allclose(path.xy[-1], b, atol=1e-6)
    assert path.t[-1] == pytest.approx(path.time) and path.method == "pmp"
    assert path.time == pytest.approx(min_time_path(field, a, b).time, rel=1e-8)


def test_affine_field_every_extremal_is_the_minimum():
    """Newton from many initial headings and durations finds only one time per pair on a
    linear field (the convex reachable set argument in the module docstring)."""
    field = thesis_field(1e-2)
    pairs = np.random.default_rng(5).uniform(0, 100, (6, 2, 2))
    best = pmp_travel_times(field, pairs[:, 0], pairs[:, 1])
    offsets = np.array([-2.0, -1.0, -0.5, 0.5, 1.0, 2.0])
    scales = np.array([0.7, 1.5])
    psi0 = best.heading[:, None, None] + offsets[None, :, None] + 0 * scales
    T0 = best.time[:, None, None] * scales[None, None, :] + 0 * offsets[:, None]
    reps = offsets.size * scales.size
    starts = np.repeat(pairs[:, 0], reps, axis=0)
    goals = np.repeat(pairs[:, 1], reps, axis=0)
    out = pmp_travel_times(
        field, starts, goals, initial=(psi0.ravel(), T0.ravel()), max_iter=60, restarts=False
    )
    assert out.accepted.sum() >= reps  # most starts converge
    expected = np.repeat(best.time, reps)
    found = out.accepted
    np.testing.assert_allclose(out.time[found], expected[found], rtol=1e-9)


@settings(max_examples=12, deadline=None, derandomize=True)
@given(
    entries=st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6),
    strength=st.sampled_from([1e-3, 1e-2, 5e-2]),
    margin=st.sampled_from([1.02, 1.5]),
    seed=st.integers(0, 2**16),
)
def test_random_affine_fields_agree_with_shooting(entries, strength, margin, seed):
    """Random affine drifts v_c = A x + c on a 100 m square, v just above the strongest drift:
    every pair is accepted and equals CVODES shooting to 1e-8."""
    field = LinearField(strength * np.reshape(entries[:4], (2, 2)), 0.2 * np.array(entries[4:]))
    corners = np.array([[0, 0], [0, 100], [100, 0], [100, 100]], dtype=float)
    speed = max(0.05, margin * float(np.max(np.linalg.norm(field.velocity(corners), axis=1))))
    pairs = np.random.default_rng(seed).uniform(0, 100, (3, 2, 2))
    out = pmp_travel_times(field, pairs[:, 0], pairs[:, 1], speed)
    assert out.accepted.all() and not out.restarted.any()
    for k, (a, b) in enumerate(pairs):
        shoot = min_time_path(field, a, b, speed, method="shooting").time
        assert out.time[k] == pytest.approx(shoot, rel=1e-8)


# -- closed forms ---------------------------------------------------------------------------------


def test_uniform_field_equals_the_closed_form():
    """Uniform drift: pmp equals (3.4) to 1e-10; the matrix uses (3.4) itself."""
    drift = (0.3, -0.4)
    rng = np.random.default_rng(6)
    a, b = rng.uniform(0, 1000, (2, 200, 2))
    out = pmp_travel_times(UniformField(*drift), a, b, speed=1.2)
    exact = uniform_travel_times(drift, a, b, 1.2)
    assert out.accepted.all()
    np.testing.assert_allclose(out.time, exact, rtol=1e-10)


def test_still_water_is_euclidean_over_speed():
    """field None: pmp gives |b - a| / v, and so does the matrix."""
    rng = np.random.default_rng(7)
    a, b = rng.uniform(0, 50, (2, 100, 2))
    out = pmp_travel_times(None, a, b, speed=2.0)
    np.testing.assert_allclose(out.time, np.linalg.norm(b - a, axis=1) / 2.0, rtol=1e-12)
    points = rng.uniform(0, 50, (6, 2))
    matrix = travel_time_matrix(None, points, speed=2.0, method="pmp")
    np.testing.assert_allclose(
        matrix, np.linalg.norm(points[:, None] - points[None], axis=2) / 2.0, rtol=1e-12
    )


# -- gridded fields -------------------------------------------------------------------------------


def smooth_gridded_field() -> GriddedField:
    """B-spline samples of a rotating, stretching field with a sinusoidal part (100 m square)."""
    xs = ys = np.linspace(0.0, 100.0, 21)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    vx = 0.003 * X + 0.002 * Y + 0.1 * np.sin(Y / 15)
    vy = -0.002 * X + 0.003 * Y + 0.1 * np.cos(X / 20)
    return GriddedField(xs, ys, vx, vy)


def test_gridded_field_agrees_with_refined_collocation():
    """A B-spline GriddedField: pmp (tol 1e-8) within 1e-7 of collocation on 64 intervals, and
    the matrix keeps collocation as its default there."""
    field = smooth_gridded_field()
    pairs = np.random.default_rng(8).uniform(5, 95, (4, 2, 2))
    out = pmp_travel_times(field, pairs[:, 0], pairs[:, 1], tol=1e-8)
    assert out.accepted.all()
    fine = CollocationSolver(field, intervals=64)
    for k, (a, b) in enumerate(pairs):
        assert out.time[k] == pytest.approx(fine.solve(a, b).time, rel=1e-7)
    _, info = travel_time_matrix(field, pairs[:2, 0], return_info=True, jobs=1)
    assert info["method"] == "collocation"


def test_bilinear_gridded_field_is_refused():
    """Piecewise-bilinear drift has no continuous Jacobian: method 'pmp' says so."""
    xs = ys = np.linspace(0.0, 10.0, 3)
    field = GriddedField(xs, ys, np.zeros((3, 3)), np.zeros((3, 3)), method="linear")
    with pytest.raises(InstanceError, match="smooth"):
        travel_time_matrix(field, [[1, 1], [5, 5]], method="pmp")


# -- guards, fallback, reporting ------------------------------------------------------------------


def test_conjugate_point_is_rejected_and_restarts_find_the_faster_path():
    """Upstream on a jet's axis the straight extremal (T = 60 / (1 - 0.6) = 150 s) is past a
    conjugate point: rejected; the restarts find a path leaving the axis, and scipy confirms
    that this path reaches the goal sooner."""
    field = JetField()
    a, b = np.array([[0.0, 0.0]]), np.array([[-60.0, 0.0]])
    plain = pmp_travel_times(field, a, b, restarts=False)
    assert not plain.accepted[0] and plain.reason[0] == pmp.CONJUGATE
    assert plain.extremal_time[0] == pytest.approx(150.0, rel=1e-12)
    assert plain.line_time[0] == pytest.approx(150.0, rel=1e-12)
    out = pmp_travel_times(field, a, b)
    assert out.accepted[0] and out.restarted[0]
    assert out.time[0] < 0.9 * 150.0
    end = reintegrate(field, a[0], out.heading[0], out.time[0])
    assert np.linalg.norm(end - b[0]) < 1e-6


def test_rejected_pair_falls_back_and_is_reported_when_collocation_does_no_better():
    """Without restarts the jet pair goes to collocation, is named in info['fallback'], and,
    as collocation finds nothing faster than the rejected extremal, in info['suspect']."""
    points = np.array([[0.0, 0.0], [-60.0, 0.0], [-30.0, 10.0]])
    options = {"restarts": False}
    with pytest.warns(RuntimeWarning, match=r"\(0, 1\)"):
        matrix, info = travel_time_matrix(
            JetField(), points, method="pmp", jobs=1, return_info=True, pmp_options=options
        )
    assert info["fallback"] == [(0, 1)]
    assert info["fallback_reason"] == [pmp.CONJUGATE]
    assert (0, 1) in info["suspect"]
    assert matrix[0, 1] <= 150.0 * (1 + 1e-8)


def test_unconverged_pairs_fall_back_to_collocation_and_are_named():
    """max_iter too small for Newton: exactly the pairs pmp did not accept are re-solved by
    collocation, listed by (i, j), and their entries equal collocation's."""
    field = thesis_field(1e-2)
    points = np.random.default_rng(9).uniform(0, 100, (6, 2))
    options = {"max_iter": 3, "restarts": False}
    rows, cols = all_pairs(len(points))
    direct = pmp_travel_times(field, points[rows], points[cols], **options)
    expected = [(int(rows[r]), int(cols[r])) for r in direct.failed]
    assert 0 < len(expected) < rows.size  # a mix of accepted and failed pairs
    matrix, info = travel_time_matrix(field, points, jobs=1, return_info=True, pmp_options=options)
    assert info["fallback"] == expected
    assert set(info["fallback_reason"]) == {pmp.NOT_CONVERGED}
    reference = travel_time_matrix(field, points, method="collocation", jobs=1)
    for i, j in expected:
        assert matrix[i, j] == reference[i, j]
    accepted = direct.accepted
    np.testing.assert_array_equal(matrix[rows[accepted], cols[accepted]], direct.time[accepted])


def test_result_does_not_depend_on_jobs():
    """Fixed batches: one thread and two threads give the same matrix, bit for bit."""
    field = thesis_field(1e-3)
    points = thesis_points(45, 5, seed=10)  # 2450 pairs in two batches
    one = travel_time_matrix(field, points, jobs=1)
    two = travel_time_matrix(field, points, jobs=2)
    np.testing.assert_array_equal(one, two)


def test_progress_bar_and_coincident_points():
    """progress=True still works; coincident points get 0 both ways."""
    field = thesis_field(1e-2)
    matrix, info = travel_time_matrix(
        field, [[1, 1], [1, 1], [50, 60]], progress=True, return_info=True
    )
    assert info["method"] == "pmp"
    assert matrix[0, 1] == 0.0 and matrix[1, 0] == 0.0
    assert matrix[0, 2] == matrix[1, 2] > 0


def test_bad_input_is_named():
    """Mismatched pairs, a bad initial guess or a non-finite row raise InstanceError."""
    field = thesis_field(1e-2)
    with pytest.raises(InstanceError, match="differ in shape"):
        pmp_travel_times(field, [[0, 0], [1, 1]], [[2, 2]])
    with pytest.raises(InstanceError, match="initial"):
        pmp_travel_times(field, [[0, 0]], [[2, 2]], initial=([0.0], [-1.0]))
    with pytest.raises(InstanceError, match="goals row 0"):
        pmp_travel_times(field, [[0, 0]], [[np.nan, 2]])
    with pytest.raises(InstanceError, match="method"):
        travel_time_matrix(field, [[0, 0], [1, 1]], method="magic")


def test_triangle_violations_finds_a_planted_detour():
    """triangle_violations names (i, k) when t(i, k) exceeds a detour through j."""
    points = np.random.default_rng(11).uniform(0, 10, (8, 2))
    matrix = np.linalg.norm(points[:, None] - points[None], axis=2)
    assert triangle_violations(matrix) == []
    matrix[2, 5] *= 3.0
    assert triangle_violations(matrix) == [(2, 5)]
