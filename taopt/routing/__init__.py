"""Chapter 2 (and 3): open multi-vehicle routing on an asymmetric travel-time matrix."""

from taopt.routing.problem import AssignmentProblem, evaluate_routes

__all__ = ["AssignmentProblem", "evaluate_routes"]
