"""The thesis's heuristics and baselines, as ``taopt.heuristics``.

``run(name, problem, seed=0)`` dispatches on the problem type:

* :class:`taopt.AssignmentProblem` (chapter 2): "VN", "VM", "EVN", "EVM", "MC", "GA".
* :class:`taopt.DeliveryInstance` (chapter 5): "NIA", "MMA", "SMMA", "GA".
"""

from taopt.heuristics.registry import METHODS, register, run  # noqa: I001

# Importing the modules registers their methods.
from taopt.heuristics import clustering, ga_routing, sequencing, ga_delivery  # noqa: F401, E402

__all__ = ["run", "register", "METHODS"]
