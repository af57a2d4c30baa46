"""Starts and cut-offs of the budgeted exact model: a greedy plan, chapter 2's routes
repaired into the limits, the incumbent check and ``Σ_k T_k`` (thesis §6.2)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from taopt.budgeted.problem import (
    TIME_TOLERANCE,
    BudgetedProblem,
    violations,
)
from taopt.runtime import Deadline


def greedy_budgeted(problem: BudgetedProblem) -> list[list[int]] | None:
    """A quick feasible start: repeatedly append the cheapest (route end, target) pair that
    keeps every limit; None if it gets stuck (this proves nothing)."""
    n, m = problem.n, problem.m
    cost = problem.cost[:, :n]
    routes: list[list[int]] = [[] for _ in range(m)]
    ends = np.arange(n, n + m)
    times = np.zeros(m)
    left = np.ones(n, dtype=bool)
    for _ in range(n):
        price = np.where(left[None, :], cost[ends], np.inf)
        price[np.array([len(r) for r in routes]) >= problem.capacity] = np.inf
        price[times[:, None] + price > problem.max_time[:, None]] = np.inf
        k, target = np.unravel_index(int(np.argmin(price)), price.shape)
        if not np.isfinite(price[k, target]):
            return None
        routes[k].append(int(target))
        times[k] += price[k, target]
        ends[k] = target
        left[target] = False
    return routes


def repaired_routes(
    problem: BudgetedProblem,
    routes: list[list[int]],
    passes: int = 3,
    deadline: Deadline | None = None,
) -> list[list[int]] | None:
    """A feasible start from any routes (e.g. chapter 2's optimum, which ignores the
    limits): cut every route back until it meets its limits, insert the targets cut off
    where they cost least without breaking a limit, then move single targets while that
    lowers the total (``passes`` sweeps, cut short once ``deadline`` has expired: each move
    keeps the limits). None if a target fits nowhere (proves nothing).

    Notes
    -----
    O(passes · n · (n + m)) insertion prices; only a start for the MIP rounds.
    """
    cost = problem.cost
    n = problem.n
    routes = [list(r) for r in routes]
    loose: list[int] = []
    for k, route in enumerate(routes):
        while route and (
            len(route) > problem.capacity[k] or problem.route_cost(k, route) > problem.max_time[k]
        ):
            loose.append(route.pop())

    def best_place(target: int, exclude: tuple[int, int] | None = None) -> tuple[float, int, int]:
        best = (math.inf, -1, -1)
        for k, route in enumerate(routes):
            if len(route) + 1 > problem.capacity[k]:
                continue
            time_k = problem.route_cost(k, route)
            points = [n + k, *route]
            for q, a in enumerate(points):
                if exclude == (k, q):
                    continue
                b = route[q] if q < len(route) else None
                delta = cost[a, target] + (0.0 if b is None else cost[target, b] - cost[a, b])
                if time_k + delta <= problem.max_time[k] and delta < best[0]:
                    best = (delta, k, q)
        return best

    for target in sorted(loose, key=lambda t: -cost[:, t].min()):
        delta, k, q = best_place(target)
        if k < 0:
            return None
        routes[k].insert(q, target)
    for _ in range(passes):
        improved = False
        for target in range(n):
            if deadline is not None and deadline.expired():
                break
            k = next(v for v, route in enumerate(routes) if target in route)
            q = routes[k].index(target)
            points = [n + k, *routes[k]]
            a = points[q]
            b = routes[k][q + 1] if q + 1 < len(routes[k]) else None
            saving = cost[a, target] + (0.0 if b is None else cost[target, b] - cost[a, b])
            del routes[k][q]
            delta, k2, q2 = best_place(target)
            if k2 >= 0 and delta < saving - 1e-9:
                routes[k2].insert(q2, target)
                improved = True
            else:
                routes[k].insert(q, target)
        if not improved:
            break
    return routes if not violations(problem, routes) else None


def _as_routes(problem: BudgetedProblem, incumbent: Any) -> tuple[list[list[int]] | None, str]:
    """The incumbent's routes if they meet every constraint; else None and why not."""
    if incumbent is None:
        return None, ""
    routes = getattr(incumbent, "routes", incumbent)
    routes = [[int(t) for t in route] for route in routes]
    found = violations(problem, routes)
    if found:  # a heuristic that missed a limit: its answer is no start, and no error
        return None, "; ".join(found)
    return routes, ""


def total_time_cap(problem: BudgetedProblem) -> float | None:
    """``Σ_k T_k`` (with the scorer's tolerance) when every vehicle has a time limit, else
    None: no feasible answer takes longer in total, so a lower bound above it proves that
    no assignment meets the limits."""
    if not np.isfinite(problem.max_time).all():
        return None
    slack = TIME_TOLERANCE * np.maximum(1.0, problem.max_time)
    return float(np.sum(problem.max_time + slack)) * (1 + 1e-9)
