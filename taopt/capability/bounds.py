"""Chapter 3 bounds, per capability class (§3.4.2, Theorem 3.4).

* :func:`arborescence_bound` — valid: the sum over classes of chapter 2's Edmonds bound.
* :func:`thesis_mcga` — Theorem 3.4's f^a = Σ_q f^a_q with Algorithm 1 per class, as
  printed; NOT a valid bound on asymmetric costs (as Lemma 2.4).
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


__all__ = ["arborescence_bound", "thesis_mcga"]
