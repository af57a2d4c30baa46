"""Random scenarios of the thesis's §2.5 experiment, with a disk cache of travel times.

Setup (§2.5): vehicles of speed ``v = 1`` in a ``1000 m`` square, drift
``v_c = 1e-3 [0.3x + 0.2y, -0.2x + 0.3y]`` (:func:`taopt.fields.thesis_field`),
targets and vehicle starts uniformly random. The travel-time matrix
``t(i, j)`` comes from :func:`taopt.navigation.travel_time_matrix` (minimum-time
navigation, §2.3) and is cached as ``.npy`` plus a ``.json`` description (never
pickle), because it dominates the cost of a scenario.

Example
-------
>>> from taopt.routing.scenarios import scenario_seed
>>> scenario_seed(1, 0) == scenario_seed(1, 0) != scenario_seed(1, 1)
True
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from taopt.errors import InstanceError, OutputError
from taopt.fields import Field, field_from_dict, thesis_field
from taopt.instance import Instance
from taopt.io import save_json, unique_temp
from taopt.routing.problem import AssignmentProblem

THESIS_SIDE = 1000.0
THESIS_SPEED = 1.0

__all__ = ["THESIS_SIDE", "THESIS_SPEED", "Scenario", "scenario_seed", "drift_scenario"]


def scenario_seed(seed: int, k: int) -> int:
    """Seed of scenario ``k`` of a study with seed ``seed``.

    Derived with :class:`numpy.random.SeedSequence` from ``(seed, k)``, so a
    scenario's data does not depend on how many scenarios are run or in which
    order (a resumed or parallel study draws the same scenarios).
    """
    if int(seed) < 0 or int(k) < 0:
        raise InstanceError(f"seed and scenario index must be >= 0, got {seed}, {k}")
    return int(np.random.SeedSequence(int(seed), spawn_key=(int(k),)).generate_state(1)[0])


@dataclass(frozen=True)
class Scenario:
    """One random scenario: the instance (positions, field) and its assignment problem."""

    instance: Instance
    problem: AssignmentProblem
    seed: int

    @property
    def points(self) -> np.ndarray:
        """(n + m, 2): targets first, then vehicle starts."""
        return self.instance.points


def _cache_key(description: dict[str, Any]) -> str:
    text = json.dumps(description, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def drift_scenario(
    n: int,
    m: int,
    seed: int,
    field: Field | None | str = "thesis",
    side: float = THESIS_SIDE,
    speed: float = THESIS_SPEED,
    cache_dir: str | os.PathLike | None = None,
    jobs: int | None = 1,
    method: str = "auto",
) -> Scenario:
    """Build the §2.5 scenario with seed ``seed``.

    Parameters
    ----------
    n, m : int
        Targets and vehicles.
    seed : int
        Scenario seed (see :func:`scenario_seed`); positions are drawn by
        :meth:`taopt.Instance.random` with it.
    field : Field, None or "thesis"
        The drift; "thesis" is ``thesis_field(1e-3)``.
    side, speed : float
        Square edge (m) and vehicle speed (m/s).
    cache_dir : path, optional
        Folder for cached travel-time matrices (``<key>.npy`` + ``<key>.json``).
    jobs : int, optional
        Worker processes for the travel-time matrix.
    method : str
        Navigation method for non-uniform fields (see ``travel_time_matrix``).

    Returns
    -------
    Scenario
    """
    from taopt.navigation import travel_time_matrix

    if field == "thesis":
        field = thesis_field()
    if isinstance(field, dict):
        field = field_from_dict(field)
    if isinstance(field, str):  # Instance would refuse it too
        raise InstanceError(f"field must be a taopt.fields.Field, None or 'thesis', got {field!r}")
    instance = Instance.random(n, m, side=side, field=field, speed=speed, seed=int(seed))
    points = instance.points
    description = {
        "kind": "travel_time_matrix",
        "n": int(n),
        "m": int(m),
        "seed": int(seed),
        "side": float(side),
        "speed": float(speed),
        "field": None if field is None else field.to_dict(),
        "method": method,
        "points_sha": hashlib.sha256(np.ascontiguousarray(points).tobytes()).hexdigest()[:16],
    }
    matrix = None
    if cache_dir is not None:
        folder = Path(cache_dir)
        folder.mkdir(parents=True, exist_ok=True)
        key = _cache_key(description)
        npy, meta = folder / f"{key}.npy", folder / f"{key}.json"
        if npy.exists() and meta.exists():
            try:
                if json.loads(meta.read_text()) == description:
                    matrix = np.load(npy, allow_pickle=False)
            except (OSError, ValueError):
                matrix = None
    if matrix is None:
        matrix = travel_time_matrix(field, points, speed=speed, jobs=jobs, method=method)
        if cache_dir is not None:
            tmp = unique_temp(npy, ".tmp.npy")  # per process: parallel writers never share it
            try:
                np.save(tmp, matrix, allow_pickle=False)
                os.replace(tmp, npy)
                save_json(description, meta)  # atomic, written after the .npy it describes
            except BaseException as exc:
                npy.unlink(missing_ok=True)  # no .npy without the description that keys it
                if isinstance(exc, OSError):
                    detail = exc.strerror or str(exc)
                    raise OutputError(f"{npy}: cannot be written ({detail})") from None
                raise
            finally:
                tmp.unlink(missing_ok=True)
    problem = AssignmentProblem(matrix, n_targets=n, name=f"n{n}m{m}-seed{seed}")
    return Scenario(instance=instance, problem=problem, seed=int(seed))
