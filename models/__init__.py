"""Exact formulations (cvxpy + HiGHS), as ``taopt.models``.

* :func:`solve_routing` — chapter 2, (2.2)–(2.5) with DFJ / MTZ / flow subtour elimination.
* :func:`solve_delivery` — chapter 5, a linear equivalent of (5.1)–(5.7).
* :func:`solve_sop` — sequential ordering (precedence-constrained Hamiltonian path); the
  registered SOP "exact" is the portfolio :func:`taopt.models.sop.solve_sop_problem` (the
  DP over order ideals of :mod:`taopt.models.sop_dp`, then this MILP).
* :func:`lp_bound` — the LP relaxation of (2.2)–(2.5), a valid lower bound.
* :func:`solve_capability` — chapter 3, (3.1)–(3.3) as printed, corrected per class, joint.
* :func:`solve_comm` — chapter 4's f_o: (4.1)–(4.2) without communication limits, per class.
* ``"DP"`` — chapter 5's exact optimum by dynamic programming over order ideals
  (:func:`taopt.delivery.schedule.optimal_plan`, core code because every ordering heuristic
  is scored through the same DP; registered here with the other exact methods).

Importing this package registers every exact method in :mod:`taopt.registry`
(``taopt.solve(problem, "exact")``); no other import is needed for any of them. They never run a heuristic themselves: the registry's
``warm_start`` names the heuristic(s) whose best result :func:`taopt.solve` passes in as
``incumbent``.
"""

from __future__ import annotations

from typing import Any

from taopt.capability.problem import CapabilityProblem
from taopt.delivery.instance import DeliveryInstance
from taopt.delivery.schedule import optimal_plan
from taopt.delivery.sop import SopProblem
from taopt.limits import milp_bytes, register_footprint
from taopt.models.capability import solve_capability, solve_exact, solve_joint
from taopt.models.comm import solve_comm  # registers CommProblem "exact"
from taopt.models.delivery import solve_delivery
from taopt.models.routing import solve_routing
from taopt.models.sop import solve_sop, solve_sop_problem
from taopt.registry import register_method
from taopt.routing.problem import AssignmentProblem


def lp_bound(problem: AssignmentProblem, sec: str = "dfj", **options: Any) -> float:
    """Valid lower bound from the LP relaxation of the exact model (2.2)–(2.5).

    Calls ``solve_routing(problem, sec=sec, relax=True, **options)`` and returns its
    objective (the relaxation's value). With "dfj" (all of (2.5)) the LP lies inside the
    arborescence polytope (in-degree 1 plus the subtour constraints imply a cut into every
    target set), so it is never below :func:`taopt.bounds.arborescence`; "mtz" and "flow"
    give weaker LPs.
    """
    result = solve_routing(problem, sec=sec, relax=True, **options)
    return float(result.bound if result.bound is not None else result.objective)


register_method(AssignmentProblem, "exact", category="exact", warm_start=("MC",))(solve_routing)


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


#: Largest delivery instance on which `taopt solve` runs the exact DP by default.
DP_DEFAULT_MAX_N = 12


def _dp_too_large(instance: DeliveryInstance) -> str:
    return (
        f"the exact DP is not run on n = {instance.n} customers > {DP_DEFAULT_MAX_N} (its states "
        f"grow as 2^n); name it with --methods DP to try (it refuses n > 14)"
    )


# chapter 5's certified optimum: the DP over order ideals, by default while it is affordable
register_method(
    DeliveryInstance,
    "DP",
    category="exact",
    default=lambda instance: instance.n <= DP_DEFAULT_MAX_N,
    not_default=_dp_too_large,
    warm_start=("NIA", "MMA", "SMMA"),
    certifies=lambda instance: instance.n <= 14,  # taopt verify --exact: the fastest exact method
)(optimal_plan)
# the delivery MILP does not scale past a handful of customers (the subset DP "DP" is the
# exact method `taopt solve` runs by default), so it runs only when asked for
register_method(
    DeliveryInstance,
    "exact",
    category="exact",
    warm_start=("NIA", "MMA", "SMMA"),
    default=False,
    not_default="the MILP (5.1)-(5.7) runs only when named (--methods exact): DP is faster",
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

__all__ = [
    "solve_capability",
    "solve_routing",
    "solve_delivery",
    "solve_sop",
    "solve_sop_problem",
    "lp_bound",
    "solve_comm",
]
