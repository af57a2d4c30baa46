"""One way to solve a cvxpy model with HiGHS and say what was proven.

Every exact model of :mod:`taopt.models` (routing, delivery, SOP) solves
through :func:`solve_highs`, so the three agree on what "optimal" means
(DESIGN invariant 4, "exact means certified"):

* **optimal** only when the incumbent is proven within
  :data:`OPTIMALITY_TOLERANCE` (relative gap ``(objective − bound) /
  |objective|`` at most 1e-6), whatever ``mip_rel_gap`` HiGHS was given;
* a MIP that HiGHS calls optimal because a looser user ``mip_rel_gap`` was
  met is **feasible**, with ``stopped_by = "mip_gap"`` and its proven bound;
* a run stopped by ``time_limit`` with a point is **time_limit**, with the
  proven bound.

The same rule, :func:`certify`, is what the models apply to their final
answer, after they combine the solver's bound with their own valid bounds
and re-score the decoded solution.

cvxpy maps HiGHS's ``kOptimal`` to "optimal" and ``kTimeLimit`` (and the other
limits) to "user_limit"; ``problem.solver_stats.extra_stats`` is HiGHS's
``HighsInfo``: ``primal_solution_status`` (2 = a feasible point exists),
``mip_dual_bound`` (the proven bound of a MIP), ``mip_gap``,
``mip_node_count`` and ``objective_function_value``.

Example
-------
>>> import cvxpy as cp
>>> x = cp.Variable(2, integer=True)
>>> run = solve_highs(cp.Problem(cp.Minimize(x.sum()), [x >= 0.5]))
>>> run.status, run.objective, run.bound
('optimal', 2.0, 2.0)
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp

from taopt.result import ERROR, FEASIBLE, INFEASIBLE, OPTIMAL, TIME_LIMIT

#: "optimal" only when (objective − bound) / |objective| is at most this.
OPTIMALITY_TOLERANCE = 1e-6

__all__ = ["OPTIMALITY_TOLERANCE", "HighsRun", "certify", "relative_gap", "solve_highs"]


@dataclass(frozen=True)
class HighsRun:
    """What one HiGHS solve found and proved.

    Attributes
    ----------
    status : str
        taopt status by :func:`certify`: "optimal", "feasible" (loose
        ``mip_rel_gap``), "time_limit", "infeasible" or "error".
    stopped_by : str
        "optimal", "mip_gap", "time_limit", "solver_limit" (a HiGHS limit other
        than ``time_limit``), "infeasible" or "error".
    solver_status : str
        cvxpy's status ("optimal", "user_limit", "infeasible", ...), or
        "solver_error" when cvxpy raised.
    has_point : bool
        HiGHS holds a feasible point (``primal_solution_status == 2``); only
        then are the variables' values meaningful.
    objective : float or None
        The model's objective at that point.
    bound : float or None
        Proven lower bound: ``mip_dual_bound`` for a MIP, the LP value for an
        LP solved to optimality; None when nothing is proven.
    mip_gap : float
        HiGHS's own ``mip_gap`` (NaN for an LP or without info).
    nodes : int
        Branch-and-bound nodes (``mip_node_count``; -1 without info).
    is_mip : bool
    message : str
        cvxpy's error text when ``solver_status == "solver_error"``.
    info : HighsInfo or None
        The raw HiGHS info.
    """

    status: str
    stopped_by: str
    solver_status: str
    has_point: bool
    objective: float | None
    bound: float | None
    mip_gap: float
    nodes: int
    is_mip: bool
    message: str = ""
    info: Any = field(default=None, repr=False)


def relative_gap(objective: float, bound: float | None) -> float:
    """``max(0, objective − bound) / |objective|`` (0 when both are 0; inf without a bound)."""
    if bound is None or not math.isfinite(objective) or not math.isfinite(bound):
        return math.inf
    difference = max(0.0, objective - bound)
    if difference == 0.0:
        return 0.0
    return math.inf if objective == 0 else difference / abs(objective)


def certify(objective: float, bound: float | None, stopped_by: str) -> tuple[str, str]:
    """The one status rule: ``(status, stopped_by)`` of a solution with a proven bound.

    Parameters
    ----------
    objective : float
        The incumbent's value (re-scored by the problem's scorer when the
        caller has one).
    bound : float or None
        A proven lower bound.
    stopped_by : str
        Why the search ended if the gap is not closed: "time_limit",
        "mip_gap", "max_rounds", "solver_limit", ...

    Returns
    -------
    tuple of str
        ``("optimal", "optimal")`` when :func:`relative_gap` is at most
        :data:`OPTIMALITY_TOLERANCE`; else ``("time_limit", stopped_by)`` for
        a time limit, ``("feasible", stopped_by)`` for anything else.
    """
    if relative_gap(objective, bound) <= OPTIMALITY_TOLERANCE:
        return OPTIMAL, "optimal"
    if stopped_by in ("time_limit", "solver_limit"):
        return TIME_LIMIT, stopped_by
    return FEASIBLE, stopped_by


def _number(info: Any, name: str, default: float = math.nan) -> float:
    value = getattr(info, name, default) if info is not None else default
    return float(value)


def solve_highs(
    problem: cp.Problem,
    time_limit: float | None = None,
    mip_rel_gap: float | None = None,
    objective_bound: float | None = None,
    verbose: bool = False,
) -> HighsRun:
    """Solve a cvxpy problem with HiGHS; never raises for a solver outcome.

    Parameters
    ----------
    problem : cvxpy.Problem
        A minimisation LP or MILP.
    time_limit : float, optional
        HiGHS ``time_limit`` in seconds (at least 1 ms is passed).
    mip_rel_gap : float, optional
        HiGHS ``mip_rel_gap`` (ignored for an LP). A run that stops because
        this gap is met but is not within :data:`OPTIMALITY_TOLERANCE` is
        "feasible".
    objective_bound : float, optional
        HiGHS ``objective_bound``: a MIP cut-off; nodes whose bound exceeds it
        are pruned (HiGHS reports "infeasible" if no point lies below it).
    verbose : bool
        HiGHS log.

    Returns
    -------
    HighsRun
        Status "error" (with ``message``) when cvxpy raised; the caller
        decides what to do with every outcome.
    """
    is_mip = bool(problem.is_mixed_integer())
    options: dict[str, Any] = {}
    if time_limit is not None:
        options["time_limit"] = max(float(time_limit), 1e-3)
    if is_mip and mip_rel_gap is not None:
        options["mip_rel_gap"] = float(mip_rel_gap)
    if objective_bound is not None:
        options["objective_bound"] = float(objective_bound)
    try:
        with warnings.catch_warnings():
            # cvxpy warns "Solution may be inaccurate" on every limit; the status says it
            warnings.filterwarnings("ignore", message="Solution may be inaccurate")
            problem.solve(solver=cp.HIGHS, verbose=verbose, **options)
    except cp.error.SolverError as exc:
        return HighsRun(
            status=ERROR,
            stopped_by="error",
            solver_status="solver_error",
            has_point=False,
            objective=None,
            bound=None,
            mip_gap=math.nan,
            nodes=-1,
            is_mip=is_mip,
            message=str(exc),
        )
    solver_status = problem.status
    info = problem.solver_stats.extra_stats if problem.solver_stats else None
    has_point = info is not None and int(getattr(info, "primal_solution_status", 0)) == 2
    objective = float(problem.value) if has_point and problem.value is not None else None
    bound = None
    if is_mip:
        dual_bound = _number(info, "mip_dual_bound")
        bound = dual_bound if math.isfinite(dual_bound) else None
    elif solver_status == "optimal" and has_point:
        bound = _number(info, "objective_function_value")  # an LP at its optimum
    if solver_status in ("infeasible", "infeasible_inaccurate", "infeasible_or_unbounded"):
        status, stopped_by = INFEASIBLE, "infeasible"
    elif solver_status in ("optimal", "optimal_inaccurate", "user_limit") and has_point:
        if solver_status == "user_limit":
            reason = "time_limit" if time_limit is not None else "solver_limit"
        else:
            reason = "mip_gap"
        status, stopped_by = certify(objective, bound, reason)
    elif solver_status == "user_limit":  # a limit before any feasible point
        status, stopped_by = TIME_LIMIT, "time_limit" if time_limit is not None else "solver_limit"
    else:
        status, stopped_by = ERROR, "error"
    return HighsRun(
        status=status,
        stopped_by=stopped_by,
        solver_status=solver_status,
        has_point=has_point,
        objective=objective,
        bound=bound,
        mip_gap=_number(info, "mip_gap") if is_mip else math.nan,
        nodes=int(_number(info, "mip_node_count", -1)) if is_mip else -1,
        is_mip=is_mip,
        info=info,
    )
