"""Seeded random instances of every family with an independent brute force, registered as
the brute-force checks of :mod:`reference` (``reference.brute_force``), and the independent
DP optimum of chapter 2's routing problem.

Shared by ``tests/core/test_exact_brute_force.py`` (exact methods against these),
``tests/core/test_family_checklist.py``, ``tests/routing/test_models_routing.py`` and
``tests/delivery/test_delivery_bounds.py``; found and imported by ``reference._discover``
(every ``tests/reference_*.py``), so no test module imports another.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from reference import brute_force, brute_force_delivery, brute_force_routing
from reference_budgeted import brute_force_budgeted

import taopt
from taopt import AssignmentProblem
from taopt.budgeted import BudgetedProblem
from taopt.comm.problem import random_problem

REL = 1e-6


def dp_optimum(problem: AssignmentProblem) -> float:
    """Independent exact value: Held–Karp per vehicle, then a DP over vehicles and subsets."""
    n, m, cost = problem.n, problem.m, problem.cost
    full = 1 << n
    # path[k][S] = cheapest open route of vehicle k visiting exactly the set S
    path = np.full((m, full), np.inf)
    for k in range(m):
        end = np.full((full, n), np.inf)  # end[S, j]: route over S finishing at j
        for j in range(n):
            end[1 << j, j] = cost[n + k, j]
        for subset in range(1, full):
            for j in range(n):
                if not subset >> j & 1 or not np.isfinite(end[subset, j]):
                    continue
                for nxt in range(n):
                    if subset >> nxt & 1:
                        continue
                    bigger = subset | 1 << nxt
                    end[bigger, nxt] = min(end[bigger, nxt], end[subset, j] + cost[j, nxt])
        path[k] = end.min(axis=1)
        path[k, 0] = 0.0
    best = path[0].copy()
    for k in range(1, m):
        new = np.full(full, np.inf)
        for subset in range(full):
            part = subset
            while True:  # every part of subset goes to vehicle k
                new[subset] = min(new[subset], best[subset ^ part] + path[k, part])
                if part == 0:
                    break
                part = (part - 1) & subset
        best = new
    return float(best[full - 1])


# ----------------------------------------------------------------------- generators
def _costs(rng: np.random.Generator, size: int, kind: int) -> np.ndarray:
    """Asymmetric costs: uniform reals, small integers (many ties), or 0/1 (many zeros)."""
    if kind == 0:
        return rng.uniform(0.0, 100.0, size=(size, size))
    if kind == 1:
        return rng.integers(0, 4, size=(size, size)).astype(float)
    return np.where(rng.random((size, size)) < 0.5, 0.0, 1.0)


def routing_instance(seed: int) -> taopt.AssignmentProblem:
    """1–7 targets, 1–7 vehicles (fewer vehicles for more targets), three cost kinds."""
    rng = np.random.default_rng([15, seed])
    n = int(rng.integers(1, 8))
    m = int(rng.integers(1, 8 if n <= 5 else 4))
    return taopt.AssignmentProblem(_costs(rng, n + m, seed % 3), n, name=f"rand-{seed}")


def delivery_instance(seed: int, customers: int) -> taopt.DeliveryInstance:
    """Customers on a 3×3 street grid with random precedences (a DAG by index order)."""
    rng = np.random.default_rng([16, seed])
    pairs = [(a, b) for a, b in itertools.combinations(range(customers), 2) if rng.random() < 0.3]
    return taopt.DeliveryInstance.grid(
        rng.uniform(0, 600, size=(customers, 2)),
        3,
        600.0,
        float(rng.uniform(1.0, 3.0)),
        1.0,
        float(rng.uniform(450.0, 1200.0)),  # every sortie to a nearest stop fits
        precedences=pairs,
    )


def sop_instance(seed: int) -> taopt.SopProblem:
    """4–7 nodes, start 0 and end n-1, random precedences among the inner nodes."""
    rng = np.random.default_rng([17, seed])
    n = int(rng.integers(4, 8))
    cost = _costs(rng, n, seed % 3)
    inner = range(1, n - 1)
    pairs = [(a, b) for a, b in itertools.combinations(inner, 2) if rng.random() < 0.25]
    return taopt.SopProblem(cost, pairs, 0, n - 1, name=f"sop-{seed}")


def sop_orders(problem):
    """Every feasible order of a small SOP (start and end fixed): each inner permutation
    that keeps the precedence closure and uses finite arcs only."""
    inner = [v for v in range(problem.n) if v not in (problem.start, problem.end)]
    for inner_order in itertools.permutations(inner):
        order = [problem.start, *inner_order, problem.end]
        where = {v: i for i, v in enumerate(order)}
        if all(where[a] < where[b] for a, b in problem.closure.edges()):
            if np.isfinite(problem.cost[order[:-1], order[1:]]).all():
                yield order


def assert_rows_hold(model, problem, tolerance: float = 1e-9) -> None:
    """Every cut row of ``model`` (a :class:`taopt.models.sop_cuts.SopCutModel`: the sum of
    its arcs, weighted or not, at least its side) holds on every feasible order of
    ``problem`` (:func:`sop_orders`), up to ``tolerance``."""
    for order in sop_orders(problem):
        used = np.zeros(model.n_arcs)
        used[model.arc_index[order[:-1], order[1:]]] = 1.0
        for row, side, weights in zip(
            model.cut_rows, model.cut_sides, model.cut_weights, strict=True
        ):
            lhs = used[row].sum() if weights is None else used[row] @ weights
            assert lhs >= side - tolerance, (order, row)


def sop_brute_force(problem: taopt.SopProblem) -> float:
    """Cheapest precedence-respecting path from start to end over every order of the rest."""
    inner = [v for v in range(problem.n) if v not in (problem.start, problem.end)]
    best = math.inf
    for order in itertools.permutations(inner):
        position = {v: i for i, v in enumerate(order)}
        if all(position[a] < position[b] for a, b in problem.precedences):
            path = [problem.start, *order, problem.end]
            best = min(best, sum(problem.cost[a, b] for a, b in itertools.pairwise(path)))
    return best


def capability_instance(seed: int) -> taopt.CapabilityProblem:
    """2–5 targets demanding one or both of {a, b}, 2–4 vehicles holding each at least once."""
    rng = np.random.default_rng([18, seed])
    n, m = int(rng.integers(2, 6)), int(rng.integers(2, 5))
    kinds = ["a", "b"] + [str(rng.choice(["a", "b"])) for _ in range(m - 2)]
    rng.shuffle(kinds)
    options = [{"a"}, {"b"}, {"a", "b"}]
    demands = [options[int(rng.integers(0, 3))] for _ in range(n)]
    return taopt.CapabilityProblem(_costs(rng, n + m, seed % 3), n, kinds, demands)


def capability_brute_force(problem: taopt.CapabilityProblem) -> float:
    """Sum of per-class brute-force optima (the §3.6 split)."""
    return sum(
        brute_force_routing(c.problem.cost, c.problem.n) for c in problem.classes if c.problem
    )


def comm_instance(seed: int) -> taopt.CommProblem:
    """Chapter 4: 2–6 targets, 2–4 vehicles, 1–2 attributes, random range."""
    rng = np.random.default_rng([19, seed])
    n, m = int(rng.integers(2, 7)), int(rng.integers(2, 5))
    attributes = int(rng.integers(1, 3))
    return random_problem(n, m, attributes, float(rng.uniform(50, 500)), seed=rng, side=1000.0)


def comm_brute_force(problem: taopt.CommProblem) -> float:
    """f_o: brute force per attribute class of the full-information problem."""
    full = problem.full_information()
    classes = getattr(full, "classes", None)
    if classes is None:
        return dp_optimum(full)
    return sum(dp_optimum(c.problem) for c in classes if c.problem)


def budgeted_instance(seed: int) -> BudgetedProblem:
    """§6.2: 2–6 targets, 1–3 vehicles, the three cost kinds; per vehicle a capacity and a
    time limit around its share of the targets (or none), so that on some instances a limit
    binds and on some no assignment meets the limits."""
    rng = np.random.default_rng([20, seed])
    n, m = int(rng.integers(2, 7)), int(rng.integers(1, 4))
    cost = _costs(rng, n + m, seed % 3)
    leg = float(np.median(cost)) + 1.0
    share = n / m
    capacity = [
        max(1, math.ceil(share * rng.uniform(0.5, 1.5))) if rng.random() < 0.8 else None
        for _ in range(m)
    ]
    max_time = [
        float(leg * share * rng.uniform(0.3, 1.2)) if rng.random() < 0.7 else None for _ in range(m)
    ]
    return BudgetedProblem(cost, n, capacity, max_time, name=f"budgeted-{seed}")


# -------------------------------------------------------------------------- checking
def exact_failures(cases, method: str) -> list[str]:
    """Run ``method`` without a time limit on each (problem, optimum); describe every miss.
    An infinite optimum (no assignment within a family's limits) must be status
    "infeasible" with no answer."""
    failures = []
    for problem, optimum in cases:
        solution = taopt.solve(problem, method)
        if math.isinf(optimum):
            if solution.status != "infeasible" or solution.solution is not None:
                failures.append(
                    f"{problem.name}: {solution.status} {solution.objective}, brute force: "
                    "no assignment within the limits"
                )
            continue
        value = taopt.evaluate(problem, solution.solution)
        tolerance = REL * max(1.0, abs(optimum))
        if (
            solution.status != "optimal"
            or abs(solution.objective - optimum) > tolerance
            or abs(value - optimum) > tolerance
            or solution.bound is None
            or solution.bound > optimum + tolerance
        ):
            failures.append(
                f"{getattr(problem, 'name', '') or problem!r}: {solution.status} "
                f"{solution.objective} (bound {solution.bound}), brute force {optimum}"
            )
    return failures


# the checks (reference.brute_force registers each; a family added later lists its own as
# BRUTE_FORCE in tests/reference_<family>.py). Default run: 270 instances; slow run: 2,670
# more (seeds after the default run's).
@brute_force("routing", "exact", fast=100, slow=1200)
def _routing_cases(seeds):
    return [(p, dp_optimum(p)) for p in map(routing_instance, seeds)]


def _delivery_cases(seeds, customers):
    cases = []
    for seed in seeds:
        instance = delivery_instance(seed, customers(seed))
        cases.append((instance, brute_force_delivery(instance)))
    return cases


@brute_force("dp", "exact", fast=30, slow=250)
def _dp_cases(seeds):
    return _delivery_cases(seeds, lambda s: 3 + s % 4)


@brute_force("milp", "milp", fast=10, slow=60)
def _milp_cases(seeds):
    return _delivery_cases(seeds, lambda s: 2 + s % 2)


@brute_force("sop", "exact", fast=40, slow=250)
def _sop_cases(seeds):
    return [(p, sop_brute_force(p)) for p in map(sop_instance, seeds)]


@brute_force("capability", "exact", fast=20, slow=150)
def _capability_cases(seeds):
    return [(p, capability_brute_force(p)) for p in map(capability_instance, seeds)]


@brute_force("joint", "joint", fast=10, slow=60)
def _joint_cases(seeds):
    return _capability_cases(seeds)


@brute_force("comm", "exact", fast=20, slow=100)
def _comm_cases(seeds):
    return [(p, comm_brute_force(p)) for p in map(comm_instance, seeds)]


@brute_force("budgeted", "exact", fast=40, slow=600)
def _budgeted_cases(seeds):
    return [(p, brute_force_budgeted(p)) for p in map(budgeted_instance, seeds)]
