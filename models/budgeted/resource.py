"""Chapter 2's two-index model with capacity and time resources per target
(``form="resource"``, the default of :func:`~taopt.models.budgeted.solve_budgeted`).

Thesis §2.2.1 (2.2)–(2.5), §6.2.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp

from taopt.budgeted.bounds import shortest_times, usable_arcs
from taopt.budgeted.problem import (
    BudgetedProblem,
)
from taopt.errors import SolverError
from taopt.models.budgeted.separation import capacity_rows
from taopt.models.highs import HighsModel
from taopt.models.routing import (
    arc_list,
    cut_rows,
    decode,
)
from taopt.routing.subtours import new_subsets


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
            np.asarray(usable.any(axis=0))[self.tails, self.heads],
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
            self.offsets[name] = columns
            values_upper, rows = _resource_rows(
                problem, name, limits, columns, (self.tails, self.heads, cost, reverse),
                starts, inner, vehicle,
            )  # fmt: skip
            columns += n
            column_upper.append(values_upper)
            costs.append(np.zeros(n))
            extra.extend(rows)
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

    def sigma(self, solution: Sequence[float] | np.ndarray) -> np.ndarray:
        """σ (one value per arc) of a column vector."""
        return np.asarray(solution, dtype=float)[: len(self.tails)]

    def add_cuts(self, cuts: list[tuple[int, ...]]) -> int:
        """Add the (2.5) rows of the subsets not in the model yet; returns how many."""
        new = new_subsets(cuts, self._known)
        if new:
            rows, low, high = cut_rows(self.problem.routing, new, self.tails, self.heads)
            pad = sp.csr_matrix((rows.shape[0], self.n_columns - len(self.tails)))
            self.model.add_rows(sp.hstack([rows, pad]).tocsr(), low, high)
            self.cuts.extend(new)
        return len(new)

    def add_capacity_cuts(self, cuts: list[tuple[tuple[int, ...], int]]) -> int:
        """Add rounded capacity rows (:func:`~taopt.models.budgeted.separation.separate_capacity`) not in the model yet."""
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


def _resource_rows(
    problem: BudgetedProblem,
    name: str,
    limits: np.ndarray,
    offset: int,
    arcs: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    starts: np.ndarray,
    inner: np.ndarray,
    vehicle: np.ndarray,
) -> tuple[np.ndarray, list[Any]]:
    """The upper bounds of resource ``name``'s n columns (the first at ``offset``) and its
    rows (:class:`ResourceModel`), each block as ((data, row, column) triplets, row count,
    right-hand side). ``arcs``: tails, heads, travel times and the reverse arc of each arc;
    ``starts``, ``inner``: the arcs out of a start point and between targets; ``vehicle``:
    the vehicle of each start arc."""
    n = problem.n
    tails, heads, cost, reverse = arcs
    top = float(limits.max())
    if name == "capacity":
        column_upper = np.full(n, max(top - 1.0, 0.0))
        start_coef, start_rhs = top - limits[vehicle], top - 1.0
        inner_coef, inner_rhs, lift = np.full(len(inner), top), top - 1.0, top - 2.0
    else:
        # time left on arrival at j: at most U_j = max_k (T_k − d_k(j)), d_k the
        # shortest time from p_k; the big-M of each row is U of its head
        reach = shortest_times(problem)[:, :n]
        most = np.clip((limits[:, None] - reach).max(axis=0), 0.0, top)
        column_upper = most
        start_rhs = most[heads[starts]]
        start_coef = np.maximum(start_rhs - limits[vehicle] + cost[starts], 0.0)
        inner_rhs = most[heads[inner]]
        inner_coef, lift = inner_rhs + cost[inner], 0.0
    extra: list[Any] = []
    # start rows: resource_j + coef σ[p_k, j] <= rhs
    count = len(starts)
    rows = np.tile(np.arange(count), 2)
    cols = np.concatenate([offset + heads[starts], starts])
    extra.append(((np.concatenate([np.ones(count), start_coef]), rows, cols), count, start_rhs))
    # inner rows: resource_j − resource_i + coef σ_ij (+ lift σ_ji) <= rhs
    count = len(inner)
    inner_data = [np.ones(count), -np.ones(count), inner_coef]
    inner_cols = [offset + heads[inner], offset + tails[inner], inner]
    if lift > 0:
        inner_data.append(np.full(count, lift))
        inner_cols.append(reverse[inner])
    rows = np.tile(np.arange(count), len(inner_data))
    extra.append(((np.concatenate(inner_data), rows, np.concatenate(inner_cols)), count, inner_rhs))
    return column_upper, extra
