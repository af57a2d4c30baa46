"""The certified optimum f_o of chapter 4: (4.1)–(4.2) with all information, exactly.

Without communication limits the problem is open multi-vehicle routing on Euclidean
distances, split exactly by attribute (each target needs one vehicle of its attribute, and
the classes share no vehicle): :meth:`~taopt.comm.problem.CommProblem.full_information` gives chapter 2's
:class:`~taopt.AssignmentProblem` (one attribute) or chapter 3's
:class:`~taopt.CapabilityProblem` with one demand per target, whose ``classes`` are
chapter 2 problems. Each class is solved by chapter 2's exact model
:func:`taopt.models.solve_routing`; the classes' routes are joined and driven as straight
lines, which is what (4.1) scores. The status is "optimal" only if every class is, and the
bound is the sum of the classes' proven bounds.

Any simulation's trajectories are at least f_o long (its first visits form routes that
serve every target once and are no longer than the trajectories, by the triangle
inequality), so ``f / f_o`` is the true gap of CAA, DAA and HDA.
"""

from __future__ import annotations

import inspect
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from taopt.comm.problem import CommProblem
from taopt.comm.trajectories import Trajectories, evaluate_trajectories
from taopt.errors import InstanceError
from taopt.limits import milp_bytes, register_footprint
from taopt.models.routing import solve_routing
from taopt.registry import register_method
from taopt.result import FEASIBLE, OPTIMAL, TIME_LIMIT, Routes, Solution, Status


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


def _solution(
    problem: CommProblem,
    routes: list[list[int]],
    status: Status,
    bound: float | None,
    runtime: float,
    info: dict[str, Any],
) -> Solution:
    """The one place this module builds a Solution."""
    trajectories = drive(problem, routes)
    return Solution(
        objective=evaluate_trajectories(problem, trajectories),
        status=status,
        solution=trajectories,
        bound=bound,
        runtime=runtime,
        method="exact",
        info=info,
    )


def solve_comm(
    problem: CommProblem,
    *,
    time_limit: float | None = None,
    incumbent: Any = None,
    sec: str = "dfj",
) -> Solution:
    """Certified optimum f_o of (4.1)–(4.2) without communication limits.

    Parameters
    ----------
    problem : CommProblem
    time_limit : float, optional
        Seconds for all classes together (shared out evenly over the classes still to solve).
    incumbent : Trajectories, Routes or Solution, optional
        A feasible solution (e.g. DAA's): its first-visit routes are offered to
        :func:`solve_routing` per class when that function takes an incumbent.
    sec : str
        Subtour elimination of the chapter 2 model ("dfj", "mtz", "flow").

    Returns
    -------
    Solution
        Payload: the trajectories of driving the optimal routes; status "optimal" when
        every class is certified, else "time_limit" (or "feasible" when a class stopped by a gap
        or round limit); bound = Σ class bounds; ``info``
        holds ``routes`` and per-class statuses.
    """
    began = time.perf_counter()
    full = problem.full_information()
    if hasattr(full, "classes"):
        parts = [(c.problem, list(c.vehicles), list(c.targets)) for c in full.classes]
    else:
        parts = [(full, list(range(problem.m)), list(range(problem.n)))]
    parts = [p for p in parts if p[0] is not None]
    start_routes = _class_incumbent(incumbent, problem)
    takes_incumbent = "incumbent" in inspect.signature(solve_routing).parameters
    routes: list[list[int]] = [[] for _ in range(problem.m)]
    statuses, bounds = [], []
    for index, (sub, vehicles, targets) in enumerate(parts):
        options: dict[str, Any] = {"sec": sec}
        if time_limit is not None:
            left = time_limit - (time.perf_counter() - began)
            options["time_limit"] = max(left / (len(parts) - index), 1e-3)
        if takes_incumbent and start_routes is not None:
            local = {t: i for i, t in enumerate(targets)}
            options["incumbent"] = [
                [local[t] for t in start_routes[j] if t in local] for j in vehicles
            ]
        result = solve_routing(sub, **options)
        for j, route in zip(vehicles, result.routes, strict=True):
            routes[j] = [targets[t] for t in route]
        statuses.append(result.status)
        bounds.append(result.bound)
    if all(s == OPTIMAL for s in statuses):
        status = OPTIMAL
    elif any(s == TIME_LIMIT for s in statuses):
        status = TIME_LIMIT
    else:  # a class stopped by a gap or round limit: feasible with its proven bound
        status = FEASIBLE
    bound = None if any(b is None for b in bounds) else float(sum(bounds))
    info = {
        "routes": routes,
        "class_status": [str(s) for s in statuses],
        "classes": len(parts),
    }
    return _solution(
        problem,
        routes,
        status,
        bound,
        time.perf_counter() - began,
        info,
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
