"""Chapter 2's heuristics made limit-aware for :class:`~taopt.budgeted.BudgetedProblem` (§6.2).

The thesis's future work (§6.2) asks whether its task-assignment algorithms keep their
performance when "each vehicle can visit a maximum number of target locations" (capacity
``Q_k``) or "has a maximum travel time" (``T_k``). Three of chapter 2's methods are made
aware of the limits here, each the smallest change that keeps the printed algorithm:

* "MC" — marginal-cost clustering (2.15): the global cheapest insertion, where a vehicle
  whose route would exceed ``Q_k`` or ``T_k`` by taking a target is refused (its marginal
  cost is ``inf``). Without limits it is chapter 2's MC, step for step.
* "EVM" — extended Voronoi clustering (2.12)–(2.14) + smallest marginal cost sequencing
  (2.18)–(2.19): the Prim-like growth refuses a (vehicle, target) pair when the vehicle is
  full or when its cluster with the target, sequenced by (2.18), would take longer than
  ``T_k``. Without limits it is chapter 2's EVM.
* "GA" — the memetic GA of §2.5 (:mod:`taopt.heuristics.ga_routing`: its encoding,
  crossover, mutations and local search), with a *penalty* for violated limits and, in
  its memetic step, a repair and a limit-aware local search (:func:`genetic_algorithm`).

A heuristic cannot prove that no feasible answer exists. When MC or EVM is left with
targets no vehicle can take, or the GA never met a feasible chromosome, the answer is
status ``"no_solution"`` (``taopt.result.NO_SOLUTION``: the heuristic's outcome, not a
failure and not a proof) with ``solution=None``, ``objective=inf``, ``info["unassigned"]`` (how many targets were left,
for MC and EVM) and ``info["error"]`` saying that this is not a proof of infeasibility.
Never a fake feasible answer: every returned payload is scored by
:func:`~taopt.budgeted.evaluate_budgeted`, which re-checks the limits.

Limits are checked with ``time <= T_k (1 + 1e-9)``, stricter than the scorer's tolerance
(:data:`taopt.budgeted.problem.TIME_TOLERANCE`), so an accepted route always passes it.

References
----------
Thesis §2.4 (2.11)–(2.19), §2.5 (the GA), §6.2 (future work).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from taopt.budgeted.problem import BudgetedProblem, evaluate_budgeted
from taopt.errors import InstanceError
from taopt.heuristics.clustering import insertion_costs, marginal_cost_sequence
from taopt.heuristics.ga_local_search import local_search
from taopt.heuristics.ga_penalised_search import SLACK, PenalisedSearch, slack_limits
from taopt.heuristics.ga_routing import (
    OPERATOR_SETS,
    _mutate,
    _separate_clones,
    decode,
    encode,
    improve_routes,
    nodes_to_genes,
    order_crossover,
    path_matrix,
    path_nodes,
)
from taopt.registry import register_improver, register_method
from taopt.result import FEASIBLE, NO_SOLUTION, Routes, Solution
from taopt.runtime import Deadline

#: The GA's memetic steps under limits (:func:`genetic_algorithm`, ``memetic``).
MEMETIC_STEPS = ("penalised", "chapter2")

__all__ = [
    "limited_marginal_cost_routes",
    "limited_extended_voronoi_routes",
    "repair",
    "limited_local_search",
    "LimitedDescent",
    "improve_budgeted",
    "route_times",
    "penalised_cost",
    "mc",
    "evm",
    "genetic_algorithm",
]


def _fits(time_needed: Any, limit: float) -> Any:
    """Whether a travel time is within ``limit`` (``inf``: no limit), with the heuristics'
    :data:`~taopt.heuristics.ga_penalised_search.SLACK`."""
    return time_needed <= limit + SLACK * max(1.0, limit) if math.isfinite(limit) else True


def _answer(
    problem: BudgetedProblem,
    routes: list[list[int]] | None,
    method: str,
    seed: Any,
    start: float,
    info: dict[str, Any],
) -> Solution:
    """A scored Solution, or status "no_solution" when ``routes`` is None."""
    if routes is None:
        return Solution(
            objective=math.inf,
            status=NO_SOLUTION,
            solution=None,
            runtime=time.perf_counter() - start,
            method=method,
            seed=seed,
            info=info,
        )
    return Solution(
        objective=evaluate_budgeted(problem, routes),  # the one scorer re-checks every limit
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        method=method,
        seed=seed,
        solution=Routes(routes),
        info=info,
    )


def _no_solution(method: str, left: int) -> dict[str, Any]:
    return {
        "unassigned": int(left),
        "error": (
            f"{method} left {left} target(s) that no vehicle can take within its capacity and "
            "maximum travel time (a heuristic's failure, not a proof that the instance is "
            "infeasible)"
        ),
    }


# -- MC (2.15), limit-aware ----------------------------------------------------------------


def limited_marginal_cost_routes(
    problem: BudgetedProblem,
    deadline: Deadline | None = None,
    initial: list[list[int]] | None = None,
) -> tuple[list[list[int]], np.ndarray]:
    """Marginal-cost clustering (2.15) where a vehicle at its limit is refused.

    Each step inserts the (target k, vehicle j, gap q) with the smallest marginal cost
    ``t(o_j ⊕_q k) − t(o_j)`` among the insertions that keep ``|o_j| + 1 <= Q_j`` and
    ``t(o_j) + marginal cost <= T_j``; an insertion that breaks a limit costs ``inf``.

    Parameters
    ----------
    problem : BudgetedProblem
    deadline : Deadline, optional
        When it expires, the remaining targets are reported as left over (no cheap
        completion: a completion that ignored the limits would not be an answer).

    Returns
    -------
    routes : list of m lists
        The (partial, if targets were left) routes; every one within its limits.
    left : (r,) int array
        Targets no vehicle could take (empty when the routes are complete).

    Notes
    -----
    As chapter 2's MC (:func:`taopt.heuristics.clustering.marginal_cost_routes`): the
    cheapest feasible insertion of every target into every route is kept in ``best`` (m, n)
    and only the row of the vehicle that changed is recomputed, over the targets still
    open: O(|o_j| r) per step with r of them, O(n^2 max|o_j|) in all (a repair, which
    re-inserts the few targets it cut off, pays only for those). The gap is the cheapest
    *feasible* one, which may not be the cheapest one. A vehicle's insertions only get dearer as its route grows (in a metric),
    so a refusal is never revisited wrongly: the row is recomputed after every change.
    Ties: lowest target, then lowest vehicle, then earliest gap (as chapter 2's MC).
    """
    n, m = problem.n, problem.m
    cost = problem.cost
    capacity, max_time = problem.capacity, problem.max_time
    initial = initial if initial is not None else [[] for _ in range(m)]
    routes = [np.array([n + j, *initial[j]], dtype=int) for j in range(m)]
    times = np.array([problem.route_cost(j, initial[j]) for j in range(m)])
    best = np.full((m, n), np.inf)
    where = np.zeros((m, n), dtype=int)
    done = np.zeros(n, dtype=bool)
    done[[k for route in initial for k in route]] = True

    def refresh(j: int) -> None:
        best[j] = np.inf  # a served target's entries are never read (masked below)
        if routes[j].size - 1 + 1 > capacity[j]:
            return
        open_targets = np.flatnonzero(~done)
        costs = insertion_costs(cost, routes[j], open_targets)  # (L, open targets)
        if math.isfinite(max_time[j]):
            limit = max_time[j] + SLACK * max(1.0, max_time[j])
            costs = np.where(times[j] + costs <= limit, costs, np.inf)
        gaps = np.argmin(costs, axis=0)  # earliest feasible gap on ties
        where[j, open_targets] = gaps
        best[j, open_targets] = costs[gaps, np.arange(open_targets.size)]

    for j in range(m):
        refresh(j)
    for _ in range(int((~done).sum())):
        if deadline is not None and deadline.expired():
            break
        masked = np.where(done[None, :], np.inf, best)
        flat = int(np.argmin(masked.T))  # target-major: lowest k, then lowest j
        k, j = divmod(flat, m)
        if not np.isfinite(masked[j, k]):
            break  # no vehicle can take any remaining target
        times[j] += best[j, k]
        routes[j] = np.insert(routes[j], where[j, k] + 1, k)
        done[k] = True
        refresh(j)
    return [[int(k) for k in route[1:]] for route in routes], np.flatnonzero(~done)


def repair(problem: BudgetedProblem, routes: list[list[int]]) -> list[list[int]] | None:
    """Routes within every limit made from ``routes``, or None when the repair fails.

    Each route is cut to its longest prefix within ``Q_k`` and ``T_k`` (travel times are
    non-negative, so every prefix of a feasible route is feasible), and the targets cut off
    are put back by the limit-aware cheapest insertion (:func:`limited_marginal_cost_routes`
    started from the cut routes). Routes already within their limits come back unchanged.
    O(n^2 max|o_j|) at worst.
    """
    cut = []
    for j, route in enumerate(routes):
        keep = min(len(route), int(min(problem.capacity[j], len(route))))
        if math.isfinite(problem.max_time[j]) and keep:
            points = [problem.n + j, *route[:keep]]
            elapsed = np.cumsum(problem.cost[points[:-1], points[1:]])
            keep = int(np.sum(_fits(elapsed, problem.max_time[j])))
            # the prefix times grow, so the fitting ones are a prefix
        cut.append([int(k) for k in route[:keep]])
    if all(len(a) == len(b) for a, b in zip(cut, routes, strict=True)):
        return [list(route) for route in routes]
    repaired, left = limited_marginal_cost_routes(problem, initial=cut)
    return None if left.size else repaired


def limited_local_search(
    problem: BudgetedProblem, routes: list[list[int]], max_moves: int = 1000
) -> tuple[list[list[int]], int]:
    """Best-improvement descent that never leaves the limits: relocate one target, or
    exchange two targets of different routes.

    Written here because chapter 2's :func:`~taopt.heuristics.ga_local_search.local_search`
    prices moves on one path and knows no route's count or time; its moves are the same
    kind (or-opt of one gene, exchange).

    Parameters
    ----------
    problem : BudgetedProblem
    routes : list of m lists
        Routes within every limit.
    max_moves : int
        Stop after this many improving moves.

    Returns
    -------
    routes : list of m lists
        Still within every limit; total travel time never higher.
    moves : int
        Improving moves made.

    Notes
    -----
    With ``s(u)`` the successor of point u on its route (a free end point after the last
    target), removing target k changes its route's time by
    ``r_k = t(p_k, s_k) − t(p_k, k) − t(k, s_k)`` and inserting it after u by
    ``t(u, k) + t(k, s(u)) − t(u, s(u))``; a relocation is allowed when the receiving route
    keeps ``|o| + 1 <= Q`` and both routes keep their ``T``. Exchanging k and l (different
    routes) replaces k by l between ``p_k`` and ``s_k`` and vice versa; counts do not change,
    so it is the only move left when every vehicle is full. O(n (n + m)) numpy work per
    move. The GA keeps one :class:`LimitedDescent` per run (the per-problem arrays built
    once).
    """
    return LimitedDescent(problem).run(routes, max_moves)


class LimitedDescent:
    """:func:`limited_local_search` with its per-problem arrays built once.

    The memetic step of :func:`genetic_algorithm` runs the descent some hundreds of times
    on one problem; the padded cost matrix, the fixed insertion terms and the limits are
    the same every time. Every table of a move is priced with the same arithmetic as the
    function's docstring states, each quantity gathered once per move (O(n (n + m)) numpy
    work, about 50 array operations).
    """

    def __init__(self, problem: BudgetedProblem) -> None:
        n, m = problem.n, problem.m
        size = n + m
        self.n, self.m, self.size = n, m, size
        cost = np.zeros((size + 1, size + 1))  # point ``size`` is the free end of every route
        cost[:size, :size] = problem.cost
        self.cost = cost
        self.capacity = problem.capacity
        self.limit = slack_limits(problem.max_time)
        self.targets = np.arange(n)
        self.points = np.arange(size)
        self.into_target = np.ascontiguousarray(cost[:size, :n].T)  # (n, n + m): t(u, k)

    def run(
        self, routes: list[list[int]], max_moves: int = 1000, deadline: Deadline | None = None
    ) -> tuple[list[list[int]], int]:
        """The descent from ``routes`` (see :func:`limited_local_search`), stopped early (the
        routes as improved so far, every limit still kept) once ``deadline`` has expired."""
        n, m, size = self.n, self.m, self.size
        cost, limit, capacity = self.cost, self.limit, self.capacity
        targets, points, into_target = self.targets, self.points, self.into_target
        routes = [list(route) for route in routes]
        route_of = np.empty(size, dtype=int)
        successor = np.full(size, size)
        predecessor = np.empty(n, dtype=int)
        times = np.zeros(m)
        counts = np.zeros(m, dtype=int)

        def book(j: int) -> None:  # route j's successors, predecessors, time and count
            path = np.array([n + j, *routes[j]], dtype=int)
            route_of[path] = j
            successor[path[:-1]] = path[1:]
            successor[path[-1]] = size
            predecessor[path[1:]] = path[:-1]
            times[j] = cost[path[:-1], path[1:]].sum()
            counts[j] = len(routes[j])

        for j in range(m):
            book(j)
        moves = 0
        while moves < max_moves:
            if deadline is not None and deadline.expired():
                break
            after = successor[:n]
            arrive = cost[predecessor, targets]  # t(p_k, k)
            leave = cost[targets, after]  # t(k, s_k)
            removal = cost[predecessor, after] - arrive - leave  # (n,)
            insertion = into_target + cost[:n, successor] - cost[points, successor][None, :]
            # (n, n + m): target k after point u
            time_of, limit_of = times[route_of], limit[route_of]  # per point, its route's
            home_time, home_limit = time_of[:n, None], limit_of[:n, None]
            same = route_of[:n, None] == route_of[None, :]
            relocate = removal[:, None] + insertion
            room = (counts + 1 <= capacity)[route_of]
            fits = np.where(
                same,
                home_time + relocate <= home_limit,
                (room & (time_of + insertion <= limit_of))
                & (time_of[:n] + removal <= limit_of[:n])[:, None],
            )
            relocate = np.where(fits, relocate, np.inf)
            relocate[targets, targets] = np.inf  # k after itself
            relocate[targets, predecessor] = np.inf  # k where it is
            # exchange k (route a) and l (route b): l takes k's place and k takes l's
            change = cost[predecessor, :n] + cost[:n, after].T
            change -= (arrive + leave)[:, None]  # (k, l)
            keeps = home_time + change <= home_limit
            keeps = keeps & keeps.T & ~same[:, :n]
            exchange = np.where(keeps, change + change.T, np.inf)
            tolerance = 1e-10 * max(float(times.sum()), 1.0)
            best_relocate = int(np.argmin(relocate))
            best_exchange = int(np.argmin(exchange))
            if min(relocate.flat[best_relocate], exchange.flat[best_exchange]) >= -tolerance:
                break
            if relocate.flat[best_relocate] <= exchange.flat[best_exchange]:
                k, u = divmod(best_relocate, size)
                old, new = int(route_of[k]), int(route_of[u])
                routes[old].remove(k)
                target_route = routes[new]
                target_route.insert(0 if u >= n else target_route.index(u) + 1, k)
            else:
                k, l = divmod(best_exchange, n)
                old, new = int(route_of[k]), int(route_of[l])
                ra, rb = routes[old], routes[new]
                ra[ra.index(k)], rb[rb.index(l)] = l, k
            book(old)
            if new != old:
                book(new)
            moves += 1
        return routes, moves


@register_improver(BudgetedProblem)
def improve_budgeted(problem: BudgetedProblem, routes: list[list[int]]) -> list[list[int]]:
    """``routes`` (within every limit) after the GA's memetic step: never worse, never outside.

    The improver of the exact model (:func:`taopt.models.budgeted.solve_budgeted` takes it
    as ``improve``; :func:`taopt.solve` passes it, the model imports no heuristic). The
    better of two candidates, as :func:`genetic_algorithm` polishes a child with
    ``memetic="chapter2"`` (a penalised-search candidate added to these made no difference
    to the exact model's time at n50m10 mid tightness, scenarios 0–4: median 1.89 s
    against 2.26 s, within this machine's noise, every optimum equal): chapter 2's
    local search (limits ignored, :func:`~taopt.heuristics.ga_routing.improve_routes`),
    :func:`repair`, then :func:`limited_local_search`; and :func:`limited_local_search`
    from ``routes`` itself. A few milliseconds at n50m10.

    Example
    -------
    >>> import numpy as np
    >>> x = np.array([1.0, 2.0, 4.0, 0.0, 5.0])
    >>> p = BudgetedProblem(abs(x[:, None] - x[None, :]), 3, capacity=[1, 2])
    >>> improve_budgeted(p, [[0], [2, 1]])
    [[0], [2, 1]]
    """
    routes = [[int(k) for k in route] for route in routes]
    descent = LimitedDescent(problem)
    best, _ = descent.run(routes)
    best_value = evaluate_budgeted(problem, best)
    unlimited = improve_routes(problem.routing, [list(route) for route in routes])
    repaired = repair(problem, [list(route) for route in unlimited])
    if repaired is not None:
        candidate, _ = descent.run(repaired)
        value = evaluate_budgeted(problem, candidate)
        if value < best_value:
            best, best_value = candidate, value
    return best


# -- EVM (2.12)–(2.14) + (2.18)–(2.19), limit-aware ------------------------------------------


def limited_extended_voronoi_routes(
    problem: BudgetedProblem,
    deadline: Deadline | None = None,
) -> tuple[list[list[int]], np.ndarray, int]:
    """Extended Voronoi clustering whose growth refuses a vehicle at its limit, then (2.18).

    ``T_j`` starts as ``{p_j}``; repeatedly the pair (vehicle j*, unclustered target k*)
    minimising ``t(i, k)`` over ``i in T_j`` (2.12)–(2.14) is proposed. It is accepted when
    ``|T_j*| + 1 <= Q_j*`` and the cluster ``T_j* ∪ {k*}`` sequenced by the smallest marginal
    cost principle (2.18)–(2.19) takes at most ``T_j*``; otherwise the pair is refused for
    good and the next cheapest pair is proposed. Each vehicle's route is the (2.18) sequence
    of its final cluster, the one checked at its last acceptance, so it is within limits.

    Once ``deadline`` (optional) has expired no further pair is proposed: the targets not
    yet clustered are returned in ``left``.

    Returns
    -------
    routes : list of m lists
        One route per vehicle (partial when targets were left).
    left : (r,) int array
        Targets every vehicle refused (or not reached before the deadline).
    refusals : int
        Pairs refused.

    Notes
    -----
    Without limits no pair is refused and the clusters are chapter 2's
    (:func:`taopt.heuristics.clustering.extended_voronoi_clusters`, equal on instances
    without ties). A refusal is final: a cluster only grows, so a full vehicle stays full,
    and a longer cluster's sequence is (in a metric, for the exact order) no shorter.
    Each proposal re-sequences one cluster, O(|T_j|^3) numpy work; at most ``n m``
    proposals.
    """
    n, m = problem.n, problem.m
    cost = problem.cost
    capacity, max_time = problem.capacity, problem.max_time
    reach = cost[n:, :n].copy()  # reach[j, k] = min over i in T_j of t(i, k)
    refused = np.zeros((m, n), dtype=bool)
    done = np.zeros(n, dtype=bool)
    clusters: list[list[int]] = [[] for _ in range(m)]
    routes: list[list[int]] = [[] for _ in range(m)]
    refusals = 0
    while not done.all():
        if deadline is not None and deadline.expired():
            break
        masked = np.where(done[None, :] | refused, np.inf, reach)
        flat = int(np.argmin(masked.T))  # lowest target, then lowest vehicle
        k, j = divmod(flat, m)
        if not np.isfinite(masked[j, k]):
            break
        accepted = len(clusters[j]) + 1 <= capacity[j]
        if accepted:
            route = marginal_cost_sequence(problem.routing, j, [*clusters[j], k])
            accepted = bool(_fits(problem.route_cost(j, route), max_time[j]))
        if not accepted:
            refused[j, k] = True
            refusals += 1
            continue
        clusters[j].append(k)
        routes[j] = route
        done[k] = True
        reach[j] = np.minimum(reach[j], cost[k, :n])
    return routes, np.flatnonzero(~done), refusals


# -- the registered methods --------------------------------------------------------------------


@register_method(BudgetedProblem, "MC", category="heuristic")
def mc(
    problem: BudgetedProblem,
    seed: int | np.random.Generator | None = 0,
    time_limit: float | None = None,
) -> Solution:
    """MC made limit-aware: cheapest insertion (2.15) where a vehicle at its limit is refused.

    Parameters
    ----------
    problem : BudgetedProblem
    seed : int
        Recorded only (deterministic).
    time_limit : float, optional
        Wall-clock seconds; when it expires the insertions stop and the targets not yet
        placed are reported unassigned (``info["stopped_by"] = "time_limit"``).

    Returns
    -------
    Solution
        Status "feasible" with the routes, or status "no_solution", ``objective = inf`` and
        ``info["unassigned"]`` when some target could not be placed (not a proof of
        infeasibility).

    Example
    -------
    Targets on a line at 1, 2, 4; vehicles at 0 and 5. Without limits MC gives vehicle 0
    targets 0 and 1 (cost 3); with ``Q = 1`` vehicle 0 takes only target 0 and vehicle 1
    takes 2 then 1 (cost 1 + 1 + 2 = 4).

    >>> import numpy as np
    >>> from taopt.budgeted import BudgetedProblem
    >>> x = np.array([1.0, 2.0, 4.0, 0.0, 5.0])
    >>> cost = abs(x[:, None] - x[None, :])
    >>> mc(BudgetedProblem(cost, 3)).routes
    [[0, 1], [2]]
    >>> s = mc(BudgetedProblem(cost, 3, capacity=[1, 2]))
    >>> s.routes, s.objective
    ([[0], [2, 1]], 4.0)

    Notes
    -----
    O(n^2 max|o_j|) (:func:`limited_marginal_cost_routes`).

    References
    ----------
    Thesis (2.15), Theorem 2.7; §6.2.
    """
    start = time.perf_counter()
    deadline = Deadline(time_limit)
    routes, left = limited_marginal_cost_routes(problem, deadline if deadline.limited else None)
    info: dict[str, Any] = {}
    if deadline.limited and deadline.expired() and left.size:
        info["stopped_by"] = "time_limit"
    if left.size:
        return _answer(problem, None, "MC", seed, start, {**info, **_no_solution("MC", left.size)})
    return _answer(problem, routes, "MC", seed, start, info)


@register_method(BudgetedProblem, "EVM", category="heuristic")
def evm(
    problem: BudgetedProblem,
    seed: int | np.random.Generator | None = 0,
    time_limit: float | None = None,
) -> Solution:
    """EVM made limit-aware: extended Voronoi growth that refuses a vehicle at its limit.

    See :func:`limited_extended_voronoi_routes`. Deterministic (``seed`` is recorded only).
    ``time_limit`` (wall-clock seconds): when it expires the growth stops and the targets not
    yet placed are reported unassigned (status "no_solution", ``info["stopped_by"] =
    "time_limit"``), as :func:`mc` does; it is the exact model's warm start, which must keep
    to its share of the limit.

    Returns
    -------
    Solution
        Status "feasible" with the routes (``info["refusals"]``: pairs refused), or status
        "no_solution", ``objective = inf`` and ``info["unassigned"]`` when some target was refused
        by every vehicle (not a proof of infeasibility).

    Example
    -------
    >>> import numpy as np
    >>> from taopt.budgeted import BudgetedProblem
    >>> x = np.array([1.0, 2.0, 4.0, 0.0, 5.0])
    >>> cost = abs(x[:, None] - x[None, :])
    >>> evm(BudgetedProblem(cost, 3, max_time=[1.5, None])).routes
    [[0], [2, 1]]

    References
    ----------
    Thesis (2.12)–(2.14), (2.18)–(2.19), Theorem 2.6; §6.2.
    """
    start = time.perf_counter()
    deadline = Deadline(time_limit)
    routes, left, refusals = limited_extended_voronoi_routes(
        problem, deadline if deadline.limited else None
    )
    info: dict[str, Any] = {"refusals": refusals}
    if deadline.limited and deadline.expired() and left.size:
        info["stopped_by"] = "time_limit"
    if left.size:
        return _answer(
            problem, None, "EVM", seed, start, {**info, **_no_solution("EVM", left.size)}
        )
    return _answer(problem, routes, "EVM", seed, start, info)


# -- the GA with a penalty -----------------------------------------------------------------------


def route_times(problem: BudgetedProblem, genes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-vehicle travel times and target counts of chromosomes with vehicle markers.

    Parameters
    ----------
    problem : BudgetedProblem
    genes : (P, n + m − 1) int array
        Chromosomes as :mod:`taopt.heuristics.ga_routing` reads them with
        ``markers="vehicle"`` (marker gene ``n + k − 1`` starts vehicle k's route).

    Returns
    -------
    times : (P, m) array
        Travel time of each vehicle's open route.
    counts : (P, m) int array
        Targets on each vehicle's route.

    Notes
    -----
    Vectorised: O(P (n + m)) numpy work (``np.bincount`` over (row, vehicle) cells).
    """
    n, m = problem.n, problem.m
    genes = np.atleast_2d(genes)
    rows, length = genes.shape
    nodes = path_nodes(problem.routing, genes)
    targets = nodes[:, 1:-1]
    is_target = targets < n
    step = np.where(is_target, problem.cost[nodes[:, :-2], np.where(is_target, targets, 0)], 0.0)
    # vehicle of each gene: the vehicle of the last marker at or before it (0 before any)
    marker_vehicle = np.where(is_target, 0, genes - n + 1)
    last_marker = np.maximum.accumulate(np.where(is_target, -1, np.arange(length)), axis=1)
    vehicle = np.where(
        last_marker >= 0,
        np.take_along_axis(marker_vehicle, np.maximum(last_marker, 0), axis=1),
        0,
    )
    cell = (np.arange(rows)[:, None] * m + vehicle).ravel()
    times = np.bincount(cell, weights=step.ravel(), minlength=rows * m).reshape(rows, m)
    counts = np.bincount(cell, weights=is_target.ravel(), minlength=rows * m).reshape(rows, m)
    return times, counts.astype(int)


def penalised_cost(
    problem: BudgetedProblem, genes: np.ndarray, weight: float, unit: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Total travel time (2.2) + ``weight`` × total violation of each chromosome.

    The violation is ``Σ_k max(0, t_k − T_k) + unit · Σ_k max(0, |o_k| − Q_k)``: excess time
    in time units, and each target beyond a capacity priced at ``unit`` time units.

    Returns
    -------
    penalised : (P,) array
    cost : (P,) array
        The plain total travel time.
    violation : (P,) array
        0 exactly for the chromosomes that keep every limit (with
        :data:`~taopt.heuristics.ga_penalised_search.SLACK`).
    """
    times, counts = route_times(problem, genes)
    limit = slack_limits(problem.max_time)
    over_time = np.where(times > limit, times - problem.max_time, 0.0)
    over_count = np.maximum(counts - problem.capacity, 0.0)
    violation = over_time.sum(axis=1) + unit * over_count.sum(axis=1)
    total = times.sum(axis=1)
    return total + weight * violation, total, violation


@register_method(BudgetedProblem, "GA", category="heuristic")
def genetic_algorithm(
    problem: BudgetedProblem,
    seed: int | np.random.Generator | None = 0,
    population: int = 120,
    generations: int = 350,
    crossover_rate: float = 0.9,
    mutation_rate: float = 0.1,
    penalty: float = 10.0,
    time_limit: float | None = None,
    memetic: str = "penalised",
) -> Solution:
    """The memetic GA of §2.5 with a penalty for violated limits.

    Chapter 2's GA (:func:`taopt.heuristics.ga_routing.genetic_algorithm`, operator set
    "memetic": vehicle markers, binary tournament, OX1, inversion / swap / slide mutation,
    elitism, local search on the 2 best distinct children) run on the *penalised* fitness
    :func:`penalised_cost`: ``f + penalty × violation``.

    A penalty for the population, a repair in the memetic step. Why: the GA's crossover,
    mutations and local search work on the whole chromosome and price moves by their exact
    O(1) change of (2.2); repairing every child would re-insert targets after every
    crossover with a rule of its own and shrink the search to the feasible region, while a
    penalty keeps every operator unchanged and lets infeasible chromosomes carry good genes
    across a tight limit. But a penalty alone rarely *reaches* the feasible region when the
    limits bite (with ``Q_k = n / m`` exactly, random chromosomes almost never have the
    right route lengths: none in 100 generations on a drift n50m10 scenario), and chapter
    2's local search, which minimises (2.2) and ignores the limits, walks straight out of
    it. So the memetic step (``memetic="penalised"``, the default) polishes each of the 2
    best distinct children with the **penalised local search**
    (:class:`~taopt.heuristics.ga_penalised_search.PenalisedSearch`: chapter 2's moves that
    keep the route starts in place, each priced by its exact change of the penalised
    fitness), then, if a limit is still broken, :func:`repair` (cut each route to its
    longest prefix within limits, re-insert the rest by the limit-aware cheapest
    insertion), then :func:`limited_local_search` (relocations and exchanges that keep every
    limit); the result replaces the child when the *penalised* fitness improves. The
    population is kept free of clones (chapter 2's ``distinct`` option), without which it
    collapsed onto one infeasible chromosome on a 6-target instance. Without limits the
    memetic step is chapter 2's alone.

    ``memetic="chapter2"`` is the step this GA had first: two candidates per child, chapter
    2's local search (limits ignored) then the repair then the limit-aware descent, and the
    child itself repaired then the descent; the better one is kept. Measured on the drift
    n50m10 scenario of seed 7 with ``Q = 5``: 8279 with the penalty and repair only, 7518
    with the limit-aware descent after the repair, 6630 with both candidates (PyVRP, 2 s:
    6139). The penalised search replaced it (2026-11-26) because chapter 2's search spent
    most of the time walking to the unconstrained optimum that the repair then cut back:
    on the chapter-6 study's n50m10 scenarios 0–4 (study seeds, same run) it gives answers
    0.5–2.3 % lower on average at Q2–Q1 and T0.6 and within 0.2 % at T1–T0.8, in less time
    at every level (``docs/reproduction/chapter6.md``). The answer is the best *feasible*
    chromosome ever seen (not the best penalised one).

    Parameters
    ----------
    problem : BudgetedProblem
    seed : int or numpy.random.Generator
        Same seed, same result.
    population, generations, crossover_rate, mutation_rate
        As chapter 2's GA (thesis: 120, 350, 0.9, 0.1).
    penalty : float
        λ, time units of penalty per time unit of excess; a target over a capacity counts
        as the median travel time between targets (``info["unit"]``) of excess.
    time_limit : float, optional
        Wall-clock seconds; the run stops after the generation during which it expires
        (``info["stopped_by"] = "time_limit"``).
    memetic : {"penalised", "chapter2"}
        The memetic step under limits (above); ``info["memetic"]``.

    Returns
    -------
    Solution
        The best feasible chromosome, decoded; status "no_solution" and ``objective = inf`` when
        no chromosome ever kept every limit (not a proof of infeasibility). ``info``:
        ``history`` (best feasible cost per generation, ``inf`` until one is found),
        ``first_feasible`` (generation of the first feasible chromosome), ``evaluations``,
        ``moves``, ``repairs`` (repairs tried), ``repaired`` (repairs that succeeded),
        ``penalty``, ``unit``, ``memetic``.

    Raises
    ------
    InstanceError
        population < 2, generations < 0, a rate outside [0, 1], a negative penalty, or an
        unknown memetic step.

    Notes
    -----
    O(generations × population × (n + m)) numpy work plus the local search
    (O((n + m)^2) per move), as chapter 2's GA. With limits the memetic step is a
    deterministic function of the chromosome, so its answer is memoised per chromosome
    (``info["memo_hits"]``): the elite, polished again generation after generation, costs
    nothing after the first time (same answers, about half the local searches at n50m10).
    The repair and the limit-aware descent are remembered per input routes as well
    (``info["route_memo_hits"]``): different chromosomes often reach the same routes, and
    about half of those calls repeat an earlier input at n50m10 Q1–Q1.5 (same answers;
    ``moves`` counts the moves actually searched).

    Example
    -------
    >>> import numpy as np
    >>> from taopt.budgeted import BudgetedProblem
    >>> x = np.array([1.0, 2.0, 4.0, 0.0, 5.0])
    >>> p = BudgetedProblem(abs(x[:, None] - x[None, :]), 3, capacity=[1, 2])
    >>> genetic_algorithm(p, seed=0, population=10, generations=20).objective
    4.0

    References
    ----------
    Thesis §2.5 (the GA), §6.2.
    """
    if population < 2 or generations < 0:
        raise InstanceError(
            f"need population >= 2 and generations >= 0, got {population}, {generations}"
        )
    for label, rate in (("crossover_rate", crossover_rate), ("mutation_rate", mutation_rate)):
        if not 0.0 <= rate <= 1.0:
            raise InstanceError(f"{label} must be in [0, 1], got {rate}")
    if not (math.isfinite(penalty) and penalty >= 0):
        raise InstanceError(f"penalty must be a number >= 0, got {penalty}")
    if memetic not in MEMETIC_STEPS:
        raise InstanceError(f"memetic must be one of {MEMETIC_STEPS}, got {memetic!r}")
    start = time.perf_counter()
    deadline = Deadline(time_limit)
    ops = OPERATOR_SETS["memetic"]
    rng = np.random.default_rng(seed)
    n, m = problem.n, problem.m
    length = n + m - 1
    between = problem.cost[:n, :n][~np.eye(n, dtype=bool)]
    unit = float(np.median(between)) if between.size else float(np.median(problem.cost[n:, :n]))
    matrix = path_matrix(problem.routing)
    descent = LimitedDescent(problem)
    penalised = PenalisedSearch(problem, penalty, unit) if memetic == "penalised" else None
    counters = {
        "moves": 0,
        "move_evaluations": 0,
        "repairs": 0,
        "repaired": 0,
        "memo_hits": 0,
        "route_memo_hits": 0,
    }
    # polished chromosome -> its memetic step's best candidate; and ("repair" | "descent",
    # routes) -> that step's answer (different chromosomes often reach the same routes)
    memo: dict[Any, Any] = {}
    # clone fingerprints, as chapter 2's GA (fixed weights: they draw nothing from ``rng``)
    weights = np.random.default_rng(0x6A).integers(1, 2**62, size=length, dtype=np.int64)

    genes = rng.permuted(np.tile(np.arange(length), (population, 1)), axis=1)
    fitness, plain, violation = penalised_cost(problem, genes, penalty, unit)
    best_feasible: np.ndarray | None = None
    best_cost = math.inf
    first_feasible = None

    def keep_feasible(generation: int) -> None:
        nonlocal best_feasible, best_cost, first_feasible
        ok = violation == 0
        if ok.any():
            row = int(np.flatnonzero(ok)[np.argmin(plain[ok])])
            if plain[row] < best_cost:
                best_feasible, best_cost = genes[row].copy(), float(plain[row])
            if first_feasible is None:
                first_feasible = generation

    keep_feasible(0)
    history = [best_cost]
    elite = genes[int(np.argmin(fitness))].copy()
    half = (population + 1) // 2
    done = 0
    for generation in range(1, generations + 1):
        if deadline.limited and deadline.expired():
            break
        done += 1
        contenders = rng.integers(0, population, size=(2 * half, ops.tournament))
        winners = contenders[np.arange(2 * half), np.argmin(fitness[contenders], axis=1)]
        mothers, fathers = genes[winners[:half]], genes[winners[half:]]
        cross = rng.random(half) < crossover_rate
        children = np.concatenate([mothers, fathers])
        if cross.any():
            children[:half][cross] = order_crossover(mothers[cross], fathers[cross], rng)
            children[half:][cross] = order_crossover(fathers[cross], mothers[cross], rng)
        children = _mutate(children[:population], ops, mutation_rate, rng)
        children[0] = elite  # elitism on the penalised fitness
        _separate_clones(children, weights, ops, rng)  # keep the population diverse
        genes = children
        fitness, plain, violation = penalised_cost(problem, genes, penalty, unit)
        _polish(
            problem, (matrix, descent, penalised), genes, fitness, plain, violation, penalty,
            unit, ops, counters, memo, deadline,
        )  # fmt: skip
        elite = genes[int(np.argmin(fitness))].copy()
        keep_feasible(generation)
        history.append(best_cost)
    info: dict[str, Any] = {
        "history": history,
        "first_feasible": first_feasible,
        "population": population,
        "generations": generations,
        "evaluations": population * (done + 1),
        "penalty": penalty,
        "unit": unit,
        "memetic": memetic,
        **counters,
    }
    if done < generations:
        info.update(stopped_by="time_limit", generations_done=done)
    if best_feasible is None:
        info["error"] = (
            "GA met no chromosome that keeps every capacity and maximum travel time (a "
            "heuristic's failure, not a proof that the instance is infeasible)"
        )
        return _answer(problem, None, "GA", seed, start, info)
    routes = decode(problem.routing, best_feasible, "vehicle")
    return _answer(problem, routes, "GA", seed, start, info)


def _polish(
    problem: BudgetedProblem,
    searches: tuple[np.ndarray, LimitedDescent, PenalisedSearch | None],
    genes: np.ndarray,
    fitness: np.ndarray,
    plain: np.ndarray,
    violation: np.ndarray,
    penalty: float,
    unit: float,
    ops: Any,
    counters: dict[str, int],
    memo: dict[Any, Any],
    deadline: Deadline | None = None,
) -> None:
    """On the best distinct children, in place, where the penalised fitness improves; once
    ``deadline`` has expired no further child is polished and the searches stop early.

    With ``memetic="penalised"`` (``searches[2]`` set): the penalised local search
    (:class:`~taopt.heuristics.ga_penalised_search.PenalisedSearch`), then :func:`repair`
    if a limit is still broken, then :func:`limited_local_search`. With "chapter2": the
    better of two candidates, chapter 2's local search then :func:`repair` then
    :func:`limited_local_search`, and the child itself repaired then
    :func:`limited_local_search`. Without limits: chapter 2's local search only.
    ``searches``: the path matrix, the run's :class:`LimitedDescent` and its
    :class:`~taopt.heuristics.ga_penalised_search.PenalisedSearch` (or None)."""
    matrix, descent, penalised = searches
    values, first = np.unique(fitness, return_index=True)
    limited = problem.has_capacity or problem.has_max_time
    for row in [int(r) for r in first[: ops.polish]]:
        if deadline is not None and deadline.expired():
            return
        key = genes[row].tobytes()
        if limited and key in memo:  # polished before (often the elite): same answer
            counters["memo_hits"] += 1
            best = memo[key]
            if best is not None and best[1] < fitness[row]:
                genes[row] = best[0]
                fitness[row], plain[row], violation[row] = best[1], best[2], best[3]
            continue
        path = path_nodes(problem.routing, genes[row])[0]
        if limited and penalised is not None:  # one candidate: the penalised search's
            nodes, moves = penalised.run(matrix, path, ops.max_moves, deadline)
            starts: tuple[np.ndarray, ...] = (nodes_to_genes(problem.routing, nodes),)
        else:
            nodes, moves, evaluations = local_search(
                matrix, path, ops.max_moves, ops.neighbourhood, deadline
            )
            counters["move_evaluations"] += evaluations
            starts = (nodes_to_genes(problem.routing, nodes), genes[row]) if limited else ()
        counters["moves"] += moves
        best = None
        if not limited:  # no limit: chapter 2's memetic step exactly
            candidate = nodes_to_genes(problem.routing, nodes)
            value, total, over = penalised_cost(problem, candidate, penalty, unit)
            best = (candidate, value[0], total[0], over[0])
        for start in starts:
            candidate = start
            value, total, over = penalised_cost(problem, candidate, penalty, unit)
            routes = decode(problem.routing, candidate, "vehicle")
            if over[0] > 0:
                counters["repairs"] += 1
                routes = _remembered(memo, "repair", routes, counters, lambda r: repair(problem, r))
                if routes is None:
                    if best is None or value[0] < best[1]:
                        best = (candidate, value[0], total[0], over[0])
                    continue
                counters["repaired"] += 1
            routes = _remembered(
                memo,
                "descent",
                routes,
                counters,
                lambda r: _descend(descent, r, ops, counters, deadline),
            )
            candidate = encode(problem.routing, routes)
            value, total, over = penalised_cost(problem, candidate, penalty, unit)
            if best is None or value[0] < best[1]:
                best = (candidate, value[0], total[0], over[0])
        if limited:
            memo[key] = None if best is None else (best[0].copy(), *best[1:])
        if best is not None and best[1] < fitness[row]:
            genes[row] = best[0]
            fitness[row], plain[row], violation[row] = best[1], best[2], best[3]


def _descend(
    descent: LimitedDescent,
    routes: list[list[int]],
    ops: Any,
    counters: dict[str, int],
    deadline: Deadline | None = None,
) -> list[list[int]]:
    """:func:`limited_local_search` (the run's ``descent``) with its moves counted."""
    routes, moves = descent.run(routes, ops.max_moves, deadline)
    counters["moves"] += moves
    return routes


def _remembered(
    memo: dict[Any, Any],
    step: str,
    routes: list[list[int]],
    counters: dict[str, int],
    compute: Any,
) -> Any:
    """``compute(routes)``, remembered per (step, routes): :func:`repair` and
    :func:`limited_local_search` are deterministic functions of the routes, and about half
    of their calls in a run repeat an earlier input (n50m10 at Q1 and Q1.5). Returns a
    fresh copy of the routes (or None), so callers may change them."""
    key = (step, tuple(tuple(route) for route in routes))
    if key in memo:
        counters["route_memo_hits"] += 1
    else:
        memo[key] = compute([list(route) for route in routes])
    found = memo[key]
    return None if found is None else [list(route) for route in found]
