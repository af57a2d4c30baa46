"""``taopt.evaluate``: the one scorer per problem (DESIGN invariant 1)."""

from __future__ import annotations

from typing import Any

from taopt.errors import InstanceError


def evaluate(problem: Any, solution: Any) -> float:
    """Score a solution after checking its feasibility.

    Parameters
    ----------
    problem : AssignmentProblem or DeliveryInstance
    solution : routes (list of lists), a Plan, or a :class:`~taopt.result.Solution`

    Returns
    -------
    float
        Chapter 2: total travel time (2.2). Chapter 5: the makespan (5.1).

    Raises
    ------
    FeasibilityError
        Naming the violated constraint and the item.
    """
    from taopt.routing.problem import AssignmentProblem, evaluate_routes

    if isinstance(problem, AssignmentProblem):
        routes = getattr(solution, "routes", solution)
        if routes is None:
            raise InstanceError("this solution carries no routes to evaluate")
        return evaluate_routes(problem, routes)
    from taopt.delivery.evaluate import evaluate_plan
    from taopt.delivery.instance import DeliveryInstance

    if isinstance(problem, DeliveryInstance):
        plan = getattr(solution, "plan", None) if hasattr(solution, "objective") else solution
        if plan is None:
            raise InstanceError("this solution carries no plan to evaluate")
        return evaluate_plan(problem, plan)
    raise InstanceError(f"evaluate() does not know problems of type {type(problem).__name__}")
