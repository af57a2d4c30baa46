"""Open multi-vehicle routing with a capacity and a maximum travel time per vehicle.

Thesis §6.2 (future work): "each vehicle can visit a maximum number of target locations"
and "… a maximum travel time". The data are chapter 2's (§2.2.1): targets ``0..n-1``, the
vehicles' start points ``n..n+m-1`` of one asymmetric travel-time matrix; a solution is one
open route per vehicle (payload :class:`taopt.result.Routes`) and the objective is (2.2),
the total travel time. Vehicle k may serve at most ``Q_k`` targets (``capacity[k]``) and
its route may take at most ``T_k`` (``max_time[k]``); either limit may be absent (stored as
``inf``).

:class:`BudgetedProblem` is deliberately *not* a subclass of
:class:`~taopt.routing.problem.AssignmentProblem`: a chapter-2 method would take it and
silently ignore the limits. Its :attr:`BudgetedProblem.routing` is the same problem without
limits (a relaxation: every bound of it is a bound here).
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from taopt.errors import FeasibilityError, InstanceError
from taopt.routing.problem import AssignmentProblem, evaluate_routes

#: Relative tolerance of the travel-time check (a MILP's rows hold to about 1e-7).
TIME_TOLERANCE = 1e-6


def _limits(values: Any, m: int, what: str, integer: bool) -> np.ndarray:
    """``values`` (None, or m entries each None / inf / a number >= 0) as a float array,
    ``inf`` for "no limit"; InstanceError naming the entry otherwise."""
    if values is None:
        return np.full(m, np.inf)
    if isinstance(values, (str, bytes)) or not isinstance(values, (Sequence, np.ndarray)):
        raise InstanceError(
            f"{what} must be None or a list of {m} limits (one per vehicle), got {values!r}"
        )
    if len(values) != m:
        raise InstanceError(
            f"{what} has {len(values)} entries but there are {m} vehicles (one limit each)"
        )
    out = np.empty(m)
    for k, value in enumerate(values):
        if value is None:
            out[k] = np.inf
            continue
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            raise InstanceError(f"{what}[{k}] = {value!r} is not a number (or None for no limit)")
        value = float(value)
        if math.isnan(value):
            raise InstanceError(f"{what}[{k}] = nan is not a number (use None for no limit)")
        if value < 0:
            raise InstanceError(f"{what}[{k}] = {value:g} is negative (a limit must be >= 0)")
        if integer and math.isfinite(value) and not value.is_integer():
            raise InstanceError(f"{what}[{k}] = {value:g} is not a whole number of targets")
        out[k] = value
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class BudgetedProblem:
    """Open multi-depot routing, (2.2)–(2.5), plus a per-vehicle capacity and time budget.

    Parameters
    ----------
    cost : (n + m, n + m) array_like
        ``cost[i, j]`` is the travel time from point i to point j, laid out exactly as
        :class:`~taopt.routing.problem.AssignmentProblem`'s (targets ``0..n-1`` first, then
        the vehicles' start points ``n..n+m-1``). The diagonal is ignored.
    n_targets : int
        n >= 1; the number of vehicles is ``m = len(cost) - n >= 1``.
    capacity : None or sequence of m (int or None)
        ``capacity[k]`` = Q_k, the most targets vehicle k may serve (an integer >= 0);
        None (the whole list or one entry) means no limit. Stored as a float array with
        ``inf`` for "no limit".
    max_time : None or sequence of m (float or None)
        ``max_time[k]`` = T_k >= 0, the longest travel time of vehicle k's open route
        (from its start to its last target); None means no limit. Stored like ``capacity``.
    name : str
        Optional label.

    Raises
    ------
    InstanceError
        The cost matrix is invalid (as for AssignmentProblem), or a limit is negative, not a
        number, not whole (capacity) or the list has the wrong length; the message names the
        entry, e.g. ``capacity[3] = -1 is negative``.

    Notes
    -----
    A route r_k = (j_1, ..., j_l) of vehicle k is feasible when ``l <= Q_k`` and
    ``t(p_k, j_1) + Σ t(j_i, j_{i+1}) <= T_k`` (to a relative tolerance of
    :data:`TIME_TOLERANCE`). An empty route is always feasible.

    Example
    -------
    >>> import numpy as np
    >>> cost = np.array([[0, 2, 9, 9], [1, 0, 9, 9], [4, 3, 0, 9], [5, 5, 9, 0]])
    >>> p = BudgetedProblem(cost, n_targets=2, capacity=[1, None])
    >>> p.capacity.tolist(), p.m
    ([1.0, inf], 2)
    >>> p.evaluate([[1], [0]])
    8.0
    >>> violations(p, [[1, 0], []])
    ['vehicle 0 serves 2 targets, capacity 1']

    References
    ----------
    Thesis §2.2 (2.2)–(2.5), §6.2 (future work).
    """

    cost: np.ndarray
    n_targets: int
    capacity: Any = None
    max_time: Any = None
    name: str = ""
    routing: AssignmentProblem = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        routing = AssignmentProblem(self.cost, self.n_targets, self.name)
        object.__setattr__(self, "routing", routing)
        object.__setattr__(self, "cost", routing.cost)
        object.__setattr__(self, "n_targets", routing.n_targets)
        object.__setattr__(self, "capacity", _limits(self.capacity, routing.m, "capacity", True))
        object.__setattr__(self, "max_time", _limits(self.max_time, routing.m, "max_time", False))

    @classmethod
    def from_routing(
        cls,
        problem: AssignmentProblem,
        capacity: Any = None,
        max_time: Any = None,
        name: str | None = None,
    ) -> BudgetedProblem:
        """The chapter-2 ``problem`` with limits added (same matrix, same name by default)."""
        return cls(
            problem.cost, problem.n, capacity, max_time, problem.name if name is None else name
        )

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
    def has_capacity(self) -> bool:
        """Whether some vehicle has a finite capacity."""
        return bool(np.isfinite(self.capacity).any())

    @property
    def has_max_time(self) -> bool:
        """Whether some vehicle has a finite maximum travel time."""
        return bool(np.isfinite(self.max_time).any())

    def replace(self, **changes: Any) -> BudgetedProblem:
        return dataclasses.replace(self, **changes)

    def route_cost(self, vehicle: int, route: Sequence[int]) -> float:
        """Travel time of one open route starting at vehicle ``vehicle``'s start point."""
        return self.routing.route_cost(vehicle, route)

    def evaluate(self, routes: Sequence[Sequence[int]]) -> float:
        """Total travel time (2.2) after checking (2.3)–(2.5) and every limit
        (:func:`evaluate_budgeted`)."""
        return evaluate_budgeted(self, routes)

    def to_dict(self) -> dict[str, Any]:
        """JSON data of kind ``budgeted_problem``; null marks "no limit" (an entry, or the
        whole list when no vehicle has that limit)."""

        def plain(values: np.ndarray, integer: bool) -> list[Any] | None:
            if not np.isfinite(values).any():
                return None
            return [
                None if not math.isfinite(v) else (int(v) if integer else float(v)) for v in values
            ]

        return {
            "schema_version": 1,
            "kind": "budgeted_problem",
            "name": self.name,
            "n_targets": self.n_targets,
            "capacity": plain(self.capacity, True),
            "max_time": plain(self.max_time, False),
            "cost": self.cost.tolist(),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any], source: str | None = None) -> BudgetedProblem:
        """Inverse of :meth:`to_dict`: checked against ``budgeted_problem.schema.json``
        first (``source`` names the data in messages), then by the constructor.

        Raises
        ------
        InstanceError
            A schema violation (naming the JSON path and the value), a matrix that is not
            square (naming the row), or the constructor's own complaint.
        """
        from taopt.instance import check_schema, check_square
        from taopt.schemas import naming

        where = source or "budgeted_problem"
        check_schema(data, "budgeted_problem", source)
        check_square(data["cost"], "cost", where)
        with naming(where):
            return cls(
                np.array(data["cost"], dtype=float),
                int(data["n_targets"]),
                data.get("capacity"),
                data.get("max_time"),
                data.get("name", ""),
            )

    def save(self, path: Any) -> None:
        from taopt.io import save_json

        save_json(self.to_dict(), path)

    @classmethod
    def load(cls, path: Any) -> BudgetedProblem:
        """Read a file written by :meth:`save` (strict JSON, validated; every failure an
        InstanceError naming the path)."""
        from taopt.io import load_json

        return cls.from_dict(load_json(path, "budgeted_problem"), source=str(path))

    def __repr__(self) -> str:
        label = f" {self.name!r}" if self.name else ""
        return f"BudgetedProblem{label}(n={self.n}, m={self.m})"


def _limit_violations(problem: BudgetedProblem, routes: Sequence[Sequence[int]]) -> list[str]:
    """The capacity and travel-time violations of routes that passed the routing check."""
    found = []
    for vehicle, route in enumerate(routes):
        route = [int(t) for t in route]
        capacity = problem.capacity[vehicle]
        if len(route) > capacity:
            found.append(f"vehicle {vehicle} serves {len(route)} targets, capacity {capacity:g}")
        limit = problem.max_time[vehicle]
        if math.isfinite(limit):
            time = problem.route_cost(vehicle, route)
            if time > limit + TIME_TOLERANCE * max(1.0, limit):
                found.append(f"vehicle {vehicle} travels {time:.10g} s, max_time {limit:g}")
    return found


def violations(problem: BudgetedProblem, routes: Sequence[Sequence[int]]) -> list[str]:
    """Every constraint ``routes`` violates, as messages; ``[]`` when feasible. Never raises.

    A routing error (wrong number of routes, a target twice or never, a bad index) is one
    message (the routing scorer's; the limits are then checked only if the routes can be
    read). For studies that count infeasible answers; :func:`evaluate_budgeted` raises.

    References
    ----------
    Thesis (2.3)–(2.5), §6.2.
    """
    try:
        evaluate_routes(problem.routing, routes)
    except FeasibilityError as exc:
        found = [str(exc)]
        try:
            readable = len(routes) == problem.m and all(
                0 <= int(t) < problem.n for route in routes for t in route
            )
        except (TypeError, ValueError):
            readable = False
        return found + (_limit_violations(problem, routes) if readable else [])
    return _limit_violations(problem, routes)


def evaluate_budgeted(problem: BudgetedProblem, routes: Sequence[Sequence[int]]) -> float:
    """The one scorer of the family: the total travel time (2.2) of feasible ``routes``.

    Parameters
    ----------
    problem : BudgetedProblem
    routes : sequence of m sequences of int
        One open route per vehicle (target indices in visiting order).

    Returns
    -------
    float
        Σ_k of the travel time of route k from vehicle k's start, (2.2).

    Raises
    ------
    FeasibilityError
        The routing scorer's complaint ((2.3)–(2.5): wrong number of routes, a target twice
        or never), or every violated limit named, e.g. ``vehicle 2 serves 6 targets,
        capacity 5; vehicle 0 travels 812.4 s, max_time 800``. (FeasibilityError, the
        project's error for an infeasible solution, is what ``taopt verify`` reports as
        "infeasible".)

    Notes
    -----
    O(n + m). The travel-time check allows a relative :data:`TIME_TOLERANCE`.

    References
    ----------
    Thesis (2.2)–(2.5), §6.2.
    """
    total = evaluate_routes(problem.routing, routes)
    found = _limit_violations(problem, routes)
    if found:
        raise FeasibilityError("; ".join(found))
    return total


__all__ = ["BudgetedProblem", "evaluate_budgeted", "violations", "TIME_TOLERANCE"]
