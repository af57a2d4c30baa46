"""The three-index (arc, vehicle) model of the budgeted family (``form="arc-vehicle"``).

Thesis §2.2.1 (2.2)–(2.5) with §6.2's capacity and travel-time rows; the model and why it is
written so: :mod:`taopt.models.budgeted`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp

from taopt.budgeted.bounds import usable_arcs
from taopt.budgeted.problem import (
    BudgetedProblem,
)
from taopt.models.budgeted.separation import capacity_rows
from taopt.models.highs import HighsModel
from taopt.models.routing import (
    arc_list,
    cut_rows,
)
from taopt.routing.subtours import new_subsets


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

    def sigma(self, solution: Sequence[float] | np.ndarray) -> np.ndarray:
        """Chapter 2's σ (one value per two-index arc) of a column vector."""
        return self.aggregate @ np.asarray(solution, dtype=float)

    def add_cuts(self, cuts: list[tuple[int, ...]]) -> int:
        """Add the (2.5) rows of the subsets not in the model yet; returns how many."""
        new = new_subsets(cuts, self._known)
        if new:
            rows, low, high = cut_rows(self.problem.routing, new, self.tails, self.heads)
            self.model.add_rows(rows @ self.aggregate, low, high)
            self.cuts.extend(new)
        return len(new)

    def add_capacity_cuts(self, cuts: list[tuple[tuple[int, ...], int]]) -> int:
        """Add rounded capacity rows (:func:`~taopt.models.budgeted.separation.separate_capacity`) not in the model yet."""
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
