"""Exact model of the budgeted family: (2.2)–(2.5) plus capacity and travel-time rows.

Thesis §2.2.1 (2.2)–(2.5) with §6.2's limits (:class:`~taopt.budgeted.BudgetedProblem`):
vehicle k serves at most ``Q_k`` targets and travels at most ``T_k``.

Form: a three-index (arc, vehicle) model
-----------------------------------------
One binary ``x[i, j, k]`` per arc ``i -> j`` (``j`` a target) and vehicle ``k``: arcs out
of a target for every vehicle, arcs out of a start point only for its own vehicle. With
``in_k(j) = Σ_i x[i, j, k]`` and ``out_k(j) = Σ_l x[j, l, k]``:

* (2.2) ``min Σ t(i, j) x[i, j, k]``
* (2.3) ``Σ_k in_k(j) = 1`` for every target j
* (2.4) ``out_k(j) <= in_k(j)`` for every target j and vehicle k (a vehicle leaves only a
  target it entered; summed over k this is (2.4), and it keeps a route on one vehicle),
  and ``Σ_j x[p_k, j, k] <= 1`` at every start point
* capacity ``Σ_{i,j} x[i, j, k] <= Q_k`` (each arc of k enters one target of k)
* travel time ``Σ_{i,j} t(i, j) x[i, j, k] <= T_k``
* (2.5) DFJ rows on the aggregated ``σ_ij = Σ_k x[i, j, k]``, added lazily: the root LP is
  separated exactly (:func:`taopt.models.routing.separate_subtours`, rows written by
  :func:`taopt.models.routing.cut_rows`), then MIP rounds add the cycles of every
  solution HiGHS reports until the round's optimum has none.

Why this form: both limits are plain rows of the LP (no big-M, no arrival-time variable),
so the LP bound sees them and the MIP rounds never return a limit-violating answer; only
(2.5) is lazy, as in chapter 2, and every row of the model is valid for every feasible
solution, so a MIP that HiGHS proves infeasible is a proof that no assignment meets the
limits. The alternatives considered: an assignment ``y[j, k]`` linked to chapter 2's
two-index σ (``σ_ij + y_ik - y_jk <= 1``: ``n^2 m`` rows, and the travel time still needs
arc–vehicle products); MTZ arrival times (big-M, a weak LP); infeasible-path cuts on the
two-index model (one cut removes one path: many rounds when a limit binds). Columns that
cannot be on a feasible route of vehicle k are never created
(:func:`taopt.budgeted.bounds.usable_arcs`): ``x[i, j, k]`` is dropped when
``d_k(i) + t(i, j) > T_k``, ``d_k`` the shortest travel time from ``p_k``, every
target-to-target arc of k when ``Q_k <= 1``, and all of k's columns when ``Q_k = 0``.
Measurements (n50m10 drift scenarios, ``benchmarks/bench_budgeted.py``) are in
``docs/families/budgeted.md``.

Reused from chapter 2 (:mod:`taopt.models.routing`): the arc list, exact separation and
row writing of (2.5), the Karp patching of a MIP answer's cycles, the first bounds; and
the live HiGHS model (:class:`taopt.models.highs.HighsModel`) with its status rule
:func:`taopt.status.decide` (through :func:`taopt.result.finish`). A problem without any finite limit is chapter 2's:
it is solved by :func:`~taopt.models.routing.solve_routing` on ``problem.routing``.

References
----------
Thesis §2.2.1 (2.2)–(2.5), §6.2.
"""

from __future__ import annotations

import bisect
import math
import time
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from taopt.budgeted.bounds import shortest_times, usable_arcs
from taopt.budgeted.problem import (
    TIME_TOLERANCE,
    BudgetedProblem,
    evaluate_budgeted,
    violations,
)
from taopt.errors import InstanceError, SolverError, require
from taopt.models.highs import OPTIMALITY_TOLERANCE, HighsModel, relative_gap
from taopt.models.routing import (
    HIGHS_OVERRUN,
    arc_list,
    assignment_bound,
    cut_rows,
    decode,
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


class BudgetedModel:
    """The three-index model (module docstring) on one live HiGHS model.

    Attributes
    ----------
    arc : (columns,) int array
        Index of each column's arc in chapter 2's arc list (``tails``, ``heads``).
    vehicle : (columns,) int array
        Each column's vehicle.
    aggregate : (arcs, columns) csr_matrix
        σ = ``aggregate @ x``: the two-index arc values of a column vector.
    """

    def __init__(self, problem: BudgetedProblem, verbose: bool = False) -> None:
        self.problem = problem
        n, m = problem.n, problem.m
        routing = problem.routing
        self.tails, self.heads = arc_list(routing)
        arcs = np.arange(len(self.tails))
        usable = usable_arcs(problem)
        arc_parts, vehicle_parts = [], []
        for k in range(m):
            own = usable[k, self.tails, self.heads]
            arc_parts.append(arcs[own])
            vehicle_parts.append(np.full(int(own.sum()), k))
        self.arc = np.concatenate(arc_parts) if arc_parts else np.zeros(0, dtype=np.int64)
        self.vehicle = (
            np.concatenate(vehicle_parts) if vehicle_parts else np.zeros(0, dtype=np.int64)
        )
        columns = len(self.arc)
        self.n_columns = columns
        tail, head = self.tails[self.arc], self.heads[self.arc]
        cost = routing.cost[tail, head]
        index = np.arange(columns)
        self.aggregate = sp.csr_matrix(
            (np.ones(columns), (self.arc, index)), shape=(len(self.tails), columns)
        )
        blocks, lower, upper = [], [], []
        # (2.3): every target entered once, over all vehicles
        blocks.append(sp.csr_matrix((np.ones(columns), (head, index)), shape=(n, columns)))
        lower.append(np.ones(n))
        upper.append(np.ones(n))
        # (2.4) per vehicle: out_k(j) - in_k(j) <= 0 (row j * m + k)
        target_tail = tail < n
        rows = np.concatenate(
            [tail[target_tail] * m + self.vehicle[target_tail], head * m + self.vehicle]
        )
        cols = np.concatenate([index[target_tail], index])
        data = np.concatenate([np.ones(int(target_tail.sum())), -np.ones(columns)])
        blocks.append(sp.csr_matrix((data, (rows, cols)), shape=(n * m, columns)))
        lower.append(np.full(n * m, -np.inf))
        upper.append(np.zeros(n * m))
        # (2.4) at the start points: each vehicle leaves its start at most once
        start = ~target_tail
        blocks.append(
            sp.csr_matrix(
                (np.ones(int(start.sum())), (self.vehicle[start], index[start])),
                shape=(m, columns),
            )
        )
        lower.append(np.full(m, -np.inf))
        upper.append(np.ones(m))
        # capacity and travel time, one row per vehicle with a finite limit
        for limits, weights in ((problem.capacity, np.ones(columns)), (problem.max_time, cost)):
            limited = np.flatnonzero(np.isfinite(limits))
            if len(limited) == 0:
                continue
            position = np.full(m, -1)
            position[limited] = np.arange(len(limited))
            keep = position[self.vehicle] >= 0
            blocks.append(
                sp.csr_matrix(
                    (weights[keep], (position[self.vehicle[keep]], index[keep])),
                    shape=(len(limited), columns),
                )
            )
            lower.append(np.full(len(limited), -np.inf))
            upper.append(limits[limited])
        self.model = HighsModel.from_arrays(
            cost=cost,
            matrix=sp.vstack(blocks).tocsr(),
            lower=np.concatenate(lower),
            upper=np.concatenate(upper),
            column_lower=np.zeros(columns),
            column_upper=np.ones(columns),
            integers=index,
            verbose=verbose,
        )
        self.column_of = np.full((m, len(self.tails)), -1, dtype=np.int64)
        self.column_of[self.vehicle, self.arc] = index
        self.arc_index = np.full((n + m, n), -1, dtype=np.int64)
        self.arc_index[self.tails, self.heads] = arcs
        self._known: set[tuple[int, ...]] = set()
        self.cuts: list[tuple[int, ...]] = []
        self._known_capacity: set[tuple[tuple[int, ...], int]] = set()
        self.capacity_cuts: list[tuple[tuple[int, ...], int]] = []

    def sigma(self, solution: np.ndarray) -> np.ndarray:
        """Chapter 2's σ (one value per two-index arc) of a column vector."""
        return self.aggregate @ np.asarray(solution, dtype=float)

    def add_cuts(self, cuts: list[tuple[int, ...]]) -> int:
        """Add the (2.5) rows of the subsets not in the model yet; returns how many."""
        new = []
        for subset in cuts:
            subset = tuple(sorted(int(v) for v in subset))
            if len(subset) >= 2 and subset not in self._known:
                self._known.add(subset)
                new.append(subset)
        if new:
            rows, low, high = cut_rows(self.problem.routing, new, self.tails, self.heads)
            self.model.add_rows(rows @ self.aggregate, low, high)
            self.cuts.extend(new)
        return len(new)

    def add_capacity_cuts(self, cuts: list[tuple[tuple[int, ...], int]]) -> int:
        """Add rounded capacity rows (:func:`separate_capacity`) not in the model yet."""
        new = [(subset, k) for subset, k in cuts if (subset, k) not in self._known_capacity]
        if new:
            self._known_capacity.update(new)
            rows, low, high = capacity_rows(self.problem, new, self.tails, self.heads)
            self.model.add_rows(rows @ self.aggregate, low, high)
            self.capacity_cuts.extend(new)
        return len(new)

    def start_vector(self, routes: list[list[int]]) -> np.ndarray | None:
        """The column vector of ``routes`` (None if a route uses a column not in the model)."""
        vector = np.zeros(self.n_columns)
        n = self.problem.n
        for k, route in enumerate(routes):
            points = [n + k, *route]
            columns = self.column_of[k, self.arc_index[points[:-1], points[1:]]]
            if (columns < 0).any():
                return None
            vector[columns] = 1.0
        return vector

    def decode(self, solution: np.ndarray) -> tuple[list[list[int]], list[list[int]]] | None:
        """Routes (from each start, on its own vehicle's columns) and leftover cycles of an
        integral column vector; None if it is not integral enough to read."""
        n = self.problem.n
        used = np.flatnonzero(np.asarray(solution) > 0.5)
        successor: dict[int, int] = {}
        for column in used:
            a = int(self.arc[column])
            tail = int(self.tails[a])
            if tail in successor:
                return None
            successor[tail] = int(self.heads[a])
        routes, reached = [], set()
        for k in range(self.problem.m):
            route, point = [], n + k
            while point in successor:
                point = successor[point]
                if point in reached:
                    return None
                route.append(point)
                reached.add(point)
            routes.append(route)
        cycles = []
        for first in range(n):
            if first in reached:
                continue
            cycle, point = [], first
            while point not in reached:
                reached.add(point)
                cycle.append(point)
                if point not in successor:
                    return None
                point = successor[point]
            cycles.append(cycle)
        return routes, cycles


class ResourceModel:
    """Chapter 2's two-index model with one capacity and one time resource per target.

    Columns: σ of chapter 2's arcs (:func:`~taopt.models.routing.arc_list`), then
    ``r_j`` (capacity left after serving j, ``0 <= r_j <= Q - 1``) if a vehicle has a
    capacity, then ``s_j`` (travel time left on arrival at j, ``0 <= s_j <= T``) if a
    vehicle has a time limit; ``Q``, ``T`` the largest effective limits (an unlimited
    capacity counts as n, an unlimited time as ``Σ_j max_i t(i, j)``, more than any open
    route takes). Rows: (2.3), (2.4), and

    * ``r_j + (Q − Q_k) σ[p_k, j] <= Q − 1`` (a route of k starts with ``Q_k − 1`` left),
    * ``r_j − r_i + Q σ_ij + (Q − 2) σ_ji <= Q − 1`` (one unit per target; the σ_ji term
      is Desrochers and Laporte's lifting),
    * ``s_j + (U_j − T_k + t(p_k, j)) σ[p_k, j] <= U_j`` and
      ``s_j − s_i + (U_j + t(i, j)) σ_ij <= U_j`` (the time left falls by t(i, j) on each
      leg), with ``s_j <= U_j = max_k (T_k − d_k(j))``, ``d_k`` the shortest time from
      ``p_k`` (:func:`~taopt.budgeted.bounds.shortest_times`): no route arrives at j with
      more time left, so ``U_j`` is a valid big-M, smaller than T (on the drift n50m10
      scenario 0 with ``T_k = 2 f0/m`` alone it raised the root LP bound from 4440 to 4471).

    For an integral σ these hold exactly when every route meets its limits (set r and s
    along each route); the r rows also forbid every cycle among targets, the s rows every
    cycle of positive travel time. Arcs no vehicle may use (:func:`usable_arcs`) are fixed
    to 0; an arc out of ``p_k`` is usable only by k.
    """

    def __init__(self, problem: BudgetedProblem, verbose: bool = False) -> None:
        self.problem = problem
        n, m = problem.n, problem.m
        routing = problem.routing
        self.tails, self.heads = arc_list(routing)
        n_arcs = len(self.tails)
        self.arcs = np.arange(n_arcs)
        cost = routing.cost[self.tails, self.heads]
        usable = usable_arcs(problem)
        is_start = self.tails >= n
        allowed = np.where(
            is_start,
            usable[np.clip(self.tails - n, 0, m - 1), self.tails, self.heads],
            usable.any(axis=0)[self.tails, self.heads],
        )
        size = n + m
        index = self.arcs
        blocks = [
            sp.csr_matrix((np.ones(n_arcs), (self.heads, index)), shape=(n, n_arcs)),
            sp.csr_matrix((np.ones(n_arcs), (self.tails, index)), shape=(size, n_arcs)),
        ]
        lower = [np.ones(n), np.full(size, -np.inf)]
        upper = [np.ones(n), np.ones(size)]
        column_upper = [allowed.astype(float)]
        costs = [cost]
        reverse = np.full(n_arcs, -1, dtype=np.int64)  # arc j -> i of each target arc i -> j
        inner = np.flatnonzero(~is_start)
        arc_index = np.full((size, n), -1, dtype=np.int64)
        arc_index[self.tails, self.heads] = index
        reverse[inner] = arc_index[self.heads[inner], self.tails[inner]]
        starts = np.flatnonzero(is_start)
        vehicle = self.tails[starts] - n
        capacity = np.minimum(problem.capacity, n)
        time_cap = float(routing.cost[:, :n].max(axis=0).sum())
        duration = np.minimum(problem.max_time, time_cap)
        self.limits = {"capacity": capacity, "time": duration}
        #: resource name -> first column of its n values
        self.offsets: dict[str, int] = {}
        extra = []  # (rows as (data, row, column) triplets, row count, right-hand side)
        columns = n_arcs
        for name, limits, active in (
            ("capacity", capacity, bool((capacity < n).any())),
            ("time", duration, problem.has_max_time),
        ):
            if not active:
                continue
            offset, top = columns, float(limits.max())
            self.offsets[name] = offset
            columns += n
            if name == "capacity":
                column_upper.append(np.full(n, max(top - 1.0, 0.0)))
                start_coef, start_rhs = top - limits[vehicle], top - 1.0
                inner_coef, inner_rhs, lift = np.full(len(inner), top), top - 1.0, top - 2.0
            else:
                # time left on arrival at j: at most U_j = max_k (T_k − d_k(j)), d_k the
                # shortest time from p_k; the big-M of each row is U of its head
                reach = shortest_times(problem)[:, :n]
                most = np.clip((limits[:, None] - reach).max(axis=0), 0.0, top)
                column_upper.append(most)
                start_rhs = most[self.heads[starts]]
                start_coef = np.maximum(start_rhs - limits[vehicle] + cost[starts], 0.0)
                inner_rhs = most[self.heads[inner]]
                inner_coef, lift = inner_rhs + cost[inner], 0.0
            costs.append(np.zeros(n))
            # start rows: resource_j + coef σ[p_k, j] <= rhs
            count = len(starts)
            rows = np.tile(np.arange(count), 2)
            cols = np.concatenate([offset + self.heads[starts], starts])
            extra.append(
                ((np.concatenate([np.ones(count), start_coef]), rows, cols), count, start_rhs)
            )
            # inner rows: resource_j − resource_i + coef σ_ij (+ lift σ_ji) <= rhs
            count = len(inner)
            data = [np.ones(count), -np.ones(count), inner_coef]
            cols = [offset + self.heads[inner], offset + self.tails[inner], inner]
            if lift > 0:
                data.append(np.full(count, lift))
                cols.append(reverse[inner])
            rows = np.tile(np.arange(count), len(data))
            extra.append(((np.concatenate(data), rows, np.concatenate(cols)), count, inner_rhs))
        self.n_columns = columns
        pad = columns - n_arcs
        matrix = [sp.hstack([b, sp.csr_matrix((b.shape[0], pad))]) for b in blocks]
        for (data, rows, cols), count, rhs in extra:
            matrix.append(sp.csr_matrix((data, (rows, cols)), shape=(count, columns)))
            lower.append(np.full(count, -np.inf))
            upper.append(np.broadcast_to(np.asarray(rhs, dtype=float), (count,)).copy())
        self.model = HighsModel.from_arrays(
            cost=np.concatenate(costs),
            matrix=sp.vstack(matrix).tocsr(),
            lower=np.concatenate(lower),
            upper=np.concatenate(upper),
            column_lower=np.zeros(columns),
            column_upper=np.concatenate(column_upper),
            integers=index,
            verbose=verbose,
        )
        self.arc_index = arc_index
        self._known: set[tuple[int, ...]] = set()
        self.cuts: list[tuple[int, ...]] = []
        self._known_capacity: set[tuple[tuple[int, ...], int]] = set()
        self.capacity_cuts: list[tuple[tuple[int, ...], int]] = []

    def sigma(self, solution: np.ndarray) -> np.ndarray:
        """σ (one value per arc) of a column vector."""
        return np.asarray(solution, dtype=float)[: len(self.tails)]

    def add_cuts(self, cuts: list[tuple[int, ...]]) -> int:
        """Add the (2.5) rows of the subsets not in the model yet; returns how many."""
        new = []
        for subset in cuts:
            subset = tuple(sorted(int(v) for v in subset))
            if len(subset) >= 2 and subset not in self._known:
                self._known.add(subset)
                new.append(subset)
        if new:
            rows, low, high = cut_rows(self.problem.routing, new, self.tails, self.heads)
            pad = sp.csr_matrix((rows.shape[0], self.n_columns - len(self.tails)))
            self.model.add_rows(sp.hstack([rows, pad]).tocsr(), low, high)
            self.cuts.extend(new)
        return len(new)

    def add_capacity_cuts(self, cuts: list[tuple[tuple[int, ...], int]]) -> int:
        """Add rounded capacity rows (:func:`separate_capacity`) not in the model yet."""
        new = [(subset, k) for subset, k in cuts if (subset, k) not in self._known_capacity]
        if new:
            self._known_capacity.update(new)
            rows, low, high = capacity_rows(self.problem, new, self.tails, self.heads)
            pad = sp.csr_matrix((rows.shape[0], self.n_columns - len(self.tails)))
            self.model.add_rows(sp.hstack([rows, pad]).tocsr(), low, high)
            self.capacity_cuts.extend(new)
        return len(new)

    def start_vector(self, routes: list[list[int]]) -> np.ndarray | None:
        """σ, r and s of ``routes`` as a MIP start."""
        n = self.problem.n
        vector = np.zeros(self.n_columns)
        cost = self.problem.cost
        for k, route in enumerate(routes):
            points = np.array([n + k, *route], dtype=np.int64)
            vector[self.arc_index[points[:-1], points[1:]]] = 1.0
            if "capacity" in self.offsets:
                offset = self.offsets["capacity"]
                left = self.limits["capacity"][k] - np.arange(1, len(route) + 1)
                vector[offset + points[1:]] = np.maximum(left, 0.0)
            if "time" in self.offsets:
                offset = self.offsets["time"]
                spent = np.cumsum(cost[points[:-1], points[1:]])
                vector[offset + points[1:]] = np.maximum(self.limits["time"][k] - spent, 0.0)
        return vector

    def route_arcs(self, routes: list[list[int]]) -> np.ndarray:
        """Arc indices (= σ columns) used by ``routes``."""
        n = self.problem.n
        arcs = [
            self.arc_index[[n + k, *route][:-1], route] for k, route in enumerate(routes) if route
        ]
        return np.concatenate(arcs) if arcs else np.zeros(0, dtype=np.int64)

    def decode(self, solution: np.ndarray) -> tuple[list[list[int]], list[list[int]]] | None:
        """Routes and leftover cycles of an integral σ; None if it cannot be read."""
        try:
            return decode(self.problem.routing, self, self.sigma(solution))
        except SolverError:
            return None


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
    e_j)`` (:func:`route_counts`, :func:`time_counts`, ``e = entry`` from
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
        members = [seed]
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
            members.append(j)
            link += joined[j]
            size = len(members)
            k = need(size, time_sum)
            violation = k - (size - inside_sum)
            if k >= 2 and violation > best:
                best, best_members, best_need = violation, list(members), k
        if best_members is not None:
            found[tuple(sorted(best_members))] = best_need
    return sorted(found.items())


def capacity_rows(
    problem: BudgetedProblem,
    cuts: list[tuple[tuple[int, ...], int]],
    tails: np.ndarray,
    heads: np.ndarray,
) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
    """Rows of rounded capacity inequalities, each in its sparser equivalent form:
    ``σ(δ⁻(S)) >= k`` or, by (2.3), ``σ(A(S)) <= |S| − k`` (as :func:`cut_rows`)."""
    size = problem.n + problem.m
    rows, columns = [], []
    lower = np.empty(len(cuts))
    upper = np.empty(len(cuts))
    for r, (subset, k) in enumerate(cuts):
        inside = np.zeros(size, dtype=bool)
        inside[list(subset)] = True
        s = len(subset)
        if s * (s - 1) <= (size - s) * s:
            arcs = np.flatnonzero(inside[tails] & inside[heads])
            lower[r], upper[r] = -np.inf, s - k
        else:
            arcs = np.flatnonzero(~inside[tails] & inside[heads])
            lower[r], upper[r] = float(k), np.inf
        rows.append(np.full(len(arcs), r))
        columns.append(arcs)
    matrix = sp.csr_matrix(
        (
            np.ones(sum(len(c) for c in columns)),
            (np.concatenate(rows) if rows else [], np.concatenate(columns) if columns else []),
        ),
        shape=(len(cuts), len(tails)),
    )
    return matrix, lower, upper


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

    def best_place(target: int, exclude: tuple[int, int] | None = None):
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
    route-count inequalities ``σ(δ⁻(S)) >= k(S)`` (:func:`separate_capacity`: k(S) from
    the capacities, :func:`route_counts`, and, with ``time_cuts``, from the time limits,
    :func:`time_counts`) separated heuristically, round after round until neither finds
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
    best_routes = given
    best_value = math.inf if given is None else evaluate_budgeted(problem, given)
    # every vehicle time-limited: a feasible answer's total is at most Σ_k T_k (the
    # scorer's tolerance included), a cut-off for the MIP rounds and, below a proven lower
    # bound, a proof that no assignment meets the limits
    cutoff = total_time_cap(problem)
    best_bound = max(entry_bound(problem.routing), arborescence_bound(problem.routing))
    if not deadline.limited or deadline.remaining() > 3e-10 * n**2 * (n + m):
        best_bound = max(best_bound, assignment_bound(problem.routing))
    # chapter 2's optimum without the limits: a valid bound (limits only remove solutions)
    # and, cut back to the limits and repaired, a start
    free = solve_routing(problem.routing, time_limit=deadline.share(0.2), max_rounds=max_rounds)
    if free.bound is not None:
        best_bound = max(best_bound, free.bound)
    info["unlimited_optimum"] = free.objective if free.status == "optimal" else None
    if cutoff is not None and best_bound > cutoff:
        return _too_long(problem, best_bound, cutoff, deadline, info)
    improved = 0

    def consider_start(routes: list[list[int]] | None) -> None:
        """Keep ``routes`` if it beats the incumbent, after ``improve`` (when given and time
        allows); each plan is scored once."""
        nonlocal best_routes, best_value, improved
        if routes is None:
            return
        value = evaluate_budgeted(problem, routes)
        left = deadline.remaining()
        if improve is not None and (left is None or left >= IMPROVE_MIN_SECONDS):
            found = [[int(t) for t in route] for route in improve(problem, routes)]
            broken = violations(problem, found)
            if broken:
                raise SolverError(
                    f"improve returned routes outside the limits: {'; '.join(broken)}"
                )
            found_value = evaluate_budgeted(problem, found)
            if found_value < value:
                routes, value, improved = found, found_value, improved + 1
        if value < best_value:
            best_routes, best_value = routes, value

    consider_start(best_routes)
    if not deadline.expired():  # each further start only when time is left for it
        consider_start(greedy_budgeted(problem))
    if free.routes is not None and not deadline.expired():
        consider_start(repaired_routes(problem, free.routes, deadline=deadline))

    def stop(stopped_by: str, extra: dict[str, Any]) -> Solution:
        info.update(extra, mip_gap=mip_gap, improved=improved)
        return finish(
            problem,
            None if best_routes is None else Routes(best_routes),
            method="exact-budgeted",
            stop=stopped_by,
            bound=best_bound,
            runtime=deadline.elapsed(),
            info=info,
        )

    if deadline.limited and deadline.remaining() < SECONDS_PER_COLUMN * (n + 1) * n * m:
        return stop("time_limit", {"stage": "build"})
    model = (ResourceModel if form == "resource" else BudgetedModel)(problem, verbose=verbose)
    info.update(columns=model.n_columns, rows=model.model.n_rows)
    # 1. root LP, (2.5) separated exactly, at most half of the time left
    model.model.relax(True)
    entry = entry_times(problem) if time_cuts else None
    root_rounds, root_bound = 0, -math.inf
    root_sigma: np.ndarray | None = None
    root_reduced: np.ndarray | None = None
    budget = deadline.share(0.5)
    root_end = None if budget is None else time.perf_counter() + budget
    try:
        while True:
            left = None if root_end is None else root_end - time.perf_counter()
            if left is not None and left < SECONDS_PER_COLUMN * model.n_columns:
                break
            root_rounds += 1
            run = model.model.solve(time_limit=left)
            if run.solver_status == "infeasible":
                break  # the MIP below proves it
            if run.solver_status != "optimal" or run.objective is None:
                break
            root_bound, root_reduced = model.model.lagrangian_bound()
            sigma = model.sigma(model.model.highs.getSolution().col_value)
            root_sigma = sigma
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
    best_bound = max(best_bound, root_bound)
    if cutoff is not None and best_bound > cutoff:
        return _too_long(problem, best_bound, cutoff, deadline, info)
    info.update(root_rounds=root_rounds, root_cuts=len(model.cuts), lp_bound=root_bound,
                root_seconds=deadline.elapsed(),
                capacity_cuts=len(model.capacity_cuts))  # fmt: skip
    if lp_start and root_sigma is not None:
        # an LP-guided start: chapter 2's optimum on travel times scaled by 1 − σ of the
        # root LP (arcs the LP uses are cheap), cut back to the limits and repaired
        scale = np.ones_like(problem.cost)
        scale[model.tails, model.heads] = 1.0 - 0.9 * np.clip(root_sigma, 0.0, 1.0)
        guided = solve_routing(problem.routing.replace(cost=problem.cost * scale),
                               time_limit=deadline.share(0.1), max_rounds=50)  # fmt: skip
        start = None if guided.routes is None else repaired_routes(problem, guided.routes)
        if start is not None:
            info["lp_start"] = evaluate_budgeted(problem, start)
            consider_start(start)
    fixed = 0
    if form == "resource" and math.isfinite(root_bound) and best_routes is not None:
        # reduced-cost fixing: a solution using arc a costs at least L + d_a
        # (HighsModel.lagrangian_bound), so an arc with L + d_a > UB is in no solution
        # better than the incumbent; the incumbent's own arcs stay
        if root_reduced is not None:
            arcs = root_reduced[: len(model.tails)]
            slack = 1e-9 * max(1.0, abs(best_value))
            off = arcs > best_value - root_bound + slack
            off[model.route_arcs(best_routes)] = False
            off &= model.model.column_upper[: len(model.tails)] > 0
            model.model.set_upper(np.flatnonzero(off), 0.0)
            fixed = int(off.sum())
    info["fixed_arcs"] = fixed
    # 2. MIP rounds
    harvested: list[tuple[int, ...]] = []
    candidates: list[tuple[float, list[list[int]]]] = []

    def consider(solution: np.ndarray) -> list[list[int]]:
        """Cycles of a MIP solution (harvested as cuts); a feasible patch is a candidate."""
        read = model.decode(solution)
        if read is None:
            return []
        routes, cycles = read
        if cycles:
            routes = repair(problem.routing, routes, cycles)
        if not violations(problem, routes):
            candidates.append((evaluate_budgeted(problem, routes), routes))
        return cycles

    # improve_during: an answer HiGHS finds that beats every answer seen is improved at once
    # and the result offered back to HiGHS at its next call for a user solution
    offered: dict[str, Any] = {"value": best_value, "routes": None, "broken": None, "count": 0}

    def harvest(solution: np.ndarray) -> None:
        count = len(candidates)
        harvested.extend(tuple(sorted(c)) for c in consider(solution))
        if not improve_during or improve is None or len(candidates) == count:
            return
        value, routes = candidates[-1]
        left = deadline.remaining()
        if value >= offered["value"] or (left is not None and left < IMPROVE_MIN_SECONDS):
            return
        offered["value"] = value
        found = [[int(t) for t in route] for route in improve(problem, routes)]
        broken = violations(problem, found)
        if broken:
            offered["broken"] = broken  # raised after the run (not inside HiGHS's callback)
            return
        found_value = evaluate_budgeted(problem, found)
        if found_value < value:
            candidates.append((found_value, found))
            offered.update(value=found_value, routes=found, count=offered["count"] + 1)

    def offer() -> np.ndarray | None:
        routes, offered["routes"] = offered["routes"], None
        return None if routes is None else model.start_vector(routes)

    target_gap = max(float(mip_gap), OPTIMALITY_TOLERANCE)
    rounds, stopped_by, nodes = 0, "time_limit", 0
    if best_routes is not None and relative_gap(best_value, min(best_bound, best_value)) <= (
        target_gap
    ):  # a start meets the root bound: proven without a MIP
        return stop("optimal", {"rounds": 0, "cuts": len(model.cuts), "nodes": 0, "offered": 0})
    while True:
        left = deadline.remaining()
        if left is not None and left < SECONDS_PER_COLUMN * model.n_columns + HIGHS_OVERRUN:
            stopped_by = "time_limit"
            break
        if rounds >= max_rounds:
            stopped_by = "max_rounds"
            break
        rounds += 1
        if best_routes is not None:
            start = model.start_vector(best_routes)
            if start is not None:
                model.model.set_start(start)
        harvested.clear()
        candidates.clear()
        offered.update(value=min(offered["value"], best_value), routes=None)
        options = dict(MIP_OPTIONS)
        if cutoff is not None:
            options["objective_bound"] = cutoff
        run = model.model.solve(
            time_limit=None if left is None else max(left - HIGHS_OVERRUN, 1e-3),
            mip_rel_gap=mip_gap,
            on_solution=harvest,
            options=options,
            offer=offer if improve_during and improve is not None else None,
        )
        if offered["broken"]:
            raise SolverError(
                f"improve returned routes outside the limits: {'; '.join(offered['broken'])}"
            )
        if run.solver_status == "infeasible":
            if best_routes is not None:  # cannot be: every feasible solution is in the model
                raise SolverError(
                    "HiGHS calls the budgeted model infeasible below a known solution"
                )
            proof = "HiGHS proved the model infeasible; every row is valid"
            if cutoff is not None:
                proof += (
                    f" (searched below the cut-off Σ_k T_k = {cutoff:.6g}, the most a "
                    "feasible answer's total can be)"
                )
            info.update(rounds=rounds, cuts=len(model.cuts))
            return _infeasible(problem, proof, deadline, info)
        if run.solver_status not in ("optimal", "user_limit"):
            raise SolverError(f"HiGHS returned status {run.solver_status!r} on the budgeted model")
        if run.bound is not None:
            best_bound = max(best_bound, run.bound)
        nodes += max(run.nodes, 0)
        cycles: list[list[int]] = []
        if run.has_point:
            cycles = consider(np.asarray(model.model.highs.getSolution().col_value))
        if candidates:  # the round's best answer, improved
            consider_start(min(candidates, key=lambda pair: pair[0])[1])
        model.add_cuts([*map(tuple, cycles), *harvested])
        stopped_by = run.stopped_by
        if (
            best_routes is not None
            and relative_gap(best_value, min(best_bound, best_value)) <= target_gap
        ):
            break
        if run.stopped_by in ("time_limit", "solver_limit"):
            break
        if run.has_point and not cycles and run.stopped_by == "optimal":
            break  # cannot happen with an open gap: the answer is feasible and optimal
        if not run.has_point and not harvested:  # nothing learned: the next round is this one
            raise SolverError(
                f"HiGHS stopped with status {run.solver_status!r}, no answer and no proof "
                "on the budgeted model"
            )
    return stop(
        stopped_by,
        {"rounds": rounds, "cuts": len(model.cuts), "nodes": nodes, "offered": offered["count"]},
    )


@register_footprint(BudgetedProblem, "exact")
def _budgeted_footprint(problem: BudgetedProblem, options: dict[str, Any]) -> tuple[float, str]:
    """The three-index model has at most (n + 1) n m columns."""
    columns = float(problem.n + 1) * problem.n * problem.m
    return milp_bytes(columns), (
        f"the budgeted exact model of {problem.n:,} targets and {problem.m} vehicles "
        f"(at most {columns:,.0f} columns)"
    )


__all__ = [
    "BudgetedModel",
    "ResourceModel",
    "entry_times",
    "greedy_budgeted",
    "route_counts",
    "separate_capacity",
    "solve_budgeted",
    "time_counts",
    "total_time_cap",
]
