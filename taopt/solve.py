"""``taopt solve FILE``: solve an instance file exactly and with every heuristic.

The file is one of taopt's JSON kinds (schema_version 1):

* ``"instance"`` (:class:`taopt.Instance`): vehicles, targets, region and a drift field; its
  travel-time matrix is computed by minimum-time navigation, then it is solved as the
  chapter 2 problem (2.2)–(2.5);
* ``"assignment_problem"`` (:class:`taopt.AssignmentProblem`): a travel-time matrix;
* ``"delivery_instance"`` (:class:`taopt.DeliveryInstance`): the chapter 5 truck–drone problem.

Every method's result is re-scored by :func:`taopt.evaluate` and printed in one table with
its status, its ratio to a valid lower bound and, when an optimum is certified, its true gap.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import IO, Any

import pandas as pd

from taopt.errors import InstanceError
from taopt.instance import Instance, load_json
from taopt.result import OPTIMAL, Solution
from taopt.routing.problem import AssignmentProblem

DELIVERY_METHODS = ("NIA", "MMA", "SMMA", "GA", "DP")
DP_MAX_CUSTOMERS = 12  # the subset DP is exact and fast up to about a dozen customers


def assignment_from_instance(instance: Instance, progress: bool = True) -> AssignmentProblem:
    """The chapter 2 problem of an :class:`Instance`: its travel-time matrix by navigation.

    Raises
    ------
    InstanceError
        Vehicles of different speeds or several capabilities (chapter 3's heterogeneous
        problem (3.1)–(3.3) is not solved by this command).
    """
    from taopt.navigation import travel_time_matrix

    speeds = {v.speed for v in instance.vehicles}
    if len(speeds) > 1:
        raise InstanceError(
            f"vehicles have different speeds {sorted(speeds)}: (2.2)-(2.5) needs one cost matrix"
        )
    capabilities = {v.capability for v in instance.vehicles}
    if len(capabilities) > 1:
        raise InstanceError(
            f"vehicles have several capabilities {sorted(capabilities)}: the heterogeneous "
            "problem (3.1)-(3.3) is not solved by `taopt solve`"
        )
    if instance.obstacles:
        raise InstanceError(
            "obstacles need the grid planner (taopt.navigation.grid); not in `taopt solve`"
        )
    matrix = travel_time_matrix(instance.field, instance.points, speeds.pop(), progress=progress)
    return AssignmentProblem(matrix, n_targets=instance.n_targets, name=instance.name)


def delivery_table(
    instance: Any, methods: tuple[str, ...], seed: int = 0, time_limit: float = 60.0
) -> tuple[pd.DataFrame, dict[str, Solution]]:
    """Solve a :class:`DeliveryInstance` with each method; a table like :func:`taopt.demo.gap_table`.

    ``"DP"`` is the exact subset dynamic programme (``optimal_plan``); ``"exact"`` the MILP
    (``taopt.models.solve_delivery``, stopped after ``time_limit`` seconds with its gap).
    """
    import taopt
    import taopt.heuristics as heuristics
    from taopt.bounds import arborescence
    from taopt.delivery.schedule import optimal_plan
    from taopt.models import solve_delivery

    solutions: dict[str, Solution] = {}
    for method in methods:
        if method == "DP":
            solutions[method] = optimal_plan(instance)
        elif method == "exact":
            solutions[method] = solve_delivery(instance, time_limit=time_limit)
        else:
            solutions[method] = heuristics.run(method, instance, seed=seed)
    bound = arborescence(instance)
    optima = [s.objective for s in solutions.values() if s.status == OPTIMAL]
    optimum = min(optima) if optima else None
    rows = []
    for method, sol in solutions.items():
        makespan = taopt.evaluate(instance, sol)  # the one scorer
        rows.append(
            {
                "method": method,
                "status": sol.status,
                "makespan": makespan,
                "gap_to_optimum": makespan / optimum - 1.0 if optimum else float("nan"),
                "q_valid": makespan / bound,
                "seconds": sol.runtime,
            }
        )
    return pd.DataFrame(rows), solutions


def solve_file(
    path: str | Path,
    methods: tuple[str, ...] | None = None,
    seed: int = 0,
    time_limit: float = 60.0,
    plot: str | None = None,
    gantt: str | None = None,
    out: IO[str] = sys.stdout,
    progress: bool = True,
) -> dict[str, Any]:
    """Load ``path``, solve it with ``methods`` and print the gap table.

    Parameters
    ----------
    path : str or Path
        A JSON file of kind "instance", "assignment_problem" or "delivery_instance".
    methods : tuple of str, optional
        Chapter 2: "exact", "VN", "VM", "EVN", "EVM", "MC", "GA" (default all). Chapter 5:
        "NIA", "MMA", "SMMA", "GA", "DP" (exact subset DP) and "exact" (MILP); default the
        heuristics, plus "DP" up to 12 customers.
    plot : str, optional
        PNG of the best solution (routes in the field, or the truck-drone plan).
    gantt : str, optional
        Chapter 5 only: PNG of the truck and drone timelines.

    Returns
    -------
    dict with ``problem``, ``table`` (DataFrame) and ``solutions``.
    """
    from taopt.demo import DEMO_METHODS, gap_table

    data = load_json(path)
    kind = data.get("kind") if isinstance(data, dict) else None
    tic = time.perf_counter()
    if kind in ("instance", "assignment_problem"):
        instance = Instance.from_dict(data) if kind == "instance" else None
        if instance is not None:
            problem = assignment_from_instance(instance, progress=progress)
            points = instance.points
        else:
            problem = AssignmentProblem.from_dict(data)
            points = None
        table, solutions = gap_table(problem, methods=methods or DEMO_METHODS, seed=seed)
        print(f"{problem!r} from {path}", file=out)
        print(table.to_string(index=False, float_format=lambda v: f"{v:.6g}"), file=out)
        if plot:
            if points is None:
                raise InstanceError("--plot needs positions: give an 'instance' file, not a matrix")
            from taopt.routing.plot import plot_routes

            best = min(solutions.values(), key=lambda s: s.objective)
            plot_routes(
                points,
                best.routes,
                field=instance.field,
                title=f"{best.method}: total {best.objective:.1f} s",
                path=plot,
            )
            print(f"plot written to {plot}", file=out)
        if gantt:
            raise InstanceError("--gantt is for delivery instances (chapter 5)")
    elif kind == "delivery_instance":
        from taopt.delivery.instance import DeliveryInstance

        problem = DeliveryInstance.from_dict(data)
        if methods is None:
            methods = DELIVERY_METHODS if problem.n <= DP_MAX_CUSTOMERS else DELIVERY_METHODS[:-1]
        table, solutions = delivery_table(problem, tuple(methods), seed=seed, time_limit=time_limit)
        print(f"{problem!r} from {path}", file=out)
        print(table.to_string(index=False, float_format=lambda v: f"{v:.6g}"), file=out)
        best = min(solutions.values(), key=lambda s: s.objective)
        if plot:
            from taopt.delivery.plot import plot_plan

            plot_plan(problem, best.plan).figure.savefig(plot, dpi=120)
            print(f"plot written to {plot}", file=out)
        if gantt:
            from taopt.delivery.plot import plot_gantt

            plot_gantt(problem, best.plan).figure.savefig(gantt, dpi=120)
            print(f"Gantt chart written to {gantt}", file=out)
    else:
        raise InstanceError(
            f"{path}: kind {kind!r} is not one of 'instance', 'assignment_problem', 'delivery_instance'"
        )
    print(f"({time.perf_counter() - tic:.2f} s)", file=out)
    return {"problem": problem, "table": table, "solutions": solutions}


__all__ = ["solve_file", "delivery_table", "assignment_from_instance"]
