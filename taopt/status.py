"""The one status rule: what a solver's outcome certifies, in taopt's words.

Every exact method (HiGHS through cvxpy or highspy, the DFJ loop, the dynamic programmes,
CP-SAT) ends with a raw outcome of its own: a solver status, an incumbent's objective, a
proven lower bound, and whether a time limit was set. :func:`outcome` turns it into
taopt's ``(status, stopped_by)``; :func:`certify` is the rule underneath it, applied
again by a model that combines a solver's bound with its own valid bounds.

* **optimal** only when the incumbent is proven within :data:`OPTIMALITY_TOLERANCE`
  (relative gap ``(objective − bound) / |objective|`` at most 1e-6), whatever the solver
  says; a solver's "optimal" under a looser gap is **feasible** (``stopped_by="mip_gap"``);
* a run stopped by a limit with an incumbent is **time_limit** (its bound is proven); with
  no incumbent, **time_limit** too (the caller reports objective ``inf`` and its bound);
* **infeasible** when the solver proves it, **error** for anything else.

The core holds it (not :mod:`taopt.models`) because heuristics, peers and models all
need it and the core imports no method package.

Example
-------
>>> outcome("highs", "optimal", objective=10.0, bound=10.0)
('optimal', 'optimal')
>>> outcome("highs", "user_limit", objective=10.0, bound=9.0, time_limited=True)
('time_limit', 'time_limit')
>>> certify(10.0, 9.0, "mip_gap")
('feasible', 'mip_gap')
"""

from __future__ import annotations

import math

from taopt.result import ERROR, FEASIBLE, INFEASIBLE, OPTIMAL, TIME_LIMIT, Status

#: Largest relative gap still called optimal.
OPTIMALITY_TOLERANCE = 1e-6

#: Each solver's raw statuses as one of four outcomes: "optimal" (the solver claims a
#: proof), "limit" (stopped by a time, node, iteration or user limit), "infeasible",
#: "error" (anything not listed). HiGHS's are in cvxpy's words (as cvxpy's HiGHS
#: interface and :class:`taopt.models.highs.HighsModel` give them); CP-SAT's are
#: ``CpSolver.StatusName``; a DP says "complete" (every state expanded) or "stopped".
RAW_OUTCOMES: dict[str, dict[str, str]] = {
    "highs": {
        "optimal": "optimal",
        "optimal_inaccurate": "optimal",
        "user_limit": "limit",
        "infeasible": "infeasible",
        "infeasible_inaccurate": "infeasible",
        "infeasible_or_unbounded": "infeasible",
    },
    "cpsat": {
        "OPTIMAL": "optimal",
        "FEASIBLE": "limit",
        "UNKNOWN": "limit",
        "INFEASIBLE": "infeasible",
    },
    "dp": {"complete": "optimal", "stopped": "limit", "infeasible": "infeasible"},
}


def relative_gap(objective: float, bound: float | None) -> float:
    """``max(0, objective − bound) / |objective|`` (0 when both are 0; inf without a bound).

    Example
    -------
    >>> relative_gap(10.0, 9.0), relative_gap(0.0, 0.0), relative_gap(5.0, None)
    (0.1, 0.0, inf)
    """
    if bound is None or not math.isfinite(objective) or not math.isfinite(bound):
        return math.inf
    difference = max(0.0, objective - bound)
    if difference == 0.0:
        return 0.0
    return math.inf if objective == 0 else difference / abs(objective)


def certify(objective: float, bound: float | None, stopped_by: str) -> tuple[Status, str]:
    """The status of an incumbent with a proven bound: ``(status, stopped_by)``.

    Parameters
    ----------
    objective : float
        The incumbent's value (re-scored by the problem's scorer when the caller has one).
    bound : float or None
        A proven lower bound.
    stopped_by : str
        Why the search ended if the gap is not closed: "time_limit", "mip_gap",
        "max_rounds", "solver_limit", ...

    Returns
    -------
    tuple
        ``(OPTIMAL, "optimal")`` when :func:`relative_gap` is at most
        :data:`OPTIMALITY_TOLERANCE`; else ``(TIME_LIMIT, stopped_by)`` for a time or
        solver limit, ``(FEASIBLE, stopped_by)`` for anything else.

    Notes
    -----
    O(1). DESIGN invariant "exact means certified": only a closed gap is optimal.
    """
    if relative_gap(objective, bound) <= OPTIMALITY_TOLERANCE:
        return OPTIMAL, "optimal"
    if stopped_by in ("time_limit", "solver_limit"):
        return TIME_LIMIT, stopped_by
    return FEASIBLE, stopped_by


def outcome(
    solver: str,
    raw_status: str,
    *,
    objective: float | None,
    bound: float | None,
    time_limited: bool = False,
    has_point: bool | None = None,
) -> tuple[Status, str]:
    """taopt's ``(status, stopped_by)`` of a solver's raw outcome.

    Parameters
    ----------
    solver : str
        A key of :data:`RAW_OUTCOMES`: "highs", "cpsat" or "dp".
    raw_status : str
        The solver's own status word (an unknown one is an error outcome).
    objective : float or None
        The incumbent's value; None (or ``inf``) when there is none.
    bound : float or None
        The proven lower bound.
    time_limited : bool
        Whether a time limit was set (a limit then reads "time_limit", else
        "solver_limit").
    has_point : bool, optional
        Whether an incumbent exists (default: ``objective`` is finite).

    Returns
    -------
    tuple
        ``(status, stopped_by)``: a solver's optimum or a limit with an incumbent goes
        through :func:`certify` (a claimed optimum as ``stopped_by="mip_gap"``, so a
        loose solver gap is "feasible"); a limit without one is ``(TIME_LIMIT, limit)``;
        ``(INFEASIBLE, "infeasible")``; anything else ``(ERROR, "error")``.

    Notes
    -----
    O(1). Shared by :func:`taopt.models.highs.solve_highs`, ``HighsModel.solve``, the SOP
    DP and CP-SAT.

    References
    ----------
    DESIGN.md invariant 4 (exact means certified).
    """
    kind = RAW_OUTCOMES.get(solver, {}).get(raw_status, "error")
    if has_point is None:
        has_point = objective is not None and math.isfinite(objective)
    limit = "time_limit" if time_limited else "solver_limit"
    if kind == "infeasible":
        return INFEASIBLE, "infeasible"
    if kind in ("optimal", "limit") and has_point and objective is not None:
        return certify(float(objective), bound, "mip_gap" if kind == "optimal" else limit)
    if kind == "limit":  # a limit before any incumbent
        return TIME_LIMIT, limit
    return ERROR, "error"


__all__ = ["OPTIMALITY_TOLERANCE", "RAW_OUTCOMES", "relative_gap", "certify", "outcome"]
