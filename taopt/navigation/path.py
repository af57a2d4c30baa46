"""The result of one minimum-time navigation solve: a :class:`Path`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from taopt.errors import InstanceError
from taopt.fields import Field, UniformField

STILL_WATER = UniformField(0.0, 0.0)


@dataclass(frozen=True)
class Path:
    """A time-parametrised path from ``start`` to ``goal`` in a drift field.

    Attributes
    ----------
    start, goal : (2,) ndarray
        End points.
    speed : float
        Vehicle speed ``v`` relative to the field (2.1).
    time : float
        Travel time ``t(i, j)`` (the objective of §2.3).
    t : (K,) ndarray
        Time stamps of the samples, ``t[0] = 0`` and ``t[-1] = time``.
    xy : (K, 2) ndarray
        Positions at ``t``.
    heading : (K,) ndarray
        Navigation angle ``psi`` of (2.1) at ``t`` (radians).
    heading_rate : (K,) ndarray or None
        ``d psi / dt`` of the method's own heading representation (the collocation
        polynomial, or (2.6) for shooting); used by the navigation-law check.
    method : str
        "collocation", "shooting" or "closed_form".
    status : str
        The solver's own status word ("Solve_Succeeded", "converged", ...).
    success : bool
        Whether the solver reported convergence.
    iterations : int
        Solver iterations (IPOPT iterations, Newton steps; 0 for the closed form).
    info : dict
        Method-specific details (grid size, residuals, wall time).
    """

    start: np.ndarray
    goal: np.ndarray
    speed: float
    time: float
    t: np.ndarray
    xy: np.ndarray
    heading: np.ndarray
    method: str
    status: str
    success: bool = True
    iterations: int = 0
    heading_rate: np.ndarray | None = None
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def thrust(self) -> np.ndarray:
        """Unit thrust directions ``(cos psi, sin psi)``, shape (K, 2)."""
        return np.column_stack([np.cos(self.heading), np.sin(self.heading)])

    @property
    def length(self) -> float:
        """Length of the polyline through the samples (metres)."""
        return float(np.sum(np.linalg.norm(np.diff(self.xy, axis=0), axis=1)))

    def summary(self) -> str:
        return (
            f"{self.method}: t = {self.time:.6f} s from ({self.start[0]:g}, {self.start[1]:g}) to "
            f"({self.goal[0]:g}, {self.goal[1]:g}) [{self.status}, {self.iterations} iterations]"
        )


def as_field(field: Field | None) -> Field:
    """``None`` means still water."""
    if field is None:
        return STILL_WATER
    if not isinstance(field, Field):
        raise InstanceError(
            f"field must be a taopt.fields.Field or None, got {type(field).__name__}"
        )
    return field


def as_point(value: Any, what: str) -> np.ndarray:
    """A finite (2,) float array, else :class:`InstanceError` naming ``what``."""
    try:
        arr = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InstanceError(f"{what} must be two numbers, got {value!r}") from None
    if arr.shape != (2,) or not np.isfinite(arr).all():
        raise InstanceError(f"{what} must be two finite numbers, got {value!r}")
    return arr


def as_speed(speed: Any) -> float:
    try:
        value = float(speed)
    except (TypeError, ValueError):
        raise InstanceError(f"speed must be a number, got {speed!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise InstanceError(f"speed must be positive and finite, got {speed!r}")
    return value


def check_drift(field: Field, points: np.ndarray, speed: float, margin: float = 0.0) -> None:
    """Assumption 2.1 on the bounding box of ``points`` (grown by ``margin``).

    Raises
    ------
    InstanceError
        Naming the location of the strongest drift and both speeds.
    """
    lo = points.min(axis=0) - margin
    hi = points.max(axis=0) + margin
    if np.allclose(lo, hi):
        hi = lo + 1e-9
    region = (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]))
    drift = field.max_speed(region)
    if not speed > drift:
        where = tuple(round(float(c), 6) for c in field.argmax_speed(region))
        raise InstanceError(
            f"speed {speed:g} is not greater than the drift speed {drift:g} at {where} "
            "(Assumption 2.1 needs v > |v_c|; checked on the bounding box of the points)"
        )


def trivial_path(start: np.ndarray, speed: float, method: str) -> Path:
    """Start equals goal: zero time."""
    return Path(
        start=start.copy(),
        goal=start.copy(),
        speed=speed,
        time=0.0,
        t=np.zeros(1),
        xy=start.reshape(1, 2).copy(),
        heading=np.zeros(1),
        method=method,
        status="trivial",
    )
