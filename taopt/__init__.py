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
>>> taopt.available_methods(problem)[:3]
['exact', 'VN', 'VM']

Every public name is imported on first use: ``import taopt`` is light, and
``taopt.__all__`` lists the entry points, payloads and errors, and every family's problem
type (each family's spec names what it exports).
"""

from __future__ import annotations

from typing import Any

__version__ = "0.1.0"

#: Public name -> (module, attribute): imported on first use, so ``import taopt`` (and
#: ``taopt --version``) loads no numpy, cvxpy or matplotlib.
_LAZY: dict[str, tuple[str, str]] = {
    # the one entry point (the orchestration layer: imports taopt.models, taopt.heuristics)
    "solve": ("taopt.orchestration.pipeline", "solve"),
    "available_methods": ("taopt.orchestration.pipeline", "available_methods"),
    "evaluate": ("taopt.scoring", "evaluate"),
    "schedule": ("taopt.delivery.schedule", "schedule"),
    "lower": ("taopt.orchestration.pipeline", "lower"),
    # teaching: every MILP as an LP/MPS file, a student's formulation checked
    "export": ("taopt.orchestration.export", "export"),
    "check_formulation": ("taopt.orchestration.checker", "check_formulation"),
    # the instance file's parts (each family's problem type and payload are in its spec:
    # ``exports``, found by __getattr__)
    "Instance": ("taopt.instance", "Instance"),
    "Vehicle": ("taopt.instance", "Vehicle"),
    "Target": ("taopt.instance", "Target"),
    "Obstacle": ("taopt.instance", "Obstacle"),
    # results and their payloads
    "Solution": ("taopt.result", "Solution"),
    "Status": ("taopt.result", "Status"),
    "Routes": ("taopt.result", "Routes"),
    "Order": ("taopt.result", "Order"),
    # drift fields
    "UniformField": ("taopt.fields", "UniformField"),
    "LinearField": ("taopt.fields", "LinearField"),
    "GriddedField": ("taopt.fields", "GriddedField"),
    "thesis_field": ("taopt.fields", "thesis_field"),
    # errors
    "TaoptError": ("taopt.errors", "TaoptError"),
    "InstanceError": ("taopt.errors", "InstanceError"),
    "FeasibilityError": ("taopt.errors", "FeasibilityError"),
    "SolverError": ("taopt.errors", "SolverError"),
    "ConvergenceError": ("taopt.errors", "ConvergenceError"),
}


def _family_exports() -> dict[str, Any]:
    """Public names each family's spec exports (its problem type, payload, ...)."""
    from taopt.registry import families

    return {name: value for family in families() for name, value in family.exports.items()}


def _subpackage(name: str) -> bool:
    import importlib.util

    return importlib.util.find_spec(f"taopt.{name}") is not None


def __getattr__(name: str) -> Any:
    import importlib

    value: Any
    if name == "__all__":
        value = [*_PUBLIC, *sorted(set(_family_exports()) - set(_PUBLIC))]
    elif name in _LAZY:
        module, attr = _LAZY[name]
        value = getattr(importlib.import_module(module), attr)
    elif name.startswith("_"):
        raise AttributeError(f"module 'taopt' has no attribute {name!r}")
    elif name[:1].isupper() and name in _family_exports():
        value = _family_exports()[name]
    elif name.isidentifier() and _subpackage(name):  # taopt.bounds, taopt.routing, ...
        value = importlib.import_module(f"taopt.{name}")
    else:
        raise AttributeError(f"module 'taopt' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


#: Subpackages that are public namespaces (``taopt.bounds.lower``, ``taopt.navigation...``,
#: ``taopt.examples.path(NAME)``: the packaged example files, ``taopt.defaults``: SEED and
#: TIME_LIMIT shared by taopt.solve and the CLI).
_NAMESPACES = ("bounds", "navigation", "examples", "defaults")

#: The public names that are not a family's (``taopt.__all__`` adds every family's exports):
#: the entry points, the instance file, results and payloads, fields and errors of
#: :data:`_LAZY`, in its order, and the namespaces.
_PUBLIC = [*_LAZY, *_NAMESPACES]
