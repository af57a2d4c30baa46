"""The one status rule: how any engine's stop reads in taopt's words.

Every exact method and peer (HiGHS through cvxpy or highspy, the DFJ loop, the dynamic
programmes, CP-SAT) ends its search with a *stop*: why it ended (a word of :data:`STOPS`, or
its solver's own status word, translated by :data:`RAW_OUTCOMES`), its incumbent's value and
a proven lower bound. :func:`decide` is the rule that turns a stop into taopt's
``(status, stopped_by)``; :func:`taopt.result.finish` applies it to build the method's
:class:`~taopt.result.Solution` (the one path from a stop to a result).

* **optimal** only when the incumbent is proven within :data:`OPTIMALITY_TOLERANCE`
  (relative gap ``(objective − bound) / |objective|`` at most 1e-6), whatever the engine
  says; a solver's "optimal" under a looser gap is **feasible** (``stopped_by="mip_gap"``);
* a run stopped by a time or solver limit, or interrupted, is **time_limit** (its bound is
  proven), with or without an incumbent (without one the objective is ``inf``);
* any other stop with an open gap ("mip_gap", "max_rounds") is **feasible**;
* **infeasible** when the engine proves it, **error** for anything else.

This module imports nothing of taopt (the statuses live here; :mod:`taopt.result` builds on
them), so every layer can use it.

Example
-------
>>> decide("optimal", 10.0, 10.0, solver="highs")
('optimal', 'optimal')
>>> decide("user_limit", 10.0, 9.0, solver="highs", time_limited=True)
('time_limit', 'time_limit')
>>> decide("mip_gap", 10.0, 9.0)
('feasible', 'mip_gap')
>>> decide("interrupted", 10.0, 9.0)
('time_limit', 'interrupted')
"""

from __future__ import annotations

import enum
import math


class Status(str, enum.Enum):
    """Named statuses. Only a proven optimum is called OPTIMAL."""

    OPTIMAL = "optimal"
    TIME_LIMIT = "time_limit"  # stopped by a limit: objective is the incumbent, bound is proven
    FEASIBLE = "feasible"  # a feasible solution with no optimality claim (heuristics)
    RELAXATION = "relaxation"  # the value of a relaxation: a bound, not a solution
    INFEASIBLE = "infeasible"
    # a heuristic or peer ended without a feasible answer: its outcome, not a proof that
    # none exists, and not a failure of the method (the reason is in ``info["error"]``)
    NO_SOLUTION = "no_solution"
    ERROR = "error"

    def __str__(self) -> str:
        return self.value

    def __repr__(self) -> str:  # a str enum: shown as the string it equals
        return repr(self.value)

    def __format__(self, spec: str) -> str:
        return format(self.value, spec)


OPTIMAL = Status.OPTIMAL
TIME_LIMIT = Status.TIME_LIMIT
FEASIBLE = Status.FEASIBLE
RELAXATION = Status.RELAXATION
INFEASIBLE = Status.INFEASIBLE
NO_SOLUTION = Status.NO_SOLUTION
ERROR = Status.ERROR
STATUSES = tuple(Status)


#: Largest relative gap still called optimal.
OPTIMALITY_TOLERANCE = 1e-6

#: Why an engine stopped, in taopt's words: a proof ("optimal", "infeasible"), a limit
#: ("time_limit", "solver_limit": a node, iteration or memory limit; "max_states" and "size":
#: a dynamic programme's cap on its states; "interrupted": Ctrl-C or a cancellation), a
#: stopping rule with an open gap ("mip_gap", "max_rounds"), or "error".
STOPS = (
    "optimal",
    "infeasible",
    "time_limit",
    "solver_limit",
    "max_states",
    "size",
    "interrupted",
    "mip_gap",
    "max_rounds",
    "error",
)

#: The stops that make an unproven incumbent "time_limit" (the others make it "feasible").
LIMITS = ("time_limit", "solver_limit", "max_states", "size", "interrupted")

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


def decide(
    stop: str,
    objective: float | None,
    bound: float | None,
    *,
    solver: str | None = None,
    time_limited: bool = False,
    has_point: bool | None = None,
) -> tuple[Status, str]:
    """taopt's ``(status, stopped_by)`` of an engine's stop: the one status rule.

    Parameters
    ----------
    stop : str
        Why the search ended: a word of :data:`STOPS`; with ``solver``, that solver's own
        status word (a key of its :data:`RAW_OUTCOMES` table; an unknown one is an error).
    objective : float or None
        The incumbent's value (re-scored by the family's scorer when the caller has one);
        None or ``inf`` when there is none.
    bound : float or None
        A proven lower bound.
    solver : str, optional
        "highs", "cpsat" or "dp": ``stop`` is then that solver's raw status.
    time_limited : bool
        With ``solver``: whether a time limit was set (a raw limit then reads
        "time_limit", else "solver_limit").
    has_point : bool, optional
        With ``solver``: whether an incumbent exists (default: ``objective`` is finite).

    Returns
    -------
    tuple
        ``(OPTIMAL, "optimal")`` when :func:`relative_gap` is at most
        :data:`OPTIMALITY_TOLERANCE`; else ``(TIME_LIMIT, stop)`` for a stop in
        :data:`LIMITS` and ``(FEASIBLE, stop)`` for any other; ``(INFEASIBLE,
        "infeasible")`` and ``(ERROR, "error")`` for those stops. A solver's claimed optimum
        counts as the stop "mip_gap" (a loose solver gap is "feasible"); a claimed optimum
        without an incumbent is an error; a raw limit without one is ``TIME_LIMIT``.

    Notes
    -----
    O(1). Exact means certified (``docs/architecture.md``, the status rule): only a closed
    gap is optimal, and a limit never raises.
    """
    if solver is not None:
        kind = RAW_OUTCOMES.get(solver, {}).get(stop, "error")
        if has_point is None:
            has_point = objective is not None and math.isfinite(objective)
        limit = "time_limit" if time_limited else "solver_limit"
        if kind == "infeasible":
            return INFEASIBLE, "infeasible"
        if kind in ("optimal", "limit") and has_point:
            assert objective is not None
            return decide("mip_gap" if kind == "optimal" else limit, objective, bound)
        if kind == "limit":  # a limit before any incumbent
            return TIME_LIMIT, limit
        return ERROR, "error"
    if stop == "infeasible":
        return INFEASIBLE, "infeasible"
    if stop == "error":
        return ERROR, "error"
    value = math.inf if objective is None else float(objective)
    if relative_gap(value, bound) <= OPTIMALITY_TOLERANCE:
        return OPTIMAL, "optimal"
    if stop in LIMITS:
        return TIME_LIMIT, stop
    return FEASIBLE, stop


__all__ = [
    "Status",
    "STATUSES",
    "OPTIMAL",
    "TIME_LIMIT",
    "FEASIBLE",
    "RELAXATION",
    "INFEASIBLE",
    "NO_SOLUTION",
    "ERROR",
    "OPTIMALITY_TOLERANCE",
    "STOPS",
    "LIMITS",
    "RAW_OUTCOMES",
    "relative_gap",
    "decide",
]
