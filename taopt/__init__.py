"""taopt: optimisation modelling for cooperative multi-vehicle task assignment.

Navigation in drift fields (CasADi collocation, PMP shooting) produces
asymmetric travel-time matrices; exact models (cvxpy + HiGHS) certify optima
of small instances; the thesis's heuristics are compared with them on the
same data and scored by one ``evaluate`` per problem.

Quick tour
----------
>>> import numpy as np, taopt
>>> problem = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0]]), n_targets=2)
>>> taopt.evaluate(problem, [[1, 0]])
4.0
>>> taopt.solve(problem, "exact").routes
[[1, 0]]
"""

from __future__ import annotations

from typing import Any


def _map_source_tree_packages() -> None:
    """Make ``taopt.models`` and ``taopt.heuristics`` importable from a checkout.

    pyproject.toml installs the top-level folders ``models/`` and
    ``heuristics/`` as ``taopt.models`` and ``taopt.heuristics``
    (``package-dir``). Python started in the checkout root imports the local
    ``taopt/`` folder instead of the installed package, and that folder has
    no such subpackages; this finder maps them exactly as ``package-dir``
    does, so the checkout imports the same package as the installation. It
    does nothing in an installed package (the subpackages are real folders).
    """
    import importlib.abc
    import importlib.util
    import sys
    from pathlib import Path

    here = Path(__file__).resolve().parent
    root = here.parent
    mapped = {
        f"taopt.{name}": root / name
        for name in ("models", "heuristics")
        if not (here / name).is_dir() and (root / name / "__init__.py").is_file()
    }
    if not mapped or not (root / "pyproject.toml").is_file():
        return

    class _SourceTreeFinder(importlib.abc.MetaPathFinder):
        def find_spec(self, fullname, path=None, target=None):
            folder = mapped.get(fullname)
            if folder is None:
                return None
            return importlib.util.spec_from_file_location(
                fullname, folder / "__init__.py", submodule_search_locations=[str(folder)]
            )

    sys.meta_path.append(_SourceTreeFinder())


_map_source_tree_packages()

from taopt.errors import (
    ConvergenceError,
    FeasibilityError,
    InstanceError,
    SolverError,
    TaoptError,
)
from taopt.fields import GriddedField, LinearField, UniformField, thesis_field
from taopt.instance import Instance, Obstacle, Target, Vehicle
from taopt.result import Order, Routes, Solution, Status
from taopt.routing.problem import AssignmentProblem
from taopt.scoring import evaluate

__version__ = "0.1.0"

_LAZY = {
    # imported on first use, so `import taopt` stays light
    "DeliveryInstance": ("taopt.delivery", "DeliveryInstance"),
    "Plan": ("taopt.delivery", "Plan"),
    "SopProblem": ("taopt.delivery", "SopProblem"),
    "schedule": ("taopt.delivery.schedule", "schedule"),
    "CapabilityProblem": ("taopt.capability", "CapabilityProblem"),
    "CommProblem": ("taopt.comm", "CommProblem"),
    # the orchestration layer: imports the method packages (cvxpy, HiGHS)
    "solve": ("taopt.pipeline", "solve"),
}


_SUBMODULES = (
    "models",
    "heuristics",
    "bounds",
    "navigation",
    "routing",
    "delivery",
    "plot",
    "registry",
    "capability",
    "comm",
)


def __getattr__(name: str) -> Any:
    if name in _SUBMODULES:
        import importlib

        module = importlib.import_module(f"taopt.{name}")
        globals()[name] = module
        return module
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        value = getattr(importlib.import_module(module), attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'taopt' has no attribute {name!r}")


__all__ = [
    "solve",
    "AssignmentProblem",
    "DeliveryInstance",
    "SopProblem",
    "Plan",
    "Routes",
    "Order",
    "Status",
    "Instance",
    "Vehicle",
    "Target",
    "Obstacle",
    "Solution",
    "evaluate",
    "schedule",
    "UniformField",
    "LinearField",
    "GriddedField",
    "thesis_field",
    "TaoptError",
    "InstanceError",
    "FeasibilityError",
    "SolverError",
    "ConvergenceError",
]
