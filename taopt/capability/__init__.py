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

from taopt.capability.bounds import arborescence_bound, doubled_arborescence, thesis_mcga
from taopt.capability.problem import CapabilityClass, CapabilityProblem, evaluate_capability
from taopt.registry import register_family
from taopt.result import Routes

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
)

__all__ = ["CapabilityProblem", "CapabilityClass", "evaluate_capability"]
