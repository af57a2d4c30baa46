"""The §3.3 grid planner: 8 and 16 neighbours, lattice error, obstacles, inf, Remark 3.1."""

from __future__ import annotations

import numpy as np
import pytest

from taopt.errors import InstanceError
from taopt.fields import UniformField, thesis_field
from taopt.navigation import travel_time_matrix
from taopt.navigation.grid import (
    LATTICE_ERROR,
    GridGraph,
    crossed_cells,
    grid_travel_time_matrix,
    lattice_error_bound,
)
from taopt.navigation.uniform import uniform_travel_times

SQUARE = (0.0, 1000.0, 0.0, 1000.0)
THESIS_OBSTACLES = [
    [(150, 100), (300, 100), (300, 120), (150, 120)],
    [(400, 350), (420, 350), (420, 500), (400, 500)],
    [(600, 600), (750, 600), (750, 620), (600, 620)],
]


def centres(raw: np.ndarray, cell: float) -> np.ndarray:
    return (np.floor(raw / cell) + 0.5) * cell


def triangle_excess(matrix: np.ndarray) -> float:
    """Largest t(i, k) - (t(i, j) + t(j, k)) over finite triples, relative to the entry."""
    via = np.min(matrix[:, :, None] + matrix[None, :, :], axis=1)
    finite = np.isfinite(matrix)
    return float(np.max(np.where(finite, (matrix - via) / np.maximum(matrix, 1.0), -np.inf)))


def test_crossed_cells_fractions_add_to_one():
    """Every move's crossed cells start at its own cell, end at the neighbour, sum to 1."""
    from taopt.navigation.grid import MOVES_16

    for move in MOVES_16:
        cells = crossed_cells(move)
        assert cells[0][0] == (0, 0) and cells[-1][0] == move
        assert sum(f for _, f in cells) == pytest.approx(1.0)
        steps = [np.subtract(b[0], a[0]) for a, b in zip(cells[:-1], cells[1:], strict=True)]
        assert all(np.abs(s).sum() == 1 for s in steps) or len(cells) == 2  # edge-adjacent


@pytest.mark.parametrize("neighbours", [8, 16])
def test_still_water_lattice_error_within_theory(neighbours):
    """In still water grid/Euclid is in [1, 1 + LATTICE_ERROR] and nearly reaches the top."""
    rng = np.random.default_rng(1)
    pts = centres(rng.uniform(0, 200, (40, 2)), 1.0)
    grid = grid_travel_time_matrix(None, pts, (0, 200, 0, 200), 1.0, neighbours=neighbours)
    euclid = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    off = euclid > 0
    ratio = grid[off] / euclid[off]
    assert ratio.min() >= 1 - 1e-12
    assert ratio.max() <= 1 + LATTICE_ERROR[neighbours] + 1e-12
    assert ratio.max() > 1 + 0.8 * LATTICE_ERROR[neighbours]


def test_lattice_error_constants():
    """8.24 % and 2.75 % in still water; the bound grows with the current."""
    assert LATTICE_ERROR[8] == pytest.approx(1 / np.cos(np.pi / 8) - 1)
    assert LATTICE_ERROR[8] == pytest.approx(0.0824, abs=1e-4)
    assert LATTICE_ERROR[16] == pytest.approx(0.0275, abs=1e-4)
    assert lattice_error_bound(0.0, 8) == pytest.approx(LATTICE_ERROR[8], abs=1e-6)
    assert lattice_error_bound(0.0, 16) == pytest.approx(LATTICE_ERROR[16], abs=1e-6)
    assert lattice_error_bound(0.5, 8) > lattice_error_bound(0.2, 8) > LATTICE_ERROR[8]


@pytest.mark.parametrize("neighbours", [8, 16])
def test_uniform_current_lattice_error_within_bound(neighbours):
    """In a uniform current the ratio to the closed form (3.4) is in [1, 1 + bound(|v_c|)]."""
    field = UniformField(0.4, -0.25)
    rng = np.random.default_rng(2)
    pts = centres(rng.uniform(0, 100, (30, 2)), 1.0)
    grid = grid_travel_time_matrix(field, pts, (0, 100, 0, 100), 1.0, neighbours=neighbours)
    exact = uniform_travel_times([0.4, -0.25], pts[:, None], pts[None], 1.0)
    off = exact > 0
    ratio = grid[off] / exact[off]
    assert ratio.min() >= 1 - 1e-12
    assert ratio.max() <= 1 + lattice_error_bound(float(np.hypot(0.4, 0.25)), neighbours) + 1e-4


@pytest.mark.slow
@pytest.mark.parametrize("cell", [20.0, 10.0])
def test_thesis_field_grid_never_below_collocation(cell):
    """On the obstacle-free thesis field grid >= collocation, within the current's bound."""
    field = thesis_field()
    pts = centres(np.random.default_rng(3).uniform(0, 1000, (7, 2)), cell)
    reference = travel_time_matrix(field, pts, jobs=1)
    strongest = field.max_speed(SQUARE)
    off = ~np.eye(len(pts), dtype=bool)
    for neighbours in (8, 16):
        grid = grid_travel_time_matrix(field, pts, SQUARE, cell, neighbours=neighbours)
        ratio = grid[off] / reference[off]
        assert ratio.min() >= 1 - 1e-6  # collocation is converged to ~1e-8
        assert ratio.max() <= 1 + lattice_error_bound(strongest, neighbours) + 1e-3


def test_sixteen_neighbours_never_slower_than_eight():
    """The 16-move graph contains the 8-move graph, so its times are never larger."""
    field = thesis_field(1e-2)
    pts = np.random.default_rng(4).uniform(0, 100, (12, 2))
    obstacles = [[(40, 10), (45, 10), (45, 90), (40, 90)]]
    eight = grid_travel_time_matrix(field, pts[pts[:, 0] < 39], (0, 100, 0, 100), 2.0, obstacles)
    sixteen = grid_travel_time_matrix(
        field, pts[pts[:, 0] < 39], (0, 100, 0, 100), 2.0, obstacles, neighbours=16
    )
    assert np.all(sixteen <= eight + 1e-12)


@pytest.mark.parametrize("neighbours", [8, 16])
def test_triangle_inequality_exact_where_finite(neighbours):
    """Remark 3.1: the matrix (legs included) satisfies the triangle inequality exactly."""
    graph = GridGraph(thesis_field(), SQUARE, 10.0, THESIS_OBSTACLES, neighbours=neighbours)
    rng = np.random.default_rng(5)
    pts = rng.uniform(0, 1000, (60, 2))
    free = ~graph.blocked[graph.cell_index(pts)]
    pts = np.vstack([pts[free], pts[free][:2] + 0.3])  # two pairs sharing a cell
    matrix = graph.travel_time_matrix(pts)
    assert np.isfinite(matrix).all()
    assert triangle_excess(matrix) <= 1e-12


@pytest.mark.parametrize("neighbours", [8, 16])
def test_paths_never_enter_obstacle_cells(neighbours):
    """Every point of every planned path lies in a free cell; path time equals the matrix."""
    graph = GridGraph(thesis_field(), SQUARE, 10.0, THESIS_OBSTACLES, neighbours=neighbours)
    pairs = [((200, 60), (220, 160)), ((380, 420), (440, 430)), ((680, 560), (690, 660))]
    pts = np.array([p for pair in pairs for p in pair], dtype=float)
    matrix = graph.travel_time_matrix(pts)
    for k in range(len(pairs)):
        line = graph.path(pts[2 * k], pts[2 * k + 1])
        assert graph.path_time(line) == pytest.approx(matrix[2 * k, 2 * k + 1], rel=1e-12)
        for a, b in zip(line[:-1], line[1:], strict=True):
            for s in (np.arange(100) + 0.5) / 100:  # open segment (a corner move may touch)
                xy = (1 - s) * a + s * b
                cell = graph.cell_index(xy[None])[0]
                assert not graph.blocked[cell], f"path enters blocked cell at {xy}"
        straight = uniform_travel_times(
            graph.field.velocity(pts[2 * k])[0], *pts[2 * k : 2 * k + 2]
        )
        assert matrix[2 * k, 2 * k + 1] > 1.05 * straight  # a detour round the obstacle


def test_knight_move_cannot_jump_a_thin_wall():
    """A one-cell wall blocks 16-neighbour moves too (every crossed cell is checked)."""
    wall = [(4.2, 0), (4.8, 0), (4.8, 9), (4.2, 9)]  # overlaps column 4 only, rows 0..8
    pts = [[3.5, 4.5], [5.5, 4.5]]
    for neighbours in (8, 16):
        graph = GridGraph(None, (0, 10, 0, 10), 1.0, [wall], neighbours=neighbours)
        assert graph.blocked.reshape(10, 10)[4, :9].all() and not graph.blocked[4 * 10 + 9]
        t = graph.travel_time_matrix(pts)[0, 1]
        assert t >= 2 * np.hypot(1, 4.5) - 1e-9  # must go round the top of the wall


def test_partial_overlap_blocks_but_touching_does_not():
    """A cell is blocked when an obstacle overlaps its interior, not when it only touches it."""
    box = [(2.0, 2.0), (4.3, 2.0), (4.3, 4.0), (2.0, 4.0)]
    graph = GridGraph(None, (0, 10, 0, 10), 1.0, [box])
    blocked = graph.blocked.reshape(10, 10)
    assert blocked[2:5, 2:4].all()  # column 4 overlapped by 0.3
    assert not blocked[1, 2] and not blocked[2, 1] and not blocked[2, 4] and not blocked[5, 2]


def test_unreachable_pairs_are_inf():
    """A walled-in point, and a current too strong to stem, give inf (never a big number)."""
    ring = [
        [(3, 3), (7, 3), (7, 4), (3, 4)],
        [(3, 6), (7, 6), (7, 7), (3, 7)],
        [(3, 4), (4, 4), (4, 6), (3, 6)],
        [(6, 4), (7, 4), (7, 6), (6, 6)],
    ]
    pts = [[5.5, 5.5], [1.5, 1.5], [8.5, 8.5]]
    t = grid_travel_time_matrix(None, pts, (0, 10, 0, 10), 1.0, ring, neighbours=16)
    assert np.isinf(t[0, 1:]).all() and np.isinf(t[1:, 0]).all()
    assert np.isfinite(t[1:, 1:]).all()
    fast = grid_travel_time_matrix(
        UniformField(1.5, 0.0), [[1.5, 5.5], [8.5, 5.5]], (0, 10, 0, 10), 1.0
    )
    assert np.isfinite(fast[0, 1]) and np.isinf(fast[1, 0])  # v = 1 < |v_c| = 1.5 upstream


def test_bad_input_is_named():
    """Points in obstacles or outside, bad cells and neighbourhoods raise InstanceError."""
    box = [(0.0, 0.0), (5.0, 0.0), (5.0, 5.0), (0.0, 5.0)]
    with pytest.raises(InstanceError, match="point 0 .* blocked"):
        grid_travel_time_matrix(None, [[2, 2], [8, 8]], (0, 10, 0, 10), 1.0, [box])
    with pytest.raises(InstanceError, match="outside the grid"):
        grid_travel_time_matrix(None, [[2, 2], [18, 8]], (0, 10, 0, 10), 1.0)
    with pytest.raises(InstanceError, match="neighbours must be 8 or 16"):
        grid_travel_time_matrix(None, [[2, 2]], (0, 10, 0, 10), 1.0, neighbours=4)
    with pytest.raises(InstanceError, match="cell size"):
        grid_travel_time_matrix(None, [[2, 2]], (0, 10, 0, 10), 0.0)
