"""PyVRP and OR-Tools on :class:`~taopt.budgeted.BudgetedProblem`: capacity and route time.

The general vehicle-routing solvers a user would reach for, given the §6.2 limits
natively: each target has demand 1 and vehicle k capacity ``Q_k`` (PyVRP's load
dimension, OR-Tools' "Load" dimension), and vehicle k's route travel time is at most
``T_k`` (PyVRP's ``max_distance``, distance being the travel time; OR-Tools' "Time"
dimension). The routes are open as in :mod:`taopt.heuristics.peers`: a dummy end point
reachable from everywhere at cost 0.

Each runs in the chapter 2 peers' worker process (``_peer_worker.py``, whose PyVRP and
OR-Tools models add the load and time dimensions when a request carries ``capacity`` and
``max_time``), for the reason given in :mod:`taopt.heuristics.peers` (docs/architecture.md "Known
traps"); the worker management (start-up handshake, Ctrl-C, crashes, hangs) is that
module's.

Integer units
-------------
Both solvers take integers. The travel times are scaled so that the largest becomes
:data:`LARGEST_ENTRY` = 1e10 (not the chapter-2 peers' 1e7: a travel-time limit needs the
finer grid) and rounded (:func:`taopt.heuristics.peers.integer_costs`), so a route of at
most n arcs is off by at most ``0.5 n`` units, a relative ``5e-11 n`` of the largest
entry. ``T_k`` is passed as ``floor(T_k · scale · (1 + TIME_TOLERANCE / 2))``: a route
that takes exactly ``T_k`` (the boundary case, e.g. the unlimited optimum at ``τ = 1``)
stays feasible for the solver, and a route the solver accepts is within the scorer's
tolerance unless ``0.5 n`` units exceed ``T_k · scale · TIME_TOLERANCE / 2`` (only for a
``T_k`` below ``1e-4 n`` times the largest entry). Either way the answer is re-checked.

Answers
-------
Every answer is re-checked by :func:`taopt.budgeted.violations` and scored by
:func:`taopt.budgeted.evaluate_budgeted`. A route set that breaks a limit (PyVRP's best
may, when it never found a feasible one) or no route set at all (OR-Tools' first-solution
strategy failing) is reported, not hidden: status ``"no_solution"``, ``objective = inf``,
``solution = None`` and ``info["violations"]`` (the scorer's messages, "; "-joined) or
``info["error"]``.

References
----------
Thesis §6.2; Wouda, Lan and Kool (2024), PyVRP; Perron and Didier, OR-Tools routing.
"""

from __future__ import annotations

import math
from typing import Any

from taopt.budgeted.problem import TIME_TOLERANCE, BudgetedProblem, evaluate_budgeted, violations
from taopt.errors import require
from taopt.heuristics import peers
from taopt.registry import register_method
from taopt.result import FEASIBLE, NO_SOLUTION, Routes, Solution
from taopt.runtime import Deadline

__all__ = ["pyvrp_budgeted", "ortools_budgeted", "integer_limits", "shutdown", "LARGEST_ENTRY"]

#: The largest travel time becomes this integer when ``scale`` is not given.
LARGEST_ENTRY = 10**10


#: Stops every peer worker (they restart on the next call).
shutdown = peers.shutdown


def integer_limits(problem: BudgetedProblem, scale: float) -> tuple[list, list]:
    """``Q_k`` and ``T_k`` for the solvers: integers, None for "no limit".

    ``T_k`` becomes ``floor(T_k · scale · (1 + TIME_TOLERANCE / 2))`` (module docstring).
    """
    capacity = [None if not math.isfinite(q) else int(q) for q in problem.capacity]
    stretch = 1.0 + TIME_TOLERANCE / 2
    max_time = [
        None if not math.isfinite(t) else int(math.floor(t * scale * stretch))
        for t in problem.max_time
    ]
    return capacity, max_time


def _solve(
    peer: str,
    problem: BudgetedProblem,
    seed: int,
    scale: float | None,
    options: dict[str, Any],
    deadline: Deadline,
) -> Solution:
    require(problem, BudgetedProblem, f"the {peer} peer")
    if scale is None:
        largest = float(problem.cost.max())
        scale = LARGEST_ENTRY / largest if largest > 0 else 1.0
    cost, scale = peers.integer_costs(problem.routing, scale)
    capacity, max_time = integer_limits(problem, scale)
    request = {
        "cost": cost,
        "n": problem.n,
        "m": problem.m,
        "options": {**options, "capacity": capacity, "max_time": max_time},
    }
    answer = peers._call(peer, request, deadline)
    reply = dict(answer.reply or {"routes": None, "objective": None})
    routes = reply.pop("routes")
    info: dict[str, Any] = {
        "solver_objective": reply.pop("objective"),
        "scale": scale,
        "version": answer.version,
        "startup": answer.startup,
        **{key: value for key, value in options.items() if key != "seed"},
        **reply,
    }
    if answer.stopped:
        info["stopped_by"] = "time_limit"
        info["worker"] = answer.stopped
    method = peer
    runtime = deadline.elapsed()
    if routes is None:
        why = answer.stopped or f"routing status {reply.get('routing_status')}"
        info["error"] = f"{peer} found no route set ({why})"
        return Solution(
            math.inf, NO_SOLUTION, None, runtime=runtime, method=method, seed=seed, info=info
        )
    broken = violations(problem, routes)
    if broken:
        info["violations"] = "; ".join(broken)
        info["violation_count"] = len(broken)
        info["error"] = f"{peer}'s best route set breaks {len(broken)} limit(s)"
        return Solution(
            math.inf, NO_SOLUTION, None, runtime=runtime, method=method, seed=seed, info=info
        )
    return Solution(
        objective=evaluate_budgeted(problem, routes),
        status=FEASIBLE,
        solution=Routes(routes),
        runtime=deadline.elapsed(),
        method=method,
        seed=int(seed),
        info=info,
    )


@register_method(BudgetedProblem, "pyvrp", category="peer", requires=("pyvrp",))
def pyvrp_budgeted(
    problem: BudgetedProblem,
    time_limit: float | None = 1.0,
    seed: int = 0,
    *,
    max_iterations: int | None = None,
    no_improvement: int | str | None = "auto",
    scale: float | None = None,
) -> Solution:
    """PyVRP's iterated local search with capacity ``Q_k`` and maximum route time ``T_k``.

    Parameters
    ----------
    problem : BudgetedProblem
    time_limit : float or None
        Wall-clock seconds for the whole call, the worker's start-up included (see
        :func:`taopt.heuristics.peers.pyvrp_solve`); None for no time limit.
    seed : int
        PyVRP's seed; with ``time_limit=None`` the same seed gives the same result.
    max_iterations : int, optional
        Stop after this many iterations.
    no_improvement : int, "auto" or None
        Stop after this many iterations without a better solution; "auto" (default):
        :func:`taopt.heuristics.peers.default_no_improvement` unless ``max_iterations`` is
        given; None: no such stop.
    scale : float, optional
        Integer units per unit of travel time (default: largest entry -> 1e10).

    Returns
    -------
    Solution
        Status "feasible" with routes scored by :func:`~taopt.budgeted.evaluate_budgeted`,
        or status "no_solution" (``info["violations"]``) when PyVRP's best breaks a limit.
        ``info["solver_feasible"]`` is PyVRP's own verdict.

    Raises
    ------
    InstanceError
        Bad limits, seed or scale.
    SolverError
        PyVRP missing or failing in its worker.

    Example
    -------
    >>> import numpy as np
    >>> from taopt.budgeted import BudgetedProblem
    >>> x = np.array([1.0, 2.0, 4.0, 0.0, 5.0])
    >>> p = BudgetedProblem(abs(x[:, None] - x[None, :]), 3, capacity=[1, 2])
    >>> pyvrp_budgeted(p, time_limit=None, max_iterations=50).objective
    4.0

    References
    ----------
    Thesis §6.2; Wouda, Lan and Kool (2024).
    """
    deadline = Deadline(time_limit)
    require(problem, BudgetedProblem, "the pyvrp peer")
    peers._check(
        problem.routing, time_limit, seed, "max_iterations", max_iterations, no_improvement
    )
    options = {
        "time_limit": time_limit,
        **peers.stop_options("pyvrp", problem, "max_iterations", max_iterations, no_improvement),
        "seed": int(seed),
    }
    return _solve("pyvrp", problem, seed, scale, options, deadline)


@register_method(BudgetedProblem, "ortools", category="peer", requires=("ortools",))
def ortools_budgeted(
    problem: BudgetedProblem,
    time_limit: float | None = 1.0,
    seed: int = 0,
    *,
    solution_limit: int | None = None,
    no_improvement: int | str | None = "auto",
    first_solution: str = "PATH_CHEAPEST_ARC",
    metaheuristic: str = "GUIDED_LOCAL_SEARCH",
    scale: float | None = None,
) -> Solution:
    """OR-Tools routing with a load dimension (``Q_k``) and a time dimension (``T_k``).

    Parameters
    ----------
    problem : BudgetedProblem
    time_limit : float or None
        Wall-clock seconds for the whole call, the worker's start-up included; None for no
        time limit.
    seed : int
        Recorded only (OR-Tools' routing search has no seed).
    solution_limit : int, optional
        Stop after this many solutions.
    no_improvement : int, "auto" or None
        Stop after this many solutions without a better one; "auto" (default):
        :func:`taopt.heuristics.peers.default_no_improvement` unless ``solution_limit`` is
        given; None: no such stop.
    first_solution, metaheuristic : str
        OR-Tools' ``FirstSolutionStrategy`` / ``LocalSearchMetaheuristic`` names.
    scale : float, optional
        Integer units per unit of travel time (default: largest entry -> 1e10).

    Returns
    -------
    Solution
        Status "feasible" with routes scored by :func:`~taopt.budgeted.evaluate_budgeted`,
        or status "no_solution" when OR-Tools found no route set (``info["routing_status"]``) or
        one that breaks a limit (``info["violations"]``).

    Raises
    ------
    InstanceError
        Bad limits, seed or scale.
    SolverError
        OR-Tools missing, an unknown strategy name, or a failure in its worker.

    Example
    -------
    >>> import numpy as np
    >>> from taopt.budgeted import BudgetedProblem
    >>> x = np.array([1.0, 2.0, 4.0, 0.0, 5.0])
    >>> p = BudgetedProblem(abs(x[:, None] - x[None, :]), 3, max_time=[1.5, None])
    >>> ortools_budgeted(p, time_limit=None).objective
    4.0

    References
    ----------
    Thesis §6.2; OR-Tools routing library (Google).
    """
    deadline = Deadline(time_limit)
    require(problem, BudgetedProblem, "the ortools peer")
    peers._check(
        problem.routing, time_limit, seed, "solution_limit", solution_limit, no_improvement
    )
    options = {
        "time_limit": time_limit,
        **peers.stop_options("ortools", problem, "solution_limit", solution_limit, no_improvement),
        "first_solution": str(first_solution),
        "metaheuristic": str(metaheuristic),
        "seed": int(seed),
    }
    return _solve("ortools", problem, seed, scale, options, deadline)
