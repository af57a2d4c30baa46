"""Thesis §6.2's future work: open multi-vehicle routing with capacities and travel-time limits.

Registers the family :class:`BudgetedProblem` (payload :class:`~taopt.result.Routes`, scorer
:func:`evaluate_budgeted`, bounds ``arborescence`` and ``lower``, plot ``routes``) through
:mod:`taopt.budgeted.family`.
"""

from taopt.budgeted import family as _family  # noqa: F401  (registers the family)
from taopt.budgeted.problem import BudgetedProblem, evaluate_budgeted, violations

__all__ = ["BudgetedProblem", "evaluate_budgeted", "violations"]
