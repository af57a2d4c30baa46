"""Minimum-time navigation: collocation against closed form and shooting, Lemma 2.3, (2.6)."""

from __future__ import annotations

import numpy as np
import pytest

from taopt.errors import ConvergenceError, InstanceError
from taopt.fields import LinearField, UniformField, thesis_field
from taopt.navigation import min_time_path, navigation_law, travel_time_matrix
from taopt.navigation.checks import heading_residual, matrix_report
from taopt.navigation.collocation import CollocationSolver
from taopt.navigation.uniform import uniform_travel_times


def random_pairs(n: int, side: float, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0.0, side, size=(n, 2, 2))


# -- uniform field: closed form (3.4) -------------------------------------------------------------


def test_closed_form_known_values():
    # along the drift: v + |v_c|; against it: v - |v_c|; across: sqrt(v^2 - |v_c|^2)
    drift = [0.5, 0.0]
    assert uniform_travel_times(drift, [0, 0], [3, 0], 1.0) == pytest.approx(2.0)
    assert uniform_travel_times(drift, [3, 0], [0, 0], 1.0) == pytest.approx(6.0)
    assert uniform_travel_times(drift, [0, 0], [0, 3], 1.0) == pytest.approx(3.0 / np.sqrt(0.75))


def test_uniform_collocation_equals_closed_form():
    field = UniformField(0.3, -0.4)
    for a, b in random_pairs(100, 1000.0, seed=1):
        path = min_time_path(field, a, b)
        exact = float(uniform_travel_times(field.velocity(a)[0], a, b, 1.0))
        assert path.success
        assert path.time == pytest.approx(exact, rel=1e-8)
        # the path is the straight segment (2.6 gives psi_dot = 0)
        direction = (b - a) / np.linalg.norm(b - a)
        offsets = (path.xy - a) @ np.array([-direction[1], direction[0]])
        assert np.max(np.abs(offsets)) < 1e-6 * np.linalg.norm(b - a)


def test_uniform_matrix_is_closed_form_and_still_water_is_euclidean():
    pts = np.random.default_rng(3).uniform(0, 100, (7, 2))
    field = UniformField(0.2, 0.1)
    T = travel_time_matrix(field, pts, speed=1.5)
    for i in range(7):
        for j in range(7):
            expected = (
                0.0 if i == j else min_time_path(field, pts[i], pts[j], 1.5, "closed_form").time
            )
            assert T[i, j] == pytest.approx(expected, rel=1e-12)
    still = travel_time_matrix(None, pts, speed=2.0)
    dist = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    np.testing.assert_allclose(still, dist / 2.0, rtol=1e-12)


# -- Fig. 2.1's field: collocation against shooting -----------------------------------------------


def test_collocation_agrees_with_shooting_fig21():
    """v = 1, v_c = 1e-2 [0.3x + 0.2y, -0.2x + 0.3y], points in a 100 m square (Fig. 2.1)."""
    field = thesis_field(1e-2)
    worst = 0.0
    for a, b in random_pairs(100, 100.0, seed=2):
        colloc = min_time_path(field, a, b)
        shoot = min_time_path(field, a, b, method="shooting")
        worst = max(worst, abs(colloc.time - shoot.time) / shoot.time)
        # shooting's end point is checked independently of either solver's claim
        assert np.linalg.norm(shoot.xy[-1] - b) < 1e-6
    assert worst < 1e-6


def test_fig21_asymmetry():
    """Lemma 2.3 / Fig. 2.1: t(1, 2) != t(2, 1) (our points, not the thesis's)."""
    field = thesis_field(1e-2)
    p1, p2 = np.array([10.0, 80.0]), np.array([90.0, 15.0])
    forward = min_time_path(field, p1, p2).time
    backward = min_time_path(field, p2, p1).time
    assert abs(forward - backward) / max(forward, backward) > 0.1


def test_heading_follows_navigation_law_and_residual_shrinks():
    field = thesis_field(1e-2)
    a, b = np.array([10.0, 80.0]), np.array([90.0, 15.0])
    residuals = []
    for intervals in (2, 4, 8, 16):
        path = min_time_path(field, a, b, intervals=intervals)
        residuals.append(heading_residual(field, path)["relative"])
    assert all(
        later < 0.5 * earlier for earlier, later in zip(residuals, residuals[1:], strict=False)
    )
    assert residuals[-1] < 1e-4
    shoot = min_time_path(field, a, b, method="shooting")
    assert heading_residual(field, shoot)["max"] == 0.0  # shooting integrates (2.6) itself


def test_navigation_law_matches_costate_direction():
    """(2.6) equals the rotation rate of -lambda with lambda_dot = -J^T lambda (2.8)."""
    field = LinearField([[0.01, -0.03], [0.02, 0.005]])
    xy = np.array([[1.0, 2.0]])
    for psi in np.linspace(-3, 3, 7):
        n = np.array([np.cos(psi), np.sin(psi)])
        ndot = -field.jacobian(xy)[0].T @ n
        rate = n[0] * ndot[1] - n[1] * ndot[0]
        assert navigation_law(field, xy, np.array([psi]))[0] == pytest.approx(rate, abs=1e-15)


def test_paths_start_and_end_at_the_points():
    field = thesis_field(1e-2)
    a, b = (5.0, 5.0), (60.0, 95.0)
    for method in ("collocation", "shooting"):
        path = min_time_path(field, a, b, method=method)
        np.testing.assert_allclose(path.xy[0], a, atol=1e-9)
        np.testing.assert_allclose(path.xy[-1], b, atol=1e-6)
        assert path.t[0] == 0.0 and path.t[-1] == pytest.approx(path.time)
        assert path.xy.shape == (len(path.heading), 2)
        assert path.method == method and path.iterations > 0


def test_collocation_path_is_dynamically_feasible():
    """Re-integrate (2.1) with the collocated heading (interpolated) and land near the goal."""
    from scipy.integrate import solve_ivp

    field = thesis_field(1e-2)
    a, b = np.array([20.0, 10.0]), np.array([70.0, 90.0])
    path = min_time_path(field, a, b, intervals=16)
    heading = np.unwrap(path.heading)

    def rhs(t, x):
        psi = np.interp(t, path.t, heading)  # piecewise-linear heading (fine grid)
        return np.array([np.cos(psi), np.sin(psi)]) + field.velocity(x)[0]

    sol = solve_ivp(rhs, (0, path.time), a, rtol=1e-10, atol=1e-10)
    assert np.linalg.norm(sol.y[:, -1] - b) < 1e-3 * np.linalg.norm(b - a)


def test_solver_is_reused_for_many_pairs():
    solver = CollocationSolver(thesis_field(1e-2))
    pairs = random_pairs(40, 100.0, seed=5)
    batch = solver.solve_batch(pairs[:, 0], pairs[:, 1], 1.0, size=16)
    single = np.array([solver.solve(a, b).time for a, b in pairs])
    assert batch[:, 1].all()
    np.testing.assert_allclose(batch[:, 0], single, rtol=1e-8)


# -- the thesis's field: the matrix ---------------------------------------------------------------


def check_matrix(n_targets: int, n_vehicles: int, jobs: int) -> None:
    rng = np.random.default_rng(7)
    pts = rng.uniform(0, 1000, (n_targets + n_vehicles, 2))
    field = thesis_field(1e-3)
    T = travel_time_matrix(field, pts, jobs=jobs)
    n = len(pts)
    assert T.shape == (n, n) and np.all(np.diag(T) == 0)
    off = ~np.eye(n, dtype=bool)
    assert np.all(T[off] > 0)
    report = matrix_report(T)
    assert report.max_relative_asymmetry > 0.05  # asymmetric (Lemma 2.3)
    assert report.triangle_holds(1e-6), report.summary()
    # a few entries re-solved by the independent method
    for i, j in [(0, 1), (1, 0), (n - 1, 2), (3, n - 2)]:
        ref = min_time_path(field, pts[i], pts[j], method="shooting").time
        assert T[i, j] == pytest.approx(ref, rel=1e-6)


def test_thesis_matrix_small():
    check_matrix(12, 3, jobs=1)


def test_thesis_matrix_60_points():
    """50 targets + 10 vehicles in the thesis's 1e-3 field on the 1000 m square (two workers)."""
    check_matrix(50, 10, jobs=2)


def test_matrix_reports_unconverged_pairs(monkeypatch):
    """A pair no method solves is named by index, never returned silently wrong."""
    from taopt.navigation import collocation, matrix, shooting

    def fail_batch(self, starts, goals, speed, size=32):
        out = np.zeros((len(starts), 3))
        out[:, 0] = 1.0
        out[:, 1] = 1.0
        out[1, 1] = 0.0  # the second pair (0, 2) "fails"
        return out

    def never(*args, **kwargs):
        raise ConvergenceError("no")

    monkeypatch.setattr(collocation.CollocationSolver, "solve_batch", fail_batch)
    monkeypatch.setattr(matrix, "collocation_path", never)
    monkeypatch.setattr(shooting, "shooting_path", never)
    pts = [[0, 0], [10, 0], [0, 10]]
    with pytest.raises(ConvergenceError, match=r"\(0, 2\)"):
        travel_time_matrix(thesis_field(1e-2), pts, method="collocation", jobs=1)


# -- bad input --------------------------------------------------------------------------------


def test_bad_input_raises_instance_error():
    field = thesis_field(1e-2)
    with pytest.raises(InstanceError, match="start"):
        min_time_path(field, (0, np.nan), (1, 1))
    with pytest.raises(InstanceError, match="speed"):
        min_time_path(field, (0, 0), (1, 1), speed=-1)
    with pytest.raises(InstanceError, match="method"):
        min_time_path(field, (0, 0), (1, 1), method="magic")
    with pytest.raises(InstanceError, match="uniform"):
        min_time_path(field, (0, 0), (1, 1), method="closed_form")
    with pytest.raises(InstanceError, match="Assumption 2.1"):
        min_time_path(field, (0, 0), (100, 100), speed=0.3)
    with pytest.raises(InstanceError, match="point 1"):
        travel_time_matrix(field, [[0, 0], [np.inf, 1]])
    with pytest.raises(InstanceError, match="shape"):
        travel_time_matrix(field, [1, 2, 3])


def test_same_point_is_zero_time():
    field = thesis_field(1e-2)
    assert min_time_path(field, (3, 4), (3, 4)).time == 0.0
    T = travel_time_matrix(field, [[1, 1], [1, 1], [5, 5]], jobs=1)
    assert T[0, 1] == 0.0 and T[1, 0] == 0.0 and T[0, 2] > 0


# -- checks --------------------------------------------------------------------------------


def test_matrix_report_finds_planted_violation():
    rng = np.random.default_rng(0)
    pts = rng.uniform(0, 10, (30, 2))
    T = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    report = matrix_report(T)
    assert report.max_asymmetry == 0.0 and report.worst_triangle <= 1e-12
    T[4, 9] = T[4, 9] * 3  # now t(4, 9) > t(4, j) + t(j, 9) for some j
    report = matrix_report(T)
    assert report.worst_triple[0] == 4 and report.worst_triple[2] == 9
    i, j, k = report.worst_triple
    assert report.worst_triangle == pytest.approx((T[i, k] - T[i, j] - T[j, k]) / T[i, k])
    brute = max(
        (T[a, c] - T[a, b] - T[b, c]) / T[a, c]
        for a in range(30)
        for b in range(30)
        for c in range(30)
        if len({a, b, c}) == 3
    )
    assert report.worst_triangle == pytest.approx(brute)
    assert report.asymmetric_pair == (4, 9)


# -- grid planner (§3.3) ---------------------------------------------------------------------------


def test_grid_uniform_lattice_directions_match_closed_form():
    from taopt.navigation.grid import grid_travel_time_matrix

    field = UniformField(0.3, -0.2)
    pts = np.array([[0.5, 0.5], [7.5, 0.5], [7.5, 7.5], [0.5, 7.5]])  # cell centres, lattice moves
    T = grid_travel_time_matrix(field, pts, (0, 10, 0, 10), cell=1.0)
    exact = uniform_travel_times(field.velocity(pts[:1])[0], pts[:, None], pts[None], 1.0)
    np.testing.assert_allclose(T, exact, rtol=1e-12)


def test_grid_obstacle_detour_and_triangle_inequality():
    from taopt.navigation.grid import GridGraph

    field = thesis_field(1e-2)
    wall = [(40.0, 10.0), (45.0, 10.0), (45.0, 100.0), (40.0, 100.0)]
    pts = np.random.default_rng(4).uniform(0, 38, (8, 2))
    pts = np.vstack([pts, [[80.0, 80.0], [90.0, 60.0]]])
    free = GridGraph(field, (0, 100, 0, 100), 2.0).travel_time_matrix(pts)
    walled_graph = GridGraph(field, (0, 100, 0, 100), 2.0, obstacles=[wall])
    walled = walled_graph.travel_time_matrix(pts)
    assert np.all(walled >= free - 1e-9) and walled[0, 8] > free[0, 8]
    assert matrix_report(walled).worst_triangle <= 1e-12  # Remark 3.1
    route = walled_graph.path(pts[0], pts[8])
    assert route[:, 1].min() < 10.0  # goes round the bottom of the wall
    # the grid time is never below the continuous minimum time (8 directions only)
    for i, j in [(0, 8), (8, 0), (2, 9)]:
        assert free[i, j] >= 0.98 * min_time_path(field, pts[i], pts[j]).time


def test_grid_rejects_points_in_obstacles():
    from taopt.navigation.grid import grid_travel_time_matrix

    box = [(0.0, 0.0), (5.0, 0.0), (5.0, 5.0), (0.0, 5.0)]
    with pytest.raises(InstanceError, match="point 0 .* blocked"):
        grid_travel_time_matrix(None, [[2, 2], [8, 8]], (0, 10, 0, 10), 1.0, [box])
    with pytest.raises(InstanceError, match="outside the grid"):
        grid_travel_time_matrix(None, [[2, 2], [18, 8]], (0, 10, 0, 10), 1.0)


def test_figure_2_1_draws_both_paths(tmp_path):
    from taopt.plot import figure_2_1

    out = tmp_path / "fig21.png"
    fig = figure_2_1(out)
    assert out.exists() and out.stat().st_size > 1000
    labels = [line.get_label() for line in fig.axes[0].get_lines()]
    assert any(label.startswith("1 -> 2") for label in labels)
    assert any(label.startswith("2 -> 1") for label in labels)


def test_condition_3_5_alone_is_not_sufficient_when_drift_is_faster():
    """(3.5) |sin(theta_net - theta_c)| <= v / v_c holds straight upstream (sin = 0), yet with
    v < v_c both roots of (3.4) are negative: no heading makes headway; we also need v_net > 0."""
    from taopt.navigation.uniform import net_speed

    drift, upstream = np.array([1.0, 0.0]), np.array([-1.0, 0.0])
    along = drift @ upstream
    roots = np.roots([1.0, -2 * along, -(0.5**2 - drift @ drift)])  # (3.4) with v = 0.5
    assert np.all(roots.real < 0)
    assert np.isnan(net_speed(drift, upstream, 0.5))
    assert net_speed(drift, -upstream, 0.5) == pytest.approx(1.5)


def test_shooting_matrix_retries_a_failed_pair_by_collocation(monkeypatch):
    """A pair on which shooting fails is retried (collocation), not left wrong or raised raw."""
    import taopt.navigation.shooting as shooting_module
    from taopt.errors import ConvergenceError
    from taopt.fields import thesis_field
    from taopt.navigation import travel_time_matrix

    field = thesis_field(1e-2)
    points = np.array([[10.0, 20.0], [80.0, 70.0], [30.0, 90.0]])
    reference = travel_time_matrix(field, points, method="collocation", jobs=1)
    original = shooting_module.shooting_path

    def flaky(field_, start, goal, speed=1.0, **kw):
        if np.allclose(start, points[1]) and np.allclose(goal, points[2]):
            raise ConvergenceError("forced failure for the test")
        return original(field_, start, goal, speed, **kw)

    monkeypatch.setattr(shooting_module, "shooting_path", flaky)
    matrix, info = travel_time_matrix(field, points, method="shooting", return_info=True)
    assert (1, 2) in info["retried"]
    np.testing.assert_allclose(matrix, reference, rtol=1e-6)
