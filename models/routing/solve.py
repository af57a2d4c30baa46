"""The solve driver of chapter 2's exact model: :func:`solve_routing`.

It checks the arguments and the given incumbent, then runs the DFJ loop
(:mod:`taopt.models.routing.dfj`), a compact MTZ / flow solve
(:mod:`taopt.models.routing.compact`) or an LP relaxation.

Example
-------
>>> import numpy as np
>>> from taopt import AssignmentProblem
>>> cost = np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0.0]])
>>> solve_routing(AssignmentProblem(cost, 2)).routes
[[1, 0]]
"""

from __future__ import annotations

import time
from typing import Any

from taopt.errors import InstanceError, SolverError
from taopt.models.highs import HighsModel
from taopt.models.routing.compact import _solve_compact
from taopt.models.routing.dfj import DfjModel, _solve_dfj, new_trace
from taopt.models.routing.formulation import _check, build
from taopt.result import RELAXATION, Solution, make_solution
from taopt.routing.problem import AssignmentProblem, evaluate_routes


def _as_routes(problem: AssignmentProblem, incumbent: Any) -> list[list[int]] | None:
    """The incumbent's routes (a list of routes or anything with ``.routes``), checked."""
    if incumbent is None:
        return None
    routes = getattr(incumbent, "routes", incumbent)
    routes = [[int(t) for t in route] for route in routes]
    evaluate_routes(problem, routes)  # raises FeasibilityError naming what is wrong
    return routes


def solve_routing(
    problem: AssignmentProblem,
    sec: str = "dfj",
    time_limit: float | None = None,
    mip_gap: float = 1e-6,
    relax: bool = False,
    verbose: bool = False,
    max_rounds: int = 10_000,
    incumbent: Any = None,
    improve: Any = None,
    trace: bool = False,
) -> Solution:
    """Solve (2.2)–(2.5) exactly with HiGHS (or its LP relaxation).

    Parameters
    ----------
    problem : AssignmentProblem
    sec : {"dfj", "mtz", "flow"}
        Subtour elimination; all three give the same optimum.
    time_limit : float, optional
        Wall-clock seconds for the whole call, building included: it returns
        within about ``time_limit + 0.5`` s with status "time_limit", the best
        routes found and a proven bound. A stage (building the model, an LP,
        a MIP round; for MTZ / flow, cvxpy's compilation and HiGHS's presolve)
        is not started when its per-arc estimate
        (:data:`~taopt.models.routing.BUILD_SECONDS_PER_ARC`,
        :data:`~taopt.models.routing.LP_SECONDS_PER_ARC`,
        :data:`~taopt.models.routing.COMPACT_SECONDS_PER_ARC`) exceeds the time left; the
        bound is then the best of :func:`~taopt.models.routing.entry_bound`,
        :func:`~taopt.models.routing.assignment_bound` and what was proven
        (``info["stage"] == "build"`` when no model was built).
    mip_gap : float
        Relative MIP gap passed to HiGHS (``mip_rel_gap``). The status is
        "optimal" only when the final gap is at most
        :data:`~taopt.models.highs.OPTIMALITY_TOLERANCE` (1e-6); a run stopped by a looser
        ``mip_gap`` is "feasible" with its proven bound
        (``info["stopped_by"] == "mip_gap"``).
    relax : bool
        Return the LP relaxation value instead (status "relaxation",
        objective = bound = LP value, routes None). For DFJ the LP is solved
        with *all* of (2.5), separated exactly by minimum cuts.
    verbose : bool
        HiGHS log.
    max_rounds : int
        Cap on DFJ MIP rounds. A loop stopped by it returns the best repaired
        incumbent with status "feasible" (``info["stopped_by"] ==
        "max_rounds"``) unless its gap is already closed.
    incumbent : list of routes or Solution, optional
        A feasible solution (one route per vehicle, or anything with
        ``.routes``), e.g. a heuristic's. It is the first incumbent and is
        given to HiGHS as a MIP start (``Highs.setSolution``). The models
        never call a heuristic themselves; without one, a greedy start
        (:func:`~taopt.models.routing.greedy_routes`) is used.
    improve : callable, optional
        ``improve(problem, routes) -> routes``, feasible and never worse (DFJ only). Called on
        the first incumbent and on the best patched answer of every MIP round; an answer
        that beats the incumbent becomes it. :func:`taopt.solve` passes the improver
        registered for the family (:func:`taopt.registry.improver`: the memetic GA's local
        search, :func:`taopt.heuristics.ga_routing.improve_routes`), as it passes a warm
        start. The proof does not depend on it; a better incumbent shrinks the core and
        the rounds (chapter 3's n90m10 classes: 0.76× the CPU time, ``docs/benchmarks.md``).
        Under a time limit it is not called with less than
        :data:`~taopt.models.routing.dfj.IMPROVE_MIN_SECONDS` left.
    trace : bool
        Keep the DFJ loop round by round in ``info["trace"]`` (plain JSON data, so it is
        saved with the solution): ``{"kind": "dfj", "n", "m", "rounds"}``, one round per
        LP of the root (``"stage": "root"``) and per MIP round (``"mip"``; ``"fallback"``
        for the compact model's answer should the loop stall). A round holds the point
        (``"arcs"``: ``[tail, head, σ]`` for every σ above
        :data:`~taopt.models.routing.dfj.TRACE_ZERO`; points ``0..n-1`` are targets,
        ``n..n+m-1`` start points), ``"value"`` (the LP value, or the MIP point's cost),
        ``"bound"`` (proven so far), ``"subtours"`` (the target sets S whose (2.5) row the
        point violates: separated exactly at the root, the cycles of a MIP point),
        ``"cuts"`` (the (2.5) rows this round added: its subtours, and in a MIP round the
        cycles of the other solutions HiGHS found), ``"lifted"`` (root: lifted rows added),
        ``"incumbent"`` and ``"core_arcs"`` (MIP rounds); a root round whose rows were
        rolled back is marked ``"discarded"``. Drawn by :func:`taopt.plot.trace`. Only
        ``sec="dfj"`` keeps a trace (an :class:`~taopt.errors.InstanceError` otherwise);
        ``relax=True`` keeps the root's LPs. False (the default) records nothing and
        changes nothing.

    Returns
    -------
    Solution
        ``routes`` (one list per vehicle), ``objective`` = ``evaluate(routes)``,
        ``status`` by :func:`taopt.status.decide` (through :func:`taopt.result.finish`): "optimal" (gap at
        most 1e-6), "time_limit", or "feasible" (loose ``mip_gap`` or
        ``max_rounds``; ``info["stopped_by"]`` says which),
        ``bound`` a proven lower bound, never above ``objective``.
        ``info`` holds the MIP rounds, the (2.5) rows added, the root LP and
        the solver status.

    Raises
    ------
    InstanceError
        Not an AssignmentProblem or unknown ``sec``, or ``trace`` asked of MTZ / flow
        (compact: no rounds to show).
    FeasibilityError
        ``incumbent`` is not a feasible solution.
    SolverError
        HiGHS returned an unexpected status (e.g. "infeasible"), or ``improve`` returned
        routes that are not feasible.

    Notes
    -----
    DFJ (``sec="dfj"``), on ONE live HiGHS model (:class:`DfjModel`):

    1. Root: the LP of (2.2)–(2.4) is solved and (2.5) rows violated by its
       point are separated exactly (:func:`~taopt.models.routing.separate_subtours`) and
       added, until none is left. Its duals give a proven bound L and arc reduced costs d
       (:meth:`taopt.models.highs.HighsModel.lagrangian_bound`).
    2. Core: a solution that uses arc a costs at least ``L + d_a``, so an arc
       with ``d_a > UB − L`` (UB the incumbent's value) cannot be in a better
       solution. The MIP rounds run on a core, every other σ fixed to 0
       through its bound: the arcs with ``d_a ≤ min(UB − L, cap)`` plus the
       incumbent's, ``cap`` being the :data:`~taopt.models.routing.CORE_SIZE`
       ``(n + m)``-th smallest d until the core's own optimum has no cycle, then infinite.
    3. Rounds: each MIP round is a relaxation of (2.2)–(2.5) on the core; the
       cycles among targets of its answer, and of every solution HiGHS finds
       on the way (``kCallbackMipSolution``), become new (2.5) rows; every
       solution, its cycles patched in (:func:`~taopt.models.routing.repair`), may improve the
       incumbent, which is the next round's MIP start, and the core is
       resized to the new UB.

    Each round proves ``min(B, L + min_{a ∉ core} d_a)``, with B HiGHS's bound
    on the core: a solution either stays in the core (cost at least B) or
    uses an arc outside it. The reported bound is the largest of these, L, and
    ``Σ_j min_i t(i, j)`` (:func:`~taopt.models.routing.entry_bound`); the loop stops as soon as it
    is within ``max(mip_gap, 1e-6)`` of the incumbent.

    Every MIP answer is checked by :meth:`taopt.models.highs.HighsModel.solve`
    (HiGHS's objective must be the value of its point; HiGHS 1.16 can accept a
    MIP start in its presolved space with a wrong objective and call it optimal,
    and such a run is done again without presolve). Should a round still bring
    nothing new (no cycle, no change of the core) while the gap is open, the
    loop hands its incumbent to the compact :data:`~taopt.models.routing.FALLBACK_SEC` model on all
    arcs, which ends optimal without a time limit: no run without a limit
    ends "feasible" for want of progress.

    MTZ and flow are compact: one solve on a compiled model, with the
    incumbent as MIP start.

    References
    ----------
    Thesis §2.2.1, (2.2)–(2.5).
    """
    _check(problem, sec)
    started = time.perf_counter()
    if trace and sec != "dfj":
        raise InstanceError(
            f"trace=True: only the DFJ loop (sec='dfj') has rounds to trace, not sec={sec!r} "
            "(one compact solve)"
        )
    if relax:
        return _solve_relaxation(problem, sec, started, verbose, bool(trace))
    if time_limit is not None and time_limit <= 0:
        raise InstanceError(f"time_limit must be positive, got {time_limit}")
    given = _as_routes(problem, incumbent)
    if sec == "dfj":
        return _solve_dfj(
            problem, time_limit, mip_gap, verbose, max_rounds, given, started, improve, trace
        )
    return _solve_compact(problem, sec, time_limit, mip_gap, verbose, given, started)


def _solve_relaxation(
    problem: AssignmentProblem, sec: str, started: float, verbose: bool, trace: bool = False
) -> Solution:
    """LP value of (2.2)–(2.5): DFJ with all of (2.5) (exact separation), or MTZ / flow."""
    recorded: dict[str, Any] = {}
    if sec == "dfj":
        dfj = DfjModel(problem, verbose=verbose)
        if trace:
            dfj.trace = []
        root = dfj.root(lifted=0)
        if not root.complete:
            raise SolverError("the DFJ LP relaxation did not finish")
        value, rounds, cuts = float(root.value), root.rounds, len(root.cuts)
        if dfj.trace is not None:
            recorded["trace"] = new_trace(problem, dfj.trace)
    else:
        model = HighsModel(build(problem, sec, relax=True).problem, verbose=verbose)
        run = model.solve()
        if run.solver_status != "optimal" or run.bound is None:
            raise SolverError(f"LP relaxation ended with status {run.solver_status!r}")
        value, rounds, cuts = float(run.bound), 1, 0
    info = {"rounds": rounds, "cuts": cuts, **recorded}
    return make_solution(
        problem,
        None,
        method=f"lp-{sec}",
        status=RELAXATION,
        objective=value,
        bound=value,
        runtime=time.perf_counter() - started,
        info=info,
    )


__all__ = ["solve_routing"]
