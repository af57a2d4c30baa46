"""Valid lower bounds of the budgeted family (capacity and travel-time limits, §6.2).

Every bound here is **valid** (never above the optimum; docs/architecture.md, invariant 3).
Two ideas:

* *Limits only remove solutions.* Every feasible solution of a
  :class:`~taopt.budgeted.BudgetedProblem` is a feasible solution of chapter 2's problem
  ``BudgetedProblem.routing`` with the same cost, so every valid
  chapter-2 bound is valid here. Better: an arc that no vehicle can use on a route within
  its limits (:func:`usable_arcs`) is in no feasible solution, so pricing it above any
  route (:func:`pruned_routing`) changes no feasible solution's cost and keeps every
  chapter-2 bound valid, while making it stronger.
* *Capacities force routes.* With capacities, at least ``r`` vehicles
  (:func:`min_routes`) must leave their start, so at least r targets have a start point as
  predecessor: :func:`start_count_bound`, a Lagrangian relaxation of that row on the
  assignment bound.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse.csgraph import csgraph_from_dense, dijkstra

from taopt.bounds import arborescence as generic_arborescence
from taopt.bounds import lower as generic_lower
from taopt.budgeted.problem import TIME_TOLERANCE, BudgetedProblem
from taopt.errors import require
from taopt.routing.problem import AssignmentProblem


def shortest_times(problem: BudgetedProblem) -> np.ndarray:
    """``(m, n + m)`` shortest travel times from each vehicle's start point (inf where
    unreachable); no arc enters a start point, so a start is reached only from itself.

    Notes
    -----
    One Dijkstra per vehicle (:func:`scipy.sparse.csgraph.dijkstra`), O(m (n + m)^2).
    """
    n, m = problem.n, problem.m
    graph = np.array(problem.cost, dtype=float)
    graph[:, n:] = np.inf  # no arc into a start point
    np.fill_diagonal(graph, np.inf)
    times = dijkstra(csgraph_from_dense(graph, null_value=np.inf), indices=np.arange(n, n + m))
    return np.asarray(times, dtype=float)


def usable_arcs(problem: BudgetedProblem) -> np.ndarray:
    """``(m, n + m, n)`` booleans: vehicle k may use arc ``i -> j`` on a feasible route.

    Arc ``i -> j`` (j a target, ``i != j``) is usable by k when i is a target or k's own
    start, ``Q_k >= 1`` (``Q_k >= 2`` if i is a target: j is then k's second target or
    later), and ``d_k(i) + t(i, j) <= T_k`` with ``d_k`` from :func:`shortest_times` (any
    route of k reaching i has taken at least ``d_k(i)``; travel times are >= 0), up to the
    scorer's :data:`~taopt.budgeted.problem.TIME_TOLERANCE`.
    """
    n, m = problem.n, problem.m
    size = n + m
    cost = problem.cost[:, :n]
    reach = shortest_times(problem)
    usable = np.zeros((m, size, n), dtype=bool)
    for k in range(m):
        usable[k, :n, :] = problem.capacity[k] >= 2
        usable[k, n + k, :] = problem.capacity[k] >= 1
        limit = problem.max_time[k]
        if math.isfinite(limit):
            usable[k] &= reach[k][:, None] + cost <= limit + TIME_TOLERANCE * max(1.0, limit)
    usable[:, np.arange(n), np.arange(n)] = False
    return usable


def pruned_routing(problem: BudgetedProblem) -> AssignmentProblem:
    """Chapter 2's problem with every arc no vehicle may use (:func:`usable_arcs`) priced
    above any route (the sum of all travel times plus 1).

    Every feasible solution of ``problem`` uses usable arcs only, so it is a solution of the
    returned problem with the same cost: any valid lower bound of the returned problem is
    one of ``problem``.
    """
    usable = usable_arcs(problem).any(axis=0)
    cost = np.array(problem.cost, dtype=float)
    big = float(cost.sum()) + 1.0
    block = cost[:, : problem.n]
    block[~usable] = big
    np.fill_diagonal(cost, 0.0)
    return AssignmentProblem(cost, problem.n, problem.name)


def min_routes(problem: BudgetedProblem) -> int:
    """The fewest non-empty routes that can serve n targets within the capacities: the
    smallest r whose r largest capacities sum to at least n (``m + 1`` when all m do not:
    then no solution is feasible)."""
    ordered = np.sort(problem.capacity)[::-1]
    total = np.cumsum(ordered)
    enough = np.flatnonzero(total >= problem.n)
    return int(enough[0]) + 1 if len(enough) else problem.m + 1


def start_count_bound(problem: BudgetedProblem, steps: int = 40) -> float:
    """Valid lower bound: the assignment bound with "at least r routes start" dualised.

    Every feasible solution gives each target one predecessor (a target or a start point),
    each point being the predecessor of at most one target, only along usable arcs
    (:func:`usable_arcs`), and at least ``r = min_routes(problem)`` targets have a start
    point as predecessor. Relaxing that last row with a multiplier λ >= 0 gives, for every
    λ, ``g(λ) = λ r + min_assignment(t − λ on the arcs out of start points) <= f*``
    (weak duality: a feasible solution's assignment has at least r start arcs, so its
    Lagrangian cost is at most its cost). ``g`` is concave; λ is bisected on its slope
    ``r − (start arcs used)``, and the largest g seen is returned. ``λ = 0`` is the plain
    assignment bound on the usable arcs. Infeasible problems (r > m) give ``inf`` only
    when no assignment exists at all; otherwise the best g.

    Notes
    -----
    ``steps`` rectangular assignments (:func:`scipy.optimize.linear_sum_assignment`,
    O((n + m) n^2) each).
    """
    n = problem.n
    routing = pruned_routing(problem)
    cost = np.array(routing.cost[:, :n], dtype=float)  # (n + m) predecessors x n targets
    cost[np.arange(n), np.arange(n)] = float(routing.cost.sum()) + 1.0
    r = min(min_routes(problem), problem.m)

    def g(lam: float) -> tuple[float, int]:
        shifted = cost.copy()
        shifted[n:] -= lam
        rows, cols = linear_sum_assignment(shifted.T)  # target -> predecessor
        starts = int((cols >= n).sum())
        return float(shifted.T[rows, cols].sum()) + lam * r, starts

    best, starts = g(0.0)
    if starts >= r:
        return best
    low, high = 0.0, float(cost.max() - cost.min()) + 1.0
    for _ in range(steps):
        middle = 0.5 * (low + high)
        value, starts = g(middle)
        best = max(best, value)
        if starts >= r:
            high = middle
        else:
            low = middle
    return best


def arborescence_bound(problem: BudgetedProblem) -> float:
    """Valid: chapter 2's min-cost arborescence bound of :func:`pruned_routing` (at least
    that of ``problem.routing``, since pruning only raises arc costs)."""
    return float(generic_arborescence(pruned_routing(problem)))


def lower(problem: BudgetedProblem, strength: str = "auto") -> float:
    """The strongest valid lower bound of the family at a cost ``strength``.

    ``"fast"``: :func:`arborescence_bound`. ``"auto"``: the larger of chapter 2's
    ``lower(pruned_routing(problem), "auto")`` (the degree-penalised arborescence) and
    :func:`start_count_bound`. ``"strong"``: the same with chapter 2's "strong" (its DFJ
    LP). All valid (module docstring); a problem with ``Σ Q_k < n`` is infeasible and gets
    ``inf``.

    References
    ----------
    Thesis §2.4.3 (the arborescence bound), §6.2.
    """
    require(problem, BudgetedProblem, "lower()")
    if problem.capacity.sum() < problem.n:
        return math.inf
    if strength == "fast":
        return arborescence_bound(problem)
    value = float(generic_lower(pruned_routing(problem), strength))
    return max(value, start_count_bound(problem), arborescence_bound(problem))


__all__ = [
    "shortest_times",
    "usable_arcs",
    "pruned_routing",
    "min_routes",
    "start_count_bound",
    "arborescence_bound",
    "lower",
]
