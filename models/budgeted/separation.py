"""Rounded route-count inequalities of the budgeted model: the counts, the heuristic
separation and the rows (thesis §6.2; Laporte and Nobert's rounded capacity inequalities)."""

from __future__ import annotations

import bisect

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from taopt.budgeted.bounds import usable_arcs
from taopt.budgeted.problem import (
    TIME_TOLERANCE,
    BudgetedProblem,
)
from taopt.routing.subtours import rounded_cut_rows


def route_counts(problem: BudgetedProblem) -> np.ndarray:
    """``k[s]``: the fewest vehicles whose capacities together hold ``s`` targets
    (``s = 0..n``; an unlimited capacity holds n).

    Every route serves at most ``Q_k`` targets, so a set S of targets is served by at
    least ``k[|S|]`` routes, each entering S at least once: the rounded capacity
    inequality ``σ(δ⁻(S)) >= k[|S|]`` holds for every feasible σ. With equal
    capacities ``k[s] = ceil(s / Q)``.
    """
    n = problem.n
    held = np.cumsum(np.sort(np.minimum(problem.capacity, n))[::-1])
    sizes = np.arange(n + 1)
    return np.where(sizes > 0, np.searchsorted(held, sizes, side="left") + 1, 0)


def entry_times(problem: BudgetedProblem) -> np.ndarray:
    """``e_j``: the least travel time of an arc into target j that some vehicle may use
    (:func:`~taopt.budgeted.bounds.usable_arcs`); 0 without any time limit."""
    if not problem.has_max_time:
        return np.zeros(problem.n)
    usable = usable_arcs(problem).any(axis=0)
    priced = np.where(usable, problem.cost[:, : problem.n], np.inf)
    least = priced.min(axis=0)
    return np.where(np.isfinite(least), least, 0.0)


def time_counts(problem: BudgetedProblem, total: np.ndarray | float) -> np.ndarray:
    """The fewest vehicles whose time limits (with the scorer's tolerance) sum to at
    least ``total`` (0 for ``total <= 0``); 1 when a vehicle has no time limit.

    Routes touching a set S of targets enter each ``j ∈ S`` by a distinct arc of at
    least ``e_j`` (:func:`entry_times`), so together they take at least ``Σ_{j∈S} e_j``,
    and each takes at most its ``T_k``: S is served by at least this many routes.
    """
    total = np.asarray(total, dtype=float)
    return np.where(total > 0, np.searchsorted(_time_held(problem), total, side="left") + 1, 0)


def _time_held(problem: BudgetedProblem) -> np.ndarray:
    """Cumulative sums of the time limits (with the scorer's tolerance), longest first."""
    return np.cumsum(np.sort(problem.max_time * (1.0 + TIME_TOLERANCE))[::-1])


def separate_capacity(
    problem: BudgetedProblem,
    tails: np.ndarray,
    heads: np.ndarray,
    sigma: np.ndarray,
    tolerance: float = 1e-6,
    entry: np.ndarray | None = None,
) -> list[tuple[tuple[int, ...], int]]:
    """Target sets S whose rounded route-count inequality ``σ(δ⁻(S)) >= k(S)`` is
    violated by σ, found heuristically; ``k(S)`` the larger of the capacity count
    ``route_counts(problem)[|S|]`` and the time count ``time_counts(problem, Σ_{j∈S}
    e_j)`` (:func:`~taopt.models.budgeted.separation.route_counts`, :func:`~taopt.models.budgeted.separation.time_counts`, ``e = entry`` from
    :func:`entry_times`, or no time count when None).

    Under (2.3) ``σ(δ⁻(S)) = |S| − σ(A(S))`` with ``A(S)`` the arcs inside S, so along a
    growing S the inflow is updated in O(n). Candidates: the connected components of
    the support of σ among targets, and from every target a set grown greedily by
    adding the target most joined to S (largest ``Σ_{i∈S} σ_ij + σ_ji``) while it is
    joined at all; the most violated set of each growth is kept.

    Returns
    -------
    list of (subset, k)
        Sorted target tuples and their right-hand sides ``k(S) >= 2``, each violated
        by more than ``tolerance``; no duplicates.

    Notes
    -----
    O(n^3) numpy work per call (n growths of n steps); a heuristic, as in CVRP codes
    (exact separation of rounded capacity inequalities is NP-hard), so an empty answer
    proves nothing. Sets needing one route are (2.5)'s, separated exactly elsewhere.

    References
    ----------
    Thesis §6.2 (capacity, travel time); Laporte and Nobert's rounded capacity
    inequalities for the CVRP, here for open routes from distinct start points.
    """
    n = problem.n
    by_size = route_counts(problem).tolist()
    held = _time_held(problem).tolist()
    entry = np.zeros(n) if entry is None else np.asarray(entry, dtype=float)

    def need(size: int, time_sum: float) -> int:
        # time_counts(problem, time_sum) for one number (bisect_left is searchsorted "left")
        by_time = bisect.bisect_left(held, time_sum) + 1 if time_sum > 0 else 0
        return max(int(by_size[size]), by_time)

    if need(n, float(entry.sum())) < 2:
        return []
    inner = (tails < n) & (heads < n) & (sigma > 1e-9)
    weight = np.zeros((n, n))
    np.add.at(weight, (tails[inner], heads[inner]), sigma[inner])
    joined = weight + weight.T
    found: dict[tuple[int, ...], int] = {}

    support = sp.csr_matrix(joined > 0)
    count, label = connected_components(support, directed=False)
    for component in range(count):
        members = np.flatnonzero(label == component)
        size, k = len(members), need(len(members), float(entry[members].sum()))
        if k >= 2 and k - (size - weight[np.ix_(members, members)].sum()) > tolerance:
            found[tuple(int(v) for v in members)] = k
    for seed in range(n):
        group = [seed]
        inside = np.zeros(n, dtype=bool)
        inside[seed] = True
        link = joined[seed].copy()
        inside_sum, time_sum = 0.0, float(entry[seed])
        best, best_members, best_need = tolerance, None, 0
        while True:
            link[inside] = -1.0
            j = int(np.argmax(link))
            if link[j] <= 1e-9:
                break
            inside_sum += link[j]
            time_sum += float(entry[j])
            inside[j] = True
            group.append(j)
            link += joined[j]
            size = len(group)
            k = need(size, time_sum)
            violation = k - (size - inside_sum)
            if k >= 2 and violation > best:
                best, best_members, best_need = violation, list(group), k
        if best_members is not None:
            found[tuple(sorted(best_members))] = best_need
    return sorted(found.items())


def capacity_rows(
    problem: BudgetedProblem,
    cuts: list[tuple[tuple[int, ...], int]],
    tails: np.ndarray,
    heads: np.ndarray,
) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
    """Rows of rounded capacity inequalities ``σ(δ⁻(S)) >= k``, each in its sparser equivalent
    form (the core's :func:`~taopt.routing.subtours.rounded_cut_rows`, which writes chapter
    2's subtour rows too)."""
    return rounded_cut_rows(problem.n + problem.m, cuts, tails, heads)
