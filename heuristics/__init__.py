"""The thesis's heuristics and baselines, as ``taopt.heuristics``.

Importing this package registers every heuristic in :mod:`taopt.registry`:

* :class:`taopt.AssignmentProblem` (chapter 2): "VN", "VM", "EVN", "EVM", "MC", "GA".
* :class:`taopt.DeliveryInstance` (chapter 5): "NIA", "MMA", "SMMA", "GA".
* :class:`taopt.SopProblem` (sequential ordering): "NIA", "MMA", "SMMA", "GA".
* :class:`taopt.CapabilityProblem` (chapter 3): "DTAA", "GA" (per class), "MC" (per class).
* :class:`taopt.CommProblem` (chapter 4, simulations): "CAA", "DAA", "HDA".
* Peers for :class:`taopt.AssignmentProblem`: "pyvrp" and "ortools" (extra ``taopt[peers]``;
  each runs in its own worker process, see :mod:`taopt.heuristics.peers`).

Run one with :func:`taopt.solve` (or :func:`run`, kept for older scripts).
"""

from taopt.heuristics.registry import run  # noqa: I001

# Importing the modules registers their methods.
from taopt.heuristics import clustering, ga_routing, sequencing, ga_delivery  # noqa: F401, E402
from taopt.heuristics import ils_delivery  # noqa: F401, E402  (ILS over orders, chapter 5)
from taopt.heuristics import comm  # noqa: F401, E402
from taopt.heuristics import peers  # noqa: F401, E402  (PyVRP, OR-Tools: run in worker processes)
from taopt.heuristics import dtaa, capability  # noqa: F401, E402  (chapter 3)

__all__ = ["run"]
