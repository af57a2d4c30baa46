"""Chapter 2 clustering heuristics: VN, VM, EVN, EVM and MC (thesis §2.4–§2.5).

Two clustering strategies assign targets to vehicles, two target-visiting
metrics put each vehicle's targets in order, and MC does both at once:

* Voronoi clustering (2.11): each target goes to the vehicle whose start
  reaches it fastest.
* Extended Voronoi clustering (2.12)–(2.14): Prim-like growth from the
  vehicles; a target joins the vehicle owning the closest start *or already
  clustered target*. Identical to Algorithm 1 (:func:`taopt.routing.bounds.mcga_tree`).
* Nearest inserting principle (2.16)–(2.17): append the closest unordered
  target to the route's end.
* Smallest marginal cost principle (2.18)–(2.19): cheapest insertion over
  the vehicle's unordered targets and all positions after its start.
* Marginal-cost clustering MC (2.15): cheapest insertion over all targets,
  vehicles and positions.

VN, VM, EVN and EVM are "cluster, then sequence each cluster" (§2.5); MC
is already a full assignment. Every solution is scored by the one scorer
(:func:`taopt.evaluate`).

Conventions shared by all methods (where the equations are silent)
------------------------------------------------------------------
* A route ``o_j`` starts with the vehicle's start ``p_j`` at position 1;
  ``1 < q <= |o_j| + 1`` means the start stays first and target k may go
  into any gap after it or at the end (the route is open, so the end costs
  ``t(last, k)`` only). Marginal cost of inserting k between a and b:
  ``t(a, k) + t(k, b) - t(a, b)``.
* Ties in an argmin (other than Voronoi boundaries) go to the lowest index:
  lowest target k first, then lowest vehicle j, then the earliest position q.
* Voronoi boundary ties in (2.11) are broken uniformly at random, with the
  method's seed (a ``numpy.random.Generator``), as the thesis says.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from taopt.registry import register_method
from taopt.result import FEASIBLE, Routes, Solution, make_solution
from taopt.routing.bounds import mcga_tree
from taopt.routing.problem import AssignmentProblem
from taopt.runtime import Deadline

# -- clustering strategies ------------------------------------------------------------


def voronoi_clusters(
    problem: AssignmentProblem, seed: int | np.random.Generator | None = 0
) -> np.ndarray:
    """Voronoi clustering (2.11): target k -> ``argmin_j t(p_j, k)``.

    Parameters
    ----------
    problem : AssignmentProblem
    seed : int or numpy.random.Generator
        Breaks boundary ties (several vehicles at exactly the same travel
        time) uniformly at random, as the thesis prescribes.

    Returns
    -------
    (n,) int array
        ``cluster[k]`` in ``0..m-1``.
    """
    rng = np.random.default_rng(seed)
    from_vehicles = problem.cost[problem.n :, : problem.n]  # (m, n)
    nearest = from_vehicles.min(axis=0)
    on_boundary = from_vehicles == nearest[None, :]
    # A random key per (vehicle, target); the tied vehicle with the smallest key wins.
    keys = np.where(on_boundary, rng.random(from_vehicles.shape), np.inf)
    return np.argmin(keys, axis=0)


def extended_voronoi_clusters(problem: AssignmentProblem) -> np.ndarray:
    """Extended Voronoi clustering (2.12)–(2.14).

    ``T_j`` starts as ``{p_j}``; repeatedly the pair (vehicle j*, unclustered
    target k*) minimising ``t(i, k)`` over ``i in T_j`` is chosen and k* is
    added to ``T_j*``. This is Algorithm 1; ties as in
    :func:`taopt.routing.bounds.mcga_tree` (lowest target; among equal
    sources, the one clustered first, vehicles first in index order).

    Returns
    -------
    (n,) int array
        ``cluster[k]`` in ``0..m-1``.
    """
    return mcga_tree(problem).vehicle.copy()


# -- target-visiting metrics ----------------------------------------------------------


def nearest_sequence(problem: AssignmentProblem, vehicle: int, targets: Sequence[int]) -> list[int]:
    """Nearest inserting principle (2.16)–(2.17) for one vehicle.

    From the route's last point, append the unordered target with the smallest
    travel time; ties to the lowest target index. O(|T_j|^2).
    """
    remaining = np.array(sorted(int(k) for k in targets), dtype=int)
    route: list[int] = []
    last = problem.n + vehicle
    cost = problem.cost
    while remaining.size:
        pick = int(np.argmin(cost[last, remaining]))
        last = int(remaining[pick])
        route.append(last)
        remaining = np.delete(remaining, pick)
    return route


def insertion_costs(cost: np.ndarray, nodes: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """Marginal cost ``t(o ⊕_q k) - t(o)`` of every candidate at every position (2.15)/(2.18).

    Parameters
    ----------
    cost : (N, N) array
    nodes : (L,) int array
        The route ``o_j`` as points, the vehicle start first.
    candidates : (K,) int array
        Targets to insert.

    Returns
    -------
    (L, K) array
        Row ``r`` (``q = r + 2`` in the thesis's 1-based positions) is the
        cost of inserting after ``nodes[r]``: ``t(a, k) + t(k, b) - t(a, b)``
        for a gap (a, b), and ``t(last, k)`` at the open end.
    """
    out = cost[np.ix_(nodes, candidates)].copy()  # t(a, k)
    if nodes.size > 1:
        before, after = nodes[:-1], nodes[1:]
        out[:-1] += cost[np.ix_(candidates, after)].T - cost[before, after][:, None]
    return out


def marginal_cost_sequence(
    problem: AssignmentProblem, vehicle: int, targets: Sequence[int], transposed: bool = False
) -> list[int]:
    """Smallest marginal cost principle (2.18)–(2.19) for one vehicle.

    Repeatedly inserts the (target, position) pair with the smallest increase
    of the route's travel time; positions ``1 < q <= |o_j| + 1`` (after the
    start). Ties: lowest target index, then earliest position.
    O(|T_j|^3) numpy work.

    ``transposed=True`` is a reproduction option, never the default: the insertion costs
    are computed on the transposed matrix (``t(k, i)`` where (2.18) has ``t(i, k)``), as if
    the travel times had been stored the other way round; the route is still scored on the
    true matrix. See :func:`vm_transposed`.
    """
    remaining = np.array(sorted(int(k) for k in targets), dtype=int)
    nodes = np.array([problem.n + vehicle], dtype=int)
    matrix = problem.cost.T if transposed else problem.cost
    while remaining.size:
        costs = insertion_costs(matrix, nodes, remaining)  # (L, K)
        # Flatten column-major so argmin's first hit is the lowest target, then earliest q.
        flat = int(np.argmin(costs.T))
        pick, gap = divmod(flat, costs.shape[0])
        nodes = np.insert(nodes, gap + 1, remaining[pick])
        remaining = np.delete(remaining, pick)
    return [int(k) for k in nodes[1:]]


# -- MC: marginal-cost clustering (2.15) ----------------------------------------------


def marginal_cost_routes(
    problem: AssignmentProblem, deadline: Deadline | None = None
) -> list[list[int]]:
    """Marginal-cost-based clustering MC (2.15): global cheapest insertion.

    Each step inserts the (target k, vehicle j, position q) with the smallest
    ``t(o_j ⊕_q k) - t(o_j)`` over all unclustered targets, all vehicles and
    all positions after the vehicle's start.

    Parameters
    ----------
    problem : AssignmentProblem
    deadline : Deadline, optional
        When it expires, the targets not yet inserted are appended by
        :func:`append_nearest` (O(m n) per target instead of O(|o_j| n)), so the
        routes are always complete.

    Notes
    -----
    Keeps ``best[j, k]`` (the cheapest insertion of k into vehicle j's route)
    and ``where[j, k]`` (its gap); after an insertion into vehicle j* only
    row j* is recomputed, O(|o_j*| n). Ties: lowest target, then lowest
    vehicle, then earliest position.
    """
    n, m = problem.n, problem.m
    cost = problem.cost
    all_targets = np.arange(n)
    # Empty routes: the only position is the end, cost t(p_j, k).
    best = cost[n:, :n].copy()  # (m, n)
    where = np.zeros((m, n), dtype=int)
    routes = [np.array([n + j], dtype=int) for j in range(m)]
    done = np.zeros(n, dtype=bool)
    for _ in range(n):
        if deadline is not None and deadline.expired():
            return append_nearest(problem, [route[1:].tolist() for route in routes], done)
        masked = np.where(done[None, :], np.inf, best)
        flat = int(np.argmin(masked.T))  # target-major: lowest k, then lowest j
        k, j = divmod(flat, m)
        routes[j] = np.insert(routes[j], where[j, k] + 1, k)
        done[k] = True
        costs = insertion_costs(cost, routes[j], all_targets)  # (L, n)
        where[j] = np.argmin(costs, axis=0)  # earliest position on ties
        best[j] = costs[where[j], all_targets]
    return [[int(k) for k in route[1:]] for route in routes]


def append_nearest(
    problem: AssignmentProblem, routes: list[list[int]], done: np.ndarray
) -> list[list[int]]:
    """Complete partial ``routes``: append, one at a time, the target not ``done`` closest to
    the end of some route (the nearest inserting principle (2.16) over all vehicles).

    The cheap completion of a construction stopped by a time limit: O(m n) per target.
    """
    n, m = problem.n, problem.m
    cost = problem.cost
    routes = [list(route) for route in routes]
    ends = np.array([route[-1] if route else n + j for j, route in enumerate(routes)])
    left = np.flatnonzero(~done)
    while left.size:
        step = cost[np.ix_(ends, left)]  # (m, |left|)
        flat = int(np.argmin(step.T))  # lowest target, then lowest vehicle
        index, j = divmod(flat, m)
        k = int(left[index])
        routes[j].append(k)
        ends[j] = k
        left = np.delete(left, index)
    return [[int(k) for k in route] for route in routes]


# -- the registered methods ------------------------------------------------------------


def cluster_then_sequence(
    problem: AssignmentProblem, clusters: np.ndarray, metric: str
) -> list[list[int]]:
    """Sequence each vehicle's cluster with ``metric`` "nearest" (2.16), "marginal" (2.18)
    or "marginal-transposed" (2.18 on the transposed matrix, a reproduction option)."""
    if metric == "nearest":
        return [
            nearest_sequence(problem, j, np.flatnonzero(clusters == j).tolist())
            for j in range(problem.m)
        ]
    transposed = metric == "marginal-transposed"
    return [
        marginal_cost_sequence(problem, j, np.flatnonzero(clusters == j).tolist(), transposed)
        for j in range(problem.m)
    ]


@register_method(AssignmentProblem, "VN", style=("-", "o"))
def vn(problem: AssignmentProblem, seed: int | np.random.Generator | None = 0) -> Solution:
    """VN: Voronoi clustering (2.11) + nearest inserting principle (2.16)–(2.17).

    Example
    -------
    Three targets on a line at 1, 2, 4 and one vehicle at 0 (symmetric
    distances): VN visits 0, 1, 2 in that order at cost 4.

    >>> import numpy as np, taopt
    >>> x = np.array([1.0, 2.0, 4.0, 0.0])
    >>> p = taopt.AssignmentProblem(abs(x[:, None] - x[None, :]), 3)
    >>> taopt.heuristics.run("VN", p).routes
    [[0, 1, 2]]
    """
    start = time.perf_counter()
    clusters = voronoi_clusters(problem, seed)
    return make_solution(
        problem,
        Routes(cluster_then_sequence(problem, clusters, "nearest")),
        method="VN",
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        seed=seed,
    )


@register_method(AssignmentProblem, "VM", style=("--", "s"))
def vm(problem: AssignmentProblem, seed: int | np.random.Generator | None = 0) -> Solution:
    """VM: Voronoi clustering (2.11) + smallest marginal cost principle (2.18)–(2.19)."""
    start = time.perf_counter()
    clusters = voronoi_clusters(problem, seed)
    return make_solution(
        problem,
        Routes(cluster_then_sequence(problem, clusters, "marginal")),
        method="VM",
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        seed=seed,
    )


@register_method(AssignmentProblem, "EVN", style=("-.", "D"))
def evn(problem: AssignmentProblem, seed: int | np.random.Generator | None = 0) -> Solution:
    """EVN: extended Voronoi clustering (2.12)–(2.14) + nearest inserting (2.16)–(2.17).

    Deterministic (``seed`` is recorded only).
    """
    start = time.perf_counter()
    clusters = extended_voronoi_clusters(problem)
    return make_solution(
        problem,
        Routes(cluster_then_sequence(problem, clusters, "nearest")),
        method="EVN",
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        seed=seed,
    )


@register_method(AssignmentProblem, "EVM", style=(":", "^"))
def evm(problem: AssignmentProblem, seed: int | np.random.Generator | None = 0) -> Solution:
    """EVM: extended Voronoi clustering (2.12)–(2.14) + smallest marginal cost (2.18)–(2.19).

    The algorithm of Theorem 2.6. Deterministic (``seed`` is recorded only).
    """
    start = time.perf_counter()
    clusters = extended_voronoi_clusters(problem)
    return make_solution(
        problem,
        Routes(cluster_then_sequence(problem, clusters, "marginal")),
        method="EVM",
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        seed=seed,
    )


@register_method(AssignmentProblem, "VM-transposed", default=False)
def vm_transposed(
    problem: AssignmentProblem, seed: int | np.random.Generator | None = 0
) -> Solution:
    """VM with its insertion step (2.18)–(2.19) on the transposed matrix (reproduction option).

    Not a method of the thesis and never a default: it reads ``t(k, i)`` where (2.18) reads
    ``t(i, k)``, as if the travel-time matrix had been stored the other way round. It is kept
    because it reproduces the thesis's VM column of Table 2.1 far better than VM does (see
    docs/reproduction/chapter2.md); the route is scored on the true matrix.
    """
    start = time.perf_counter()
    clusters = voronoi_clusters(problem, seed)
    routes = cluster_then_sequence(problem, clusters, "marginal-transposed")
    return make_solution(
        problem,
        Routes(routes),
        method="VM-transposed",
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        seed=seed,
    )


@register_method(AssignmentProblem, "EVM-transposed", default=False)
def evm_transposed(
    problem: AssignmentProblem, seed: int | np.random.Generator | None = 0
) -> Solution:
    """EVM with its insertion step on the transposed matrix (reproduction option; see
    :func:`vm_transposed`)."""
    start = time.perf_counter()
    clusters = extended_voronoi_clusters(problem)
    routes = cluster_then_sequence(problem, clusters, "marginal-transposed")
    return make_solution(
        problem,
        Routes(routes),
        method="EVM-transposed",
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        seed=seed,
    )


@register_method(AssignmentProblem, "MC", style=("--", "v"))
def mc(
    problem: AssignmentProblem,
    seed: int | np.random.Generator | None = 0,
    time_limit: float | None = None,
) -> Solution:
    """MC: marginal-cost-based clustering (2.15), a complete assignment by itself.

    The algorithm of Theorem 2.7. Deterministic (``seed`` is recorded only).
    O(n^2 max|o_j|): about 4 s for 1,000 targets and one vehicle. Under ``time_limit``
    (seconds) the insertions stop when it expires and the remaining targets are appended
    by :func:`append_nearest`; ``info["stopped_by"]`` is then "time_limit" (the result is
    still a complete, feasible assignment).

    Example
    -------
    Targets at 1, 2, 4 on a line, vehicles at 0 and 5 (symmetric distances).
    Step 1: target 0 from vehicle 0 and target 2 from vehicle 1 both cost 1;
    the lowest target wins: target 0 -> vehicle 0. Step 2: target 1 at vehicle
    0's end and target 2 at vehicle 1 both cost 1: target 1 -> vehicle 0.
    Step 3: target 2 -> vehicle 1 (1). Total 1 + 1 + 1 = 3.

    >>> import numpy as np, taopt
    >>> x = np.array([1.0, 2.0, 4.0, 0.0, 5.0])
    >>> p = taopt.AssignmentProblem(abs(x[:, None] - x[None, :]), 3)
    >>> s = taopt.heuristics.run("MC", p)
    >>> s.routes, s.objective
    ([[0, 1], [2]], 3.0)
    """
    start = time.perf_counter()
    deadline = Deadline(time_limit)
    routes = marginal_cost_routes(problem, deadline if deadline.limited else None)
    solution = make_solution(
        problem,
        Routes(routes),
        method="MC",
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        seed=seed,
    )
    if deadline.limited and deadline.expired():
        solution = solution.replace(info={"stopped_by": "time_limit"})
    return solution


__all__ = [
    "voronoi_clusters",
    "extended_voronoi_clusters",
    "nearest_sequence",
    "marginal_cost_sequence",
    "insertion_costs",
    "marginal_cost_routes",
    "append_nearest",
    "cluster_then_sequence",
    "vn",
    "vm",
    "evn",
    "evm",
    "vm_transposed",
    "evm_transposed",
    "mc",
]
