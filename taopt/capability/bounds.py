"""Chapter 3 bounds, per capability class (§3.4.2, §3.6).

The problem splits exactly by class, so each bound is the sum over the classes q of the
chapter 2 bound of class q's problem (targets T_q, vehicles R_q):

* :func:`arborescence_bound` — **valid** lower bound: Σ_q of Edmonds' minimum-cost
  arborescence (:func:`taopt.routing.bounds.arborescence_bound`).
* :func:`thesis_mcga` — Theorem 3.4's ``f^a = Σ_q f^a_q`` with Algorithm 1 ("MCGA") per
  class, as printed; NOT a valid lower bound on asymmetric costs (as Lemma 2.4;
  :mod:`taopt.orchestration.studies.capability_claims` finds instances where it exceeds the optimum). It is the
  denominator of the thesis's quality ratio (3.15).
* :func:`doubled_arborescence` — Lemma 3.6's ``f^da = Σ_q f^da_q``: every edge of Algorithm
  1's tree of class q doubled in the opposite direction. An upper bound on the optimum when
  the costs satisfy the triangle inequality (Remark 3.1), and ``2 f^a`` on symmetric costs.
"""

from __future__ import annotations

from taopt.capability.problem import CapabilityProblem
from taopt.routing import bounds as routing_bounds


def arborescence_bound(problem: CapabilityProblem) -> float:
    """Valid lower bound: Σ_q of the min-cost arborescence bound of class q."""
    return sum(routing_bounds.arborescence_bound(c.problem) for c in problem.classes if c.problem)


def thesis_mcga(problem: CapabilityProblem) -> float:
    """Theorem 3.4's f^a: Algorithm 1 on each class, summed (not valid on asymmetric costs)."""
    return sum(routing_bounds.thesis_mcga(c.problem) for c in problem.classes if c.problem)


def doubled_arborescence(problem: CapabilityProblem) -> float:
    """Lemma 3.6's f^da: Algorithm 1's tree of each class with every edge doubled, summed.

    Example
    -------
    >>> import numpy as np
    >>> x = np.array([1.0, 3.0, 0.0])                  # targets at 1, 3; a vehicle at 0
    >>> p = CapabilityProblem(abs(x[:, None] - x[None, :]), 2, ["a"], [{"a"}, {"a"}])
    >>> doubled_arborescence(p), thesis_mcga(p)        # symmetric: f^da = 2 f^a
    (6.0, 3.0)
    """
    return sum(routing_bounds.f_da(c.problem) for c in problem.classes if c.problem)


def capability_lower(problem: CapabilityProblem, strength: str) -> float:
    """:func:`taopt.bounds.lower` for chapter 3: the arborescence ("fast"), or the sum over
    the classes of chapter 2's bound at that strength (the classes are independent)."""
    from taopt.routing.bounds import routing_lower

    if strength == "fast":
        return float(arborescence_bound(problem))
    return float(
        sum(routing_lower(c.problem, strength) for c in problem.classes if c.problem is not None)
    )


__all__ = ["arborescence_bound", "thesis_mcga", "doubled_arborescence", "capability_lower"]
