"""The payload of a chapter 4 solution — driven trajectories — and the family's one scorer.

A :class:`Trajectories` holds, per vehicle, its waypoints ``(t, x, y)`` (the start at
``t = 0``, every point where it turned, stopped, restarted or visited a target, and its
position when the last target was visited) and its visits ``(target, waypoint index)``.
:func:`evaluate_trajectories` recomputes (4.1) from the waypoints alone and checks (4.2):
every target visited by a vehicle of its attribute, every visit at the target's position,
no vehicle faster than unit speed.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt.errors import FeasibilityError, InstanceError
from taopt.result import register_payload

#: Absolute tolerance (metres / seconds) of the scorer's position and speed checks.
TOLERANCE = 1e-6


_COORDINATE = {"type": "number", "minimum": -1_000_000_000, "maximum": 1_000_000_000}


@register_payload(
    "trajectories",
    schema={
        "description": "Chapter 4: waypoints (t, x, y) of each vehicle (|value| <= 1e9) and "
        "its visits (target, waypoint index).",
        "type": "object",
        "required": ["paths", "visits"],
        "additionalProperties": False,
        "properties": {
            "paths": {
                "type": "array",
                "items": {
                    "type": "array",
                    "minItems": 1,
                    "items": {"type": "array", "minItems": 3, "maxItems": 3, "items": _COORDINATE},
                },
            },
            "visits": {
                "type": "array",
                "items": {
                    "type": "array",
                    "items": {
                        "type": "array",
                        "minItems": 2,
                        "maxItems": 2,
                        "items": {"$ref": "#/$defs/index"},
                    },
                },
            },
        },
    },
)
@dataclass(frozen=True, eq=False)
class Trajectories:
    """Driven trajectories of the m vehicles (the payload of a chapter 4 solution).

    Parameters
    ----------
    paths : sequence of m (k_j, 3) arrays
        Waypoints ``(t, x, y)`` of each vehicle, times non-decreasing, the first at t = 0 at
        its start; straight unit-speed (or slower) motion between consecutive waypoints.
    visits : sequence of m sequences of (target, waypoint index)
        The targets each vehicle visited, in order, with the waypoint where it was there.

    Example
    -------
    >>> tr = Trajectories([[[0, 0, 0], [2, 2, 0]]], [[(1, 1)]])
    >>> tr.lengths().tolist(), tr.visited_targets(0)
    ([2.0], [1])
    """

    paths: tuple[np.ndarray, ...]
    visits: tuple[tuple[tuple[int, int], ...], ...]

    def __init__(self, paths: Sequence[Any], visits: Sequence[Sequence[Any]]) -> None:
        clean = []
        for j, path in enumerate(paths):
            array = np.array(path, dtype=float)
            if array.ndim != 2 or array.shape[1] != 3 or array.shape[0] < 1:
                raise FeasibilityError(
                    f"trajectory of vehicle {j} must be a (k, 3) array of (t, x, y), "
                    f"got shape {array.shape}"
                )
            array.setflags(write=False)
            clean.append(array)
        if len(visits) != len(clean):
            raise FeasibilityError(f"{len(clean)} trajectories but {len(visits)} visit lists")
        pairs = []
        for j, seq in enumerate(visits):
            row = []
            for item in seq:
                try:
                    target, index = (int(v) for v in item)
                except (TypeError, ValueError):
                    raise FeasibilityError(
                        f"visit {item!r} of vehicle {j} is not a (target, waypoint) pair"
                    ) from None
                row.append((target, index))
            pairs.append(tuple(row))
        object.__setattr__(self, "paths", tuple(clean))
        object.__setattr__(self, "visits", tuple(pairs))

    def __len__(self) -> int:
        return len(self.paths)

    def __iter__(self) -> Iterator[np.ndarray]:
        return iter(self.paths)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Trajectories):
            return NotImplemented
        return (
            self.visits == other.visits
            and all(
                a.shape == b.shape and bool(np.array_equal(a, b))
                for a, b in zip(self.paths, other.paths, strict=True)
            )
            and len(self.paths) == len(other.paths)
        )

    __hash__ = object.__hash__

    def lengths(self) -> np.ndarray:
        """(m,) distance driven by each vehicle, ``d_j`` of (4.1)."""
        return np.array([path_length(p) for p in self.paths])

    def visited_targets(self, vehicle: int) -> list[int]:
        """Targets visited by ``vehicle``, in order (repeats kept)."""
        return [t for t, _ in self.visits[vehicle]]

    def first_visit_routes(self) -> list[list[int]]:
        """Routes that serve each target once: every target goes to its first visitor.

        Each route is the vehicle's first visits in order; by the triangle inequality it is
        no longer than the vehicle's trajectory, so these routes score at most (4.1) of the
        trajectories in :meth:`~taopt.comm.problem.CommProblem.full_information` (an incumbent for the exact
        model).
        """
        first: dict[int, tuple[float, int, int]] = {}
        for j, seq in enumerate(self.visits):
            for order, (target, index) in enumerate(seq):
                key = (float(self.paths[j][index, 0]), j, order)
                if target not in first or key < first[target]:
                    first[target] = key
        routes: list[list[tuple[int, int]]] = [[] for _ in self.paths]
        for target, (_, j, order) in first.items():
            routes[j].append((order, target))
        return [[t for _, t in sorted(r)] for r in routes]

    def position(self, vehicle: int, time: float) -> np.ndarray:
        """Position of ``vehicle`` at ``time`` (linear between waypoints; held at the ends)."""
        path = self.paths[vehicle]
        t = path[:, 0]
        return np.array([np.interp(time, t, path[:, 1]), np.interp(time, t, path[:, 2])])

    @property
    def end_time(self) -> float:
        """Time of the last waypoint (when the last target was visited)."""
        return float(max(p[-1, 0] for p in self.paths))

    def to_dict(self) -> dict[str, Any]:
        return {
            "paths": [p.tolist() for p in self.paths],
            "visits": [[list(v) for v in seq] for seq in self.visits],
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Trajectories:
        if not isinstance(data, Mapping) or "paths" not in data or "visits" not in data:
            raise InstanceError("a trajectories payload needs 'paths' and 'visits'")
        return cls(data["paths"], data["visits"])

    def __repr__(self) -> str:
        total = float(self.lengths().sum())
        return f"Trajectories(m={len(self.paths)}, total={total:.6g})"


def path_length(path: np.ndarray) -> float:
    """Length of the polyline through the (x, y) columns of a (k, 3) waypoint array."""
    if len(path) < 2:
        return 0.0
    steps = np.diff(path[:, 1:], axis=0)
    return float(np.hypot(steps[:, 0], steps[:, 1]).sum())


def evaluate_trajectories(problem: Any, trajectories: Trajectories) -> float:
    """The one scorer of chapter 4: check (4.2) on the trajectories, then return (4.1).

    Checks, naming the vehicle, target or waypoint: one trajectory per vehicle, starting at
    its start at t = 0; times non-decreasing; speed at most 1 (unit speed, §4.2); every
    visit at the target's position by a vehicle whose ability matches its attribute; every
    target visited at least once.

    Returns
    -------
    float
        ``f = Σ_j d_j`` (4.1), the total length of the trajectories.

    Raises
    ------
    FeasibilityError
    """
    if not isinstance(trajectories, Trajectories):
        trajectories = Trajectories.from_dict(trajectories)
    if len(trajectories) != problem.m:
        raise FeasibilityError(
            f"expected {problem.m} trajectories (one per vehicle), got {len(trajectories)}"
        )
    scale = TOLERANCE * max(1.0, problem.side())
    visited = np.zeros(problem.n, dtype=bool)
    total = 0.0
    for j, path in enumerate(trajectories.paths):
        start = problem.vehicles[j]
        if abs(path[0, 0]) > TOLERANCE or np.hypot(*(path[0, 1:] - start)) > scale:
            raise FeasibilityError(
                f"vehicle {j}'s trajectory starts at t={path[0, 0]:g}, {path[0, 1:].tolist()}, "
                f"not at its start {start.tolist()} at t=0"
            )
        if not np.isfinite(path).all():
            raise FeasibilityError(f"vehicle {j}'s trajectory has a non-finite waypoint")
        dt = np.diff(path[:, 0])
        if (dt < -TOLERANCE).any():
            k = int(np.flatnonzero(dt < -TOLERANCE)[0])
            raise FeasibilityError(f"vehicle {j}: waypoint {k + 1} goes back in time")
        steps = np.diff(path[:, 1:], axis=0)
        legs = np.hypot(steps[:, 0], steps[:, 1])
        fast = legs > dt * (1.0 + 1e-9) + scale
        if fast.any():
            k = int(np.flatnonzero(fast)[0])
            raise FeasibilityError(
                f"vehicle {j} drives {legs[k]:.6g} m in {dt[k]:.6g} s between waypoints "
                f"{k} and {k + 1}: faster than unit speed"
            )
        total += float(legs.sum())
        for target, index in trajectories.visits[j]:
            if not 0 <= target < problem.n:
                raise FeasibilityError(f"vehicle {j} visits {target}, which is not a target")
            if not 0 <= index < len(path):
                raise FeasibilityError(
                    f"vehicle {j}'s visit of target {target} names waypoint {index}, "
                    f"but it has {len(path)}"
                )
            if not problem.can_visit(j, target):
                raise FeasibilityError(
                    f"vehicle {j} (ability {problem.vehicle_ability[j]!r}) visits target "
                    f"{target} (attribute {problem.target_attribute[target]!r}): (4.2) needs "
                    "a matching ability"
                )
            where = path[index, 1:]
            if np.hypot(*(where - problem.targets[target])) > scale:
                raise FeasibilityError(
                    f"vehicle {j}'s visit of target {target} is at {where.tolist()}, not at "
                    f"the target {problem.targets[target].tolist()}"
                )
            visited[target] = True
    if not visited.all():
        q = int(np.flatnonzero(~visited)[0])
        raise FeasibilityError(
            f"target {q} (attribute {problem.target_attribute[q]!r}) is never visited ((4.2))"
        )
    return total


__all__ = ["Trajectories", "evaluate_trajectories", "path_length", "TOLERANCE"]
