"""The exact solve of the budgeted family: a short driver over the stages of
:func:`solve_budgeted` (first bounds and starts, the root LP with its cuts, an LP-guided
start and reduced-cost fixing, the MIP rounds), sharing one :class:`_Search` state.

The model and why it is written so: :mod:`taopt.models.budgeted`.

References
----------
Thesis §2.2.1 (2.2)–(2.5), §6.2.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt.budgeted.problem import BudgetedProblem, evaluate_budgeted, violations
from taopt.errors import InstanceError, SolverError, require
from taopt.models.budgeted.arc_vehicle import BudgetedModel
from taopt.models.budgeted.resource import ResourceModel
from taopt.models.budgeted.separation import entry_times, separate_capacity
from taopt.models.budgeted.starts import (
    _as_routes,
    greedy_budgeted,
    repaired_routes,
    total_time_cap,
)
from taopt.models.highs import OPTIMALITY_TOLERANCE, relative_gap
from taopt.models.routing import (
    HIGHS_OVERRUN,
    assignment_bound,
    entry_bound,
    repair,
    separate_subtours,
    solve_routing,
)
from taopt.models.routing.dfj import IMPROVE_MIN_SECONDS
from taopt.registry import register_method
from taopt.result import Routes, Solution, finish, make_solution
from taopt.routing.bounds import arborescence_bound
from taopt.runtime import Deadline, milp_bytes, register_footprint

#: HiGHS options of the MIP rounds (as chapter 2's DFJ loop).
MIP_OPTIONS = {"mip_pool_soft_limit": 500}

#: The models :func:`solve_budgeted` can build (``form``).
FORMS = ("resource", "arc-vehicle")

#: Seconds per column before HiGHS first checks its clock (an upper estimate): a stage is
#: not started under a time limit when this exceeds the time left.
SECONDS_PER_COLUMN = 4e-6


def _infeasible(
    problem: BudgetedProblem, proof: str, deadline: Deadline, info: dict[str, Any]
) -> Solution:
    """The one way this module reports status "infeasible": no answer, the reason in
    ``info["proof"]``, and the bound +inf (no assignment meets the limits)."""
    info.update(proof=proof)
    return finish(
        problem,
        None,
        method="exact-budgeted",
        stop="infeasible",
        bound=math.inf,
        runtime=deadline.elapsed(),
        info=info,
    )


def _too_long(
    problem: BudgetedProblem,
    bound: float,
    cutoff: float,
    deadline: Deadline,
    info: dict[str, Any],
) -> Solution:
    """Status "infeasible": a proven lower bound on the total exceeds ``Σ_k T_k``."""
    proof = (
        f"a proven lower bound on the total travel time, {bound:.6g}, exceeds the most "
        f"any answer within the time limits can take, Σ_k T_k = {cutoff:.6g}"
    )
    return _infeasible(problem, proof, deadline, info)


def _improve_once(
    problem: BudgetedProblem, improve: Any, routes: list[list[int]]
) -> tuple[list[list[int]], list[str]]:
    """``improve(problem, routes)`` as lists of ints, and the limits it breaks (if any)."""
    found = [[int(t) for t in route] for route in improve(problem, routes)]
    return found, violations(problem, found)


class _Search:
    """The state of one :func:`solve_budgeted` call: the best routes and their value, the
    proven lower bound, the ``Σ_k T_k`` cut-off and the ``info`` of the answer."""

    def __init__(
        self,
        problem: BudgetedProblem,
        deadline: Deadline,
        info: dict[str, Any],
        given: list[list[int]] | None,
        improve: Any,
        mip_gap: float,
    ) -> None:
        self.problem = problem
        self.deadline = deadline
        self.info = info
        self.improve = improve
        self.mip_gap = mip_gap
        self.best_routes = given
        self.best_value = math.inf if given is None else evaluate_budgeted(problem, given)
        # every vehicle time-limited: a feasible answer's total is at most Σ_k T_k (the
        # scorer's tolerance included), a cut-off for the MIP rounds and, below a proven
        # lower bound, a proof that no assignment meets the limits
        self.cutoff = total_time_cap(problem)
        self.best_bound = -math.inf
        self.improved = 0

    def first_bounds(self, max_rounds: int) -> Solution:
        """Chapter 2's bounds, then chapter 2's optimum without the limits (a valid bound:
        limits only remove solutions); returns that solve, whose routes make a start."""
        problem, deadline = self.problem, self.deadline
        n, m = problem.n, problem.m
        self.best_bound = max(entry_bound(problem.routing), arborescence_bound(problem.routing))
        spare = deadline.remaining()  # None without a limit
        if spare is None or spare > 3e-10 * n**2 * (n + m):
            self.best_bound = max(self.best_bound, assignment_bound(problem.routing))
        free = solve_routing(problem.routing, time_limit=deadline.share(0.2), max_rounds=max_rounds)
        if free.bound is not None:
            self.best_bound = max(self.best_bound, free.bound)
        self.info["unlimited_optimum"] = free.objective if free.status == "optimal" else None
        return free

    def over_cutoff(self) -> bool:
        """Whether the proven bound exceeds ``Σ_k T_k`` (no assignment meets the limits)."""
        return self.cutoff is not None and self.best_bound > self.cutoff

    def too_long(self) -> Solution:
        """Status "infeasible" by :meth:`over_cutoff`."""
        assert self.cutoff is not None
        return _too_long(self.problem, self.best_bound, self.cutoff, self.deadline, self.info)

    def consider_start(self, routes: list[list[int]] | None) -> None:
        """Keep ``routes`` if it beats the incumbent, after ``improve`` (when given and time
        allows); each plan is scored once."""
        if routes is None:
            return
        problem = self.problem
        value = evaluate_budgeted(problem, routes)
        left = self.deadline.remaining()
        if self.improve is not None and (left is None or left >= IMPROVE_MIN_SECONDS):
            found, broken = _improve_once(problem, self.improve, routes)
            if broken:
                raise SolverError(
                    f"improve returned routes outside the limits: {'; '.join(broken)}"
                )
            found_value = evaluate_budgeted(problem, found)
            if found_value < value:
                routes, value, self.improved = found, found_value, self.improved + 1
        if value < self.best_value:
            self.best_routes, self.best_value = routes, value

    def gap_closed(self, target_gap: float) -> bool:
        """Whether the incumbent is within ``target_gap`` of the proven bound."""
        return (
            self.best_routes is not None
            and relative_gap(self.best_value, min(self.best_bound, self.best_value)) <= target_gap
        )

    def stop(self, stopped_by: str, extra: dict[str, Any]) -> Solution:
        """The answer: the incumbent, the bound and the stop, by :func:`taopt.result.finish`."""
        self.info.update(extra, mip_gap=self.mip_gap, improved=self.improved)
        return finish(
            self.problem,
            None if self.best_routes is None else Routes(self.best_routes),
            method="exact-budgeted",
            stop=stopped_by,
            bound=self.best_bound,
            runtime=self.deadline.elapsed(),
            info=self.info,
        )


Model = BudgetedModel | ResourceModel


@dataclass
class _Root:
    """What the root LP left: its rounds, bound, σ and reduced costs (None if not solved)."""

    rounds: int = 0
    bound: float = -math.inf
    sigma: np.ndarray | None = None
    reduced: np.ndarray | None = None


def _root_lp(
    problem: BudgetedProblem,
    model: Model,
    deadline: Deadline,
    capacity_cuts: bool,
    time_cuts: bool,
) -> _Root:
    """Stage 1: the root LP, (2.5) separated exactly, then (``capacity_cuts``) rounded
    route-count rows separated heuristically, in at most half of the time left."""
    model.model.relax(True)
    entry = entry_times(problem) if time_cuts else None
    root = _Root()
    budget = deadline.share(0.5)
    root_end = None if budget is None else time.perf_counter() + budget
    try:
        while True:
            left = None if root_end is None else root_end - time.perf_counter()
            if left is not None and left < SECONDS_PER_COLUMN * model.n_columns:
                break
            root.rounds += 1
            run = model.model.solve(time_limit=left)
            if run.solver_status == "infeasible":
                break  # the MIP below proves it
            if run.solver_status != "optimal" or run.objective is None:
                break
            root.bound, root.reduced = model.model.lagrangian_bound()
            sigma = model.sigma(model.model.highs.getSolution().col_value)
            root.sigma = sigma
            found = separate_subtours(problem.routing, model.tails, model.heads, sigma,
                                      deadline=root_end)  # fmt: skip
            if model.add_cuts(found):
                continue
            if not capacity_cuts:
                break
            if not model.add_capacity_cuts(
                separate_capacity(problem, model.tails, model.heads, sigma, entry=entry)
            ):
                break
    finally:
        model.model.relax(False)
    return root


def _lp_guided_start(search: _Search, model: Model, root_sigma: np.ndarray) -> None:
    """Stage 1b: chapter 2's optimum on travel times scaled by 1 − σ of the root LP (arcs
    the LP uses are cheap), cut back to the limits and repaired, offered as a start."""
    problem = search.problem
    scale = np.ones_like(problem.cost)
    scale[model.tails, model.heads] = 1.0 - 0.9 * np.clip(root_sigma, 0.0, 1.0)
    guided = solve_routing(problem.routing.replace(cost=problem.cost * scale),
                           time_limit=search.deadline.share(0.1), max_rounds=50)  # fmt: skip
    start = None if guided.routes is None else repaired_routes(problem, guided.routes)
    if start is not None:
        search.info["lp_start"] = evaluate_budgeted(problem, start)
        search.consider_start(start)


def _fix_by_reduced_cost(search: _Search, model: Model, form: str, root: _Root) -> int:
    """Reduced-cost fixing (``form="resource"``): a solution using arc a costs at least
    L + d_a (:meth:`HighsModel.lagrangian_bound`), so an arc with L + d_a > UB is in no
    solution better than the incumbent; the incumbent's own arcs stay. Returns how many."""
    if form != "resource" or not math.isfinite(root.bound) or search.best_routes is None:
        return 0
    if root.reduced is None or not isinstance(model, ResourceModel):  # form "resource"
        return 0
    arcs = root.reduced[: len(model.tails)]
    slack = 1e-9 * max(1.0, abs(search.best_value))
    off = arcs > search.best_value - root.bound + slack
    off[model.route_arcs(search.best_routes)] = False
    off &= model.model.column_upper[: len(model.tails)] > 0
    model.model.set_upper(np.flatnonzero(off), 0.0)
    return int(off.sum())


class _MipRounds:
    """Stage 2: MIP rounds, each a relaxation of the problem (every row valid); the cycles
    of every answer HiGHS reports become (2.5) rows, each answer (its cycles patched, within
    the limits) a candidate incumbent and the next MIP start.

    With ``improve_during`` an answer HiGHS finds that beats every answer seen is improved
    at once and the result offered back to HiGHS at its next call for a user solution.
    """

    def __init__(self, search: _Search, model: Model, improve_during: bool) -> None:
        self.search = search
        self.model = model
        self.during = improve_during and search.improve is not None
        self.harvested: list[tuple[int, ...]] = []
        self.candidates: list[tuple[float, list[list[int]]]] = []
        self.offered_value = search.best_value
        self.offered_routes: list[list[int]] | None = None
        self.broken: list[str] | None = None
        self.offered = 0

    def consider(self, solution: np.ndarray) -> list[list[int]]:
        """Cycles of a MIP solution (harvested as cuts); a feasible patch is a candidate."""
        problem = self.search.problem
        read = self.model.decode(solution)
        if read is None:
            return []
        routes, cycles = read
        if cycles:
            routes = repair(problem.routing, routes, cycles)
        if not violations(problem, routes):
            self.candidates.append((evaluate_budgeted(problem, routes), routes))
        return cycles

    def harvest(self, solution: np.ndarray) -> None:
        """HiGHS's callback on each answer it finds (:meth:`HighsModel.solve`)."""
        count = len(self.candidates)
        self.harvested.extend(tuple(sorted(c)) for c in self.consider(solution))
        if not self.during or len(self.candidates) == count:
            return
        value, routes = self.candidates[-1]
        left = self.search.deadline.remaining()
        if value >= self.offered_value or (left is not None and left < IMPROVE_MIN_SECONDS):
            return
        self.offered_value = value
        problem = self.search.problem
        found, broken = _improve_once(problem, self.search.improve, routes)
        if broken:
            self.broken = broken  # raised after the run (not inside HiGHS's callback)
            return
        found_value = evaluate_budgeted(problem, found)
        if found_value < value:
            self.candidates.append((found_value, found))
            self.offered_value, self.offered_routes = found_value, found
            self.offered += 1

    def offer(self) -> np.ndarray | None:
        """HiGHS's call for a user solution: the last improved answer, once."""
        routes, self.offered_routes = self.offered_routes, None
        return None if routes is None else self.model.start_vector(routes)

    def infeasible(self, rounds: int) -> Solution:
        """HiGHS proved the model infeasible: no assignment meets the limits."""
        search, model = self.search, self.model
        if search.best_routes is not None:  # cannot be: every feasible solution is in the model
            raise SolverError("HiGHS calls the budgeted model infeasible below a known solution")
        proof = "HiGHS proved the model infeasible; every row is valid"
        if search.cutoff is not None:
            proof += (
                f" (searched below the cut-off Σ_k T_k = {search.cutoff:.6g}, the most a "
                "feasible answer's total can be)"
            )
        search.info.update(rounds=rounds, cuts=len(model.cuts))
        return _infeasible(search.problem, proof, search.deadline, search.info)

    def run(self, max_rounds: int) -> Solution:
        """The rounds, until a round's optimum has no cycle, the gap is closed or a limit."""
        search, model = self.search, self.model
        target_gap = max(float(search.mip_gap), OPTIMALITY_TOLERANCE)
        rounds, stopped_by, nodes = 0, "time_limit", 0
        if search.gap_closed(target_gap):  # a start meets the root bound: proven without a MIP
            return search.stop(
                "optimal", {"rounds": 0, "cuts": len(model.cuts), "nodes": 0, "offered": 0}
            )
        while True:
            left = search.deadline.remaining()
            if left is not None and left < SECONDS_PER_COLUMN * model.n_columns + HIGHS_OVERRUN:
                stopped_by = "time_limit"
                break
            if rounds >= max_rounds:
                stopped_by = "max_rounds"
                break
            rounds += 1
            if search.best_routes is not None:
                mip_start = model.start_vector(search.best_routes)
                if mip_start is not None:
                    model.model.set_start(mip_start)
            self.harvested.clear()
            self.candidates.clear()
            self.offered_value = min(self.offered_value, search.best_value)
            self.offered_routes = None
            options: dict[str, Any] = dict(MIP_OPTIONS)
            if search.cutoff is not None:
                options["objective_bound"] = search.cutoff
            run = model.model.solve(
                time_limit=None if left is None else max(left - HIGHS_OVERRUN, 1e-3),
                mip_rel_gap=search.mip_gap,
                on_solution=self.harvest,
                options=options,
                offer=self.offer if self.during else None,
            )
            if self.broken:
                raise SolverError(
                    f"improve returned routes outside the limits: {'; '.join(self.broken)}"
                )
            if run.solver_status == "infeasible":
                return self.infeasible(rounds)
            if run.solver_status not in ("optimal", "user_limit"):
                raise SolverError(
                    f"HiGHS returned status {run.solver_status!r} on the budgeted model"
                )
            if run.bound is not None:
                search.best_bound = max(search.best_bound, run.bound)
            nodes += max(run.nodes, 0)
            cycles: list[list[int]] = []
            if run.has_point:
                cycles = self.consider(np.asarray(model.model.highs.getSolution().col_value))
            if self.candidates:  # the round's best answer, improved
                search.consider_start(min(self.candidates, key=lambda pair: pair[0])[1])
            model.add_cuts([*map(tuple, cycles), *self.harvested])
            stopped_by = run.stopped_by
            if search.gap_closed(target_gap):
                break
            if run.stopped_by in ("time_limit", "solver_limit"):
                break
            if run.has_point and not cycles and run.stopped_by == "optimal":
                break  # cannot happen with an open gap: the answer is feasible and optimal
            if (
                not run.has_point and not self.harvested
            ):  # nothing learned: the next round is this one
                raise SolverError(
                    f"HiGHS stopped with status {run.solver_status!r}, no answer and no proof "
                    "on the budgeted model"
                )
        return search.stop(
            stopped_by,
            {"rounds": rounds, "cuts": len(model.cuts), "nodes": nodes, "offered": self.offered},
        )


@register_method(
    BudgetedProblem, "exact", category="exact", certifies=True, warm_start=("MC", "EVM")
)
def solve_budgeted(
    problem: BudgetedProblem,
    time_limit: float | None = None,
    mip_gap: float = 1e-6,
    verbose: bool = False,
    max_rounds: int = 10_000,
    incumbent: Any = None,
    form: str = "resource",
    capacity_cuts: bool = True,
    time_cuts: bool = True,
    lp_start: bool = True,
    improve: Any = None,
    improve_during: bool = True,
) -> Solution:
    """Solve (2.2)–(2.5) with per-vehicle capacity and travel-time limits exactly (HiGHS).

    Parameters
    ----------
    problem : BudgetedProblem
    time_limit : float, optional
        Wall-clock seconds for the whole call (:class:`taopt.runtime.Deadline`): it returns
        with status "time_limit", the best routes found (None if none) and a proven bound.
    mip_gap : float
        HiGHS's ``mip_rel_gap``; "optimal" only when the final gap is at most 1e-6.
    verbose : bool
        HiGHS log.
    max_rounds : int
        Cap on MIP rounds (status "feasible", ``info["stopped_by"] == "max_rounds"``).
    incumbent : list of routes or Solution, optional
        A start (e.g. MC's or EVM's routes). Used only if it meets every limit (a heuristic
        may miss one: ``info["incumbent_rejected"]`` says why); never raises for that.
    form : {"resource", "arc-vehicle"}
        The model (module docstring): chapter 2's two-index σ with capacity and time
        resources per target (:class:`ResourceModel`, default), or the three-index model
        (:class:`BudgetedModel`), kept for comparison.
    capacity_cuts, time_cuts : bool
        Separate rounded route-count inequalities at the root (Notes); ``time_cuts`` adds
        the count the time limits force to the capacities' count.
    lp_start : bool
        Build a start from the root LP (Notes).
    improve : callable, optional
        ``improve(problem, routes) -> routes`` within every limit and never worse, called on
        every start before reduced-cost fixing (the better start fixes more arcs) and on
        each MIP round's best answer; a returned plan outside the limits is a SolverError.
        :func:`taopt.solve` passes the family's registered improver
        (:func:`taopt.registry.improver`: the GA's memetic step,
        :func:`taopt.heuristics.budgeted.improve_budgeted`), as it passes a warm start; not
        called with less than :data:`~taopt.models.routing.dfj.IMPROVE_MIN_SECONDS` left.
        ``info["improved"]`` counts the answers it bettered.
    improve_during : bool
        With ``improve``: also inside a MIP round, each answer HiGHS finds that beats every
        answer seen (its cycles patched, within the limits) is improved at once and offered
        back to HiGHS (:meth:`~taopt.models.highs.HighsModel.solve`'s ``offer``), which
        takes it as its incumbent when it is better; ``info["offered"]`` counts them. Off,
        the improver sees a round's answers only when the round ends, which under a time
        limit can be never (one round of 30 s).

    Returns
    -------
    Solution
        ``routes`` and ``objective`` = :func:`~taopt.budgeted.evaluate_budgeted`; status
        "optimal", "infeasible" (no assignment meets the limits: ``info["proof"]``),
        "time_limit" or "feasible" (loose ``mip_gap`` / ``max_rounds``); ``bound`` a proven
        lower bound, never above the objective.

    Raises
    ------
    InstanceError
        Not a BudgetedProblem, or a non-positive ``time_limit``.
    SolverError
        HiGHS returned an unexpected status, or ``improve`` returned routes outside the
        limits.

    Notes
    -----
    The model and why it is written so: module docstring. The loop: (1) the root LP with
    (2.5) separated exactly until no row is violated, then (``capacity_cuts``) rounded
    route-count inequalities ``σ(δ⁻(S)) >= k(S)`` (:func:`~taopt.models.budgeted.separation.separate_capacity`: k(S) from
    the capacities, :func:`~taopt.models.budgeted.separation.route_counts`, and, with ``time_cuts``, from the time limits,
    :func:`~taopt.models.budgeted.separation.time_counts`) separated heuristically, round after round until neither finds
    a violated row; the MTZ-type capacity rows alone leave the LP bound near chapter 2's
    optimum (drift n50m10, ``Q_k = 8``, ``T_k = 2 f0/m``: root LP 4192 → 4281 on scenario
    2, 4369 → 4411 on scenario 1, optima 4288.7 and 4458.9); (1b) (``lp_start``) chapter
    2's optimum on travel times scaled by ``1 − 0.9 σ`` of the root LP, repaired into the
    limits by :func:`repaired_routes`, as a further start (scenario 1: 4542.7 against
    5247.9 from the unlimited optimum), and reduced-cost fixing against the best start;
    (2) MIP rounds, each a relaxation
    of the problem (every row valid), the cycles among targets of its answer and of every
    solution HiGHS reports added as (2.5) rows, each answer (its cycles patched in by
    :func:`~taopt.models.routing.repair`, kept if it meets the limits) a candidate
    incumbent and the next MIP start. It stops when a round's optimum has no cycle (then
    it is feasible and optimal), or the gap is closed. Each round's dual bound is valid:
    the rows only remove infeasible solutions. When every vehicle has a time limit,
    :func:`total_time_cap` (``Σ_k T_k``) is HiGHS's ``objective_bound`` in every round and
    a proven lower bound above it is an infeasibility proof at once. Size: at most
    ``(n + 1) n m`` columns and
    ``n (m + 1) + 3 m`` rows before the cuts.

    References
    ----------
    Thesis §2.2.1 (2.2)–(2.5), §6.2.
    """
    require(problem, BudgetedProblem, "solve_budgeted")
    if time_limit is not None and time_limit <= 0:
        raise InstanceError(f"time_limit must be positive, got {time_limit}")
    if form not in FORMS:
        raise InstanceError(f"form must be one of {FORMS}, got {form!r}")
    deadline = Deadline(time_limit)
    given, rejected = _as_routes(problem, incumbent)
    info: dict[str, Any] = {"incumbent_rejected": rejected} if rejected else {}
    n, m = problem.n, problem.m
    if not (problem.has_capacity or problem.has_max_time):
        # no limit: chapter 2's problem, chapter 2's exact loop
        plain = solve_routing(
            problem.routing, time_limit=time_limit, mip_gap=mip_gap, verbose=verbose,
            max_rounds=max_rounds, incumbent=given,
        )  # fmt: skip
        info.update(plain.info, model="chapter 2 (no finite limit)")
        return make_solution(  # chapter 2's status and bound, re-scored for this problem
            problem,
            None if plain.routes is None else Routes(plain.routes),
            method="exact-budgeted",
            status=plain.status,
            bound=plain.bound,
            runtime=deadline.elapsed(),
            info=info,
        )
    if problem.capacity.sum() < n:
        proof = f"the capacities sum to {problem.capacity.sum():g} < n = {n}"
        return _infeasible(problem, proof, deadline, info)
    search = _Search(problem, deadline, info, given, improve, mip_gap)
    free = search.first_bounds(max_rounds)
    if search.over_cutoff():
        return search.too_long()
    search.consider_start(search.best_routes)
    if not deadline.expired():  # each further start only when time is left for it
        search.consider_start(greedy_budgeted(problem))
    if free.routes is not None and not deadline.expired():
        # chapter 2's optimum cut back to the limits and repaired
        search.consider_start(repaired_routes(problem, free.routes, deadline=deadline))
    spare = deadline.remaining()
    if spare is not None and spare < SECONDS_PER_COLUMN * (n + 1) * n * m:
        return search.stop("time_limit", {"stage": "build"})
    model = (ResourceModel if form == "resource" else BudgetedModel)(problem, verbose=verbose)
    info.update(columns=model.n_columns, rows=model.model.n_rows)
    root = _root_lp(problem, model, deadline, capacity_cuts, time_cuts)
    search.best_bound = max(search.best_bound, root.bound)
    if search.over_cutoff():
        return search.too_long()
    info.update(root_rounds=root.rounds, root_cuts=len(model.cuts), lp_bound=root.bound,
                root_seconds=deadline.elapsed(),
                capacity_cuts=len(model.capacity_cuts))  # fmt: skip
    if lp_start and root.sigma is not None:
        _lp_guided_start(search, model, root.sigma)
    info["fixed_arcs"] = _fix_by_reduced_cost(search, model, form, root)
    return _MipRounds(search, model, improve_during).run(max_rounds)


@register_footprint(BudgetedProblem, "exact")
def _budgeted_footprint(problem: BudgetedProblem, options: dict[str, Any]) -> tuple[float, str]:
    """The three-index model has at most (n + 1) n m columns."""
    columns = float(problem.n + 1) * problem.n * problem.m
    return milp_bytes(columns), (
        f"the budgeted exact model of {problem.n:,} targets and {problem.m} vehicles "
        f"(at most {columns:,.0f} columns)"
    )
