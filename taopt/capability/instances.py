"""Chapter 3 instances: an :class:`~taopt.Instance` to a :class:`CapabilityProblem`, and §3.7's scenarios.

:func:`capability_problem_from_instance` computes the travel times of an instance (the §3.3
grid planner when it has obstacles, minimum-time navigation otherwise) and builds the
problem from its vehicles' capabilities and its targets' demands.

:func:`thesis_scenario` draws one scenario of the §3.7 experiment:

* the 1000 m square, vehicle speed ``v = 1``, the field
  ``1e-3 [0.3x + 0.2y, -0.2x + 0.3y]`` (:func:`taopt.fields.thesis_field`);
* the three rectangular obstacles ``[150, 300] x [100, 120]``, ``[400, 420] x [350, 500]``,
  ``[600, 750] x [600, 620]`` (:data:`THESIS_OBSTACLES`);
* targets and vehicle starts uniform in the square outside the obstacles (rejection
  sampling: a point is redrawn while it falls in a grid cell an obstacle overlaps; with the
  study's 10 m cells, which the thesis's rectangles fit exactly, that is "outside the
  obstacles");
* capabilities ``A = {"c0", ..., "c{|A|-1}"}``: every capability is given to one vehicle
  first (a random vehicle for each, so every demand can be served, as §3.7 asks), and the
  other ``m - |A|`` vehicles get a capability drawn uniformly from A;
* demands (the thesis says only "randomly generated"): each target demands a subset of A
  drawn uniformly from its ``2^|A| - 1`` non-empty subsets (each capability independently
  with probability 1/2, redrawn while empty); so a target demands ``|A| / 2`` capabilities
  on average, and ``|A| = 1`` is chapter 2's problem.

Travel times: :data:`STUDY_CELL` = 10 m cells and :data:`STUDY_NEIGHBOURS` = 16 moves. The
lattice-error table (``taopt.navigation.grid.lattice_error_table``, in
``docs/reproduction/chapter3.md``) shows the grid's excess over collocation does not depend
on the cell size (it is the lattice's, 20 m to 2.5 m alike: about 4 % on average with 8
moves and 1 % with 16); 10 m is the coarsest size that represents the thesis's rectangles
exactly (their sides are multiples of 10 m and their 20 m thickness is two cells) and keeps
a 100-point matrix well under a second. 16 moves cut the excess four-fold at twice the cost.
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt.capability.problem import CapabilityProblem
from taopt.errors import InstanceError
from taopt.fields import Field, thesis_field
from taopt.instance import Instance, Obstacle, Target, Vehicle

THESIS_SIDE = 1000.0
THESIS_SPEED = 1.0
#: The three rectangles of §3.7, as polygons.
THESIS_OBSTACLES = (
    Obstacle(((150.0, 100.0), (300.0, 100.0), (300.0, 120.0), (150.0, 120.0)), "o1"),
    Obstacle(((400.0, 350.0), (420.0, 350.0), (420.0, 500.0), (400.0, 500.0)), "o2"),
    Obstacle(((600.0, 600.0), (750.0, 600.0), (750.0, 620.0), (600.0, 620.0)), "o3"),
)
#: Grid cell side (m) of the study's travel times (see the module notes).
STUDY_CELL = 10.0
#: Grid neighbourhood of the study's travel times.
STUDY_NEIGHBOURS = 16

__all__ = [
    "THESIS_SIDE",
    "THESIS_SPEED",
    "THESIS_OBSTACLES",
    "STUDY_CELL",
    "STUDY_NEIGHBOURS",
    "CapabilityScenario",
    "capability_problem_from_instance",
    "instance_travel_times",
    "thesis_scenario",
    "scenario_seed",
    "random_demands",
]


def _grid(instance: Instance, cell: float, neighbours: int, speed: float) -> Any:
    from taopt.navigation.grid import GridGraph

    return GridGraph(
        instance.field, instance.region, cell, instance.obstacles, speed, neighbours=neighbours
    )


def _point_text(point: Any) -> str:
    """``(50.0, 20.0)``: plain floats, not numpy's ``np.float64(50.0)``."""
    return f"({', '.join(repr(float(x)) for x in point)})"


def _check_points(instance: Instance, graph: Any = None) -> None:
    """Name a target or vehicle start inside an obstacle (or an obstacle's cell)."""
    names = [f"target {t.id!r}" for t in instance.targets]
    names += [f"vehicle {v.id!r} (start)" for v in instance.vehicles]
    points = instance.points
    for k, obstacle in enumerate(instance.obstacles):
        inside = np.flatnonzero(obstacle.contains(points))
        if inside.size:
            p = int(inside[0])
            raise InstanceError(
                f"{names[p]} at {_point_text(points[p])} lies inside obstacle {obstacle.id or k!r}"
            )
    if graph is not None:
        cells = graph.cell_index(points)
        bad = np.flatnonzero((cells < 0) | graph.blocked[np.maximum(cells, 0)])
        if bad.size:
            p = int(bad[0])
            raise InstanceError(
                f"{names[p]} at {_point_text(points[p])} lies in a grid cell of side {graph.cell:g} "
                "that an obstacle overlaps; use a smaller cell"
            )


def instance_travel_times(
    instance: Instance,
    speed: float,
    cell: float = STUDY_CELL,
    neighbours: int = STUDY_NEIGHBOURS,
    method: str = "auto",
    progress: bool = False,
    jobs: int | None = 1,
) -> np.ndarray:
    """Travel-time matrix of the instance's points for vehicles of ``speed``.

    Parameters
    ----------
    method : {"auto", "grid", "navigation"}
        "grid": the §3.3 planner (:func:`taopt.navigation.grid_travel_time_matrix`);
        "navigation": minimum-time navigation (collocation; closed form in a uniform
        field or still water), which knows no obstacles; "auto": grid when the instance
        has obstacles.

    Returns
    -------
    (n + m, n + m) ndarray
        ``inf`` where a point cannot reach another.
    """
    if method not in ("auto", "grid", "navigation"):
        raise InstanceError(f"method must be 'auto', 'grid' or 'navigation', got {method!r}")
    if method == "auto":
        method = "grid" if instance.obstacles else "navigation"
    if method == "navigation":
        if instance.obstacles:
            raise InstanceError("navigation knows no obstacles: use method='grid'")
        from taopt.navigation import travel_time_matrix

        return np.asarray(
            travel_time_matrix(
                instance.field, instance.points, speed, progress=progress, jobs=jobs
            ),
            dtype=float,
        )
    graph = _grid(instance, cell, neighbours, speed)
    _check_points(instance, graph)
    return graph.travel_time_matrix(instance.points)


def capability_problem_from_instance(
    instance: Instance,
    cell: float = STUDY_CELL,
    neighbours: int = STUDY_NEIGHBOURS,
    method: str = "auto",
    progress: bool = False,
    jobs: int | None = 1,
) -> CapabilityProblem:
    """The chapter 3 problem (3.1)–(3.3) of an :class:`~taopt.Instance`.

    Vehicles' capabilities and targets' demands come from the instance; travel times from
    :func:`instance_travel_times` (grid planner when there are obstacles). Vehicles of
    different speeds get one matrix per capability (all vehicles of one capability must then
    share a speed).

    Parameters
    ----------
    instance : Instance
    cell, neighbours : float, int
        Grid planner settings (used when the instance has obstacles or ``method="grid"``).
    method : {"auto", "grid", "navigation"}
    progress : bool
        Progress bar of the navigation matrix.
    jobs : int, optional
        Worker processes of the navigation matrix.

    Returns
    -------
    CapabilityProblem

    Raises
    ------
    InstanceError
        A target or vehicle inside an obstacle (named), vehicles of one capability with
        different speeds, a demanded target that no vehicle of its capability can reach
        (named by :class:`CapabilityProblem`).

    Example
    -------
    >>> from taopt import Instance, Target, Vehicle
    >>> inst = Instance(
    ...     vehicles=(Vehicle("a", (0, 0), capability="sonar"), Vehicle("b", (9, 0),
    ...               capability="camera")),
    ...     targets=(Target("t", (3, 4), demands=("sonar", "camera")),),
    ...     region=(0, 10, 0, 10))
    >>> p = capability_problem_from_instance(inst)
    >>> round(p.evaluate([[0], [0]]), 6)  # 5 + sqrt(36 + 16)
    12.211103
    """
    _check_points(instance)
    speeds: dict[Hashable, float] = {}
    for v in instance.vehicles:
        if speeds.setdefault(v.capability, v.speed) != v.speed:
            raise InstanceError(
                f"vehicles of capability {v.capability!r} have different speeds "
                f"({speeds[v.capability]:g} and {v.speed:g} for vehicle {v.id!r}); one cost "
                "matrix per capability needs one speed per capability"
            )
    distinct = sorted(set(speeds.values()))
    matrices = {
        speed: instance_travel_times(instance, speed, cell, neighbours, method, progress, jobs)
        for speed in distinct
    }
    cost: Any
    if len(distinct) == 1:
        cost = matrices[distinct[0]]
    else:
        cost = {cap: matrices[speed] for cap, speed in speeds.items()}
    return CapabilityProblem(
        cost,
        instance.n_targets,
        tuple(v.capability for v in instance.vehicles),
        tuple(frozenset(t.demands) for t in instance.targets),
        name=instance.name,
    )


@dataclass(frozen=True)
class CapabilityScenario:
    """One §3.7 scenario: the instance (positions, field, obstacles) and its problem."""

    instance: Instance
    problem: CapabilityProblem
    seed: int


def scenario_seed(*key: int) -> int:
    """A 32-bit seed from integers (``numpy.random.SeedSequence``), order-independent of runs."""
    if any(int(k) < 0 for k in key):
        raise InstanceError(f"seed keys must be >= 0, got {key}")
    return int(np.random.SeedSequence([int(k) for k in key]).generate_state(1)[0])


def random_demands(
    rng: np.random.Generator, n: int, capabilities: Sequence[str]
) -> list[tuple[str, ...]]:
    """A uniformly random non-empty subset of ``capabilities`` for each of ``n`` targets."""
    demands = []
    for _ in range(n):
        while True:
            pick = rng.random(len(capabilities)) < 0.5
            if pick.any():
                break
        demands.append(tuple(c for c, p in zip(capabilities, pick, strict=True) if p))
    return demands


def thesis_scenario(
    n: int,
    m: int,
    n_capabilities: int,
    seed: int,
    cell: float = STUDY_CELL,
    neighbours: int = STUDY_NEIGHBOURS,
    field: Field | None | str = "thesis",
    obstacles: Sequence[Obstacle] = THESIS_OBSTACLES,
    side: float = THESIS_SIDE,
    speed: float = THESIS_SPEED,
) -> CapabilityScenario:
    """Draw the §3.7 scenario with seed ``seed`` (see the module notes for every choice).

    Parameters
    ----------
    n, m : int
        Targets and vehicles (the thesis: n in {50, 70, 90}, m = 10).
    n_capabilities : int
        |A|, 1 <= |A| <= m (the thesis: 1, 3, 5, 7, 10).
    seed : int
        Same seed, same scenario.
    cell, neighbours : float, int
        Grid planner settings.
    field : Field, None or "thesis"
    obstacles : sequence of Obstacle
    side, speed : float

    Returns
    -------
    CapabilityScenario

    Example
    -------
    >>> s = thesis_scenario(8, 3, 2, seed=1)
    >>> s.problem.n, s.problem.m, len(s.problem.capabilities)
    (8, 3, 2)
    """
    if not (isinstance(n, (int, np.integer)) and n >= 1 and isinstance(m, (int, np.integer))):
        raise InstanceError(f"need integers n >= 1 and m >= 1, got n={n!r}, m={m!r}")
    if not 1 <= n_capabilities <= m:
        raise InstanceError(f"need 1 <= |A| <= m = {m}, got |A| = {n_capabilities}")
    if isinstance(field, str):
        if field != "thesis":
            raise InstanceError(f"field must be a Field, None or 'thesis', got {field!r}")
        field = thesis_field()
    rng = np.random.default_rng(seed)
    region = (0.0, float(side), 0.0, float(side))
    from taopt.navigation.grid import GridGraph

    blocked_grid = GridGraph(None, region, cell, obstacles)

    def draw(count: int) -> np.ndarray:
        out = np.empty((0, 2))
        while len(out) < count:
            batch = rng.uniform(0.0, side, size=(2 * (count - len(out)) + 4, 2))
            cells = blocked_grid.cell_index(batch)
            keep = batch[(cells >= 0) & ~blocked_grid.blocked[np.maximum(cells, 0)]]
            out = np.vstack([out, keep])
        return out[:count]

    targets_xy = draw(n)
    vehicles_xy = draw(m)
    labels = [f"c{q}" for q in range(n_capabilities)]
    capability = np.empty(m, dtype=object)
    first = rng.permutation(m)[:n_capabilities]
    capability[first] = labels
    rest = np.setdiff1d(np.arange(m), first)
    capability[rest] = [labels[q] for q in rng.integers(0, n_capabilities, size=len(rest))]
    demands = random_demands(rng, n, labels)
    instance = Instance(
        vehicles=tuple(
            Vehicle(f"v{k}", tuple(p), speed, str(capability[k])) for k, p in enumerate(vehicles_xy)
        ),
        targets=tuple(Target(f"t{k}", tuple(p), demands[k]) for k, p in enumerate(targets_xy)),
        region=region,
        field=field,
        obstacles=tuple(obstacles),
        name=f"n{n}m{m}A{n_capabilities}-{seed}",
        metadata={"seed": int(seed), "cell": float(cell), "neighbours": int(neighbours)},
    )
    problem = capability_problem_from_instance(instance, cell, neighbours, method="grid")
    return CapabilityScenario(instance, problem, int(seed))
