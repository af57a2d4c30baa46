"""Chapter 2's local search with the budgeted GA's penalty priced into every move.

The memetic GA of the budgeted family (:func:`taopt.heuristics.budgeted.genetic_algorithm`)
scores a chromosome by ``f + λ × violation`` (:func:`~taopt.heuristics.budgeted.penalised_cost`),
but chapter 2's :func:`~taopt.heuristics.ga_local_search.local_search` minimises ``f``
alone: from a child near the limits it walks to the unconstrained local optimum, which the
repair then has to cut back. :class:`PenalisedSearch` makes the same kinds of move on
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

Each pass prices every move at once (numpy tables, as chapter 2's search) and then makes not
one move but every improving move among the best few of each table whose routes no better
move touches, best first: moves on disjoint routes change the penalised fitness by the sum
of their own changes (a move's arcs lie on its own routes, an arc into a route start costs
0, a route's penalty depends on that route alone), so this is a steepest descent that does
not throw away the other routes' improvements it has already priced. Why: in the GA's
memetic step a child needs several times the moves chapter 2's unlimited children need (21
against 2.2 per search at n120m10), and one pass costs about twice one of chapter 2's.

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
from taopt.runtime import Deadline

#: A move of the search: (kind, row, column, segment length) of its table cell.
Move = tuple[str, int, int, int]

#: Best moves kept per table and pass; the improving ones on disjoint routes are all made.
CANDIDATES = 8

#: Relative slack of the budgeted heuristics' own travel-time check (stricter than the
#: scorer's): the GA's penalty, this search and the limit-aware descent all use it.
SLACK = 1e-9


def slack_limits(max_time: np.ndarray) -> np.ndarray:
    """Each travel-time limit ``T_k`` plus :data:`SLACK` (relative; ``inf`` stays ``inf``)."""
    return np.where(np.isfinite(max_time), max_time + SLACK * np.maximum(1.0, max_time), np.inf)


class PenalisedSearch:
    """Steepest descent of one vehicle-marker path on the penalised fitness.

    Parameters
    ----------
    problem : BudgetedProblem
    weight : float
        λ: penalty per unit of violation.
    unit : float
        Time units of violation per target over a capacity.
    neighbourhood : tuple of str
        Moves tried, a subset of chapter 2's
        :data:`~taopt.heuristics.ga_local_search.NEIGHBOURHOOD`.

    Notes
    -----
    Moves (those of chapter 2's local search that keep every route start in place):
    reversal of a run of targets inside one route, relocation of 1–3 consecutive targets
    (inside a route or into another), exchange of two targets, and 2-opt* (two routes swap
    their tails). Per pass, O(L^2) numpy work on the path of L genes, about twice chapter
    2's tables (each is split into the parts of the two routes it touches), then the
    improving moves among the :data:`CANDIDATES` best of each table that touch disjoint
    routes are all made (module docstring). Every route's time and count are recomputed
    after each pass (O(L)).

    Raises
    ------
    InstanceError
        An unknown move name.
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
        self.time_limit = slack_limits(self.max_time)
        self.capacity = np.append(problem.capacity, np.inf)
        self.timed = bool(np.isfinite(problem.max_time).any())
        self.counted = bool(np.isfinite(problem.capacity).any())

    def run(
        self,
        matrix: np.ndarray,
        nodes: np.ndarray,
        max_moves: int = 1000,
        deadline: Deadline | None = None,
    ) -> tuple[np.ndarray, int]:
        """The descent from path ``nodes`` (:func:`~taopt.heuristics.ga_routing.path_nodes`),
        stopped early (with the path so far) once ``deadline`` has expired.

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
            if deadline is not None and deadline.expired():
                break
            found = self._improving_moves(matrix, nodes)
            if not found:
                break
            chosen = _independent(found, nodes >= self.n, max_moves - moves)
            nodes = (
                _apply(nodes, *chosen[0]) if len(chosen) == 1 else _apply_all(nodes, chosen, self.n)
            )
            moves += len(chosen)
        return nodes, moves

    def _improving_moves(self, matrix: np.ndarray, nodes: np.ndarray) -> list[tuple[float, Move]]:
        """One pass: the :data:`CANDIDATES` best moves of each table that improve the
        penalised fitness by more than the tolerance, with their changes, best first."""
        tables = _MoveTables(self, matrix, nodes)
        if "reverse" in self.neighbourhood:
            tables.reverse()
        if "relocate" in self.neighbourhood:
            tables.relocate()
        if "exchange" in self.neighbourhood:
            tables.exchange()
        if "tails" in self.neighbourhood:
            tables.tails()
        tables.found.sort(key=lambda item: item[0])  # stable: ties keep the order of the tables
        return tables.found


class _MoveTables:
    """One pass of :class:`PenalisedSearch` on path ``nodes``: the path's routes, times,
    counts and penalties, and one table per move kind of the change of the penalised
    fitness; :meth:`keep` collects the improving cells in :attr:`found`."""

    def __init__(self, search: PenalisedSearch, matrix: np.ndarray, nodes: np.ndarray) -> None:
        self.search = search
        n, inner = search.n, nodes.size - 2
        self.nodes, self.inner = nodes, inner
        self.reverse_block, self.relocate_block, self.exchange_block, self.later = _move_masks(
            inner
        )
        self.position = np.arange(nodes.size)
        self.cost = cost = matrix[nodes][:, nodes]
        self.forward = forward = np.diagonal(cost, 1)  # a[q]: arc q -> q + 1, q = 0..L
        self.prefix = np.concatenate(([0.0], np.cumsum(forward)))  # F[q] = a[0] + .. + a[q-1]
        self.is_start = is_start = nodes >= n  # route starts and the end point
        self.starts_upto = starts_upto = np.cumsum(is_start)  # starts at positions 0..q
        self.route = route = starts_upto - 1  # route (in path order) of each position
        vehicle = nodes[is_start] - n  # vehicle of each route; m for the end point
        times = np.bincount(route[:-1], weights=forward, minlength=vehicle.size)
        counts = np.bincount(route, weights=(~is_start).astype(float), minlength=vehicle.size)
        # per route: how far its time is over its limit (and over the limit with slack),
        # how many targets over its capacity, and its penalty now (-inf: no limit)
        over_time = times - search.max_time[vehicle]
        over_limit = times - search.time_limit[vehicle]
        self.room = counts - search.capacity[vehicle]
        self.weight = weight = search.weight
        self.per_target = search.weight * search.unit
        base_time = weight * np.where(over_limit > 0, over_time, 0.0)
        self.base_count = self.per_target * np.maximum(self.room, 0.0)
        # the time penalty change is weight * (change + over_time) - base_time above the
        # limit and -base_time below it: per route, the threshold and the constant part
        self.threshold = -over_limit
        self.above = weight * np.where(np.isfinite(over_time), over_time, 0.0) - base_time
        self.below = -base_time
        self.tolerance = 1e-10 * max(float(forward.sum()), 1.0)
        self.found: list[tuple[float, Move]] = []
        self.genes = slice(1, inner + 1)
        self.rows, self.columns = route[self.genes][:, None], route[self.genes][None, :]

    def time_change(self, r: np.ndarray, change: np.ndarray) -> np.ndarray:
        """Change of route r's time penalty when its time changes by ``change``."""
        if not self.search.timed:  # no finite travel-time limit: never a change (and cheap)
            return np.zeros(r.shape)
        return np.where(
            change > self.threshold[r], self.weight * change + self.above[r], self.below[r]
        )

    def count_change(self, r: np.ndarray, change: Any) -> np.ndarray:
        """Change of route r's capacity penalty when its count changes by ``change``."""
        if not self.search.counted:
            return np.zeros(r.shape)
        return self.per_target * np.maximum(self.room[r] + change, 0.0) - self.base_count[r]

    def keep(self, kind: str, length: int, table: np.ndarray) -> None:
        """Collect the :data:`CANDIDATES` best cells of ``table`` below -tolerance."""
        flat = table.ravel()
        better = np.flatnonzero(flat < -self.tolerance)
        if better.size > CANDIDATES:
            better = better[np.argpartition(flat[better], CANDIDATES)[:CANDIDATES]]
        for index in better.tolist():
            row, column = divmod(index, table.shape[1])
            self.found.append((float(flat[index]), (kind, row, column, length)))

    def reverse(self) -> None:
        """Reversal of i..j (rows i, columns j, 1..L): a run of targets of one route."""
        cost, forward, inner, genes = self.cost, self.forward, self.inner, self.genes
        delta = cost[0:inner, 1 : inner + 1] + cost[1 : inner + 1, 2 : inner + 2]
        backward = np.concatenate(([0.0], np.cumsum(np.diagonal(cost, -1))))[1 : inner + 1]
        fsum = self.prefix[1 : inner + 1]
        delta += (backward - fsum - forward[1 : inner + 1])[None, :]
        delta += (fsum - backward - forward[0:inner])[:, None]
        delta += self.time_change(self.rows, delta) + self.reverse_block
        no_start = self.starts_upto[genes][None, :] == self.starts_upto[0:inner][:, None]
        self.keep("reverse", 0, np.where(no_start, delta, np.inf))

    def relocate(self) -> None:
        """Relocation of i..i+length-1 between p and p + 1 (rows i, columns p = 0..L)."""
        cost, forward, inner, prefix = self.cost, self.forward, self.inner, self.prefix
        route, starts_upto, timed = self.route, self.starts_upto, self.search.timed
        to = route[0 : inner + 1]
        insertion = cost.T[1 : inner + 1, 0 : inner + 1] - forward[None, 0 : inner + 1]
        for length, block in self.relocate_block.items():
            count = block.shape[0]
            first = self.position[1 : count + 1]
            last = first + length - 1
            inside = prefix[last] - prefix[first]  # the segment's own arcs
            removal = cost[first - 1, last + 1] - forward[first - 1] - forward[last]
            add = insertion[:count] + cost[length : inner + 1, 1 : inner + 2]
            whole = add + removal[:, None]
            source = route[first]
            same = source[:, None] == to[None, :]
            penalty: float | np.ndarray = 0.0
            if timed:  # the receiving route's time: the only route, inside one
                received = np.where(same, whole, add + inside[:, None])
                penalty = self.time_change(to[None, :], received)
            # the segment's route loses it and the receiving route's count grows
            leaving = self.count_change(source, -length)
            if timed:
                leaving = leaving + self.time_change(source, removal - inside)
            whole += np.where(same, 0.0, leaving[:, None] + self.count_change(to, length)[None, :])
            whole += penalty + block
            whole[starts_upto[last] != starts_upto[first - 1]] = np.inf  # a start in it
            self.keep("relocate", length, whole)

    def exchange(self) -> None:
        """Exchange of the genes at i < j - 1 (rows i, columns j, 1..L), both targets:
        route of i gets j in i's place (``gets``), route of j gets i (its transpose)."""
        cost, forward, inner = self.cost, self.forward, self.inner
        first_arc = cost[0:inner, 1 : inner + 1]  # [i-1, j-1]: M[i-1, j]
        second_arc = cost[1 : inner + 1, 2 : inner + 2]  # [i-1, j-1]: M[i, j+1]
        around = forward[0:inner] + forward[1 : inner + 1]  # a[i-1] + a[i]
        gets = first_arc + second_arc.T - around[:, None]
        delta = gets + gets.T
        if self.search.timed:  # counts never change; ``delta`` is symmetric
            same = self.rows == self.columns
            one_side = self.time_change(self.rows, np.where(same, delta, gets))
            delta += one_side + np.where(same, 0.0, one_side.T)
        delta += self.exchange_block
        starts = self.is_start[self.genes]
        delta[starts] = np.inf
        delta[:, starts] = np.inf
        self.keep("exchange", 0, delta)

    def tails(self) -> None:
        """2-opt*: cuts before c < d (rows c - 1, columns d - 1, 0..L) in different routes.
        Route a of c - 1 takes the tail after d - 1 and route b the tail after c - 1: the
        table is ``one_side`` (route a's change) plus its transpose (route b's)."""
        cost, forward, inner, prefix = self.cost, self.forward, self.inner, self.prefix
        position, size = self.position, self.nodes.size
        following = np.minimum.accumulate(np.where(self.is_start, position, size)[::-1])[
            ::-1
        ]  # next start at or after each position: a tail cut before q runs to it
        tail_time = (prefix[following] - prefix[position])[1 : inner + 2]
        tail_count = (following - position)[1 : inner + 2]
        half = cost[0 : inner + 1, 1 : inner + 2] - forward[0 : inner + 1, None]
        a = self.route[0 : inner + 1][:, None]
        one_side = half + self.count_change(a, tail_count[None, :] - tail_count[:, None])
        if self.search.timed:
            one_side += self.time_change(a, half + (tail_time[None, :] - tail_time[:, None]))
        delta = one_side + one_side.T
        self.keep("tails", 0, np.where(self.later | (a == a.T), np.inf, delta))


def _touched(move: Move, route: np.ndarray) -> set[int]:
    """The routes (in path order) a move changes, from the positions of its table cell."""
    kind, row, column, _ = move
    if kind == "reverse":
        return {int(route[row + 1])}
    if kind == "relocate":
        return {int(route[row + 1]), int(route[column])}
    if kind == "exchange":
        return {int(route[row + 1]), int(route[column + 1])}
    return {int(route[row]), int(route[column])}  # tails: the routes of c - 1 and d - 1


def _independent(found: list[tuple[float, Move]], is_start: np.ndarray, most: int) -> list[Move]:
    """Best first, the moves whose routes no earlier chosen move touches (at most ``most``).

    Moves on disjoint sets of routes change the penalised fitness by the sum of their own
    changes: a move's travel-time change is on arcs of its own routes (an arc into a route
    start costs 0), and each route's penalty depends on that route alone.
    """
    route = np.cumsum(is_start) - 1
    chosen: list[Move] = []
    used: set[int] = set()
    for _, move in found:
        routes = _touched(move, route)
        if routes & used:
            continue
        chosen.append(move)
        used |= routes
        if len(chosen) == most:
            break
    return chosen


def _apply_all(nodes: np.ndarray, moves: list[Move], n: int) -> np.ndarray:
    """The path after ``moves`` (table cells of one pass, on disjoint routes), each applied
    to its own routes' lists with the offsets of the path they were priced on."""
    is_start = nodes >= n
    route = np.cumsum(is_start) - 1
    first = np.flatnonzero(is_start)  # position of each route's start (and of the end)
    offset = np.arange(nodes.size) - first[route]
    routes = [nodes[a:b].tolist() for a, b in zip(first[:-1], first[1:], strict=True)]

    def where(position: int) -> tuple[list[int], int]:
        return routes[route[position]], int(offset[position])

    for kind, row, column, length in moves:
        if kind == "reverse":
            path, i = where(row + 1)
            j = i + column - row
            path[i : j + 1] = path[i : j + 1][::-1]
        elif kind == "exchange":
            (a, i), (b, j) = where(row + 1), where(column + 1)
            a[i], b[j] = b[j], a[i]
        elif kind == "relocate":
            (a, i), (b, p) = where(row + 1), where(column)
            if a is b:  # chapter 2's relocation, on this route alone
                a[:] = _apply(np.array(a), kind, i - 1, p, length).tolist()
            else:
                b[p + 1 : p + 1] = a[i : i + length]
                del a[i : i + length]
        else:  # tails: cuts after positions c - 1 and d - 1
            (a, i), (b, j) = where(row), where(column)
            a[i + 1 :], b[j + 1 :] = b[j + 1 :], a[i + 1 :]
    return np.array([point for path in routes for point in path] + [int(nodes[-1])], dtype=np.intp)


__all__ = ["SLACK", "PenalisedSearch", "slack_limits"]
