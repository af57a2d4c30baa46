"""Chapter 3: heterogeneous vehicles and multi-capability demands, (3.1)–(3.3).

The family's spec is :mod:`taopt.capability.family`: :class:`CapabilityProblem` (payload :class:`~taopt.result.Routes`,
scorer :func:`evaluate_capability`, bounds ``arborescence``, ``thesis_mcga`` and
``doubled_arborescence`` per class).

* :mod:`taopt.capability.instances` — an :class:`~taopt.Instance` to a problem (grid
  planner with obstacles), and §3.7's scenario generator.
* :mod:`taopt.orchestration.studies.capability_claims` — checks of Theorems 3.4, 3.5, 3.7 and Lemma 3.6.
* :mod:`taopt.orchestration.studies.capability` — the §3.7 study (Figs. 3.4–3.6, Tables 3.1–3.2).
* :mod:`taopt.capability.plot` — field, obstacles, grid paths, routes by capability.
"""

from taopt.capability import family as _family  # noqa: F401  (registers the family)
from taopt.capability.problem import CapabilityClass, CapabilityProblem, evaluate_capability

__all__ = ["CapabilityProblem", "CapabilityClass", "evaluate_capability"]
