"""Reference problems of the budgeted family (capacities and travel-time limits, thesis §6.2),
each with its optimum by an independent brute force over every assignment and order."""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any

import numpy as np

from taopt.budgeted import BudgetedProblem


def brute_force_budgeted(problem: BudgetedProblem) -> float:
    """min over every split of the targets into one ordered open route per vehicle that meets
    Q_k and T_k: the total travel time (inf when none does)."""
    n, m, cost = problem.n, problem.m, problem.cost
    best = np.inf
    for owner in itertools.product(range(m), repeat=n):
        groups = [[j for j in range(n) if owner[j] == k] for k in range(m)]
        if any(len(g) > problem.capacity[k] for k, g in enumerate(groups)):
            continue
        total = 0.0
        for k, group in enumerate(groups):
            route_best = np.inf
            for order in itertools.permutations(group):
                at, length = n + k, 0.0
                for j in order:
                    length, at = length + cost[at, j], j
                if length <= problem.max_time[k] + 1e-9:
                    route_best = min(route_best, length)
            total += route_best
        best = min(best, total)
    return float(best)


def budgeted_small() -> Any:
    """Six targets, two vehicles; vehicle 1 may serve at most 4 targets (unlimited, it serves
    all six) and vehicle 0 travel at most 90 s (both limits bind)."""
    from reference import Reference  # (reference.py imports this module to collect REFERENCES)

    rng = np.random.default_rng(17)
    points = rng.uniform(0, 100, size=(8, 2))
    drift = np.array([0.3, -0.1])
    diff = points[None, :, :] - points[:, None, :]
    cost = np.hypot(*diff.transpose(2, 0, 1)) * (1 + 0.2 * np.sign(diff @ drift))
    problem = BudgetedProblem(cost, n_targets=6, capacity=[None, 4], max_time=[90.0, None])
    return Reference(
        "budgeted-small", problem, brute_force_budgeted(problem), "brute force (tests)"
    )


REFERENCES: list[Callable[[], Any]] = [budgeted_small]
