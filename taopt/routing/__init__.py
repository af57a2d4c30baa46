"""Chapter 2: open multi-vehicle routing on an asymmetric travel-time matrix.

Registers the family :class:`AssignmentProblem` (payload :class:`~taopt.result.Routes`,
scorer :func:`evaluate_routes`, bounds ``arborescence`` and ``thesis_mcga``).
"""

from typing import Any

from taopt.errors import InstanceError
from taopt.registry import register_family
from taopt.result import Routes
from taopt.routing.bounds import arborescence_bound, thesis_mcga
from taopt.routing.problem import AssignmentProblem, evaluate_routes


def _plot_routes(problem: AssignmentProblem, routes: Any, path: str, instance: Any = None) -> None:
    """The routes over the drift field (needs the positions of an instance file)."""
    from taopt.routing.plot import plot_routes

    if instance is None:
        raise InstanceError("a route plot needs positions: give an 'instance' file, not a matrix")
    total = problem.evaluate(list(routes))
    plot_routes(
        instance.points,
        list(routes),
        field=instance.field,
        title=f"{problem.name or 'routes'}: total travel time {total:.1f} s",
        path=path,
    )


register_family(
    AssignmentProblem,
    kind="assignment_problem",
    payload=Routes,
    title="open multi-vehicle routing on a travel-time matrix (chapter 2)",
    evaluate=evaluate_routes,
    bounds={"arborescence": arborescence_bound, "thesis_mcga": thesis_mcga},
    plots={"routes": _plot_routes},
)

__all__ = ["AssignmentProblem", "evaluate_routes"]
