"""The certified optimum f_o of chapter 4: (4.1)–(4.2) with all information, exactly.

Without communication limits the problem is open multi-vehicle routing on Euclidean
distances, split exactly by attribute (each target needs one vehicle of its attribute, and
the classes share no vehicle): :meth:`~taopt.comm.problem.CommProblem.full_information` gives chapter 2's
:class:`~taopt.AssignmentProblem` (one attribute) or chapter 3's
:class:`~taopt.CapabilityProblem` with one demand per target, whose ``classes`` are
chapter 2 problems. The classes are solved by chapter 3's decomposition,
:func:`taopt.models.capability.solve_classes` (chapter 2's exact model
:func:`taopt.models.solve_routing` per class, one shared wall-clock limit); the classes'
routes are joined and driven as straight lines, which is what (4.1) scores. The bound is
the sum of the classes' proven bounds, and the status is :func:`taopt.status.decide`'s
("optimal" only when the gap is closed).

Any simulation's trajectories are at least f_o long (its first visits form routes that
serve every target once and are no longer than the trajectories, by the triangle
inequality), so ``f / f_o`` is the true gap of CAA, DAA and HDA.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from taopt.capability.problem import CapabilityClass
from taopt.comm.problem import CommProblem
from taopt.comm.trajectories import Trajectories
from taopt.errors import InstanceError
from taopt.models.capability import solve_classes
from taopt.registry import register_method
from taopt.result import Routes, Solution, finish
from taopt.runtime import milp_bytes, register_footprint


def drive(problem: CommProblem, routes: Sequence[Sequence[int]]) -> Trajectories:
    """Trajectories of vehicles driving ``routes`` at unit speed from their starts, no waiting."""
    if len(routes) != problem.m:
        raise InstanceError(f"expected {problem.m} routes (one per vehicle), got {len(routes)}")
    paths, visits = [], []
    for j, route in enumerate(routes):
        point = problem.vehicles[j]
        clock = 0.0
        path = [(0.0, float(point[0]), float(point[1]))]
        seen = []
        for q in route:
            target = problem.targets[int(q)]
            clock += float(np.hypot(*(target - point)))
            path.append((clock, float(target[0]), float(target[1])))
            seen.append((int(q), len(path) - 1))
            point = target
        paths.append(np.array(path))
        visits.append(seen)
    return Trajectories(paths, visits)


def _class_incumbent(incumbent: Any, problem: CommProblem) -> list[list[int]] | None:
    if incumbent is None:
        return None
    if isinstance(incumbent, Solution):
        incumbent = incumbent.solution
    if isinstance(incumbent, Trajectories):
        return incumbent.first_visit_routes()
    return list(Routes(incumbent))


def solve_comm(
    problem: CommProblem,
    *,
    time_limit: float | None = None,
    incumbent: Any = None,
    sec: str = "dfj",
    workers: int | None = None,
    improve: Any = None,
) -> Solution:
    """Certified optimum f_o of (4.1)–(4.2) without communication limits.

    Parameters
    ----------
    problem : CommProblem
    time_limit : float, optional
        Seconds for all classes together (shared out evenly over the classes still to solve).
    incumbent : Trajectories, Routes or Solution, optional
        A feasible solution (e.g. DAA's): its first-visit routes are offered to
        :func:`~taopt.models.routing.solve_routing` per class when that function takes an incumbent.
    sec : str
        Subtour elimination of the chapter 2 model ("dfj", "mtz", "flow").
    workers : int, optional
        Processes for the classes (as :func:`taopt.models.capability.solve_capability`;
        default: one per core for two or more large classes, else 1).
    improve : callable, optional
        Passed to each class's :func:`~taopt.models.routing.solve_routing`
        (``improve(class_problem, routes) -> routes``); :func:`taopt.solve` passes the
        registered improver (:func:`taopt.registry.improver`).

    Returns
    -------
    Solution
        Payload: the trajectories of driving the optimal routes; status by
        :func:`taopt.status.decide` of their length against bound = Σ class bounds:
        "optimal" when the gap is closed, else "time_limit" (or "feasible" when the first
        unfinished class stopped by a gap or round limit); with a class without routes
        in time, "time_limit", objective ``inf`` and no payload. ``info`` holds
        ``routes``, ``class_status``, ``per_class`` and ``workers``.

    Notes
    -----
    The classes are solved by :func:`taopt.models.capability.solve_classes`, chapter 3's
    per-class decomposition with its shared wall-clock limit (serial smallest first, or
    worker processes; a second pass for classes stopped by their share).
    """
    began = time.perf_counter()
    full = problem.full_information()
    if hasattr(full, "classes"):
        classes = list(full.classes)
    else:  # one attribute: one class, every vehicle and target
        label = problem.attributes[0]
        classes = [CapabilityClass(label, tuple(range(problem.n)), tuple(range(problem.m)), full)]
    start_routes = _class_incumbent(incumbent, problem)
    starts = {}
    for cls in classes:
        if cls.problem is not None and start_routes is not None:
            local = {t: i for i, t in enumerate(cls.targets)}
            starts[cls.capability] = [
                [local[t] for t in start_routes[j] if t in local] for j in cls.vehicles
            ]
    split = solve_classes(
        classes,
        time_limit=time_limit,
        start=began,
        incumbents=starts,
        sec=sec,
        workers=workers,
        improve=improve,
    )
    solved = [cls for cls in classes if cls.problem is not None]
    info: dict[str, Any] = {
        "class_status": [str(split.results[cls.capability].status) for cls in solved],
        "classes": len(solved),
        "per_class": split.per_class,
        "workers": split.workers,
    }
    if not split.complete:  # a class has no routes in time: no trajectories
        return finish(
            problem,
            None,
            method="exact",
            stop="time_limit",
            bound=split.bound,
            runtime=time.perf_counter() - began,
            info={**info, "routes": None},
        )
    routes: list[list[int]] = [[] for _ in range(problem.m)]
    for cls in solved:
        for j, route in cls.lift(split.results[cls.capability].routes).items():
            routes[j] = route
    return finish(  # certified on the scored length (4.1) of the driven routes
        problem,
        drive(problem, routes),
        method="exact",
        stop=split.stopped_by,
        bound=split.bound,
        runtime=time.perf_counter() - began,
        info={**info, "routes": routes},
    )


register_method(CommProblem, "exact", category="exact", warm_start=("DAA",))(solve_comm)


@register_footprint(CommProblem, "exact")
def _footprint(problem: CommProblem, options: dict[str, Any]) -> tuple[float, str]:
    """One routing model per ability class, (n_a + m_a)^2 arcs each (the flow version n_a
    more per arc), counted from the targets' attributes and the vehicles' abilities."""
    labels = np.arange(len(problem.attributes))
    targets = np.bincount(problem.target_code, minlength=len(labels)).astype(float)
    vehicles = np.bincount(problem.vehicle_code, minlength=len(labels)).astype(float)
    arcs = (targets + vehicles) ** 2 * (targets > 0)
    if options.get("sec", "dfj") == "flow":
        arcs = arcs * (targets + 1)
    columns = float(arcs.sum())
    return milp_bytes(columns), (
        f"the exact models of {problem.n:,} targets and {problem.m} vehicles in "
        f"{int((targets > 0).sum())} ability classes ({columns:,.0f} columns)"
    )


__all__ = ["solve_comm", "drive"]
