"""Registration of the budgeted family (thesis §6.2's capacity and travel-time limits).

The family's spec (:class:`taopt.registry.Family`), found on disk by
:func:`taopt.families.ensure_families`: problem :class:`BudgetedProblem`, file kind
``budgeted_problem``, payload :class:`~taopt.result.Routes`, the one scorer
:func:`evaluate_budgeted`, the valid bounds ``arborescence`` and ``lower`` of
:mod:`taopt.budgeted.bounds`, the plot ``routes`` and the chapter-6 study ``taopt study budgeted``.
"""

from __future__ import annotations

from taopt.budgeted.bounds import arborescence_bound, lower
from taopt.budgeted.plot import plot_budgeted_routes
from taopt.budgeted.problem import BudgetedProblem, evaluate_budgeted
from taopt.registry import Bound, Family, Study, register_family
from taopt.result import Routes
from taopt.routing.plot import routes_lines

FAMILY = register_family(
    Family(
        problem_type=BudgetedProblem,
        kind="budgeted_problem",
        payload=Routes,
        title="open multi-vehicle routing with capacities and travel-time limits (§6.2)",
        evaluate=evaluate_budgeted,
        bounds={"arborescence": Bound(arborescence_bound), "lower": Bound(lower)},
        plots={"routes": plot_budgeted_routes},
        describe=routes_lines,
        studies=(Study("budgeted", "taopt.orchestration.studies.budgeted"),),
    )
)

__all__ = ["FAMILY"]
