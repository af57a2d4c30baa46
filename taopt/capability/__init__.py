"""Chapter 3: heterogeneous vehicles and multi-capability demands, (3.1)–(3.3).

Registers the family :class:`CapabilityProblem` (payload :class:`~taopt.result.Routes`,
scorer :func:`evaluate_capability`, bounds ``arborescence``, ``thesis_mcga`` and
``doubled_arborescence`` per class).

* :mod:`taopt.capability.instances` — an :class:`~taopt.Instance` to a problem (grid
  planner with obstacles), and §3.7's scenario generator.
* :mod:`taopt.studies.capability_claims` — checks of Theorems 3.4, 3.5, 3.7 and Lemma 3.6.
* :mod:`taopt.studies.capability` — the §3.7 study (Figs. 3.4–3.6, Tables 3.1–3.2).
* :mod:`taopt.capability.plot` — field, obstacles, grid paths, routes by capability.
"""

from typing import Any

from taopt.bounds import capability_lower
from taopt.capability.bounds import arborescence_bound, doubled_arborescence, thesis_mcga
from taopt.capability.problem import CapabilityClass, CapabilityProblem, evaluate_capability
from taopt.registry import register_family
from taopt.result import Routes


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


register_family(
    CapabilityProblem,
    kind="capability_problem",
    payload=Routes,
    title="heterogeneous vehicles and multi-capability demands (chapter 3)",
    evaluate=evaluate_capability,
    bounds={
        "arborescence": arborescence_bound,
        "thesis_mcga": thesis_mcga,
        "doubled_arborescence": doubled_arborescence,
        "lower": capability_lower,
    },
    plots={"routes": _plot_routes},
)

__all__ = ["CapabilityProblem", "CapabilityClass", "evaluate_capability"]
