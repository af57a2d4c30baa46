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

from taopt.capability.bounds import arborescence_bound, doubled_arborescence, thesis_mcga
from taopt.capability.problem import CapabilityClass, CapabilityProblem, evaluate_capability
from taopt.errors import InstanceError
from taopt.registry import register_family
from taopt.result import Routes


def _plot_routes(problem: CapabilityProblem, routes: Any, path: str, instance: Any = None) -> None:
    """Routes coloured by capability over the field and obstacles (needs an instance file)."""
    from taopt.capability.plot import plot_routes

    if instance is None:
        raise InstanceError("a route plot needs positions: give an 'instance' file, not a matrix")
    total = problem.evaluate(list(routes))
    plot_routes(
        instance,
        problem,
        list(routes),
        title=f"{problem.name or 'routes'}: total travel time {total:.1f} s",
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
    },
    plots={"routes": _plot_routes},
)

__all__ = ["CapabilityProblem", "CapabilityClass", "evaluate_capability"]
