"""Chapter 2: open multi-vehicle routing on an asymmetric travel-time matrix.

Registers the family :class:`AssignmentProblem` (payload :class:`~taopt.result.Routes`,
scorer :func:`evaluate_routes`, bounds ``arborescence`` and ``thesis_mcga``).
"""

from taopt.registry import register_family
from taopt.result import Routes
from taopt.routing.bounds import arborescence_bound, thesis_mcga
from taopt.routing.problem import AssignmentProblem, evaluate_routes

register_family(
    AssignmentProblem,
    kind="assignment_problem",
    payload=Routes,
    title="open multi-vehicle routing on a travel-time matrix (chapter 2)",
    evaluate=evaluate_routes,
    bounds={"arborescence": arborescence_bound, "thesis_mcga": thesis_mcga},
)

__all__ = ["AssignmentProblem", "evaluate_routes"]
