"""Plot of the budgeted family: the routes, titled with the total and the binding limits.

Reuses chapter 2's drawing (:func:`taopt.routing.plot.plot_routes`): with an instance file
the legs are drawn over its field, otherwise on the schematic layout of the matrix
(:func:`taopt.plot.schematic_layout`, said in the caption).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from taopt.budgeted.problem import TIME_TOLERANCE, BudgetedProblem, evaluate_budgeted


def binding_limits(problem: BudgetedProblem, routes: Sequence[Sequence[int]]) -> list[str]:
    """The limits a feasible ``routes`` meets with equality, e.g. ``["Q0 = 3", "T2"]``."""
    found = []
    for k, route in enumerate(routes):
        if len(route) == problem.capacity[k]:
            found.append(f"Q{k} = {len(route)}")
        limit = problem.max_time[k]
        if math.isfinite(limit):
            if problem.route_cost(k, route) >= limit - TIME_TOLERANCE * max(1.0, limit):
                found.append(f"T{k}")
    return found


def plot_budgeted_routes(
    problem: BudgetedProblem,
    routes: Any,
    path: str,
    instance: Any = None,
    method: str = "",
) -> None:
    """Draw ``routes`` (scored by :func:`~taopt.budgeted.evaluate_budgeted`) to ``path``;
    the title names the total travel time and which limits bind."""
    from taopt.plot import schematic_layout
    from taopt.routing.plot import plot_routes

    routes = [list(r) for r in routes]
    total = evaluate_budgeted(problem, routes)
    binding = binding_limits(problem, routes)
    title = (
        f"{problem.name or 'budgeted routes'}: {method or 'best'} routes, total {total:.1f} s; "
        + (f"binding: {', '.join(binding)}" if binding else "no limit binds")
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
    from taopt.routing.plot import plot_instance_routes

    plot_instance_routes(instance, routes, title=title, path=path)


__all__ = ["binding_limits", "plot_budgeted_routes"]
