"""The chapter-2 family's spec: open multi-vehicle routing on an asymmetric travel-time matrix.

:class:`~taopt.AssignmentProblem` (payload :class:`~taopt.result.Routes`, scorer
:func:`~taopt.routing.problem.evaluate_routes`), its bounds (the valid arborescence, the
thesis's Algorithm 1 as printed, the degree-penalised arborescence as ``lower``), its plot,
its adapter from an ``instance`` file (one capability, one speed, no obstacles) and the
§2.5 study (``taopt study drift``).
"""

from __future__ import annotations

from typing import Any

from taopt.registry import Bound, Family, Study, register_family
from taopt.result import Routes
from taopt.routing.bounds import arborescence_bound, routing_lower, thesis_mcga
from taopt.routing.plot import routes_lines
from taopt.routing.problem import AssignmentProblem, evaluate_routes


def _plot_routes(
    problem: AssignmentProblem, routes: Any, path: str, instance: Any = None, method: str = ""
) -> None:
    """The routes over the drift field, each leg along its minimum-time path.

    Without an instance file (a bare matrix) the points are placed by classical MDS of the
    travel-time matrix (:func:`taopt.plot.schematic_layout`) and the caption says so.
    """
    from taopt.plot import schematic_layout
    from taopt.routing.plot import plot_instance_routes, plot_routes

    routes = list(routes)
    total = problem.evaluate(routes)
    title = (
        f"{problem.name or 'routes'}: {method or 'best'} routes, total travel time {total:.1f} s"
    )
    if instance is None:
        plot_routes(
            schematic_layout(problem.cost),
            routes,
            title=title,
            unit="s, schematic",
            caption="schematic layout: the file has no positions; points placed by classical "
            "MDS of the symmetrised travel-time matrix (distances approximate t(i, j))",
            path=path,
        )
        return
    plot_instance_routes(instance, routes, title=title, path=path)


def _from_instance(instance: Any, progress: bool = True) -> AssignmentProblem | None:
    """The chapter 2 problem (2.2)–(2.5) of an instance with one capability, one speed and no
    obstacles (travel times by navigation in its drift field); None for any other instance."""
    from taopt.navigation import travel_time_matrix
    from taopt.runtime import check_memory, navigation_bytes

    speeds = {v.speed for v in instance.vehicles}
    capabilities = {v.capability for v in instance.vehicles}
    if len(speeds) != 1 or len(capabilities) != 1 or instance.obstacles:
        return None
    points = instance.n_targets + len(instance.vehicles)
    check_memory(  # the size guard: the matrix and navigation's work arrays, before navigating
        navigation_bytes(points),
        f"the travel-time matrix of {instance.name or 'this instance'} "
        f"({instance.n_targets:,} targets + {len(instance.vehicles)} vehicles = "
        f"{points:,} points, {points**2:,} pairs)",
    )
    matrix = travel_time_matrix(instance.field, instance.points, speeds.pop(), progress=progress)
    return AssignmentProblem(matrix, n_targets=instance.n_targets, name=instance.name)


FAMILY = register_family(
    Family(
        problem_type=AssignmentProblem,
        kind="assignment_problem",
        payload=Routes,
        title="open multi-vehicle routing on a travel-time matrix (chapter 2)",
        evaluate=evaluate_routes,
        bounds={
            "arborescence": Bound(arborescence_bound),
            "thesis_mcga": Bound(thesis_mcga, valid=False, column="q_thesis"),
            "lower": Bound(routing_lower),
        },
        plots={"routes": _plot_routes},
        adapter=_from_instance,
        studies=(Study("drift", "taopt.orchestration.studies.drift"),),
        describe=routes_lines,
    )
)
