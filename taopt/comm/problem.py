"""Chapter 4 problem data: dispersed vehicles with one ability, targets with one attribute, range r.

Thesis §4.2: vehicles ``R = {0..m-1}`` start at points in the plane, each with one ability
``a_j``; targets ``T = {0..n-1}`` each have one attribute ``a^q`` and must be visited by a
vehicle whose ability matches (4.2). Vehicles move at unit speed along straight lines, so
distance and time are the same number; two vehicles communicate while they are at most
``r`` apart (4.3). The objective (4.1) is the total distance driven until every target has
been visited.

Only the data lives here. The simulation (:mod:`taopt.comm.engine`) runs the algorithms of
:mod:`taopt.heuristics.comm` on it; :meth:`~taopt.comm.problem.CommProblem.full_information` gives the problem
without communication limits, whose exact optimum ``f_o`` is certified by
``taopt.solve(problem, "exact")``.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Hashable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt.errors import InstanceError

#: Side of the thesis's square area (§4.4), metres.
THESIS_SIDE = 1000.0


def _points(value: Any, what: str) -> np.ndarray:
    try:
        points = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InstanceError(f"{what} must be an (k, 2) array of numbers") from None
    if points.ndim != 2 or points.shape[1] != 2:
        raise InstanceError(f"{what} must have shape (k, 2), got {points.shape}")
    if points.shape[0] < 1:
        raise InstanceError(f"{what} is empty: need at least one")
    bad = np.argwhere(~np.isfinite(points))
    if bad.size:
        k = int(bad[0][0])
        raise InstanceError(f"{what}[{k}] = {points[k].tolist()} is not finite")
    points.setflags(write=False)
    return points


def _labels(value: Any, count: int, what: str) -> tuple[Hashable, ...]:
    if isinstance(value, (str, bytes)):
        raise InstanceError(f"{what} must be a sequence of labels, one per item")
    labels = tuple(value.tolist() if isinstance(value, np.ndarray) else value)
    if len(labels) != count:
        raise InstanceError(f"{what} has {len(labels)} labels, expected {count}")
    for k, label in enumerate(labels):
        if isinstance(label, (bool, np.bool_)) or not isinstance(label, (str, int, np.integer)):
            raise InstanceError(f"{what}[{k}] = {label!r} is not a label (a string or integer)")
    return tuple(int(x) if isinstance(x, np.integer) else x for x in labels)


@dataclass(frozen=True, eq=False)
class CommProblem:
    """Task assignment under a limited communication range, thesis (4.1)–(4.3).

    Parameters
    ----------
    targets : (n, 2) array_like
        Target positions (metres).
    vehicles : (m, 2) array_like
        The vehicles' start positions (metres).
    target_attribute : sequence of n labels
        ``a^q``: the ability a vehicle needs to visit target q (strings or integers).
    vehicle_ability : sequence of m labels
        ``a_j``: vehicle j's one ability.
    comm_range : float
        ``r >= 0`` (metres): vehicles j and k communicate while ``|p_j - p_k| <= r`` (4.3).
    name : str

    Raises
    ------
    InstanceError
        No targets or vehicles, a non-finite position, ``r`` negative or not finite, a label
        count that does not match, or a target whose attribute no vehicle has (named).

    Example
    -------
    >>> p = CommProblem([[1, 0], [2, 0]], [[0, 0]], ["a", "a"], ["a"], comm_range=10)
    >>> p.n, p.m, p.attributes
    (2, 1, ('a',))
    >>> p.distance(p.n + 0, 1)          # vehicle 0's start to target 1
    2.0
    """

    targets: Any
    vehicles: Any
    target_attribute: Any
    vehicle_ability: Any
    comm_range: float
    name: str = ""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        targets = _points(self.targets, "targets")
        vehicles = _points(self.vehicles, "vehicles")
        n, m = targets.shape[0], vehicles.shape[0]
        attribute = _labels(self.target_attribute, n, "target_attribute")
        ability = _labels(self.vehicle_ability, m, "vehicle_ability")
        have = set(ability)
        for q, label in enumerate(attribute):
            if label not in have:
                raise InstanceError(
                    f"target {q} has attribute {label!r}, which no vehicle has "
                    f"(vehicle abilities: {sorted(have, key=str)})"
                )
        r = self.comm_range
        if isinstance(r, (bool, np.bool_)) or not isinstance(r, (int, float, np.number)):
            raise InstanceError(f"comm_range must be a number of metres, got {r!r}")
        r = float(r)
        if not math.isfinite(r) or r < 0:
            raise InstanceError(f"comm_range must be finite and >= 0, got {r}")
        set_(self, "targets", targets)
        set_(self, "vehicles", vehicles)
        set_(self, "target_attribute", attribute)
        set_(self, "vehicle_ability", ability)
        set_(self, "comm_range", r)
        set_(self, "name", str(self.name))
        labels = tuple(dict.fromkeys(ability + attribute))
        code = {label: k for k, label in enumerate(labels)}
        set_(self, "_labels", labels)
        target_code = np.array([code[a] for a in attribute], dtype=np.int64)
        vehicle_code = np.array([code[a] for a in ability], dtype=np.int64)
        target_code.setflags(write=False)
        vehicle_code.setflags(write=False)
        set_(self, "_target_code", target_code)
        set_(self, "_vehicle_code", vehicle_code)
        set_(self, "_cache", {})

    # -- sizes and labels ------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of targets."""
        return int(self.targets.shape[0])

    @property
    def m(self) -> int:
        """Number of vehicles."""
        return int(self.vehicles.shape[0])

    @property
    def attributes(self) -> tuple[Hashable, ...]:
        """The set A of abilities/attributes, in order of first appearance (vehicles first)."""
        # ignore (here and below): set by __post_init__ (object.__setattr__), not a field
        return self._labels  # type: ignore[attr-defined]

    @property
    def target_code(self) -> np.ndarray:
        """(n,) int: index in :attr:`attributes` of each target's attribute."""
        return self._target_code  # type: ignore[attr-defined]

    @property
    def vehicle_code(self) -> np.ndarray:
        """(m,) int: index in :attr:`attributes` of each vehicle's ability."""
        return self._vehicle_code  # type: ignore[attr-defined]

    @property
    def points(self) -> np.ndarray:
        """(n + m, 2): targets first, then the vehicles' starts (chapter 2's numbering)."""
        cache = self._cache  # type: ignore[attr-defined]
        if "points" not in cache:
            pts = np.vstack([self.targets, self.vehicles])
            pts.setflags(write=False)
            cache["points"] = pts
        return cache["points"]

    @property
    def distances(self) -> np.ndarray:
        """(n + m, n + m) Euclidean distances between :attr:`points` (unit speed: times)."""
        cache = self._cache  # type: ignore[attr-defined]
        if "distances" not in cache:
            from scipy.spatial.distance import cdist

            dist = cdist(self.points, self.points)
            dist.setflags(write=False)
            cache["distances"] = dist
        return cache["distances"]

    def distance(self, i: int, j: int) -> float:
        """Distance between points i and j (targets ``0..n-1``, vehicle starts ``n..n+m-1``)."""
        return float(self.distances[i, j])

    def can_visit(self, vehicle: int, target: int) -> bool:
        """Whether ``a_vehicle = a^target`` (4.2)."""
        return bool(self.vehicle_code[vehicle] == self.target_code[target])

    def side(self) -> float:
        """Side of the smallest square at the origin holding every point (for plots)."""
        return float(max(1.0, np.max(np.abs(self.points))))

    # -- variants ------------------------------------------------------------------------------
    def replace(self, **changes: Any) -> CommProblem:
        """A copy with some fields changed, e.g. ``problem.replace(comm_range=300)``."""
        return dataclasses.replace(self, **changes)

    def full_information(self) -> Any:
        """The same problem without communication limits, for the certified optimum f_o.

        Returns
        -------
        AssignmentProblem
            When every vehicle and target share one label (|A| = 1): chapter 2's open
            routing on the Euclidean distances.
        CapabilityProblem
            Otherwise: chapter 3's problem with one demand per target (its attribute), which
            splits exactly into one open-routing problem per attribute class.
        """
        cost = np.array(self.distances)
        if len(self.attributes) == 1:
            from taopt.routing.problem import AssignmentProblem

            return AssignmentProblem(cost, n_targets=self.n, name=self.name)
        from taopt.capability.problem import CapabilityProblem

        return CapabilityProblem(
            cost,
            self.n,
            self.vehicle_ability,
            tuple(frozenset([a]) for a in self.target_attribute),
            self.name,
        )

    # -- JSON ----------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Plain JSON data (schema_version 1, kind "comm_problem")."""
        return {
            "schema_version": 1,
            "kind": "comm_problem",
            "name": self.name,
            "targets": self.targets.tolist(),
            "vehicles": self.vehicles.tolist(),
            "target_attribute": list(self.target_attribute),
            "vehicle_ability": list(self.vehicle_ability),
            "comm_range": self.comm_range,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str | None = None) -> CommProblem:
        """From JSON data (validated against ``comm_problem.schema.json`` first).

        Parameters
        ----------
        data : mapping
            Parsed JSON of kind "comm_problem".
        source : str, optional
            What to call the data in messages (the file path); default "comm_problem".

        Raises
        ------
        InstanceError
            A schema violation (a coordinate or range above 1e9 in absolute value included)
            or the constructor's complaint; the message starts with ``source``.
        """
        from taopt.instance import check_schema
        from taopt.schemas import naming

        label = source or "comm_problem"
        check_schema(data, "comm_problem", label)
        with naming(label):
            return cls(
                data["targets"],
                data["vehicles"],
                data["target_attribute"],
                data["vehicle_ability"],
                data["comm_range"],
                data.get("name", ""),
            )

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the problem as JSON (atomically)."""
        from taopt.io import save_json

        save_json(self.to_dict(), path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> CommProblem:
        """Read a problem written by :meth:`save` (strict JSON, validated; every failure an
        InstanceError starting with the path)."""
        from taopt.io import load_json

        return cls.from_dict(load_json(path), source=str(path))  # from_dict checks the schema

    def __repr__(self) -> str:
        label = f" {self.name!r}" if self.name else ""
        return (
            f"CommProblem{label}(n={self.n}, m={self.m}, |A|={len(self.attributes)}, "
            f"r={self.comm_range:g})"
        )


def random_problem(
    n: int,
    m: int,
    n_attributes: int,
    comm_range: float,
    seed: int | np.random.Generator | None = 0,
    side: float = THESIS_SIDE,
    name: str = "",
) -> CommProblem:
    """A random scenario of §4.4: uniform positions in a ``side`` square, random labels.

    Abilities: every one of the ``n_attributes`` labels ``0..|A|-1`` is held by at least one
    vehicle (a random permutation for the first |A| vehicles, uniform for the rest, then
    shuffled); attributes: every label is some target's (as §4.2 asks: the union of the
    abilities equals the union of the attributes), the remaining targets uniform.

    Parameters
    ----------
    n, m : int
        Targets and vehicles (``1 <= |A| <= min(n, m)``).
    n_attributes : int
        |A|.
    comm_range : float
        r in metres.
    seed : int or numpy.random.Generator
    side : float
        Side of the square (the thesis: 1000 m).

    Raises
    ------
    InstanceError
        ``|A|`` outside ``1..min(n, m)``.

    Example
    -------
    >>> p = random_problem(30, 6, 3, 200.0, seed=1)
    >>> p.n, p.m, len(p.attributes)
    (30, 6, 3)
    """
    n, m, k = int(n), int(m), int(n_attributes)
    if n < 1 or m < 1:
        raise InstanceError(f"need n >= 1 and m >= 1, got n={n}, m={m}")
    if not 1 <= k <= min(n, m):
        raise InstanceError(f"|A| = {k} must lie in 1..min(n, m) = 1..{min(n, m)}")
    rng = np.random.default_rng(seed)
    targets = rng.uniform(0.0, side, size=(n, 2))
    vehicles = rng.uniform(0.0, side, size=(m, 2))
    ability = np.concatenate([rng.permutation(k), rng.integers(0, k, size=m - k)])
    attribute = np.concatenate([rng.permutation(k), rng.integers(0, k, size=n - k)])
    ability = rng.permutation(ability)
    attribute = rng.permutation(attribute)
    return CommProblem(
        targets,
        vehicles,
        [int(a) for a in attribute],
        [int(a) for a in ability],
        comm_range,
        name,
    )


__all__ = ["CommProblem", "random_problem", "THESIS_SIDE"]
