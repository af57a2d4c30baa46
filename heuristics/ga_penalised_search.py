"""Chapter 2's local search with the budgeted GA's penalty priced into every move.

The memetic GA of the budgeted family (:func:`taopt.heuristics.budgeted.genetic_algorithm`)
scores a chromosome by ``f + λ × violation`` (:func:`~taopt.heuristics.budgeted.penalised_cost`),
but chapter 2's :func:`~taopt.heuristics.ga_local_search.local_search` minimises ``f``
alone: from a child near the limits it walks to the unconstrained local optimum, which the
repair then has to cut back. :func:`penalised_local_search` makes the same kinds of move on
the same single-path reading of a chromosome and prices each by its exact change of the
penalised fitness: the change of ``f`` (the formulas of chapter 2's local search) plus, for
each of the one or two routes a move changes, the change of that route's penalty
``λ (max(0, t_k − T_k) + unit · max(0, |o_k| − Q_k))``.

Why a second local search and not an option of the first: a move's penalty needs the change
of each route's travel time and count separately, not only their sum, so every table is
split by route; and the moves that carry a route start elsewhere (a reversal or a
relocation across a marker, an exchange with a marker) change which vehicle owns which
targets wholesale, so they are left out: the route starts stay put and the vehicle of each
route is fixed for the whole descent.

Example
-------
Two targets at 1 and 2 on a line, two vehicles at 0 and 3, each allowed one target. The
path ``0 -> 1 -> 2`` for vehicle 0 breaks its capacity; the penalised search hands target
1 (position 2 on the line) to vehicle 1:

>>> import numpy as np
>>> from taopt.budgeted import BudgetedProblem
>>> from taopt.heuristics.ga_routing import path_matrix, path_nodes
>>> x = np.array([1.0, 2.0, 0.0, 3.0])
>>> p = BudgetedProblem(abs(x[:, None] - x[None, :]), 2, capacity=[1, 1])
>>> nodes = path_nodes(p.routing, np.array([0, 1, 2]))[0]
>>> nodes.tolist()
[2, 0, 1, 3, 4]
>>> search = PenalisedSearch(p, weight=10.0, unit=1.0)
>>> better, moves = search.run(path_matrix(p.routing), nodes)
>>> better.tolist(), moves
([2, 0, 3, 1, 4], 1)

References
----------
Thesis §2.5 (the GA and its local search), §6.2 (the limits).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from taopt.budgeted.problem import BudgetedProblem
from taopt.errors import InstanceError
from taopt.heuristics.ga_local_search import NEIGHBOURHOOD, _apply, _move_masks

#: Relative slack on a travel-time limit, as :func:`taopt.heuristics.budgeted.penalised_cost`.
SLACK = 1e-9


class PenalisedSearch:
    """Best-improvement descent of one vehicle-marker path on the penalised fitness.

    Parameters
    ----------
    problem : BudgetedProblem
    weight : float
        λ: penalty per unit of violation.
    unit : float
        Time units of violation per target over a capacity.

    Notes
    -----
    Moves (those of chapter 2's local search that keep every route start in place):
    reversal of a run of targets inside one route, relocation of 1–3 consecutive targets
    (inside a route or into another), exchange of two targets, and 2-opt* (two routes swap
    their tails). Per pass, O(L^2) numpy work on the path of L genes, about twice chapter
    2's tables (each is split into the parts of the two routes it touches). Every route's
    time and count are recomputed after each move (O(L)).
    """

    def __init__(
        self,
        problem: BudgetedProblem,
        weight: float,
        unit: float,
        neighbourhood: tuple[str, ...] = NEIGHBOURHOOD,
    ) -> None:
        unknown = set(neighbourhood) - set(NEIGHBOURHOOD)
        if unknown:
            raise InstanceError(
                f"unknown local-search moves {sorted(unknown)}; use {NEIGHBOURHOOD}"
            )
        self.neighbourhood = tuple(neighbourhood)
        self.n, self.m = problem.n, problem.m
        self.weight, self.unit = float(weight), float(unit)
        # per vehicle, plus a sentinel for the end point (never a route of a move)
        self.max_time = np.append(problem.max_time, np.inf)
        self.time_limit = np.where(
            np.isfinite(self.max_time),
            self.max_time + SLACK * np.maximum(1.0, self.max_time),
            np.inf,
        )
        self.capacity = np.append(problem.capacity, np.inf)
        self.timed = bool(np.isfinite(problem.max_time).any())
        self.counted = bool(np.isfinite(problem.capacity).any())

    def run(
        self, matrix: np.ndarray, nodes: np.ndarray, max_moves: int = 1000
    ) -> tuple[np.ndarray, int]:
        """The descent from path ``nodes`` (:func:`~taopt.heuristics.ga_routing.path_nodes`).

        Returns
        -------
        nodes : ndarray
            The improved path (a new array); its penalised fitness is never higher.
        moves : int
            Improving moves made.
        """
        nodes = np.array(nodes, dtype=np.intp)
        inner = nodes.size - 2
        moves = 0
        if inner < 2:
            return nodes, moves
        while moves < max_moves:
            _, move = self._best_move(matrix, nodes)
            if move is None:
                break
            nodes = _apply(nodes, *move)
            moves += 1
        return nodes, moves

    def _best_move(
        self, matrix: np.ndarray, nodes: np.ndarray
    ) -> tuple[float, tuple[str, int, int, int] | None]:
        """The best move of one pass and its change of the penalised fitness (move None
        when none improves by more than the tolerance)."""
        n, inner = self.n, nodes.size - 2
        reverse_block, relocate_block, exchange_block, later = _move_masks(inner)
        position = np.arange(nodes.size)
        cost = matrix[nodes][:, nodes]
        forward = np.diagonal(cost, 1)  # a[q]: arc q -> q + 1, q = 0..L
        prefix = np.concatenate(([0.0], np.cumsum(forward)))  # F[q] = a[0] + .. + a[q-1]
        is_start = nodes >= n  # route starts and the end point
        starts_upto = np.cumsum(is_start)  # starts at positions 0..q
        route = starts_upto - 1  # route (in path order) of each position
        vehicle = nodes[is_start] - n  # vehicle of each route; m for the end point
        times = np.bincount(route[:-1], weights=forward, minlength=vehicle.size)
        counts = np.bincount(route, weights=(~is_start).astype(float), minlength=vehicle.size)
        # per route: how far its time is over its limit (and over the limit with slack),
        # how many targets over its capacity, and its penalty now (-inf: no limit)
        over_time = times - self.max_time[vehicle]
        over_limit = times - self.time_limit[vehicle]
        room = counts - self.capacity[vehicle]
        weight, per_target = self.weight, self.weight * self.unit
        base_time = weight * np.where(over_limit > 0, over_time, 0.0)
        base_count = per_target * np.maximum(room, 0.0)

        def time_change(r: np.ndarray, change: np.ndarray) -> np.ndarray:
            """Change of route r's time penalty when its time changes by ``change``."""
            if not self.timed:  # no finite travel-time limit: never a change (and cheap)
                return np.zeros(r.shape)
            return (
                weight * np.where(change > -over_limit[r], change + over_time[r], 0.0)
                - base_time[r]
            )

        def count_change(r: np.ndarray, change: Any) -> np.ndarray:
            """Change of route r's capacity penalty when its count changes by ``change``."""
            if not self.counted:
                return np.zeros(r.shape)
            return per_target * np.maximum(room[r] + change, 0.0) - base_count[r]

        tolerance = 1e-10 * max(float(forward.sum()), 1.0)
        found: list[tuple[float, tuple[str, int, int, int]]] = []

        def keep(kind: str, length: int, table: np.ndarray) -> None:
            flat = int(np.argmin(table))
            row, column = divmod(flat, table.shape[1])
            found.append((float(table.flat[flat]), (kind, row, column, length)))

        genes = slice(1, inner + 1)
        rows, columns = route[genes][:, None], route[genes][None, :]
        if "reverse" in self.neighbourhood:
            # reversal of i..j (rows i, columns j, 1..L): a run of targets of one route
            delta = cost[0:inner, 1 : inner + 1] + cost[1 : inner + 1, 2 : inner + 2]
            backward = np.concatenate(([0.0], np.cumsum(np.diagonal(cost, -1))))[1 : inner + 1]
            fsum = prefix[1 : inner + 1]
            delta += (backward - fsum - forward[1 : inner + 1])[None, :]
            delta += (fsum - backward - forward[0:inner])[:, None]
            delta += time_change(rows, delta) + reverse_block
            no_start = starts_upto[genes][None, :] == starts_upto[0:inner][:, None]
            keep("reverse", 0, np.where(no_start, delta, np.inf))
        if "relocate" in self.neighbourhood:
            # relocation of i..i+length-1 between p and p + 1 (rows i, columns p = 0..L)
            to = route[0 : inner + 1]
            insertion = cost.T[1 : inner + 1, 0 : inner + 1] - forward[None, 0 : inner + 1]
            for length, block in relocate_block.items():
                count = block.shape[0]
                first = position[1 : count + 1]
                last = first + length - 1
                inside = prefix[last] - prefix[first]  # the segment's own arcs
                removal = cost[first - 1, last + 1] - forward[first - 1] - forward[last]
                add = insertion[:count] + cost[length : inner + 1, 1 : inner + 2]
                whole = add + removal[:, None]
                source = route[first]
                same = source[:, None] == to[None, :]
                penalty = 0.0
                if self.timed:  # the receiving route's time: the only route, inside one
                    received = np.where(same, whole, add + inside[:, None])
                    penalty = time_change(to[None, :], received)
                # the segment's route loses it and the receiving route's count grows
                leaving = count_change(source, -length)
                if self.timed:
                    leaving = leaving + time_change(source, removal - inside)
                whole += np.where(same, 0.0, leaving[:, None] + count_change(to, length)[None, :])
                whole += penalty + block
                whole[starts_upto[last] != starts_upto[first - 1]] = np.inf  # a start in it
                keep("relocate", length, whole)
        if "exchange" in self.neighbourhood:
            # exchange of the genes at i < j - 1 (rows i, columns j, 1..L), both targets:
            # route of i gets j in i's place (``gets``), route of j gets i (its transpose)
            first_arc = cost[0:inner, 1 : inner + 1]  # [i-1, j-1]: M[i-1, j]
            second_arc = cost[1 : inner + 1, 2 : inner + 2]  # [i-1, j-1]: M[i, j+1]
            around = forward[0:inner] + forward[1 : inner + 1]  # a[i-1] + a[i]
            gets = first_arc + second_arc.T - around[:, None]
            delta = gets + gets.T
            if self.timed:  # counts never change; ``delta`` is symmetric
                same = rows == columns
                one_side = time_change(rows, np.where(same, delta, gets))
                delta += one_side + np.where(same, 0.0, one_side.T)
            delta += exchange_block
            starts = is_start[genes]
            delta[starts] = np.inf
            delta[:, starts] = np.inf
            keep("exchange", 0, delta)
        if "tails" in self.neighbourhood:
            # 2-opt*: cuts before c < d (rows c - 1, columns d - 1, 0..L) in different routes.
            # Route a of c - 1 takes the tail after d - 1 and route b the tail after c - 1:
            # the table is ``one_side`` (route a's change) plus its transpose (route b's).
            following = np.minimum.accumulate(np.where(is_start, position, nodes.size)[::-1])[
                ::-1
            ]  # next start at or after each position: a tail cut before q runs to it
            tail_time = (prefix[following] - prefix[position])[1 : inner + 2]
            tail_count = (following - position)[1 : inner + 2]
            half = cost[0 : inner + 1, 1 : inner + 2] - forward[0 : inner + 1, None]
            a = route[0 : inner + 1][:, None]
            one_side = half + count_change(a, tail_count[None, :] - tail_count[:, None])
            if self.timed:
                one_side += time_change(a, half + (tail_time[None, :] - tail_time[:, None]))
            delta = one_side + one_side.T
            keep("tails", 0, np.where(later | (a == a.T), np.inf, delta))
        if not found:
            return 0.0, None
        value, move = min(found, key=lambda item: item[0])
        return (value, move) if value < -tolerance else (value, None)


__all__ = ["PenalisedSearch"]
