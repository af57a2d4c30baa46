"""Grid path planning with obstacles (thesis §3.3): 8-neighbour cells, (3.4)/(3.5), Dijkstra.

The region is cut into square cells of side ``cell``; a cell is blocked when its
centre lies in an obstacle. From each free cell the vehicle may move to its 8
neighbours, with net-velocity direction ``theta_net = (i - 1) pi / 4`` and
distance ``l`` (edge neighbours) or ``sqrt(2) l`` (corner neighbours), Fig. 3.1.
The drift is taken constant over a cell (its value at the centre of the cell
the vehicle leaves); the net speed along the move solves (3.4),

    v_net = v_c . d + sqrt(v**2 - |v_c|**2 + (v_c . d)**2),

which is real iff (3.5) ``|sin(theta_net - theta_c)| <= v / v_c`` holds. When
``v < v_c`` (allowed in chapter 3) (3.5) is not enough: straight upstream
``sin = 0`` satisfies it, but both roots of (3.4) are negative; so a move also
needs ``v_net > 0`` (see :func:`taopt.navigation.uniform.net_speed`). The
edge time is ``distance / v_net``, infinite (no edge) when (3.5) fails, when
``v_net <= 0`` or when either cell is blocked. ``scipy.sparse.csgraph.dijkstra``
then gives the shortest times between the cells of the points.

Remark 3.1: the matrix satisfies the triangle inequality exactly, being made
of shortest-path distances in one digraph (checked in the tests). It is an
upper-bound-style approximation of the continuous minimum time: paths are
restricted to 8 directions, so in free water it exceeds the collocation time
(by up to about 8 % for directions between the lattice ones).

References
----------
Thesis §3.3, (3.4), (3.5), Fig. 3.1, Remark 3.1.
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
from taopt.navigation.uniform import net_speed

# the 8 moves of Fig. 3.1: label i = 1..8 has theta_net = (i - 1) pi / 4
MOVES = np.array([(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1)])


class GridGraph:
    """The weighted cell digraph of §3.3.

    Parameters
    ----------
    field : Field or None
    region : (xmin, xmax, ymin, ymax)
    cell : float
        Cell side ``l``; the last row/column may stick out of the region.
    obstacles : sequence
        Objects with ``contains(xy) -> bool mask`` (e.g. :class:`taopt.instance.Obstacle`)
        or vertex arrays (polygons).
    speed : float
        Vehicle speed ``v``.
    cut_corners : bool
        Allow a diagonal move whose two edge-adjacent cells are blocked
        (the thesis only checks the destination cell; default True).

    Example
    -------
    >>> g = GridGraph(None, (0, 10, 0, 10), cell=1.0)
    >>> round(float(g.travel_time_matrix([[0.5, 0.5], [3.5, 3.5]])[0, 1]), 6)
    4.242641
    """

    def __init__(
        self,
        field: Field | None,
        region: Sequence[float],
        cell: float,
        obstacles: Sequence[Any] = (),
        speed: float = 1.0,
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
        if not (np.isfinite(cell) and cell > 0):
            raise InstanceError(f"cell size must be positive, got {cell!r}")
        self.region = (xmin, xmax, ymin, ymax)
        self.cell = float(cell)
        self.nx = int(np.ceil((xmax - xmin) / cell - 1e-9))
        self.ny = int(np.ceil((ymax - ymin) / cell - 1e-9))
        cx = xmin + (np.arange(self.nx) + 0.5) * cell
        cy = ymin + (np.arange(self.ny) + 0.5) * cell
        gx, gy = np.meshgrid(cx, cy, indexing="ij")  # cell (a, b) has index a * ny + b
        self.centres = np.column_stack([gx.ravel(), gy.ravel()])
        self.blocked = np.zeros(len(self.centres), dtype=bool)
        for k, obs in enumerate(obstacles):
            self.blocked |= _contains(obs, self.centres, k)
        self.graph = self._edges(cut_corners)

    def _edges(self, cut_corners: bool) -> csr_matrix:
        nx, ny, n = self.nx, self.ny, self.nx * self.ny
        a, b = np.divmod(np.arange(n), ny)
        drift = self.field.velocity(self.centres)  # constant over each cell
        free = ~self.blocked
        rows, cols, times = [], [], []
        for da, db in MOVES:
            ta, tb = a + da, b + db
            ok = (ta >= 0) & (ta < nx) & (tb >= 0) & (tb < ny)
            target = np.where(ok, ta * ny + tb, 0)
            ok &= free & free[target]
            if da and db and not cut_corners:
                side1 = np.where(ok, ta * ny + b, 0)
                side2 = np.where(ok, a * ny + tb, 0)
                ok &= free[side1] & free[side2]
            direction = np.array([da, db], dtype=float)
            length = self.cell * np.linalg.norm(direction)
            vnet = net_speed(drift, direction / np.linalg.norm(direction), self.speed)  # (3.4)
            ok &= np.isfinite(vnet)  # (3.5) and v_net > 0
            rows.append(np.flatnonzero(ok))
            cols.append(target[ok])
            times.append(length / vnet[ok])
        return csr_matrix(
            (np.concatenate(times), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
        )

    def cell_of(self, points: Any) -> np.ndarray:
        """Cell index of each point; :class:`InstanceError` if outside the grid or blocked."""
        pts = as_points(points)
        xmin, _, ymin, _ = self.region
        a = np.floor((pts[:, 0] - xmin) / self.cell).astype(int)
        b = np.floor((pts[:, 1] - ymin) / self.cell).astype(int)
        a = np.where(a == self.nx, self.nx - 1, a)  # points on the far edge
        b = np.where(b == self.ny, self.ny - 1, b)
        for k in range(len(pts)):
            if not (0 <= a[k] < self.nx and 0 <= b[k] < self.ny):
                raise InstanceError(
                    f"point {k} {pts[k].tolist()} is outside the grid region {self.region}"
                )
        cells = a * self.ny + b
        blocked = np.flatnonzero(self.blocked[cells])
        if blocked.size:
            k = int(blocked[0])
            raise InstanceError(
                f"point {k} {pts[k].tolist()} lies in a blocked cell (inside an obstacle)"
            )
        return cells

    def travel_time_matrix(self, points: Any) -> np.ndarray:
        """Shortest cell-to-cell times between the points' cells (``inf`` if unreachable)."""
        cells = self.cell_of(points)
        unique, inverse = np.unique(cells, return_inverse=True)
        dist = dijkstra(self.graph, directed=True, indices=unique)
        matrix = dist[np.ix_(inverse, unique[inverse])]
        np.fill_diagonal(matrix, 0.0)
        return matrix

    def path(self, start: Any, goal: Any) -> np.ndarray:
        """Cell centres of a shortest path from ``start``'s cell to ``goal``'s cell, (K, 2)."""
        source, target = self.cell_of(np.vstack([start, goal]))
        dist, pred = dijkstra(self.graph, directed=True, indices=source, return_predecessors=True)
        if not np.isfinite(dist[target]):
            raise InstanceError(f"{tuple(goal)} cannot be reached from {tuple(start)} on the grid")
        order = [target]
        while order[-1] != source:
            order.append(pred[order[-1]])
        return self.centres[order[::-1]]


def _contains(obstacle: Any, pts: np.ndarray, k: int) -> np.ndarray:
    if hasattr(obstacle, "contains"):
        return np.asarray(obstacle.contains(pts), dtype=bool)
    from matplotlib.path import Path as MplPath

    vertices = np.asarray(obstacle, dtype=float)
    if vertices.ndim != 2 or vertices.shape[1] != 2 or len(vertices) < 3:
        raise InstanceError(f"obstacle {k} must be a polygon with at least 3 vertices")
    return MplPath(vertices).contains_points(pts)


def grid_travel_time_matrix(
    field: Field | None,
    points: Any,
    region: Sequence[float],
    cell: float,
    obstacles: Sequence[Any] = (),
    speed: float = 1.0,
    cut_corners: bool = True,
) -> np.ndarray:
    """Travel-time matrix by the §3.3 grid planner (see :class:`GridGraph`).

    Returns
    -------
    (N, N) ndarray
        Zero diagonal, ``inf`` where a point cannot reach another.

    Notes
    -----
    Building the graph is O(cells); one Dijkstra per distinct point cell,
    O(N cells log cells).
    """
    return GridGraph(field, region, cell, obstacles, speed, cut_corners).travel_time_matrix(points)
