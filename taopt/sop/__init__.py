"""The sequential ordering problem (TSPLIB SOP): the certification set of chapter 5's exact core.

:class:`SopProblem` (precedence-constrained Hamiltonian path from ``start`` to ``end``), the
shipped TSPLIB files with their proven optima (:data:`~taopt.sop.problem.KNOWN_OPTIMA`), the
one scorer :func:`evaluate_order` and the bounds of :mod:`taopt.sop.bounds`. The family's spec
is :mod:`taopt.sop.family`; the exact DP and the flow MILP are in
:mod:`taopt.models.sop_dp` and :mod:`taopt.models.sop`.
"""

from taopt.sop import family as _family  # noqa: F401  (registers the family)
from taopt.sop.problem import KNOWN_OPTIMA, SopProblem, evaluate_order, load_sop, shipped_sop

__all__ = ["SopProblem", "evaluate_order", "load_sop", "shipped_sop", "KNOWN_OPTIMA"]
