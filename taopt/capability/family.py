"""The chapter-3 family's spec: heterogeneous vehicles and multi-capability demands.

:class:`~taopt.CapabilityProblem` (payload :class:`~taopt.result.Routes`, scorer
:func:`~taopt.capability.problem.evaluate_capability`), its bounds per capability class, its
plot, its adapter from an ``instance`` file (several capabilities or speeds, or obstacles)
and the §3.7 study (``taopt study capability``).
"""

from __future__ import annotations

from typing import Any

from taopt.capability.bounds import (
    arborescence_bound,
    capability_lower,
    doubled_arborescence,
    thesis_mcga,
)
from taopt.capability.problem import CapabilityProblem, evaluate_capability
from taopt.registry import Bound, Family, Study, register_family
from taopt.result import Routes
from taopt.routing.plot import routes_lines


def _plot_routes(
    problem: CapabilityProblem, routes: Any, path: str, instance: Any = None, method: str = ""
) -> None:
    """Routes coloured by capability over the field and obstacles.

    Without an instance file (bare matrices) the points are placed by classical MDS of the
    element-wise fastest travel time over the capabilities
    (:func:`taopt.plot.schematic_layout`) and the caption says so.
    """
    import numpy as np

    from taopt.capability.plot import plot_routes
    from taopt.plot import schematic_layout
    from taopt.routing.plot import plot_routes as plot_plain_routes

    routes = list(routes)
    total = problem.evaluate(routes)
    title = (
        f"{problem.name or 'routes'}: {method or 'best'} routes, total travel time {total:.1f} s"
    )
    if instance is not None:
        plot_routes(instance, problem, routes, title=title, path=path)
        return
    fastest = np.fmin.reduce([problem.cost_for(c) for c in problem.capabilities])
    plot_plain_routes(
        schematic_layout(fastest),
        routes,
        title=title,
        vehicle_ids=[f"v{k} ({c})" for k, c in enumerate(problem.vehicle_capability)],
        unit="s, schematic",
        caption="schematic layout: the file has no positions; points placed by classical MDS "
        "of the fastest symmetrised travel time over the capabilities",
        path=path,
    )


def _from_instance(instance: Any, progress: bool = True) -> CapabilityProblem | None:
    """The chapter 3 problem (3.1)–(3.3) of an instance with several capabilities or speeds,
    or obstacles (grid travel times); None for a chapter-2 instance."""
    from taopt.capability.instances import capability_problem_from_instance

    speeds = {v.speed for v in instance.vehicles}
    capabilities = {v.capability for v in instance.vehicles}
    if len(speeds) == 1 and len(capabilities) == 1 and not instance.obstacles:
        return None
    return capability_problem_from_instance(instance)


FAMILY = register_family(
    Family(
        problem_type=CapabilityProblem,
        kind="capability_problem",
        payload=Routes,
        title="heterogeneous vehicles and multi-capability demands (chapter 3)",
        evaluate=evaluate_capability,
        bounds={
            "arborescence": Bound(arborescence_bound),
            "thesis_mcga": Bound(thesis_mcga, valid=False, column="q_thesis"),
            "doubled_arborescence": Bound(doubled_arborescence, valid=False, side="upper"),
            "lower": Bound(capability_lower),
        },
        plots={"routes": _plot_routes},
        adapter=_from_instance,
        describe=routes_lines,
        studies=(Study("capability", "taopt.orchestration.studies.capability"),),
    )
)
