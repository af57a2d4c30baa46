"""Lower bounds, each saying whether it is valid (DESIGN invariant 3).

* :func:`arborescence` — valid. Chapter 2: Edmonds' min-cost arborescence with
  a super-root joined to every vehicle at zero cost. Chapter 5: Proposition
  5.3's min-cost arborescence of G^d rooted at the depot.
* :func:`thesis_mcga` — the thesis's Algorithm 1 ("MCGA") as printed. Kept
  because Tables 2.1–2.2 are computed with it; NOT a valid lower bound on
  asymmetric matrices (it can exceed the optimum).
"""

from __future__ import annotations

from typing import Any

from taopt.errors import InstanceError


def arborescence(problem: Any) -> float:
    """Valid lower bound from a min-cost arborescence (chapter 2 or chapter 5)."""
    from taopt.routing.problem import AssignmentProblem

    if isinstance(problem, AssignmentProblem):
        from taopt.routing.bounds import arborescence_bound

        return arborescence_bound(problem)
    from taopt.delivery.instance import DeliveryInstance

    if isinstance(problem, DeliveryInstance):
        from taopt.delivery.bounds import arborescence_bound

        return arborescence_bound(problem)
    raise InstanceError(f"arborescence() does not know problems of type {type(problem).__name__}")


def thesis_mcga(problem: Any) -> float:
    """The thesis's Algorithm 1 value f_a, as printed (not a valid bound on asymmetric costs)."""
    from taopt.routing.bounds import thesis_mcga as _mcga

    return _mcga(problem)


__all__ = ["arborescence", "thesis_mcga"]
