"""The chapter 2 assignment problem on a travel-time matrix, and its one scorer.

Thesis §2.2.1: targets ``T = {0..n-1}``, vehicle start points
``R = {n..n+m-1}``; a solution is one open route per vehicle (the vehicles do
not return), and the objective (2.2) is the total travel time.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt.errors import FeasibilityError, InstanceError


@dataclass(frozen=True, eq=False)
class AssignmentProblem:
    """Open multi-depot routing on an asymmetric cost matrix, (2.2)–(2.5).

    Parameters
    ----------
    cost : (n + m, n + m) array_like
        ``cost[i, j]`` is the travel time from point i to point j. Points
        ``0..n-1`` are targets, ``n..n+m-1`` the vehicles' start positions.
        The diagonal is ignored.
    n_targets : int
        n >= 1; the number of vehicles is ``m = len(cost) - n >= 1``.
    name : str
        Optional label (e.g. the scenario or TSPLIB name).

    Raises
    ------
    InstanceError
        Not square, not finite, negative, n < 1 or m < 1.

    Example
    -------
    >>> import numpy as np
    >>> p = AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0]]), n_targets=2)
    >>> p.evaluate([[1, 0]])
    4.0
    """

    cost: np.ndarray
    n_targets: int
    name: str = ""

    def __post_init__(self) -> None:
        cost = np.array(self.cost, dtype=float)
        if cost.ndim != 2 or cost.shape[0] != cost.shape[1]:
            raise InstanceError(f"cost must be a square matrix, got shape {cost.shape}")
        off = ~np.eye(cost.shape[0], dtype=bool)
        bad = np.argwhere(~np.isfinite(cost) & off)
        if bad.size:
            i, j = bad[0]
            raise InstanceError(f"cost[{i}, {j}] = {cost[i, j]} is not finite")
        bad = np.argwhere((cost < 0) & off)
        if bad.size:
            i, j = bad[0]
            raise InstanceError(f"cost[{i}, {j}] = {cost[i, j]} is negative")
        n = int(self.n_targets)
        if n < 1:
            raise InstanceError(f"n_targets must be >= 1, got {self.n_targets}")
        if cost.shape[0] - n < 1:
            raise InstanceError(
                f"cost has {cost.shape[0]} points but n_targets={n}: need at least one vehicle point"
            )
        np.fill_diagonal(cost, 0.0)
        cost.setflags(write=False)
        object.__setattr__(self, "cost", cost)
        object.__setattr__(self, "n_targets", n)

    @property
    def n(self) -> int:
        """Number of targets."""
        return self.n_targets

    @property
    def m(self) -> int:
        """Number of vehicles."""
        return self.cost.shape[0] - self.n_targets

    @property
    def targets(self) -> range:
        return range(self.n_targets)

    @property
    def vehicle_points(self) -> range:
        """Indices of the vehicles' start points in ``cost`` (thesis's R)."""
        return range(self.n_targets, self.cost.shape[0])

    @property
    def is_symmetric(self) -> bool:
        return bool(np.allclose(self.cost, self.cost.T))

    def replace(self, **changes: Any) -> AssignmentProblem:
        return dataclasses.replace(self, **changes)

    def route_cost(self, vehicle: int, route: Sequence[int]) -> float:
        """Travel time of one open route starting at vehicle ``vehicle``'s start point."""
        if len(route) == 0:
            return 0.0
        nodes = np.asarray([self.n_targets + vehicle, *route], dtype=int)
        return float(self.cost[nodes[:-1], nodes[1:]].sum())

    def evaluate(self, routes: Sequence[Sequence[int]]) -> float:
        """Total travel time (2.2) of ``routes`` after checking (2.3)–(2.5).

        Raises
        ------
        FeasibilityError
            Wrong number of routes, a bad index, a target visited twice
            (violates (2.3)/(2.4)) or never visited (violates (2.3)).
        """
        return evaluate_routes(self, routes)

    def to_dict(self) -> dict[str, Any]:
        return {
            "schema_version": 1,
            "kind": "assignment_problem",
            "name": self.name,
            "n_targets": self.n_targets,
            "cost": self.cost.tolist(),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any], source: str | None = None) -> AssignmentProblem:
        """Inverse of :meth:`to_dict`: checked against ``assignment_problem.schema.json``
        first (``source`` names the data in messages), then by the constructor.

        Raises
        ------
        InstanceError
            A schema violation (naming the JSON path and the value), a matrix that is not
            square (naming the row), or the constructor's own complaint.
        """
        from taopt.instance import check_schema
        from taopt.schemas import naming

        check_schema(data, "assignment_problem", source)
        cost = data["cost"]
        for i, row in enumerate(cost):
            if len(row) != len(cost):
                raise InstanceError(
                    f"{source or 'assignment_problem'}: cost[{i}]: expected {len(cost)} numbers "
                    f"(cost must be square), got {len(row)}"
                )
        with naming(source or "assignment_problem"):
            return cls(np.array(cost, dtype=float), int(data["n_targets"]), data.get("name", ""))

    def save(self, path: Any) -> None:
        from taopt.io import save_json

        save_json(self.to_dict(), path)

    @classmethod
    def load(cls, path: Any) -> AssignmentProblem:
        """Read a file written by :meth:`save` (strict JSON, validated; every failure an
        InstanceError naming the path)."""
        from taopt.io import load_json

        return cls.from_dict(load_json(path, "assignment_problem"), source=str(path))

    def __repr__(self) -> str:
        label = f" {self.name!r}" if self.name else ""
        return f"AssignmentProblem{label}(n={self.n}, m={self.m})"


def evaluate_routes(problem: AssignmentProblem, routes: Sequence[Sequence[int]]) -> float:
    """The one scorer of chapter 2: feasibility check, then objective (2.2)."""
    if isinstance(routes, np.ndarray) or not isinstance(routes, Sequence):
        routes = list(routes)
    if len(routes) != problem.m:
        raise FeasibilityError(f"expected {problem.m} routes (one per vehicle), got {len(routes)}")
    seen: dict[int, int] = {}
    total = 0.0
    for vehicle, route in enumerate(routes):
        clean = []
        for target in route:
            if isinstance(target, bool) or not isinstance(target, (int, np.integer)):
                raise FeasibilityError(
                    f"route of vehicle {vehicle}: {target!r} is not an integer target index"
                )
            target = int(target)
            if not 0 <= target < problem.n:
                raise FeasibilityError(
                    f"route of vehicle {vehicle}: index {target} is not a target (targets are 0..{problem.n - 1})"
                )
            if target in seen:
                raise FeasibilityError(
                    f"target {target} is visited twice (vehicles {seen[target]} and {vehicle}); (2.3) allows once"
                )
            seen[target] = vehicle
            clean.append(target)
        total += problem.route_cost(vehicle, clean)
    if len(seen) != problem.n:
        missing = sorted(set(range(problem.n)) - set(seen))
        raise FeasibilityError(
            f"target {missing[0]} is never visited ((2.3)); missing: {missing[:10]}"
        )
    return total
