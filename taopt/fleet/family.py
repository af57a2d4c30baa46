"""Registration of the fleet family (thesis §6.2, recommendations 2 and 3).

The family's spec (:class:`taopt.registry.Family`), found on disk by
:func:`taopt.families.ensure_families`: problem :class:`FleetProblem`, file kind
``fleet_problem``, payload :class:`FleetPlan`, the one scorer :func:`evaluate_fleet` and the
valid bound ``reach``.
"""

from __future__ import annotations

from typing import Any

from taopt.fleet.bounds import fleet_lower, reach_bound, work_bound
from taopt.fleet.evaluate import evaluate_fleet
from taopt.fleet.plot import save_fleet_gantt, save_fleet_plot
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie
from taopt.registry import Bound, Family, Study, register_family


def _plan_lines(problem: FleetProblem, plan: FleetPlan, file: Any = None) -> list[str]:
    """Each truck's walk (``s<stop>``; the customers it serves as ``c<j>@<position>``) and
    each drone's sorties (launch and recovery positions in its truck's walk)."""
    lines = []
    for k, route in enumerate(plan.routes):
        served = ", ".join(f"c{j}@{p}" for p, j in plan.truck_service[k])
        walk = " -> ".join(f"s{w}" for w in route)
        lines.append(f"  truck {k}: {walk}" + (f"; serves {served}" if served else ""))
        for d, flights in enumerate(plan.sorties[k]):
            text = "; ".join(
                f"{f.launch} -> " + " -> ".join(f"c{j}" for j in f.customers) + f" -> {f.recovery}"
                for f in flights
            )
            lines.append(f"    drone ({k}, {d}) [positions]: {text or 'idle'}")
    return lines


FAMILY = register_family(
    Family(
        problem_type=FleetProblem,
        kind="fleet_problem",
        payload=FleetPlan,
        title="trucks carrying multi-parcel drones, precedence across the fleet (§6.2)",
        evaluate=evaluate_fleet,
        bounds={
            "reach": Bound(reach_bound),
            "work": Bound(work_bound),
            "lower": Bound(fleet_lower),
        },
        plots={"plan": save_fleet_plot, "gantt": save_fleet_gantt},
        describe=_plan_lines,
        studies=(Study("fleet", "taopt.orchestration.studies.fleet"),),
        exports={"FleetPlan": FleetPlan, "Sortie": Sortie},
    )
)

__all__ = ["FAMILY"]
