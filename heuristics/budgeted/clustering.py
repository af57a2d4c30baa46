"""MC (2.15) and EVM (2.12)–(2.14) + (2.18)–(2.19) made limit-aware (thesis §2.4, §6.2):
a vehicle is refused a target that would break its capacity or travel time."""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from taopt.budgeted.problem import BudgetedProblem
from taopt.heuristics.budgeted.common import _answer, _fits, _no_solution
from taopt.heuristics.clustering import insertion_costs, marginal_cost_sequence
from taopt.heuristics.ga_penalised_search import SLACK
from taopt.registry import register_method
from taopt.result import Solution
from taopt.runtime import Deadline

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
