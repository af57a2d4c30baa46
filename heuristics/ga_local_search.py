"""The memetic GA's local search: best-improvement descent of one vehicle-marker path.

The genetic algorithm of thesis §2.5 (:mod:`taopt.heuristics.ga_routing`) improves its best
children with :func:`local_search`. A chromosome read with ``markers="vehicle"`` is one path
through the points of the cost matrix (the multiple travelling salesman problem as a single
one; :func:`~taopt.heuristics.ga_routing.path_nodes`), so every move of
:data:`NEIGHBOURHOOD` (2-opt reversal, or-opt relocation, exchange, 2-opt* tails) has an
exact O(1) cost change, and all of them are priced at once as numpy tables.

Example
-------
Two targets, one vehicle (point 2); the path visits 0 then 1, and one reversal makes it
1 then 0 (travel time 3 + 1 instead of 4 + 2):

>>> import numpy as np, taopt
>>> from taopt.heuristics.ga_routing import path_matrix, path_nodes
>>> problem = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0.0]]), 2)
>>> nodes = path_nodes(problem, np.array([0, 1]))[0]
>>> nodes.tolist()
[2, 0, 1, 3]
>>> improved, moves, _ = local_search(path_matrix(problem), nodes)
>>> improved.tolist(), moves
([2, 1, 0, 3], 1)

References
----------
Thesis §2.5 (the GA); the moves are the classical ones of vehicle-routing local search.
"""

from __future__ import annotations

import functools

import numpy as np

from taopt.errors import InstanceError
from taopt.runtime import Deadline

#: The local-search moves, in the order they are tried.
NEIGHBOURHOOD = ("reverse", "relocate", "tails", "exchange")


def local_search(
    matrix: np.ndarray,
    nodes: np.ndarray,
    max_moves: int = 1000,
    neighbourhood: tuple[str, ...] = NEIGHBOURHOOD,
    deadline: Deadline | None = None,
) -> tuple[np.ndarray, int, int]:
    """Best-improvement descent of one path: 2-opt, or-opt, exchange and 2-opt* moves.

    Parameters
    ----------
    matrix : ndarray
        :func:`~taopt.heuristics.ga_routing.path_matrix` of the problem.
    nodes : (L + 2,) int array
        The path (:func:`~taopt.heuristics.ga_routing.path_nodes`): vehicle 0's start first, the end point
        last (both stay put); a point ``>= nodes[0]`` starts a route.
    max_moves : int
        Stop after this many improving moves.
    neighbourhood : tuple of str
        Moves tried, a subset of :data:`NEIGHBOURHOOD`: "reverse" (reverse
        positions i..j), "relocate" (move 1-3 consecutive genes elsewhere),
        "exchange" (swap two non-adjacent genes), "tails" (2-opt*: two routes
        swap what follows a cut in each, possibly nothing).
    deadline : Deadline, optional
        Stop (with the path as improved so far) once it has expired; it is looked at
        before every move, so a caller's wall-clock limit holds on long paths too.

    Returns
    -------
    nodes : ndarray
        The improved path (a new array), never longer than the input.
    moves : int
        Improving moves made.
    evaluations : int
        Candidate moves priced.

    Raises
    ------
    InstanceError
        An unknown move name.

    Notes
    -----
    Per move, O(L^2) numpy work. With ``M = matrix[nodes][:, nodes]``,
    ``a[k] = M[k, k + 1]`` the path's arcs and ``F``, ``B`` prefix sums of the
    forward and backward arcs, the length (2.2) changes by

    * reverse i..j: ``M[i-1, j] + M[i, j+1] - a[i-1] - a[j] + (B[j] - B[i]) -
      (F[j] - F[i])`` (the reversed segment is re-priced exactly, as the costs
      are asymmetric);
    * relocate i..j between p and p + 1: ``M[i-1, j+1] - a[i-1] - a[j] +
      M[p, i] + M[j, p+1] - a[p]``;
    * exchange i < j - 1: ``M[i-1, j] + M[j, i+1] + M[j-1, i] + M[i, j+1] -
      a[i-1] - a[i] - a[j-1] - a[j]``;
    * tails, cuts before c < d in different routes: ``M[c-1, d] + M[d-1, c] -
      a[c-1] - a[d-1]`` (a tail's last arc leads into a route start or the
      end, which costs 0 either way).
    """
    nodes = np.array(nodes, dtype=np.intp)
    inner = nodes.size - 2  # L genes between the fixed start and end
    moves = evaluations = 0
    if inner < 2:
        return nodes, moves, evaluations
    unknown = set(neighbourhood) - set(NEIGHBOURHOOD)
    if unknown:
        raise InstanceError(f"unknown local-search moves {sorted(unknown)}; use {NEIGHBOURHOOD}")
    reverse_block, relocate_block, exchange_block, later = _move_masks(inner)
    position = np.arange(1, inner + 1)
    per_iteration = {
        "reverse": inner * (inner - 1) // 2,
        "relocate": sum(block.shape[0] * (inner - size) for size, block in relocate_block.items()),
        "tails": inner * (inner + 1) // 2,  # pairs of cuts, same-route pairs included
        "exchange": (inner - 1) * (inner - 2) // 2,
    }
    while moves < max_moves:
        if deadline is not None and deadline.expired():
            break
        cost = matrix[nodes][:, nodes]
        forward = np.diagonal(cost, 1)  # a[k], k = 0..L
        tolerance = 1e-10 * max(float(forward.sum()), 1.0)
        best_delta, best_move = 0.0, None
        candidates = []
        if "reverse" in neighbourhood:
            # Reversal of i..j: rows i, columns j (1..L).
            backward = np.diagonal(cost, -1)  # b[k] = M[k + 1, k]
            fsum = np.concatenate(([0.0], np.cumsum(forward)))[1 : inner + 1]  # F[1..L]
            bsum = np.concatenate(([0.0], np.cumsum(backward)))[1 : inner + 1]  # B[1..L]
            delta = cost[0:inner, 1 : inner + 1] + cost[1 : inner + 1, 2 : inner + 2]
            delta += (bsum - fsum - forward[1 : inner + 1])[None, :]
            delta += (fsum - bsum - forward[0:inner])[:, None]
            delta += reverse_block
            candidates.append(("reverse", 0, delta))
        if "relocate" in neighbourhood:
            # Segment i..i+length-1 between p and p + 1: rows i (1..), columns p (0..L).
            insertion = cost.T[1 : inner + 1, 0 : inner + 1] - forward[None, 0 : inner + 1]
            for length, block in relocate_block.items():
                count = block.shape[0]
                first = position[:count]
                delta = insertion[:count] + cost[length : inner + 1, 1 : inner + 2]
                removal = (
                    cost[first - 1, first + length]
                    - forward[first - 1]
                    - forward[first + length - 1]
                )
                delta += removal[:, None]
                delta += block
                candidates.append(("relocate", length, delta))
        if "tails" in neighbourhood:
            # Cut before positions c (row) and d (column), c < d in different routes, and
            # swap what follows each cut up to its route's end (2-opt*).
            route = np.cumsum(nodes[: inner + 1] >= nodes[0]) - 1  # route of position c - 1
            half = cost[0 : inner + 1, 1 : inner + 2] - forward[0 : inner + 1, None]
            delta = half + half.T
            delta[later | (route[:, None] == route[None, :])] = np.inf
            candidates.append(("tails", 0, delta))
        if "exchange" in neighbourhood:
            # Swap the genes at positions i < j - 1: rows i, columns j (1..L).
            pair = cost[0:inner, 1 : inner + 1] + cost[1 : inner + 1, 2 : inner + 2]
            around = forward[0:inner] + forward[1 : inner + 1]
            delta = pair + pair.T
            delta -= around[:, None]
            delta -= around[None, :]
            delta += exchange_block
            candidates.append(("exchange", 0, delta))
        evaluations += sum(per_iteration[kind] for kind in neighbourhood)
        for kind, length, delta in candidates:
            flat = int(np.argmin(delta))
            if delta.flat[flat] < best_delta:
                row, column = divmod(flat, delta.shape[1])
                best_delta, best_move = float(delta.flat[flat]), (kind, row, column, length)
        if best_move is None or not best_delta < -tolerance:
            break
        nodes = _apply(nodes, *best_move)
        moves += 1
    return nodes, moves, evaluations


def _apply(nodes: np.ndarray, kind: str, row: int, column: int, length: int) -> np.ndarray:
    """The path after one move found by :func:`local_search` (row/column of its delta table)."""
    if kind == "reverse":
        i, j = row + 1, column + 1
        nodes[i : j + 1] = nodes[i : j + 1][::-1]
        return nodes
    if kind == "exchange":
        i, j = row + 1, column + 1
        nodes[[i, j]] = nodes[[j, i]]
        return nodes
    if kind == "relocate":
        i, p = row + 1, column
        segment = nodes[i : i + length].copy()
        rest = np.concatenate((nodes[:i], nodes[i + length :]))
        at = p + 1 if p < i else p + 1 - length
        return np.concatenate((rest[:at], segment, rest[at:]))
    # tails: cuts before c < d; each tail runs to the position before the next route start
    c, d = row + 1, column + 1
    is_start = nodes >= nodes[0]
    end_c = c + int(np.argmax(is_start[c:]))  # first start (or the end point) at or after c
    end_d = d + int(np.argmax(is_start[d:]))
    return np.concatenate(
        (nodes[:c], nodes[d:end_d], nodes[end_c:d], nodes[c:end_c], nodes[end_d:])
    )


@functools.lru_cache(maxsize=64)
def _move_masks(inner: int) -> tuple[np.ndarray, dict[int, np.ndarray], np.ndarray, np.ndarray]:
    """+inf at the moves a path with ``inner`` free genes cannot make, per move type.

    Reversal needs j > i; a segment i..i+length-1 cannot go between p and p + 1
    for p in i-1..i+length-1 (that is where it already is); an exchange needs
    j > i + 1 (neighbours are a relocation). The last array is True where a
    tails move is not counted (c >= d; it is symmetric).
    """
    position = np.arange(1, inner + 1)
    reverse_block = np.where(position[None, :] > position[:, None], 0.0, np.inf)
    exchange_block = np.where(position[None, :] > position[:, None] + 1, 0.0, np.inf)
    place = np.arange(inner + 1)[None, :]
    relocate_block = {
        length: np.where(
            (place < position[: inner - length + 1, None] - 1)
            | (place > position[: inner - length + 1, None] + length - 1),
            0.0,
            np.inf,
        )
        for length in (1, 2, 3)
        if inner - length + 1 >= 1
    }
    later = ~np.triu(np.ones((inner + 1, inner + 1), dtype=bool), 1)
    for block in (reverse_block, exchange_block, later, *relocate_block.values()):
        block.setflags(write=False)
    return reverse_block, relocate_block, exchange_block, later


__all__ = ["NEIGHBOURHOOD", "local_search"]
