"""Chapter 2: open multi-vehicle routing on an asymmetric travel-time matrix.

Registers the family :class:`AssignmentProblem` (payload :class:`~taopt.result.Routes`,
scorer :func:`evaluate_routes`, bounds ``arborescence`` and ``thesis_mcga``).
"""

from typing import Any

from taopt.bounds import routing_lower
from taopt.registry import register_family
from taopt.result import Routes
from taopt.routing.bounds import arborescence_bound, thesis_mcga
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


register_family(
    AssignmentProblem,
    kind="assignment_problem",
    payload=Routes,
    title="open multi-vehicle routing on a travel-time matrix (chapter 2)",
    evaluate=evaluate_routes,
    bounds={
        "arborescence": arborescence_bound,
        "thesis_mcga": thesis_mcga,
        "lower": routing_lower,
    },
    plots={"routes": _plot_routes},
)

__all__ = ["AssignmentProblem", "evaluate_routes"]
