"""Chapter 2: open multi-vehicle routing on an asymmetric travel-time matrix.

The family's spec is :mod:`taopt.routing.family` (payload
:class:`~taopt.result.Routes`, scorer :func:`evaluate_routes`, bounds ``arborescence``,
``thesis_mcga`` as printed and ``lower``).
"""

from taopt.routing import family as _family  # noqa: F401  (registers the family)
from taopt.routing.problem import AssignmentProblem, evaluate_routes

__all__ = ["AssignmentProblem", "evaluate_routes"]
