"""The compact solves of (2.2)–(2.5) (MTZ, flow) and what every routing solve shares.

:func:`_solve_compact` solves the compiled MTZ or flow model once, the incumbent as MIP start;
the DFJ loop (:mod:`taopt.models.routing.dfj`) falls back on it. The helpers here (the first
incumbent, HiGHS's time limit, the one builder of a :class:`~taopt.result.Solution`) and the
per-arc time estimates are used by both solves.

References
----------
Thesis §2.2.1, (2.2)–(2.5).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from taopt.errors import SolverError
from taopt.models.highs import HighsModel
from taopt.models.routing.formulation import (
    RoutingModel,
    assignment_bound,
    build,
    decode,
    entry_bound,
    greedy_routes,
)
from taopt.result import Routes, Solution, finish
from taopt.routing.problem import AssignmentProblem, evaluate_routes

#: Seconds per arc to build and compile the MTZ / flow model through cvxpy and for
#: HiGHS's MIP presolve, which does not stop at its time limit (flow at n = 150, m = 5,
#: 23,100 arcs, loaded 2-core machine: 0.5 s of cvxpy, then 1.75 s of presolve on a
#: 1.26 s limit): an upper estimate.
COMPACT_SECONDS_PER_ARC = 1e-4


#: HiGHS overruns its own ``time_limit``: MIP presolve and node 0 look at the clock
#: rarely (0.62 s of presolve on a 0.6 s limit for MTZ at n = 150, 0.3-0.65 s late on a
#: loaded machine). A MIP run is given the time left minus this.
HIGHS_OVERRUN = 0.25


#: Seconds per ``n^2 (n + m)`` of :func:`assignment_bound` (an upper estimate, as above).
ASSIGNMENT_SECONDS_PER_CUBE = 3e-10


def _first_incumbent(
    problem: AssignmentProblem, given: list[list[int]] | None
) -> tuple[list[list[int]], float]:
    """The better of the given routes and the greedy start, with its value."""
    best_routes = greedy_routes(problem)
    best_value = evaluate_routes(problem, best_routes)
    if given is not None:
        value = evaluate_routes(problem, given)
        if value <= best_value:
            best_routes, best_value = given, value
    return best_routes, best_value


def _start_vector(
    problem: AssignmentProblem,
    model: HighsModel,
    formulation: RoutingModel,
    routes: Sequence[Sequence[int]],
) -> np.ndarray:
    """σ, and MTZ positions u or single-commodity flows f, of ``routes`` as a MIP start."""
    n = problem.n
    vector = np.zeros(model.n_columns)
    arc_index = np.full((n + problem.m, n), -1, dtype=np.int64)
    arc_index[formulation.tails, formulation.heads] = np.arange(len(formulation.tails))
    arc_columns = model.columns(formulation.arc_use)
    for k, route in enumerate(routes):
        points = np.array([n + k, *route], dtype=np.int64)
        arcs = arc_index[points[:-1], points[1:]]
        vector[arc_columns[arcs]] = 1.0
        if formulation.order is not None:  # u_j = position of j on its route
            vector[model.columns(formulation.order)[points[1:]]] = np.arange(1, len(route) + 1)
        if formulation.flow is not None:  # f on the arc into j = targets from j to the end
            vector[model.columns(formulation.flow)[arcs]] = np.arange(len(route), 0, -1)
    return vector


def _highs_limit(left: float | None) -> float | None:
    """HiGHS's ``time_limit`` for ``left`` seconds: :data:`HIGHS_OVERRUN` less (at least 1 ms)."""
    return None if left is None else max(left - HIGHS_OVERRUN, 1e-3)


def _solve_compact(
    problem: AssignmentProblem,
    sec: str,
    time_limit: float | None,
    mip_gap: float,
    verbose: bool,
    given: list[list[int]] | None,
    started: float,
) -> Solution:
    """MTZ or flow: one solve of the compiled model, the incumbent as MIP start."""

    def remaining() -> float | None:
        return None if time_limit is None else time_limit - (time.perf_counter() - started)

    n, m = problem.n, problem.m
    best_routes, best_value = _first_incumbent(problem, given)
    best_bound = entry_bound(problem)
    left = remaining()
    if left is None or left > ASSIGNMENT_SECONDS_PER_CUBE * n**2 * (n + m):
        best_bound = max(best_bound, assignment_bound(problem))
    left = remaining()
    if left is not None and left < COMPACT_SECONDS_PER_ARC * ((n + m) * n - n):
        # cvxpy's build and compilation, and HiGHS's presolve (which does not stop at its
        # time limit), would not fit: the incumbent and the bounds so far
        info = {"rounds": 0, "cuts": 0, "stopped_by": "time_limit", "solver_status": ""}
        info.update(stage="build", mip_gap=mip_gap)
        return finish(
            problem,
            None if best_routes is None else Routes(best_routes),
            method=f"exact-{sec}",
            stop="time_limit",
            bound=best_bound,
            runtime=time.perf_counter() - started,
            info=info,
        )
    formulation = build(problem, sec)
    model = HighsModel(formulation.problem, verbose=verbose)
    left = remaining()
    model.set_start(_start_vector(problem, model, formulation, best_routes))
    run = model.solve(time_limit=_highs_limit(left), mip_rel_gap=mip_gap)
    if run.solver_status not in ("optimal", "user_limit"):
        raise SolverError(f"HiGHS returned status {run.solver_status!r} on the {sec} model")
    if run.bound is not None:
        best_bound = max(best_bound, run.bound)
    stopped_by = run.stopped_by
    if run.has_point:
        routes, subtours = decode(problem, formulation, model.values(formulation.arc_use))
        if subtours:
            raise SolverError(f"{sec} model returned a subtour {subtours[0]}; (2.5) violated")
        value = evaluate_routes(problem, routes)
        if value < best_value:
            best_routes, best_value = routes, value
    info = {
        "rounds": 1,
        "cuts": 0,
        "nodes": run.nodes,
        "solver_status": run.solver_status,
        "mip_gap": mip_gap,
        "stopped_by": stopped_by,
    }
    return finish(
        problem,
        None if best_routes is None else Routes(best_routes),
        method=f"exact-{sec}",
        stop=stopped_by,
        bound=best_bound,
        runtime=time.perf_counter() - started,
        info=info,
    )


__all__ = ["COMPACT_SECONDS_PER_ARC", "HIGHS_OVERRUN", "ASSIGNMENT_SECONDS_PER_CUBE"]
