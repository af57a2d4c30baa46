"""``taopt.evaluate``: the one scorer per problem family (docs/architecture.md, invariant 1).

:func:`evaluate` is a ``functools.singledispatch`` function on the problem's class; each
family hooks its scorer in with :func:`taopt.registry.register_family`. The scorer checks
feasibility first and raises :class:`~taopt.errors.FeasibilityError` naming the violated
constraint and the item.
"""

from __future__ import annotations

import functools
from typing import Any

from taopt.errors import InstanceError


@functools.singledispatch
def evaluate(problem: Any, solution: Any) -> float:
    """Score a solution of ``problem`` after checking its feasibility.

    Parameters
    ----------
    problem : a registered problem (AssignmentProblem, DeliveryInstance, SopProblem, ...)
    solution : its payload (routes as a list of lists or ``Routes``, a ``Plan``, an
        ``Order``, ...) or a :class:`~taopt.result.Solution` carrying one

    Returns
    -------
    float
        The family's objective: total travel time (2.2) / (3.1), total distance (4.1),
        the makespan (5.1), the path cost of an SOP order.

    Raises
    ------
    FeasibilityError
        Naming the violated constraint and the item.
    InstanceError
        ``problem`` is not of a registered type.
    """
    raise InstanceError(
        f"evaluate() does not know problems of type {type(problem).__name__} "
        "(no family registered for it)"
    )


__all__ = ["evaluate"]
