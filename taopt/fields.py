"""Time-invariant drift fields (winds, currents), thesis (2.1).

Every field gives the drift velocity ``v_c(x, y)`` and its Jacobian at many
points at once (vectorised over an (N, 2) array), a symbolic CasADi version of
the velocity for the collocation solver, its maximum speed over a rectangular
region (Assumption 2.1 needs ``v > max |v_c|``), and a JSON-able ``to_dict``.

The thesis's field is ``LinearField(1e-3 * [[0.3, 0.2], [-0.2, 0.3]])`` on a
1000 m square (§2.5); Fig. 2.1 uses ``1e-2`` on a 100 m square.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from taopt.errors import InstanceError
from taopt.schemas import validate

Region = tuple[float, float, float, float]  # (xmin, xmax, ymin, ymax)


def _points(xy: Any) -> np.ndarray:
    arr = np.asarray(xy, dtype=float)
    if arr.ndim == 1 and arr.size == 2:
        arr = arr.reshape(1, 2)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InstanceError(f"points must have shape (N, 2), got {arr.shape}")
    return arr


class Field(ABC):
    """A planar, time-invariant drift field."""

    kind: str = "field"

    @abstractmethod
    def velocity(self, xy: Any) -> np.ndarray:
        """Drift velocity at points ``xy`` (N, 2) -> (N, 2)."""

    @abstractmethod
    def jacobian(self, xy: Any) -> np.ndarray:
        """Jacobian ``d v_c / d [x, y]`` at points ``xy`` (N, 2) -> (N, 2, 2).

        ``J[k, a, b] = d v_c[a] / d xy[b]`` at point k.
        """

    @abstractmethod
    def casadi(self, x: Any, y: Any) -> tuple[Any, Any]:
        """Symbolic drift velocity ``(v_cx, v_cy)`` for CasADi expressions ``x, y``."""

    @abstractmethod
    def max_speed(self, region: Region) -> float:
        """Maximum drift speed ``max |v_c|`` over the rectangle ``region``."""

    def argmax_speed(self, region: Region) -> np.ndarray:
        """A point of ``region`` where the drift speed is (near) maximal."""
        pts = _region_samples(region, 101)
        speeds = np.linalg.norm(self.velocity(pts), axis=1)
        return pts[int(np.argmax(speeds))]

    @abstractmethod
    def to_dict(self) -> dict[str, Any]:
        """JSON-able description; :func:`field_from_dict` inverts it."""

    @property
    def is_uniform(self) -> bool:
        return False

    def speed(self, xy: Any) -> np.ndarray:
        """Drift speed ``|v_c|`` at points ``xy``."""
        return np.linalg.norm(self.velocity(xy), axis=1)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Field) and self.to_dict() == other.to_dict()

    def __hash__(self) -> int:
        return hash(repr(self.to_dict()))


def _region_samples(region: Region, k: int) -> np.ndarray:
    xmin, xmax, ymin, ymax = region
    gx, gy = np.meshgrid(np.linspace(xmin, xmax, k), np.linspace(ymin, ymax, k))
    return np.column_stack([gx.ravel(), gy.ravel()])


class UniformField(Field):
    """Spatially constant drift ``v_c = (vx, vy)``.

    Example
    -------
    >>> UniformField(0.3, 0.0).velocity([[0, 0], [5, 5]])
    array([[0.3, 0. ],
           [0.3, 0. ]])
    """

    kind = "uniform"

    def __init__(self, vx: float, vy: float) -> None:
        self.vx = float(vx)
        self.vy = float(vy)
        if not (np.isfinite(self.vx) and np.isfinite(self.vy)):
            raise InstanceError(f"UniformField velocity must be finite, got ({vx}, {vy})")

    def velocity(self, xy: Any) -> np.ndarray:
        pts = _points(xy)
        return np.broadcast_to(np.array([self.vx, self.vy]), pts.shape).copy()

    def jacobian(self, xy: Any) -> np.ndarray:
        return np.zeros((_points(xy).shape[0], 2, 2))

    def casadi(self, x: Any, y: Any) -> tuple[Any, Any]:
        return self.vx + 0 * x, self.vy + 0 * y

    def max_speed(self, region: Region) -> float:
        return float(np.hypot(self.vx, self.vy))

    def argmax_speed(self, region: Region) -> np.ndarray:
        return np.array([region[0], region[2]], dtype=float)

    @property
    def is_uniform(self) -> bool:
        return True

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "vx": self.vx, "vy": self.vy}

    def __repr__(self) -> str:
        return f"UniformField({self.vx!r}, {self.vy!r})"


class LinearField(Field):
    """Affine drift ``v_c(p) = A @ p + b``.

    Parameters
    ----------
    A : (2, 2) array_like
        Constant Jacobian. The thesis's field (§2.5) is
        ``1e-3 * [[0.3, 0.2], [-0.2, 0.3]]``; Fig. 2.1 uses ``1e-2``.
    b : (2,) array_like
        Offset, default ``(0, 0)``.

    Notes
    -----
    ``|A p + b|`` is convex in ``p``, so its maximum over a rectangle is at a corner.
    """

    kind = "linear"

    def __init__(self, A: Any, b: Any = (0.0, 0.0)) -> None:
        self.A = np.array(A, dtype=float)
        self.b = np.array(b, dtype=float)
        if self.A.shape != (2, 2) or self.b.shape != (2,):
            raise InstanceError(
                f"LinearField needs A (2, 2) and b (2,), got {self.A.shape}, {self.b.shape}"
            )
        if not (np.isfinite(self.A).all() and np.isfinite(self.b).all()):
            raise InstanceError("LinearField A and b must be finite")

    def velocity(self, xy: Any) -> np.ndarray:
        return _points(xy) @ self.A.T + self.b

    def jacobian(self, xy: Any) -> np.ndarray:
        return np.broadcast_to(self.A, (_points(xy).shape[0], 2, 2)).copy()

    def casadi(self, x: Any, y: Any) -> tuple[Any, Any]:
        A, b = self.A, self.b
        return A[0, 0] * x + A[0, 1] * y + b[0], A[1, 0] * x + A[1, 1] * y + b[1]

    def max_speed(self, region: Region) -> float:
        xmin, xmax, ymin, ymax = region
        corners = np.array([[xmin, ymin], [xmin, ymax], [xmax, ymin], [xmax, ymax]], dtype=float)
        return float(np.max(np.linalg.norm(self.velocity(corners), axis=1)))

    def argmax_speed(self, region: Region) -> np.ndarray:
        xmin, xmax, ymin, ymax = region
        corners = np.array([[xmin, ymin], [xmin, ymax], [xmax, ymin], [xmax, ymax]], dtype=float)
        return corners[int(np.argmax(np.linalg.norm(self.velocity(corners), axis=1)))]

    @property
    def is_uniform(self) -> bool:
        return not self.A.any()

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "A": self.A.tolist(), "b": self.b.tolist()}

    def __repr__(self) -> str:
        return f"LinearField({self.A.tolist()!r}, b={self.b.tolist()!r})"


class GriddedField(Field):
    """Drift sampled on a regular grid (an ocean model, measurements), interpolated.

    Parameters
    ----------
    x, y : 1-D array_like
        Strictly increasing grid coordinates (at least 2 each; 4 or more for the
        cubic interpolant).
    vx, vy : 2-D array_like, shape (len(x), len(y))
        Samples ``vx[i, j] = v_cx(x[i], y[j])``.
    method : {"bspline", "linear"}
        CasADi interpolant. "bspline" (default) is twice differentiable, which
        the collocation solver and the navigation law (2.6) need; "linear" is
        piecewise bilinear.

    Notes
    -----
    Numeric and symbolic evaluations both call the same CasADi interpolant, so
    the velocity used by collocation and by shooting is the same function.
    Outside the grid the interpolant extrapolates; keep the region inside it.
    """

    kind = "gridded"

    def __init__(self, x: Any, y: Any, vx: Any, vy: Any, method: str = "bspline") -> None:
        import casadi as ca

        self.x = np.asarray(x, dtype=float)
        self.y = np.asarray(y, dtype=float)
        self.vx = np.asarray(vx, dtype=float)
        self.vy = np.asarray(vy, dtype=float)
        self.method = method
        shape = (self.x.size, self.y.size)
        for name, arr in (("x", self.x), ("y", self.y)):
            if arr.ndim != 1 or arr.size < 2 or not np.all(np.diff(arr) > 0):
                raise InstanceError(
                    f"GriddedField {name} must be strictly increasing with >= 2 values"
                )
        for name, arr in (("vx", self.vx), ("vy", self.vy)):
            if arr.shape != shape:
                raise InstanceError(f"GriddedField {name} must have shape {shape}, got {arr.shape}")
            if not np.isfinite(arr).all():
                bad = np.argwhere(~np.isfinite(arr))[0]
                raise InstanceError(f"GriddedField {name}[{bad[0]}, {bad[1]}] is not finite")
        if method not in ("bspline", "linear"):
            raise InstanceError(
                f"GriddedField method must be 'bspline' or 'linear', got {method!r}"
            )
        if method == "bspline" and min(shape) < 4:
            raise InstanceError("GriddedField 'bspline' needs at least 4 samples per axis")
        # CasADi wants the data flattened in Fortran order (x fastest).
        grid = [self.x.tolist(), self.y.tolist()]
        data = np.stack([self.vx, self.vy], axis=-1)  # (nx, ny, 2)
        flat = data.transpose(1, 0, 2).reshape(-1, 2)  # x fastest
        self._interp = ca.interpolant("drift", method, grid, flat.ravel().tolist())
        p = ca.MX.sym("p", 2)
        v = self._interp(p)
        self._vel = ca.Function("drift_velocity", [p], [v])
        self._jac = ca.Function("drift_jacobian", [p], [ca.jacobian(v, p)])

    def velocity(self, xy: Any) -> np.ndarray:
        pts = _points(xy)
        out = np.array(self._vel.map(pts.shape[0])(pts.T))
        return out.T.reshape(-1, 2)

    def jacobian(self, xy: Any) -> np.ndarray:
        pts = _points(xy)
        out = np.array(self._jac.map(pts.shape[0])(pts.T))  # (2, 2N)
        return out.reshape(2, pts.shape[0], 2).transpose(1, 0, 2)

    def casadi(self, x: Any, y: Any) -> tuple[Any, Any]:
        import casadi as ca

        v = self._interp(ca.vertcat(x, y))
        return v[0], v[1]

    def max_speed(self, region: Region) -> float:
        # Dense samples of the region (the spline can overshoot the data); the same
        # samples as argmax_speed, so an error message names a consistent location.
        pts = _region_samples(region, 101)
        return float(np.max(self.speed(pts)))

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "x": self.x.tolist(),
            "y": self.y.tolist(),
            "vx": self.vx.tolist(),
            "vy": self.vy.tolist(),
            "method": self.method,
        }

    def __repr__(self) -> str:
        return f"GriddedField({self.x.size}x{self.y.size}, method={self.method!r})"


def thesis_field(scale: float = 1e-3) -> LinearField:
    """The thesis's field ``scale * [0.3x + 0.2y, -0.2x + 0.3y]`` (§2.5: 1e-3, Fig. 2.1: 1e-2)."""
    return LinearField(scale * np.array([[0.3, 0.2], [-0.2, 0.3]]))


#: The ``kind`` of a drift-field file (``field.schema.json``).
FIELD_KINDS = ("uniform", "linear", "gridded")


def field_from_dict(data: dict[str, Any]) -> Field:
    """Inverse of ``Field.to_dict``, checked against ``field.schema.json`` first.

    Raises
    ------
    InstanceError
        Not an object with a known ``kind``, a missing or misspelt key, a value of the
        wrong type or shape (the message names the key and the value), or the field
        constructor's own complaint (e.g. a grid that is not strictly increasing).

    Example
    -------
    >>> field_from_dict({"kind": "uniform", "vx": 0.2, "vy": 0.0})
    UniformField(0.2, 0.0)
    """
    if not isinstance(data, dict) or "kind" not in data:
        raise InstanceError("field must be an object with a 'kind'")
    kind = data["kind"]
    if kind not in FIELD_KINDS:
        raise InstanceError(f"unknown field kind {kind!r} (expected uniform, linear or gridded)")
    validate(data, "field")
    if kind == "gridded":
        # the schema cannot relate lengths: vx, vy are len(x) rows of len(y) numbers
        for name in ("vx", "vy"):
            table = data[name]
            if len(table) != len(data["x"]):
                raise InstanceError(
                    f"field: {name}: expected {len(data['x'])} rows (one per x), got {len(table)}"
                )
            for i, row in enumerate(table):
                if len(row) != len(data["y"]):
                    raise InstanceError(
                        f"field: {name}[{i}]: expected {len(data['y'])} numbers (one per y), "
                        f"got {len(row)}"
                    )
    if kind == "uniform":
        return UniformField(data["vx"], data["vy"])
    if kind == "linear":
        return LinearField(data["A"], data.get("b", (0.0, 0.0)))
    return GriddedField(data["x"], data["y"], data["vx"], data["vy"], data.get("method", "bspline"))


__all__ = [
    "Field",
    "UniformField",
    "LinearField",
    "GriddedField",
    "thesis_field",
    "field_from_dict",
]
