"""Grid path planning in currents with obstacles (thesis §3.3): cells, (3.4)/(3.5), Dijkstra.

The region is cut into square cells of side ``l`` (``cell``). A cell is *blocked* when an
obstacle overlaps its interior (touching its boundary is not enough); a path never enters a
blocked cell. From each free cell the vehicle may move straight to

* 8 neighbours (Fig. 3.1, as printed): net-velocity direction ``theta_net = (i - 1) pi / 4``,
  distance ``l`` (edge neighbours) or ``sqrt(2) l`` (corner neighbours); or
* 16 neighbours: the 8 above plus the 8 "knight" cells ``(±1, ±2)``, ``(±2, ±1)`` at
  distance ``sqrt(5) l`` (directions ``atan(1/2)`` off the axes), which cuts the lattice
  error in still water from at most 8.24 % to at most 2.75 % (see Notes).

The current is constant within each cell (§3.3: "the currents within each square cell are
assumed to be the same"; its value at the cell centre). A move runs on the straight segment
between two cell centres, and the vehicle holds the net direction of the move (3.4) in each
cell it crosses, so its time is the sum over the crossed cells of (length inside the cell)
/ ``v_net`` of that cell, with

    v_net = v_c . d + sqrt(v**2 - |v_c|**2 + (v_c . d)**2)                    (3.4)

real iff (3.5) ``|sin(theta_net - theta_c)| <= v / v_c`` holds (and, when ``v < v_c``, also
``v_net > 0``: straight upstream satisfies (3.5) with both roots negative; see
:func:`taopt.navigation.uniform.net_speed`). An edge or corner move spends half its length
in each of its two cells (a corner move crosses the shared corner point); a knight move
crosses four cells, a quarter of its length in each. A move is impossible (no edge: ``inf``)
when a crossed cell is blocked or (3.4) has no positive root in one of them. The thesis
divides the whole distance by the ``v_net`` of the cell being left; splitting the move at
the cell boundaries is the same model of a piecewise-constant current, but second-order
accurate in the cell size, whereas the leaving-cell rule is first-order (its error is O(l),
of either sign depending on how the current changes along the move).

A point is joined to the centre of its own cell by a straight leg in that cell's current (so
the matrix is between the points themselves, not their cells); two points in the same cell
are joined directly. ``scipy.sparse.csgraph.dijkstra`` gives the shortest times between the
cells; ``inf`` marks a point that cannot reach another (walled in, or a current it cannot
stem).

Remark 3.1: the matrix satisfies the triangle inequality exactly (up to floating-point
rounding of sums), being made of shortest-path distances in one digraph plus legs that obey
it in a uniform current.

Notes
-----
Lattice error: a straight line between two adjacent lattice directions ``a`` and ``b`` is
replaced by a two-leg path along ``a`` and ``b``. In still water the worst ratio is at the
bisector, ``1 / cos((b - a) / 2)``: ``1 / cos(22.5°) = 1.0824`` for 8 neighbours and
``1 / cos(atan(1/2) / 2) = 1.0275`` for 16 (:data:`LATTICE_ERROR`). In a current the
set reachable in unit time is a disc of radius ``v`` centred at ``v_c``, seen off-centre
from the start, so the lattice directions cut it into unequal arcs and the worst ratio
grows with ``|v_c| / v`` (:func:`lattice_error_bound`: 13.3 % and 4.4 % at
``|v_c| = 0.51 v``, the strongest current of the thesis field on the 1000 m square). Building the graph is O(cells x neighbours);
one Dijkstra per distinct point cell, O(cells log cells) each.

References
----------
Thesis §3.3, (3.4), (3.5), Fig. 3.1, Fig. 3.2, Remark 3.1.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from taopt.errors import InstanceError
from taopt.fields import Field
from taopt.navigation.matrix import as_points
from taopt.navigation.path import as_field, as_speed
from taopt.navigation.uniform import net_speed, uniform_travel_times

#: The 8 moves of Fig. 3.1: label i = 1..8 has theta_net = (i - 1) pi / 4.
MOVES_8 = ((1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1))
#: The 16 moves: Fig. 3.1's 8 and the 8 knight moves, in order of angle.
MOVES_16 = (
    (1, 0),
    (2, 1),
    (1, 1),
    (1, 2),
    (0, 1),
    (-1, 2),
    (-1, 1),
    (-2, 1),
    (-1, 0),
    (-2, -1),
    (-1, -1),
    (-1, -2),
    (0, -1),
    (1, -2),
    (1, -1),
    (2, -1),
)
NEIGHBOURHOODS = {8: MOVES_8, 16: MOVES_16}
#: Worst relative excess of a lattice path over the straight line in a uniform current.
LATTICE_ERROR = {8: 1.0 / np.cos(np.pi / 8) - 1.0, 16: 1.0 / np.cos(np.arctan(0.5) / 2) - 1.0}


def crossed_cells(move: tuple[int, int]) -> tuple[tuple[tuple[int, int], float], ...]:
    """Cells crossed by the segment between two cell centres ``move`` apart, with fractions.

    Returns ``((da, db), fraction)`` pairs relative to the starting cell, in order: the
    share of the move's length inside each cell (the fractions add to 1).

    Example
    -------
    >>> crossed_cells((2, 1))
    (((0, 0), 0.25), ((1, 0), 0.25), ((1, 1), 0.25), ((2, 1), 0.25))
    """
    da, db = move
    if max(abs(da), abs(db)) == 1:
        return (((0, 0), 0.5), ((da, db), 0.5))
    sa, sb = (1 if da > 0 else -1), (1 if db > 0 else -1)
    if abs(da) == 2:  # (±2, ±1): x crosses first
        return (((0, 0), 0.25), ((sa, 0), 0.25), ((sa, sb), 0.25), ((da, db), 0.25))
    # (±1, ±2): y crosses first
    return (((0, 0), 0.25), ((0, sb), 0.25), ((sa, sb), 0.25), ((da, db), 0.25))


class GridGraph:
    """The weighted cell digraph of §3.3.

    Parameters
    ----------
    field : Field or None
        The drift (None: still water), taken constant over each cell.
    region : (xmin, xmax, ymin, ymax)
    cell : float
        Cell side ``l``; the last row/column may stick out of the region.
    obstacles : sequence
        Polygons: :class:`taopt.instance.Obstacle` objects, vertex arrays ``(K, 2)``, or
        objects with ``contains(xy) -> bool mask`` (then a cell is blocked when its centre
        or one of its corners is inside).
    speed : float
        Vehicle speed ``v``.
    neighbours : {8, 16}
        The move set (8: Fig. 3.1 as printed; 16: plus the knight moves).
    cut_corners : bool
        Allow a corner move whose two edge-adjacent cells are blocked (the segment then only
        touches them at the shared corner point; default True).

    Raises
    ------
    InstanceError
        A bad region, cell size, speed, neighbourhood or obstacle.

    Example
    -------
    >>> g = GridGraph(None, (0, 10, 0, 10), cell=1.0)
    >>> round(float(g.travel_time_matrix([[0.5, 0.5], [3.5, 3.5]])[0, 1]), 6)
    4.242641
    >>> round(float(GridGraph(None, (0, 10, 0, 10), 1.0, neighbours=16)
    ...     .travel_time_matrix([[0.5, 0.5], [4.5, 2.5]])[0, 1]), 6)  # two knight moves
    4.472136
    """

    def __init__(
        self,
        field: Field | None,
        region: Sequence[float],
        cell: float,
        obstacles: Sequence[Any] = (),
        speed: float = 1.0,
        neighbours: int = 8,
        cut_corners: bool = True,
    ) -> None:
        self.field = as_field(field)
        self.speed = as_speed(speed)
        try:
            xmin, xmax, ymin, ymax = (float(v) for v in region)
        except (TypeError, ValueError):
            raise InstanceError(
                f"region must be (xmin, xmax, ymin, ymax), got {region!r}"
            ) from None
        if not (xmin < xmax and ymin < ymax):
            raise InstanceError(f"region {tuple(region)} must have xmin < xmax and ymin < ymax")
        try:
            cell = float(cell)
        except (TypeError, ValueError):
            raise InstanceError(f"cell size must be a positive number, got {cell!r}") from None
        if not (np.isfinite(cell) and cell > 0):
            raise InstanceError(f"cell size must be positive, got {cell!r}")
        if neighbours not in NEIGHBOURHOODS:
            raise InstanceError(f"neighbours must be 8 or 16, got {neighbours!r}")
        self.region = (xmin, xmax, ymin, ymax)
        self.cell = cell
        self.neighbours = int(neighbours)
        self.nx = int(np.ceil((xmax - xmin) / cell - 1e-9))
        self.ny = int(np.ceil((ymax - ymin) / cell - 1e-9))
        cx = xmin + (np.arange(self.nx) + 0.5) * cell
        cy = ymin + (np.arange(self.ny) + 0.5) * cell
        gx, gy = np.meshgrid(cx, cy, indexing="ij")  # cell (a, b) has index a * ny + b
        self.centres = np.column_stack([gx.ravel(), gy.ravel()])
        self.blocked = np.zeros(len(self.centres), dtype=bool)
        for k, obs in enumerate(obstacles):
            self.blocked |= self._overlaps(obs, k)
        self.drift = self.field.velocity(self.centres)  # constant over each cell
        self.graph = self._edges(cut_corners)

    # -- construction ---------------------------------------------------------------------
    def _overlaps(self, obstacle: Any, k: int) -> np.ndarray:
        """Cells whose interior the obstacle overlaps."""
        vertices = getattr(obstacle, "vertices", None)
        if vertices is None and not hasattr(obstacle, "contains"):
            vertices = obstacle
        mask = np.zeros(len(self.centres), dtype=bool)
        half = self.cell / 2
        if vertices is None:  # only a membership test: centre and corners
            for dx in (0.0, -0.999 * half, 0.999 * half):
                for dy in (0.0, -0.999 * half, 0.999 * half):
                    mask |= np.asarray(obstacle.contains(self.centres + [dx, dy]), dtype=bool)
            return mask
        from matplotlib.path import Path as MplPath
        from matplotlib.transforms import Bbox

        vertices = np.asarray(vertices, dtype=float)
        if vertices.ndim != 2 or vertices.shape[1] != 2 or len(vertices) < 3:
            raise InstanceError(f"obstacle {k} must be a polygon with at least 3 vertices")
        if not np.isfinite(vertices).all():
            raise InstanceError(f"obstacle {k} has a vertex that is not finite")
        polygon = MplPath(np.vstack([vertices, vertices[:1]]), closed=True)
        low, high = vertices.min(axis=0), vertices.max(axis=0)
        near = np.flatnonzero(
            np.all(self.centres + half > low, axis=1) & np.all(self.centres - half < high, axis=1)
        )
        shrink = half * (1 - 1e-9)  # the open cell: touching its boundary does not count
        for index in near:
            x, y = self.centres[index]
            box = Bbox([[x - shrink, y - shrink], [x + shrink, y + shrink]])
            mask[index] = polygon.intersects_bbox(box, filled=True)
        return mask

    def _edges(self, cut_corners: bool) -> csr_matrix:
        nx, ny, n = self.nx, self.ny, self.nx * self.ny
        a, b = np.divmod(np.arange(n), ny)
        free = ~self.blocked
        rows, cols, times = [], [], []
        for move in NEIGHBOURHOODS[self.neighbours]:
            da, db = move
            ok = (a + da >= 0) & (a + da < nx) & (b + db >= 0) & (b + db < ny) & free
            direction = np.array(move, dtype=float)
            length = self.cell * float(np.linalg.norm(direction))
            unit = direction / np.linalg.norm(direction)
            time = np.zeros(n)
            for (ca, cb), share in crossed_cells(move):
                index = np.where(ok, (a + ca) * ny + (b + cb), 0)
                ok &= free[index]
                with np.errstate(invalid="ignore"):
                    vnet = net_speed(self.drift[index], unit, self.speed)  # (3.4), (3.5)
                ok &= np.isfinite(vnet)
                time = time + np.where(ok, share * length / np.where(ok, vnet, 1.0), 0.0)
            if da and db and abs(da) == abs(db) and not cut_corners:
                side1 = np.where(ok, (a + da) * ny + b, 0)
                side2 = np.where(ok, a * ny + (b + db), 0)
                ok &= free[side1] | free[side2]
            rows.append(np.flatnonzero(ok))
            cols.append(((a + da) * ny + (b + db))[ok])
            times.append(time[ok])
        return csr_matrix(
            (np.concatenate(times), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
        )

    # -- points ---------------------------------------------------------------------------
    def cell_index(self, points: Any) -> np.ndarray:
        """Cell index of each point, -1 outside the grid (no other check)."""
        pts = as_points(points)
        xmin, _, ymin, _ = self.region
        a = np.floor((pts[:, 0] - xmin) / self.cell).astype(int)
        b = np.floor((pts[:, 1] - ymin) / self.cell).astype(int)
        a = np.where(a == self.nx, self.nx - 1, a)  # points on the far edge
        b = np.where(b == self.ny, self.ny - 1, b)
        inside = (a >= 0) & (a < self.nx) & (b >= 0) & (b < self.ny)
        return np.where(inside, a * self.ny + b, -1)

    def cell_of(self, points: Any) -> np.ndarray:
        """Cell index of each point; :class:`InstanceError` if outside the grid or blocked."""
        pts = as_points(points)
        cells = self.cell_index(pts)
        outside = np.flatnonzero(cells < 0)
        if outside.size:
            k = int(outside[0])
            raise InstanceError(
                f"point {k} {pts[k].tolist()} is outside the grid region {self.region}"
            )
        blocked = np.flatnonzero(self.blocked[cells])
        if blocked.size:
            k = int(blocked[0])
            raise InstanceError(
                f"point {k} {pts[k].tolist()} lies in a blocked cell (inside an obstacle, or "
                f"in a cell of side {self.cell:g} that an obstacle overlaps)"
            )
        return cells

    def _legs(self, pts: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Straight times point -> own cell centre and back, in that cell's current."""
        drift = self.drift[cells]
        centre = self.centres[cells]
        out = uniform_travel_times(drift, pts, centre, self.speed)
        back = uniform_travel_times(drift, centre, pts, self.speed)
        return np.atleast_1d(out), np.atleast_1d(back)

    def travel_time_matrix(self, points: Any) -> np.ndarray:
        """Travel times between the points (``inf`` where one cannot reach another).

        ``t(i, j)`` = leg from point i to its cell centre + shortest cell path + leg from
        j's cell centre to point j; points in the same cell are joined straight.
        """
        pts = as_points(points)
        cells = self.cell_of(pts)
        unique, inverse = np.unique(cells, return_inverse=True)
        dist = dijkstra(self.graph, directed=True, indices=unique)[:, unique]
        out, back = self._legs(pts, cells)
        matrix = out[:, None] + dist[np.ix_(inverse, inverse)] + back[None, :]
        same = cells[:, None] == cells[None, :]
        if same.any():
            i, j = np.nonzero(same)
            matrix[i, j] = uniform_travel_times(self.drift[cells[i]], pts[i], pts[j], self.speed)
        np.fill_diagonal(matrix, 0.0)
        return matrix

    def path(self, start: Any, goal: Any) -> np.ndarray:
        """A shortest path as a polyline ``(K, 2)``: start, cell centres, goal.

        Raises
        ------
        InstanceError
            A point outside the grid or in a blocked cell, or ``goal`` unreachable.
        """
        pts = as_points(np.vstack([start, goal]))
        source, target = self.cell_of(pts)
        if source == target:
            return pts.copy()
        dist, pred = dijkstra(self.graph, directed=True, indices=source, return_predecessors=True)
        if not np.isfinite(dist[target]):
            raise InstanceError(
                f"{tuple(pts[1].tolist())} cannot be reached from {tuple(pts[0].tolist())} on the grid"
            )
        order = [int(target)]
        while order[-1] != source:
            order.append(int(pred[order[-1]]))
        return np.vstack([pts[:1], self.centres[order[::-1]], pts[1:]])

    def path_time(self, polyline: Any) -> float:
        """Time along a polyline of :meth:`path` by the same rules (legs and moves)."""
        xy = as_points(polyline)
        if len(xy) == 2:
            cell = self.cell_of(xy[:1])[0]
            return float(uniform_travel_times(self.drift[cell], xy[0], xy[1], self.speed))
        cells = self.cell_of(xy[1:-1])
        out, _ = self._legs(xy[:1], cells[:1])
        _, back = self._legs(xy[-1:], cells[-1:])
        total = float(out[0] + back[0])
        for u, w in zip(cells[:-1], cells[1:], strict=True):
            total += float(self.graph[u, w])
        return total


def lattice_error_bound(current: float, neighbours: int = 8, speed: float = 1.0) -> float:
    """Worst relative excess of a lattice path over the straight line in a uniform current.

    Maximised over the current's direction and the direction of travel (dense sampling,
    accurate to about 1e-5) for a current of magnitude ``current`` and vehicle speed
    ``speed``; ``current = 0`` gives :data:`LATTICE_ERROR`.

    Example
    -------
    >>> round(lattice_error_bound(0.0, 8), 4), round(lattice_error_bound(0.0, 16), 4)
    (0.0824, 0.0275)
    """
    if neighbours not in NEIGHBOURHOODS:
        raise InstanceError(f"neighbours must be 8 or 16, got {neighbours!r}")
    if not 0 <= current < speed:
        raise InstanceError(f"need 0 <= current < speed, got {current} and {speed}")
    moves = np.array(NEIGHBOURHOODS[neighbours], dtype=float)
    units = moves / np.linalg.norm(moves, axis=1)[:, None]
    following = np.roll(units, -1, axis=0)
    heading = np.linspace(0.0, 2 * np.pi, 721, endpoint=False)
    drift = current * np.column_stack([np.cos(heading), np.sin(heading)])  # (H, 2)
    share = np.linspace(0.0, 1.0, 401)[1:-1]
    worst = 0.0
    for a, b in zip(units, following, strict=True):
        d = (1 - share)[:, None] * a + share[:, None] * b  # directions inside the sector
        alpha, beta = np.linalg.solve(np.column_stack([a, b]), d.T)  # d = alpha a + beta b
        speed_a = net_speed(drift, a, speed)[:, None]
        speed_b = net_speed(drift, b, speed)[:, None]
        norm = np.linalg.norm(d, axis=1)
        straight = norm[None, :] / net_speed(drift[:, None, :], (d / norm[:, None])[None], speed)
        lattice = alpha[None, :] / speed_a + beta[None, :] / speed_b
        worst = max(worst, float(np.nanmax(lattice / straight)) - 1.0)
    return worst


def lattice_error_table(
    cells: Sequence[float] = (20.0, 10.0, 5.0, 2.5),
    neighbourhoods: Sequence[int] = (8, 16),
    n_points: int = 12,
    seed: int = 0,
    field: Field | None | str = "thesis",
    side: float = 1000.0,
    jobs: int | None = 1,
) -> Any:
    """Grid times against collocation on an obstacle-free square (the study of issue item 1).

    ``n_points`` random points are snapped to the centres of each grid (so no leg is
    involved and only the lattice and the cell-wise current matter); every ordered pair's
    grid time is divided by the direct-collocation minimum time of
    :func:`taopt.navigation.travel_time_matrix` between the same two points.

    Returns
    -------
    pandas.DataFrame
        One row per (cell, neighbours): ``pairs``, ``min_ratio``, ``mean_ratio``,
        ``max_ratio`` (grid / collocation), ``bound`` (:func:`lattice_error_bound` at the
        strongest current in the square), ``grid_seconds`` (graph and all Dijkstras).
    """
    import time

    import pandas as pd

    from taopt.fields import thesis_field
    from taopt.navigation.matrix import travel_time_matrix

    if isinstance(field, str):
        if field != "thesis":
            raise InstanceError(f"field must be a Field, None or 'thesis', got {field!r}")
        field = thesis_field()
    field = as_field(field)
    region = (0.0, side, 0.0, side)
    strongest = float(field.max_speed(region))
    raw = np.random.default_rng(seed).uniform(0.0, side, size=(n_points, 2))
    off = ~np.eye(n_points, dtype=bool)
    rows = []
    for cell in cells:
        points = (np.floor(raw / cell) + 0.5) * cell
        reference = np.asarray(travel_time_matrix(field, points, jobs=jobs), dtype=float)
        for neighbours in neighbourhoods:
            began = time.perf_counter()
            grid = grid_travel_time_matrix(field, points, region, cell, neighbours=neighbours)
            seconds = time.perf_counter() - began
            ratio = grid[off] / reference[off]
            rows.append(
                {
                    "cell": float(cell),
                    "neighbours": int(neighbours),
                    "pairs": int(off.sum()),
                    "min_ratio": float(ratio.min()),
                    "mean_ratio": float(ratio.mean()),
                    "max_ratio": float(ratio.max()),
                    "bound": 1.0 + lattice_error_bound(strongest, neighbours),
                    "grid_seconds": seconds,
                }
            )
    return pd.DataFrame(rows)


def grid_travel_time_matrix(
    field: Field | None,
    points: Any,
    region: Sequence[float],
    cell: float,
    obstacles: Sequence[Any] = (),
    speed: float = 1.0,
    neighbours: int = 8,
    cut_corners: bool = True,
) -> np.ndarray:
    """Travel-time matrix by the §3.3 grid planner (see :class:`GridGraph`).

    Parameters
    ----------
    field : Field or None
    points : (N, 2) array_like
        Targets first, then vehicle starts (the thesis's order), each in a free cell.
    region : (xmin, xmax, ymin, ymax)
    cell : float
        Cell side (m).
    obstacles : sequence of polygons
    speed : float
        Vehicle speed ``v``.
    neighbours : {8, 16}
        Fig. 3.1's 8 moves, or 16 (plus knight moves).
    cut_corners : bool
        See :class:`GridGraph`.

    Returns
    -------
    (N, N) ndarray
        Zero diagonal, ``inf`` where a point cannot reach another.

    Raises
    ------
    InstanceError
        A point outside the region or inside an obstacle cell; bad parameters.

    Example
    -------
    >>> t = grid_travel_time_matrix(None, [[0.5, 0.5], [2.5, 0.5]], (0, 4, 0, 4), 1.0)
    >>> t.tolist()
    [[0.0, 2.0], [2.0, 0.0]]

    Notes
    -----
    Building the graph is O(cells); one Dijkstra per distinct point cell,
    O(N cells log cells).

    References
    ----------
    Thesis §3.3, (3.4), (3.5), Remark 3.1.
    """
    graph = GridGraph(field, region, cell, obstacles, speed, neighbours, cut_corners)
    return graph.travel_time_matrix(points)


__all__ = [
    "GridGraph",
    "grid_travel_time_matrix",
    "crossed_cells",
    "MOVES_8",
    "MOVES_16",
    "NEIGHBOURHOODS",
    "LATTICE_ERROR",
    "lattice_error_bound",
    "lattice_error_table",
]
