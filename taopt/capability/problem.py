"""Chapter 3 problem data: heterogeneous vehicles, multi-capability demands, one scorer.

Thesis §3.2.1: targets ``T = {0..n-1}``, vehicle start points ``n..n+m-1`` (as chapter 2);
vehicle k has ONE capability ``a_k``; the classes ``R_q`` are the vehicles of each
capability; target j demands a set of capabilities (``y_jq = 1`` of (3.2)) and must be
visited exactly once by a vehicle of each demanded capability. The objective (3.1) is the
total travel time of all vehicles (open routes, as (2.2)).

Costs: one ``(n + m) × (n + m)`` matrix, or one per capability (a mapping) when vehicle
kinds differ in speed. ``inf`` marks a pair no vehicle can travel (obstacles, or a current
that blocks the way, (3.5)); it is allowed only where no vehicle of a class that needs the
pair would use it.

The problem splits exactly into one chapter 2 problem per capability class (§3.6): the
classes share no vehicle and no (target, capability) demand, and (3.1) is the sum of the
classes' totals. :meth:`CapabilityProblem.classes` gives those sub-problems.
"""

from __future__ import annotations

import dataclasses
import math
import os
import warnings
from collections.abc import Hashable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt.errors import FeasibilityError, InstanceError
from taopt.routing.problem import AssignmentProblem


def _matrix(value: Any, what: str) -> np.ndarray:
    try:
        cost = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InstanceError(f"{what} must be a square matrix of numbers") from None
    if cost.ndim != 2 or cost.shape[0] != cost.shape[1]:
        raise InstanceError(f"{what} must be a square matrix, got shape {cost.shape}")
    off = ~np.eye(cost.shape[0], dtype=bool)
    bad = np.argwhere(np.isnan(cost) & off)
    if bad.size:
        i, j = bad[0]
        raise InstanceError(f"{what}[{i}, {j}] is NaN")
    bad = np.argwhere((cost < 0) & off)
    if bad.size:
        i, j = bad[0]
        raise InstanceError(f"{what}[{i}, {j}] = {cost[i, j]} is negative")
    np.fill_diagonal(cost, 0.0)
    cost.setflags(write=False)
    return cost


@dataclass(frozen=True)
class CapabilityClass:
    """One capability class q of §3.6: its targets T_q, vehicles R_q and chapter 2 problem.

    Attributes
    ----------
    capability : label
    targets : tuple of int
        Indices (in the whole problem) of the targets demanding this capability (T_q).
    vehicles : tuple of int
        Indices 0..m-1 of the vehicles with this capability (R_q).
    problem : AssignmentProblem or None
        The class's open-routing problem on T_q and R_q (targets renumbered 0..|T_q|-1
        in the order of ``targets``, vehicles in the order of ``vehicles``); None when the
        class has no demanded target.
    """

    capability: Hashable
    targets: tuple[int, ...]
    vehicles: tuple[int, ...]
    problem: AssignmentProblem | None

    def lift(self, routes: Sequence[Sequence[int]]) -> dict[int, list[int]]:
        """Routes of the class problem mapped back: vehicle index -> list of target indices."""
        return {
            self.vehicles[j]: [self.targets[t] for t in route] for j, route in enumerate(routes)
        }


@dataclass(frozen=True, eq=False)
class CapabilityProblem:
    """Heterogeneous open multi-vehicle routing, thesis (3.1)–(3.3) (with subtour elimination).

    Parameters
    ----------
    cost : (n + m, n + m) array_like, or mapping capability -> such an array
        Travel times, targets first then the vehicles' starts (as
        :class:`~taopt.AssignmentProblem`); a mapping gives each capability class its own
        matrix (vehicle kinds of different speeds). ``inf``: the pair cannot be travelled.
    n_targets : int
        n >= 1.
    vehicle_capability : sequence of m labels
        The capability a_k of each vehicle (strings or integers).
    demands : sequence of n collections of labels
        The capabilities each target demands (y_jq = 1), each non-empty. A list naming
        a capability twice is read as a set, with a warning (a file doing so is refused by
        its schema).
    name : str

    Raises
    ------
    InstanceError
        Bad shapes or values; a target demanding a capability no vehicle has; a demanded
        target that no vehicle of its class can reach, or a pair inside a class that cannot
        be travelled (named: target, capability, vehicle); a mapping missing a capability.

    Example
    -------
    >>> import numpy as np
    >>> x = np.array([1.0, 2.0, 0.0, 3.0])          # targets at 1, 2; vehicles at 0, 3
    >>> p = CapabilityProblem(abs(x[:, None] - x[None, :]), 2, ["a", "b"], [{"a"}, {"a", "b"}])
    >>> p.evaluate([[0, 1], [1]])                   # a: 0 -> 1 -> 2 (2), b: 3 -> 2 (1)
    3.0
    """

    cost: Any
    n_targets: int
    vehicle_capability: tuple[Hashable, ...]
    demands: tuple[frozenset, ...]
    name: str = ""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        n = self.n_targets
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            from taopt.instance import plain

            raise InstanceError(f"n_targets must be an integer >= 1, got {plain(n)!r}")
        n = int(n)
        set_(self, "n_targets", n)
        if isinstance(self.vehicle_capability, (str, bytes)):
            raise InstanceError("vehicle_capability must be a sequence of labels, one per vehicle")
        capability = tuple(self.vehicle_capability)
        for k, label in enumerate(capability):
            if not isinstance(label, Hashable) or isinstance(label, (float, bool)):
                raise InstanceError(f"vehicle_capability[{k}] = {label!r} is not a label")
        m = len(capability)
        if m < 1:
            raise InstanceError("need at least one vehicle (vehicle_capability is empty)")
        set_(self, "vehicle_capability", capability)
        if isinstance(self.cost, Mapping):
            matrices = {cap: _matrix(c, f"cost[{cap!r}]") for cap, c in self.cost.items()}
            missing = sorted({str(c) for c in capability} - {str(c) for c in matrices})
            if missing:
                raise InstanceError(f"cost has no matrix for capability {missing[0]!r}")
        else:
            shared = _matrix(self.cost, "cost")
            matrices = {cap: shared for cap in dict.fromkeys(capability)}
        for cap, matrix in matrices.items():
            if matrix.shape[0] != n + m:
                raise InstanceError(
                    f"cost for capability {cap!r} has {matrix.shape[0]} points, expected "
                    f"n + m = {n} + {m} = {n + m}"
                )
        set_(self, "cost", matrices if isinstance(self.cost, Mapping) else shared)
        set_(self, "_matrices", matrices)
        if isinstance(self.demands, (str, bytes)) or len(self.demands) != n:
            raise InstanceError(f"demands must hold one set of capabilities per target ({n})")
        demands = []
        have = set(capability)
        for j, wanted in enumerate(self.demands):
            if isinstance(wanted, (str, bytes)) or not isinstance(wanted, Iterable):
                raise InstanceError(f"demands[{j}] must be a collection of capabilities")
            if not isinstance(wanted, (set, frozenset)):
                wanted = list(wanted)
                if len(set(wanted)) != len(wanted):  # documented normalisation, with a warning
                    warnings.warn(
                        f"demands[{j}] lists a capability twice; it is demanded once",
                        stacklevel=3,
                    )
            wanted = frozenset(wanted)
            if not wanted:
                raise InstanceError(f"target {j} demands no capability")
            for cap in sorted(wanted, key=str):
                if cap not in have:
                    raise InstanceError(
                        f"target {j} demands capability {cap!r}, which no vehicle has "
                        f"(vehicles have {sorted(have, key=str)})"
                    )
            demands.append(wanted)
        set_(self, "demands", tuple(demands))
        set_(self, "name", str(self.name))
        set_(self, "_classes", self._split())

    # -- the classes of §3.6 ---------------------------------------------------------------
    def _split(self) -> tuple[CapabilityClass, ...]:
        n = self.n_targets
        classes = []
        for cap in self.capabilities:
            targets = tuple(j for j in range(n) if cap in self.demands[j])
            vehicles = tuple(k for k, c in enumerate(self.vehicle_capability) if c == cap)
            matrix = self.cost_for(cap)
            problem = None
            if targets:
                points = np.array(list(targets) + [n + k for k in vehicles])
                sub = matrix[np.ix_(points, points)]
                reach = sub[len(targets) :, : len(targets)]
                for t, target in enumerate(targets):
                    if not np.isfinite(reach[:, t]).any():
                        raise InstanceError(
                            f"target {target} demands capability {cap!r} but no vehicle of that "
                            f"capability can reach it (all travel times are inf)"
                        )
                bad = np.argwhere(~np.isfinite(sub[:, : len(targets)]))
                bad = bad[bad[:, 0] != bad[:, 1]]
                if bad.size:
                    i, t = (int(v) for v in bad[0])
                    source = (
                        f"target {points[i]}"
                        if i < len(targets)
                        else f"vehicle {vehicles[i - len(targets)]}"
                    )
                    raise InstanceError(
                        f"capability class {cap!r}: the way from {source} to target "
                        f"{targets[t]} cannot be travelled (inf); every pair inside a class must "
                        "be reachable"
                    )
                problem = AssignmentProblem(sub, n_targets=len(targets), name=f"{self.name}[{cap}]")
            classes.append(CapabilityClass(cap, targets, vehicles, problem))
        return tuple(classes)

    # -- views ---------------------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of targets."""
        return self.n_targets

    @property
    def m(self) -> int:
        """Number of vehicles."""
        return len(self.vehicle_capability)

    @property
    def capabilities(self) -> tuple[Hashable, ...]:
        """The distinct capabilities (the set A), in order of first appearance."""
        return tuple(dict.fromkeys(self.vehicle_capability))

    @property
    def classes(self) -> tuple[CapabilityClass, ...]:
        """One :class:`CapabilityClass` per capability (the exact split of §3.6)."""
        # ignore (here and below): set by __post_init__ (object.__setattr__), not a field
        return self._classes  # type: ignore[attr-defined]

    def cost_for(self, capability: Hashable) -> np.ndarray:
        """The travel-time matrix of the vehicles of ``capability``."""
        return self._matrices[capability]  # type: ignore[attr-defined]

    def demand_pairs(self) -> int:
        """Σ_j |demands_j|: how many (target, capability) visits are required."""
        return sum(len(d) for d in self.demands)

    def replace(self, **changes: Any) -> CapabilityProblem:
        return dataclasses.replace(self, **changes)

    def evaluate(self, routes: Sequence[Sequence[int]]) -> float:
        """Total travel time (3.1) after checking every demand is served once (3.2)."""
        return evaluate_capability(self, routes)

    def join(self, class_routes: Mapping[Hashable, Sequence[Sequence[int]]]) -> list[list[int]]:
        """Whole-problem routes from per-class routes (class problem indexing)."""
        routes: list[list[int]] = [[] for _ in range(self.m)]
        for cls in self.classes:
            if cls.problem is None:
                continue
            for vehicle, route in cls.lift(class_routes[cls.capability]).items():
                routes[vehicle] = route
        return routes

    # -- JSON -----------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        def encode(matrix: np.ndarray) -> list:
            return [[None if not math.isfinite(v) else float(v) for v in row] for row in matrix]

        cost: Any
        if isinstance(self.cost, Mapping):
            cost = {str(cap): encode(c) for cap, c in self.cost.items()}
        else:
            cost = encode(self.cost)
        return {
            "schema_version": 1,
            "kind": "capability_problem",
            "name": self.name,
            "n_targets": self.n_targets,
            "vehicle_capability": [str(c) for c in self.vehicle_capability],
            "demands": [sorted(str(c) for c in d) for d in self.demands],
            "cost": cost,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str | None = None) -> CapabilityProblem:
        """From JSON data; ``null`` in a cost matrix means the pair cannot be travelled.

        Raises
        ------
        InstanceError
            A schema violation (naming the JSON path and the value), a matrix that is not
            square (naming the matrix and the row), or the constructor's own complaint.
        """
        from taopt.instance import check_schema
        from taopt.schemas import naming

        label = source or "capability_problem"
        check_schema(data, "capability_problem", source)

        def decode(rows: Any, where: str) -> np.ndarray:
            for i, row in enumerate(rows):
                if len(row) != len(rows):
                    raise InstanceError(
                        f"{label}: {where}[{i}]: expected {len(rows)} numbers "
                        f"(cost must be square), got {len(row)}"
                    )
            return np.array([[np.inf if v is None else v for v in row] for row in rows], float)

        cost = data["cost"]
        if isinstance(cost, dict):
            cost = {k: decode(v, f"cost.{k}") for k, v in cost.items()}
        else:
            cost = decode(cost, "cost")
        with naming(label):
            return cls(
                cost,
                data["n_targets"],
                tuple(data["vehicle_capability"]),
                tuple(frozenset(d) for d in data["demands"]),
                data.get("name", ""),
            )

    def save(self, path: str | os.PathLike[str]) -> None:
        from taopt.io import save_json

        save_json(self.to_dict(), path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> CapabilityProblem:
        """Read a file written by :meth:`save` (strict JSON, validated; every failure an
        InstanceError naming the path)."""
        from taopt.io import load_json

        return cls.from_dict(load_json(path, "capability_problem"), source=str(path))

    def __repr__(self) -> str:
        label = f" {self.name!r}" if self.name else ""
        return (
            f"CapabilityProblem{label}(n={self.n}, m={self.m}, |A|={len(self.capabilities)}, "
            f"demands={self.demand_pairs()})"
        )


def evaluate_capability(problem: CapabilityProblem, routes: Sequence[Sequence[int]]) -> float:
    """The one scorer of chapter 3: check (3.2)–(3.3) with flow and no subtours, then (3.1).

    Routes are one list of target indices per vehicle (open routes from its start). Every
    (target, demanded capability) pair must be served exactly once, by a vehicle of that
    capability; no vehicle may visit a target that does not demand its capability, nor the
    same target twice.

    Raises
    ------
    FeasibilityError
        Naming the target and the capability (and the vehicles involved).
    """
    from taopt.result import Routes

    routes = list(Routes(routes))
    if len(routes) != problem.m:
        raise FeasibilityError(f"expected {problem.m} routes (one per vehicle), got {len(routes)}")
    served: dict[tuple[int, Hashable], int] = {}
    total = 0.0
    n = problem.n
    for k, route in enumerate(routes):
        cap = problem.vehicle_capability[k]
        for target in route:
            if not 0 <= target < n:
                raise FeasibilityError(
                    f"route of vehicle {k}: index {target} is not a target (0..{n - 1})"
                )
            if cap not in problem.demands[target]:
                raise FeasibilityError(
                    f"vehicle {k} (capability {cap!r}) visits target {target}, which does not "
                    f"demand {cap!r} (it demands {sorted(problem.demands[target], key=str)})"
                )
            if (target, cap) in served:
                raise FeasibilityError(
                    f"target {target} is served twice for capability {cap!r} (vehicles "
                    f"{served[target, cap]} and {k}); (3.2) asks for exactly once"
                )
            served[target, cap] = k
        if route:
            matrix = problem.cost_for(cap)
            nodes = np.asarray([n + k, *route], dtype=int)
            legs = matrix[nodes[:-1], nodes[1:]]
            if not np.isfinite(legs).all():
                leg = int(np.flatnonzero(~np.isfinite(legs))[0])
                raise FeasibilityError(
                    f"vehicle {k} travels {nodes[leg]} -> {nodes[leg + 1]}, which cannot be "
                    "travelled (inf)"
                )
            total += float(legs.sum())
    for j in range(n):
        for cap in sorted(problem.demands[j], key=str):
            if (j, cap) not in served:
                raise FeasibilityError(f"target {j} is never served for capability {cap!r} ((3.2))")
    return total
