"""Task-assignment instances: vehicles, targets, region, drift field, obstacles.

An :class:`Instance` is immutable problem data, validated on construction
(every error an :class:`~taopt.errors.InstanceError` naming the offending
item), with JSON load/save carrying a schema version. It is the input of the
navigation layer, which turns it into a travel-time matrix; the assignment
algorithms only ever see that matrix (DESIGN invariant 2).

Point order follows the thesis (§2.2.1): targets ``0..n-1`` first, then the
vehicles' start positions ``n..n+m-1``.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt import schemas
from taopt.errors import InstanceError
from taopt.fields import Field, field_from_dict

# save_json, load_json and unique_temp live in taopt.io; re-exported here for compatibility
# (code written against `from taopt.instance import save_json` keeps working).
from taopt.io import load_json, save_json, unique_temp

SCHEMA_VERSION = 1


def _xy(value: Any, what: str) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in value)
    except (TypeError, ValueError):
        raise InstanceError(f"{what}: position must be two numbers, got {value!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise InstanceError(f"{what}: position ({x}, {y}) is not finite")
    return (x, y)


@dataclass(frozen=True)
class Vehicle:
    """A vehicle: id, start position, speed relative to the field (2.1), capability (ch. 3)."""

    id: str
    start: tuple[float, float]
    speed: float = 1.0
    capability: str = "any"


@dataclass(frozen=True)
class Target:
    """A target location and the capabilities it demands (ch. 3: one visit per capability)."""

    id: str
    position: tuple[float, float]
    demands: tuple[str, ...] = ("any",)


@dataclass(frozen=True)
class Obstacle:
    """A polygonal obstacle (ch. 3), vertices in order."""

    vertices: tuple[tuple[float, float], ...]
    id: str = ""

    def contains(self, xy: Any) -> np.ndarray:
        """Boolean mask of the points (N, 2) inside the polygon."""
        from matplotlib.path import Path as MplPath

        pts = np.atleast_2d(np.asarray(xy, dtype=float))
        return MplPath(np.asarray(self.vertices)).contains_points(pts)


@dataclass(frozen=True)
class Instance:
    """A multi-vehicle task-assignment instance (thesis §2.2, §3.2).

    Parameters
    ----------
    vehicles, targets : sequences of :class:`Vehicle`, :class:`Target`
    region : (xmin, xmax, ymin, ymax)
        The operating area; every point must lie in it.
    field : Field or None
        Time-invariant drift; None means still water.
    obstacles : sequence of :class:`Obstacle`

    Raises
    ------
    InstanceError
        Duplicate ids, non-finite coordinates, a point outside the region, a
        target demanding a capability no vehicle has, a vehicle not faster than
        the drift somewhere in the region (Assumption 2.1; the message names the
        location and both speeds).

    Example
    -------
    >>> from taopt.fields import thesis_field
    >>> inst = Instance.random(n_targets=5, n_vehicles=2, side=1000.0, field=thesis_field(), seed=0)
    >>> inst.points.shape
    (7, 2)
    """

    vehicles: tuple[Vehicle, ...]
    targets: tuple[Target, ...]
    region: tuple[float, float, float, float]
    field: Field | None = None
    obstacles: tuple[Obstacle, ...] = ()
    name: str = ""
    metadata: dict[str, Any] = dataclasses.field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "vehicles", tuple(self.vehicles))
        object.__setattr__(self, "targets", tuple(self.targets))
        object.__setattr__(self, "obstacles", tuple(self.obstacles))
        self._validate()

    # -- validation ----------------------------------------------------------------
    def _validate(self) -> None:
        try:
            xmin, xmax, ymin, ymax = (float(v) for v in self.region)
        except (TypeError, ValueError):
            raise InstanceError(
                f"region must be (xmin, xmax, ymin, ymax), got {plain(self.region)!r}"
            ) from None
        if (
            not all(math.isfinite(v) for v in (xmin, xmax, ymin, ymax))
            or xmin >= xmax
            or ymin >= ymax
        ):
            raise InstanceError(
                f"region {plain(self.region)!r} must be finite with xmin < xmax and ymin < ymax"
            )
        object.__setattr__(self, "region", (xmin, xmax, ymin, ymax))
        if not self.vehicles:
            raise InstanceError("an instance needs at least one vehicle")
        if not self.targets:
            raise InstanceError("an instance needs at least one target")

        def inside(p: tuple[float, float]) -> bool:
            return xmin <= p[0] <= xmax and ymin <= p[1] <= ymax

        seen: set[str] = set()
        vehicles = []
        for k, v in enumerate(self.vehicles):
            if not isinstance(v, Vehicle):
                raise InstanceError(f"vehicles[{k}] is not a Vehicle")
            start = _xy(v.start, f"vehicle {v.id!r}")
            if v.id in seen:
                raise InstanceError(f"duplicate id {v.id!r} (vehicle)")
            seen.add(v.id)
            if not (math.isfinite(v.speed) and v.speed > 0):
                raise InstanceError(
                    f"vehicle {v.id!r}: speed must be positive and finite, got {v.speed}"
                )
            if not inside(start):
                raise InstanceError(
                    f"vehicle {v.id!r}: start {start} is outside the region {self.region}"
                )
            vehicles.append(dataclasses.replace(v, start=start, speed=float(v.speed)))
        targets = []
        capabilities = {v.capability for v in vehicles}
        for k, t in enumerate(self.targets):
            if not isinstance(t, Target):
                raise InstanceError(f"targets[{k}] is not a Target")
            pos = _xy(t.position, f"target {t.id!r}")
            if t.id in seen:
                raise InstanceError(f"duplicate id {t.id!r} (target)")
            seen.add(t.id)
            if not inside(pos):
                raise InstanceError(
                    f"target {t.id!r}: position {pos} is outside the region {self.region}"
                )
            demands = tuple(t.demands)
            if not demands:
                raise InstanceError(f"target {t.id!r} demands no capability")
            twice = sorted({cap for cap in demands if demands.count(cap) > 1}, key=str)
            if twice:
                raise InstanceError(
                    f"target {t.id!r} demands capability {twice[0]!r} twice (one visit per "
                    "capability: list it once)"
                )
            for cap in demands:
                if cap not in capabilities:
                    raise InstanceError(
                        f"target {t.id!r} demands capability {cap!r}, which no vehicle has "
                        f"(vehicles have {sorted(capabilities)})"
                    )
            targets.append(dataclasses.replace(t, position=pos, demands=demands))
        object.__setattr__(self, "vehicles", tuple(vehicles))
        object.__setattr__(self, "targets", tuple(targets))
        for k, obs in enumerate(self.obstacles):
            if len(obs.vertices) < 3:
                raise InstanceError(f"obstacle {obs.id or k!r} needs at least 3 vertices")
            for vert in obs.vertices:
                _xy(vert, f"obstacle {obs.id or k!r}")
        if self.field is not None:
            if not isinstance(self.field, Field):
                raise InstanceError(
                    f"field must be a taopt.fields.Field, got {type(self.field).__name__}"
                )
            drift = self.field.max_speed(self.region)
            where = tuple(float(c) for c in self.field.argmax_speed(self.region))
            for v in vehicles:
                if not v.speed > drift:
                    raise InstanceError(
                        f"vehicle {v.id!r}: speed {v.speed:g} is not greater than the drift speed "
                        f"{drift:g} at {where} (Assumption 2.1 needs v > |v_c| everywhere in the region)"
                    )

    # -- views ---------------------------------------------------------------------
    @property
    def n_targets(self) -> int:
        return len(self.targets)

    @property
    def n_vehicles(self) -> int:
        return len(self.vehicles)

    @property
    def points(self) -> np.ndarray:
        """(n + m, 2) positions: targets first, then vehicle starts (thesis order)."""
        return np.array(
            [t.position for t in self.targets] + [v.start for v in self.vehicles], dtype=float
        )

    @property
    def speeds(self) -> np.ndarray:
        return np.array([v.speed for v in self.vehicles], dtype=float)

    def replace(self, **changes: Any) -> Instance:
        """A validated copy with some fields changed."""
        return dataclasses.replace(self, **changes)

    # -- construction ----------------------------------------------------------------
    @classmethod
    def random(
        cls,
        n_targets: int,
        n_vehicles: int,
        side: float = 1000.0,
        field: Field | None = None,
        speed: float = 1.0,
        seed: int | np.random.Generator | None = 0,
        name: str = "",
    ) -> Instance:
        """Uniform random targets and vehicle starts in ``[0, side]^2`` (thesis §2.5 setup)."""
        rng = np.random.default_rng(seed)
        tpos = rng.uniform(0.0, side, size=(n_targets, 2))
        vpos = rng.uniform(0.0, side, size=(n_vehicles, 2))
        return cls(
            vehicles=tuple(Vehicle(f"v{k}", tuple(p), speed) for k, p in enumerate(vpos)),
            targets=tuple(Target(f"t{k}", tuple(p)) for k, p in enumerate(tpos)),
            region=(0.0, side, 0.0, side),
            field=field,
            name=name or f"random-n{n_targets}m{n_vehicles}",
        )

    # -- JSON ------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        return {
            "schema_version": SCHEMA_VERSION,
            "kind": "instance",
            "name": self.name,
            "region": list(self.region),
            "field": None if self.field is None else self.field.to_dict(),
            "vehicles": [
                {"id": v.id, "start": list(v.start), "speed": v.speed, "capability": v.capability}
                for v in self.vehicles
            ],
            "targets": [
                {"id": t.id, "position": list(t.position), "demands": list(t.demands)}
                for t in self.targets
            ],
            "obstacles": [
                {"id": o.id, "vertices": [list(p) for p in o.vertices]} for o in self.obstacles
            ],
            "metadata": self.metadata,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any], source: str | None = None) -> Instance:
        """Inverse of :meth:`to_dict`: the data is checked against ``instance.schema.json``
        first, then by the constructor.

        Parameters
        ----------
        data : dict
            Parsed JSON (see ``docs/file-formats.md``). ``field`` is required (``None``
            for still water); ``speed`` defaults to 1, ``capability`` and ``demands`` to
            ``"any"``, ``obstacles`` to none.
        source : str, optional
            What to call the data in error messages (the file path); default "instance".

        Raises
        ------
        InstanceError
            The first schema violation (naming the JSON path and the value), or the
            constructor's own complaint.
        """
        check_schema(data, "instance", source)
        field = data["field"]
        with schemas.naming(source or "instance"):
            return cls(
                vehicles=tuple(
                    Vehicle(
                        v["id"],
                        tuple(v["start"]),
                        float(v.get("speed", 1.0)),
                        v.get("capability", "any"),
                    )
                    for v in data["vehicles"]
                ),
                targets=tuple(
                    Target(t["id"], tuple(t["position"]), tuple(t.get("demands", ["any"])))
                    for t in data["targets"]
                ),
                region=tuple(data["region"]),
                field=None if field is None else field_from_dict(field),
                obstacles=tuple(
                    Obstacle(tuple(tuple(p) for p in o["vertices"]), o.get("id", ""))
                    for o in data.get("obstacles", [])
                ),
                name=data.get("name", ""),
                metadata=dict(data.get("metadata", {})),
            )

    def save(self, path: str | os.PathLike[str]) -> None:
        save_json(self.to_dict(), path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Instance:
        """Read an instance file (strict JSON, validated; every failure an InstanceError
        naming the path)."""
        return cls.from_dict(load_json(path, "instance"), source=str(path))


def check_schema(data: Any, kind: str, source: str | None = None) -> None:
    """Raise :class:`InstanceError` unless ``data`` matches the JSON Schema of ``kind``.

    The schema version and kind are checked first, then the whole schema
    (:func:`taopt.schemas.validate`); the message names ``source`` (default ``kind``),
    the JSON path and the value.
    """
    schemas.validate(data, kind, source)


def plain(value: Any) -> Any:
    """``value`` with numpy scalars made plain Python numbers (inside lists, tuples and dicts
    too), so a message shows ``20.0``, never ``np.float64(20.0)``."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return type(value)(plain(v) for v in value)
    if isinstance(value, dict):
        return {plain(k): plain(v) for k, v in value.items()}
    return value


def check_square(rows: Any, where: str, source: str) -> None:
    """Raise :class:`InstanceError` naming the first row of ``rows`` (a schema-checked list of
    lists) whose length is not ``len(rows)``: a ragged or non-square matrix."""
    for i, row in enumerate(rows):
        if len(row) != len(rows):
            raise InstanceError(
                f"{source}: {where}[{i}]: expected {len(rows)} numbers "
                f"(the matrix must be square), got {len(row)}"
            )


def targets_from_points(points: Iterable[Sequence[float]], prefix: str = "t") -> tuple[Target, ...]:
    return tuple(Target(f"{prefix}{k}", (p[0], p[1])) for k, p in enumerate(points))


__all__ = [
    "Instance",
    "Vehicle",
    "Target",
    "Obstacle",
    "SCHEMA_VERSION",
    "save_json",
    "load_json",
    "check_schema",
    "check_square",
    "plain",
    "unique_temp",
]
