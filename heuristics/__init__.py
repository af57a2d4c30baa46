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

import importlib
import pkgutil

from taopt.heuristics.registry import run

# Importing every module of this package registers its methods (where they are defined); the
# peers' worker module (leading underscore) is imported by the worker process only.
for _module in pkgutil.iter_modules(__path__):
    if not _module.name.startswith("_"):
        importlib.import_module(f"{__name__}.{_module.name}")

__all__ = ["run"]
