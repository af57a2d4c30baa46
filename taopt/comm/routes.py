"""Route geometry of chapter 4: projected distances, insertion and removal costs.

A route ``o_j`` is an ordered list of target indices driven from the vehicle's current
position ``p_j(t)`` at unit speed; its projected distance ``d(o_j)`` is the length of that
open polyline. The marginal cost (4.9) of inserting target q at position l of ``o_j``
(``l = 0``: before the first target, ``l = |o_j|``: at the end) is

    d(p, q) + d(q, o^1) - d(p, o^1)      (l = 0, p the current position)
    d(o^l, q) + d(q, o^{l+1}) - d(o^l, o^{l+1})
    d(o^{|o|}, q)                        (l = |o|; d(p, q) when the route is empty)

and the significance of a target on a route (HDA, §4.1) is the distance saved by removing
it. Ties in a minimum go to the earliest position.

Every function takes ``start``, the (n,) distances from the vehicle's current position to
every target (:func:`distances_from`), and ``dist``, the (n, n) target–target distances, so
the engine and every policy compute the same numbers to the bit.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def distances_from(point: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """(n,) Euclidean distances from ``point`` to every target (rows of ``targets``)."""
    diff = targets - point
    return np.hypot(diff[:, 0], diff[:, 1])


def leg_lengths(
    start: np.ndarray, route: Sequence[int] | np.ndarray, dist: np.ndarray
) -> np.ndarray:
    """Lengths of the legs ``p -> o^1 -> ... -> o^{|o|}`` ((|o|,) array)."""
    if len(route) == 0:
        return np.zeros(0)
    r = np.asarray(route, dtype=np.int64)
    legs = dist[r[:-1], r[1:]]
    return np.concatenate(([start[r[0]]], legs))


def route_length(start: np.ndarray, route: Sequence[int], dist: np.ndarray) -> float:
    """Projected distance ``d(o_j)`` of driving ``route`` from the current position."""
    if len(route) == 0:
        return 0.0
    r = np.asarray(route, dtype=np.int64)
    return float(start[r[0]] + dist[r[:-1], r[1:]].sum())


def insertion_costs(
    start: np.ndarray, route: Sequence[int], candidates: np.ndarray, dist: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Cheapest insertion (4.9) of each candidate into ``route``.

    Returns
    -------
    cost : (k,) float
        ``min_l d(o ⊕_l q) - d(o)`` for each candidate q (``d(p, q)`` for an empty route).
    position : (k,) int
        The minimising l (0 = before the first target, ``|o|`` = at the end; the earliest on
        ties).

    Example
    -------
    >>> import numpy as np
    >>> x = np.array([0.0, 2.0, 1.0])                  # three targets on a line
    >>> dist = abs(x[:, None] - x[None, :])
    >>> insertion_costs(abs(x - (-1.0)), [0, 1], np.array([2]), dist)
    (array([0.]), array([1]))
    """
    candidates = np.asarray(candidates, dtype=np.int64)
    length = len(route)
    if length == 0 or candidates.size == 0:
        return start[candidates], np.zeros(candidates.size, dtype=np.int64)
    r = np.asarray(route, dtype=np.int64)
    to_node = np.empty((length + 1, candidates.size))  # d(node_l, q), node_0 = p
    to_node[0] = start[candidates]
    to_node[1:] = dist[r[:, None], candidates[None, :]]
    legs = leg_lengths(start, r, dist)
    costs = to_node[:-1] + to_node[1:] - legs[:, None]
    costs = np.vstack((costs, to_node[length : length + 1]))
    position = np.argmin(costs, axis=0)
    return costs[position, np.arange(candidates.size)], position


def removal_savings(start: np.ndarray, route: Sequence[int], dist: np.ndarray) -> np.ndarray:
    """Significance of each target on ``route``: ``d(o) - d(o minus that target)``."""
    length = len(route)
    if length == 0:
        return np.zeros(0)
    r = np.asarray(route, dtype=np.int64)
    legs = leg_lengths(start, r, dist)
    saving = legs.copy()  # the last target: only its incoming leg
    if length > 1:
        skip = np.concatenate(([start[r[1]]], dist[r[:-2], r[2:]]))  # d(node_{l-1}, o^{l+1})
        saving[:-1] = legs[:-1] + legs[1:] - skip
    return saving


class InsertionTable:
    """Cheapest insertion (4.9) of a set of candidates into one growing route, kept up to date.

    After ``insert(q, l)`` only the slots next to q change: a candidate (not yet on the route)
    whose best slot was the replaced one is recomputed in full, every other one compares its best with the two
    new slots (positions after l shift by one). The numbers are those of
    :func:`insertion_costs` on the whole route, to the bit (same formulas, same operand
    order; ties to the earliest position), at O(candidates) per insertion instead of
    O(route x candidates).

    Parameters
    ----------
    start : (n,) array
        Distances from the vehicle's current position to every target.
    candidates : (k,) int array
        Target indices whose insertion costs are tracked.
    dist : (n, n) array

    Example
    -------
    >>> import numpy as np
    >>> x = np.array([0.0, 2.0, 1.0])
    >>> table = InsertionTable(abs(x + 1.0), np.array([0, 1, 2]), abs(x[:, None] - x[None, :]))
    >>> table.insert(0, 0); table.insert(1, 1)
    >>> float(table.cost[2]), int(table.position[2])
    (0.0, 1)
    """

    def __init__(self, start: np.ndarray, candidates: np.ndarray, dist: np.ndarray) -> None:
        self.start = start
        self.dist = dist
        self.candidates = np.asarray(candidates, dtype=np.int64)
        self.route: list[int] = []
        self.cost = start[self.candidates].astype(float)
        self.position = np.zeros(self.candidates.size, dtype=np.int64)
        self._index = {int(q): c for c, q in enumerate(self.candidates)}
        self._alive = np.ones(self.candidates.size, dtype=bool)  # not on the route yet

    def _from(self, node: int | None) -> np.ndarray:
        return self.start[self.candidates] if node is None else self.dist[node, self.candidates]

    def insert(self, target: int, position: int) -> None:
        """``o ⊕_l q`` and the candidates' new cheapest insertions."""
        route = self.route
        length = len(route)
        before = None if position == 0 else route[position - 1]
        after = route[position] if position < length else None
        route.insert(position, int(target))
        if target in self._index:
            self._alive[self._index[target]] = False
        if len(self.candidates) == 0:
            return
        from_before = self._from(before)
        from_target = self.dist[target, self.candidates]
        edge = self.start[target] if before is None else self.dist[before, target]
        first = from_before + from_target - edge  # slot `position`: before -> c -> target
        if after is None:
            second = from_target  # the new end slot
        else:
            second = from_target + self.dist[after, self.candidates] - self.dist[target, after]
        stale = (self.position == position) & self._alive
        self.position[self.position > position] += 1
        cost, where = self.cost, self.position
        take_first = (first < cost) | ((first == cost) & (position < where))
        cost = np.where(take_first, first, cost)
        where = np.where(take_first, position, where)
        take_second = (second < cost) | ((second == cost) & (position + 1 < where))
        cost = np.where(take_second, second, cost)
        where = np.where(take_second, position + 1, where)
        if stale.any():
            redo = np.flatnonzero(stale)
            cost[redo], where[redo] = insertion_costs(
                self.start, route, self.candidates[redo], self.dist
            )
        self.cost, self.position = cost, where


def insert(route: list[int], target: int, position: int) -> list[int]:
    """``o ⊕_l q``: a new list with ``target`` at ``position``."""
    return [*route[:position], int(target), *route[position:]]


__all__ = [
    "distances_from",
    "leg_lengths",
    "route_length",
    "insertion_costs",
    "removal_savings",
    "insert",
    "InsertionTable",
]
