"""Exact formulations (cvxpy + HiGHS), as ``taopt.models``.

* :func:`solve_routing` — chapter 2, (2.2)–(2.5) with DFJ / MTZ / flow subtour elimination.
* :func:`solve_delivery` — chapter 5, a linear equivalent of (5.1)–(5.7) (``"milp"``).
* :func:`solve_sop` — sequential ordering (precedence-constrained Hamiltonian path); the
  registered SOP "exact" is the portfolio :func:`taopt.models.sop.solve_sop_problem` (the
  DP over order ideals of :mod:`taopt.models.sop_dp`, then this MILP).
* :func:`lp_bound` — the LP relaxation of (2.2)–(2.5), a valid lower bound.
* :func:`solve_capability` — chapter 3, (3.1)–(3.3) as printed, corrected per class, joint.
* :func:`solve_comm` — chapter 4's f_o: (4.1)–(4.2) without communication limits, per class.
* ``"exact"`` for a delivery instance — chapter 5's exact optimum by dynamic programming over
  the order ideals of G^p (:func:`taopt.delivery.ideal_dp.ideal_dp`); ``"subset-dp"`` the
  DP over all subsets (:func:`taopt.delivery.schedule.optimal_plan`, n <= 14). Core code,
  because every ordering heuristic is scored through the same DP; registered here with
  the other exact methods.

Importing this package imports every module in it, and so registers every exact method in
:mod:`taopt.registry`
(``taopt.solve(problem, "exact")``); no other import is needed for any of them. They never run a heuristic themselves: the registry's
``warm_start`` names the heuristic(s) whose best result :func:`taopt.solve` passes in as
``incumbent``.
"""

from __future__ import annotations

import importlib
import pkgutil
from typing import Any

from taopt.capability.problem import CapabilityProblem
from taopt.delivery.ideal_dp import count_ideals, ideal_dp
from taopt.delivery.instance import DeliveryInstance
from taopt.delivery.schedule import optimal_plan
from taopt.models.capability import solve_capability, solve_exact, solve_joint
from taopt.models.comm import solve_comm  # registers CommProblem "exact"
from taopt.models.delivery import solve_delivery
from taopt.models.routing import solve_routing
from taopt.models.sop import solve_sop, solve_sop_problem
from taopt.registry import register_method
from taopt.routing.problem import AssignmentProblem
from taopt.runtime import milp_bytes, register_footprint
from taopt.sop.problem import SopProblem


def lp_bound(problem: AssignmentProblem, sec: str = "dfj", **options: Any) -> float:
    """Valid lower bound from the LP relaxation of the exact model (2.2)–(2.5).

    Calls ``solve_routing(problem, sec=sec, relax=True, **options)`` and returns its
    objective (the relaxation's value). With "dfj" (all of (2.5)) the LP lies inside the
    arborescence polytope (in-degree 1 plus the subtour constraints imply a cut into every
    target set), so it is never below ``taopt.bounds.arborescence``; "mtz" and "flow"
    give weaker LPs. ``taopt.bounds.lower(problem, "strong")`` takes the same DFJ value
    from the core (:func:`taopt.routing.bounds.lp_bound`).
    """
    result = solve_routing(problem, sec=sec, relax=True, **options)
    return float(result.bound if result.bound is not None else result.objective)


register_method(AssignmentProblem, "exact", category="exact", warm_start=("MC",), style=("-", "*"))(
    solve_routing
)


@register_footprint(AssignmentProblem, "exact")
def _routing_footprint(problem: AssignmentProblem, options: dict[str, Any]) -> tuple[float, str]:
    """(2.2)–(2.5) has one binary per arc, (n + m)^2; the flow version n more per arc."""
    arcs = float(problem.n + problem.m) ** 2
    sec = options.get("sec", "dfj")
    columns = arcs * (problem.n + 1) if sec == "flow" else arcs
    return milp_bytes(columns), (
        f"the exact routing model ({sec}) of {problem.n:,} targets and {problem.m} vehicles "
        f"({columns:,.0f} columns)"
    )


#: Largest number of order ideals of G^p on which `taopt solve` runs the exact ideal DP by
#: default and `taopt verify --exact` certifies with it (about 1 GB and a minute at most;
#: the dag40 instances of Tables 5.1-5.2 have 10^4 to 6·10^5).
IDEAL_DP_DEFAULT_MAX_IDEALS = 2_000_000


def _ideal_dp_affordable(instance: DeliveryInstance) -> bool:
    return count_ideals(instance, IDEAL_DP_DEFAULT_MAX_IDEALS) is not None


def _ideal_dp_too_large(instance: DeliveryInstance) -> str:
    return (
        f"the exact DP over order ideals is not run on n = {instance.n} customers: G^p has more "
        f"than {IDEAL_DP_DEFAULT_MAX_IDEALS:,} order ideals; name it with --methods exact to try "
        f"(its time limit returns the best plan with a proven bound)"
    )


# chapter 5's certified optimum: the DP over the order ideals of G^p, by default while the
# ideals are affordable; SMMA's plan (the best of NIA, MMA, SMMA) is its incumbent
register_method(
    DeliveryInstance,
    "exact",
    category="exact",
    default=_ideal_dp_affordable,
    not_default=_ideal_dp_too_large,
    warm_start=("NIA", "MMA", "SMMA"),
    certifies=_ideal_dp_affordable,  # taopt verify --exact: the fastest exact method
)(ideal_dp)
# the subset DP over all 2^n customer sets, kept for comparison (n <= 14)
register_method(
    DeliveryInstance,
    "subset-dp",
    category="exact",
    warm_start=("NIA", "MMA", "SMMA"),
    default=False,
    not_default="the subset DP (2^n states) runs only when named (--methods subset-dp)",
    style=("-", "X"),
)(optimal_plan)
# the teaching MILP (5.1)-(5.7) does not scale past a handful of customers
register_method(
    DeliveryInstance,
    "milp",
    category="exact",
    warm_start=("NIA", "MMA", "SMMA"),
    default=False,
    not_default="the MILP (5.1)-(5.7) runs only when named (--methods milp): exact is faster",
    style=("--", "*"),
)(solve_delivery)
# the SOP portfolio: the ideal DP (dense precedence) then the flow MILP (sparse); the fast
# orderings of chapter 5 give the incumbent that prunes the DP and is kept on a time limit
register_method(SopProblem, "exact", category="exact", warm_start=("NIA", "MMA", "SMMA"))(
    solve_sop_problem
)
# chapter 3: the corrected model is "exact"; the joint MILP on request. The printed model
# (a relaxation without routes) is solve_capability(problem, "printed").
register_method(CapabilityProblem, "exact", category="exact", warm_start=("DTAA",))(solve_exact)
register_method(
    CapabilityProblem,
    "joint",
    category="exact",
    warm_start=("DTAA",),
    default=False,
    not_default="the joint MILP runs only when named (--methods joint): 'exact' is faster",
)(solve_joint)

# every other module of this package registers its own methods where they are defined (a new
# family's exact model is found here without a line in this file)
for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")

__all__ = [
    "solve_capability",
    "solve_routing",
    "solve_delivery",
    "solve_sop",
    "solve_sop_problem",
    "lp_bound",
    "solve_comm",
]
