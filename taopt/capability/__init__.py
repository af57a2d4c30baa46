"""Chapter 3: heterogeneous vehicles and multi-capability demands, (3.1)–(3.3).

Registers the family :class:`CapabilityProblem` (payload :class:`~taopt.result.Routes`,
scorer :func:`evaluate_capability`, bounds ``arborescence`` and ``thesis_mcga`` per class).
"""

from taopt.capability.bounds import arborescence_bound, thesis_mcga
from taopt.capability.problem import CapabilityClass, CapabilityProblem, evaluate_capability
from taopt.registry import register_family
from taopt.result import Routes

register_family(
    CapabilityProblem,
    kind="capability_problem",
    payload=Routes,
    title="heterogeneous vehicles and multi-capability demands (chapter 3)",
    evaluate=evaluate_capability,
    bounds={"arborescence": arborescence_bound, "thesis_mcga": thesis_mcga},
)

__all__ = ["CapabilityProblem", "CapabilityClass", "evaluate_capability"]
