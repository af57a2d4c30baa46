"""Insertion heuristics of thesis §5.4 with the topological-sorting technique (§5.4.1).

Three rules build a precedence-feasible visiting order one node at a time:

* :func:`nia_order` — the nearest inserting algorithm, (5.12)–(5.13);
* :func:`mma_order` — the minimum marginal-cost algorithm, (5.14)–(5.16);
* :func:`smma_order` — the second-order minimum marginal-cost algorithm, (5.17)–(5.18).

They are written generically on a cost matrix and precedence pairs, so the same code serves
the truck–drone delivery problem (cost = the thesis's t* matrix D^d of (5.11), start = the
depot w0) and TSPLIB sequential ordering problems (start = node 0, end = the last node).
The registered delivery methods "NIA", "MMA" and "SMMA" (see :func:`taopt.heuristics.run`)
build the order on t* and score it with the exact scheduler :func:`taopt.schedule`.

Shared machinery (§5.4.1)
-------------------------
The path R_l starts as ``[start]`` (``[start, end]`` when an end node is forced last).
A node is *viable* when it has no un-inserted predecessor in G^p' (the topological-sorting
technique: inserting a node deletes it and its outgoing precedence edges from G^p').
A viable node c_j may only be inserted after all its inserted predecessors, i.e. after
position p = max_{c_r in T^j} find(R_l, c_r), and never after a forced end node.
Because an insertion keeps the relative order of the nodes already placed, every order
produced is precedence-feasible (transitively, not only for the direct pairs).

Positions are 0-based here: "slot q" means "insert right after R_l[q]"; slot 0 is right
after the start node. Ties are broken by the lowest node index first, then the lowest slot
(the earliest position in the path); :func:`numpy.argmin` on a (node, slot) array whose rows
are sorted by node index does exactly that.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import networkx as nx
import numpy as np

from taopt.delivery.dags import cycle_path
from taopt.delivery.instance import DeliveryInstance
from taopt.errors import InstanceError, SolverError
from taopt.registry import register_method
from taopt.result import FEASIBLE, NO_SOLUTION, Order, Solution, make_solution
from taopt.sop.problem import SopProblem

# path_cost is defined in taopt.tsplib; re-exported here (heuristics and tests import it from
# this module).
from taopt.tsplib import path_cost

__all__ = [
    "nia_order",
    "mma_order",
    "smma_order",
    "path_cost",
    "check_order",
    "backtrack_order",
    "NoOrderError",
    "REPAIR_BUDGET",
]


# ---------------------------------------------------------------------------------------------
# Validation and the shared path state
# ---------------------------------------------------------------------------------------------


def _validate(
    cost: Any, precedences: Iterable[Sequence[int]], start: int, end: int | None
) -> tuple[np.ndarray, np.ndarray, list[tuple[int, int]]]:
    """Check the data; return the cost matrix, the nodes to order and the useful pairs.

    Pairs ``(start, x)`` and ``(x, end)`` always hold and are dropped; ``(x, start)`` and
    ``(end, x)`` can never hold and raise :class:`InstanceError`, as does a cycle.
    """
    matrix = np.asarray(cost, dtype=float)
    if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1] or matrix.shape[0] < 1:
        raise InstanceError(f"cost must be a square matrix, got shape {matrix.shape}")
    size = matrix.shape[0]
    if np.isnan(matrix).any():
        row, col = np.argwhere(np.isnan(matrix))[0]
        raise InstanceError(f"cost[{row}, {col}] is NaN")
    if (matrix == -np.inf).any():
        row, col = np.argwhere(matrix == -np.inf)[0]
        raise InstanceError(f"cost[{row}, {col}] is -inf")
    for name, node in (("start", start), ("end", end)):
        if node is None:
            continue
        if isinstance(node, bool) or int(node) != node or not 0 <= int(node) < size:
            raise InstanceError(f"{name} node {node!r} is not an index of the {size}x{size} matrix")
    if end is not None and end == start:
        raise InstanceError(f"end node {end} equals the start node")
    pairs: list[tuple[int, int]] = []
    graph = nx.DiGraph()
    for pair in precedences:
        if len(pair) != 2:
            raise InstanceError(f"precedence {pair!r} is not a pair (before, after)")
        before, after = (int(x) for x in pair)
        for node in (before, after):
            if not 0 <= node < size:
                raise InstanceError(
                    f"precedence ({before}, {after}) names node {node} outside 0..{size - 1}"
                )
        if before == after:
            raise InstanceError(f"self-precedence ({before}, {after})")
        if after == start:
            raise InstanceError(f"precedence ({before}, {after}) puts a node before the start node")
        if end is not None and before == end:
            raise InstanceError(f"precedence ({before}, {after}) puts a node after the end node")
        if before == start or after == end:
            continue  # always satisfied
        graph.add_edge(before, after)
        pairs.append((before, after))
    names = cycle_path(graph)
    if names:
        raise InstanceError(f"precedence cycle {names}")
    keep = np.ones(size, dtype=bool)
    keep[int(start)] = False
    if end is not None:
        keep[int(end)] = False
    return matrix, np.flatnonzero(keep), pairs


class _PathState:
    """R_l, positions, viable set (§5.4.1) and marginal costs (5.14) on a cost matrix."""

    def __init__(self, cost: np.ndarray, pairs: list[tuple[int, int]], start: int, end: int | None):
        self.cost = cost
        size = cost.shape[0]
        self.path: list[int] = [int(start)] if end is None else [int(start), int(end)]
        self.open = end is None  # an open path may grow at its end (first line of (5.14))
        self.position = np.full(size, -1, dtype=np.int64)
        self.position[self.path] = np.arange(len(self.path))
        self.predecessor = np.zeros((size, size), dtype=bool)  # predecessor[j, r]: r before j
        self.successors: list[list[int]] = [[] for _ in range(size)]
        self.waiting = np.zeros(size, dtype=np.int64)  # un-inserted predecessors in G^p'
        for before, after in set(pairs):
            self.predecessor[after, before] = True
            self.successors[before].append(after)
            self.waiting[after] += 1
        self.pending = np.zeros(size, dtype=bool)
        for node in range(size):
            if self.position[node] < 0:
                self.pending[node] = True

    # -- topological sorting technique -------------------------------------------------------
    def viable(self) -> np.ndarray:
        """T^A_{R_l}: un-inserted nodes with no un-inserted predecessor, ascending."""
        return np.flatnonzero(self.pending & (self.waiting == 0))

    def n_slots(self) -> int:
        """Number of insertion slots: after each node, but never after a forced end node."""
        return len(self.path) if self.open else len(self.path) - 1

    def earliest_slot(self, nodes: np.ndarray) -> np.ndarray:
        """p = max find(R_l, c_r) over the inserted predecessors (0 = after the start)."""
        if len(nodes) == 0:
            return np.zeros(0, dtype=np.int64)
        masked = np.where(self.predecessor[nodes], self.position[None, :], 0)
        return masked.max(axis=1)

    def insert(self, node: int, slot: int) -> None:
        """(5.13)/(5.16): put ``node`` right after R_l[slot]; update G^p' and the viable set."""
        self.path.insert(slot + 1, int(node))
        self.position[self.path[slot + 1 :]] = np.arange(slot + 1, len(self.path))
        self.pending[node] = False
        for successor in self.successors[node]:
            self.waiting[successor] -= 1

    # -- costs ------------------------------------------------------------------------------
    def slot_ends(self) -> tuple[np.ndarray, np.ndarray]:
        """Arrays ``tail[q] = R_l[q]`` and ``head[q] = R_l[q+1]`` (-1 for an open end)."""
        slots = self.n_slots()
        path = np.asarray(self.path, dtype=np.int64)
        tail = path[:slots]
        head = np.full(slots, -1, dtype=np.int64)
        following = path[1:]
        head[: len(following)] = following[:slots]
        return tail, head

    def marginal_costs(self, nodes: np.ndarray) -> np.ndarray:
        """(5.14) for every node (rows) and slot (columns); inf where (5.15) forbids the slot.

        Inserting between R_l[q] and R_l[q+1] costs t*(R_l[q], c) + t*(c, R_l[q+1]) -
        t*(R_l[q], R_l[q+1]); appending to an open path costs t*(R_l[-1], c) only. An
        infinite removed edge (e.g. a big start->end arc) is counted as 0.
        """
        tail, head = self.slot_ends()
        closed = head >= 0
        into = self.cost[tail[:, None], nodes[None, :]].T  # t*(R_l(q), c_j)
        out = np.zeros_like(into)
        removed = np.zeros(len(tail))
        if closed.any():
            out[:, closed] = self.cost[nodes[:, None], head[closed][None, :]]
            removed[closed] = self.cost[tail[closed], head[closed]]
        removed[~np.isfinite(removed)] = 0.0
        marginal = into + out - removed[None, :]
        slots = np.arange(len(tail))
        marginal[slots[None, :] < self.earliest_slot(nodes)[:, None]] = np.inf
        return marginal

    def result(self) -> list[int]:
        return list(self.path)


def _argmin_2d(values: np.ndarray) -> tuple[int, int]:
    """Row-major argmin: lowest row (node index) first, then lowest column (slot)."""
    flat = int(np.argmin(values))
    return divmod(flat, values.shape[1])


def _no_slot(rule: str, node: int) -> SolverError:
    """The error of a greedy rule that cannot place ``node``: no slot uses only usable arcs.

    A greedy dead end, not a proof that the problem is infeasible (an exact method may
    still find an order).
    """
    return SolverError(
        f"{rule} found no feasible order (greedy dead end: every slot for node {node} "
        "needs a forbidden arc)"
    )


# ---------------------------------------------------------------------------------------------
# The backtracking repair of a greedy dead end
# ---------------------------------------------------------------------------------------------

#: Partial paths the backtracking repair may extend before it gives up (deterministic). At
#: about 0.1 ms an extension, a search that gives up takes a few seconds; on random SOPs
#: with 50-80 % forbidden arcs and n <= 100 it finds an order in under 0.05 s.
REPAIR_BUDGET = 50_000


class NoOrderError(SolverError):
    """No precedence-feasible order on usable arcs was found: the greedy rule met a dead end
    and the backtracking repair found nothing either. ``proved`` is True when the repair
    tried every partial path (so no feasible order exists), False when its budget ran out."""

    def __init__(self, message: str, proved: bool) -> None:
        super().__init__(message)
        self.proved = proved


def backtrack_order(
    cost: Any,
    precedences: Iterable[Sequence[int]] = (),
    start: int = 0,
    end: int | None = None,
    budget: int = REPAIR_BUDGET,
) -> tuple[list[int] | None, bool]:
    """A precedence-feasible path on usable (finite) arcs by depth-first backtracking.

    The repair the insertion rules fall back on at a greedy dead end. From ``start`` the
    path grows by one node at a time: a node whose predecessors are all on the path, joined
    by a finite arc, cheapest arc first; ``end`` (when given) only as the last node. A
    partial path is abandoned when some node left could no longer be entered (no finite
    arc into it from the path's last node or another node left) or left (no finite arc out
    of it to another node left, or to ``end``), and every (visited set, last node) state
    that failed is remembered, so no state is searched twice.

    Parameters
    ----------
    cost, precedences, start, end
        As in :func:`nia_order`.
    budget : int
        Most partial paths extended before giving up.

    Returns
    -------
    path : list of int or None
        A feasible path, or None.
    proved : bool
        With ``path`` None: True when every state was searched (no feasible order exists),
        False when the budget ran out first.

    Example
    -------
    Arc 1 -> 2 is forbidden and 1 must precede 2, so the path must be 0, 1, 3, 2:

    >>> inf = float("inf")
    >>> C = [[0, 1, 5, 9], [1, 0, inf, 1], [1, 1, 0, 1], [1, 1, 1, 0]]
    >>> backtrack_order(C, [(1, 2)], start=0)
    ([0, 1, 3, 2], False)

    Notes
    -----
    Exponential in the worst case (the SOP's feasibility question is NP-complete with
    forbidden arcs); the memo bounds the work by the number of (set, last) states,
    O(2^n n), and ``budget`` caps it. Each extension costs O(n) numpy work (the check keeps
    counts of the usable arcs into and out of the nodes left).
    """
    matrix, _, pairs = _validate(cost, precedences, start, end)
    size = matrix.shape[0]
    usable = np.isfinite(matrix)
    np.fill_diagonal(usable, False)
    if end is not None:
        usable[end, :] = False  # nothing leaves the end of the path
        usable[:, start] = False
    successors: list[list[int]] = [[] for _ in range(size)]
    waiting = np.zeros(size, dtype=np.int64)  # predecessors not yet on the path
    for before, after in set(pairs):
        successors[before].append(after)
        waiting[after] += 1
    left = np.ones(size, dtype=bool)  # nodes not yet on the path
    arcs = usable.astype(np.int64)
    entries = arcs.sum(axis=0)  # usable arcs into each node from the nodes left
    exits = arcs.sum(axis=1)  # usable arcs out of each node to the nodes left
    inner = np.ones(size, dtype=bool)  # nodes that must leave on an arc (not the end)
    if end is not None:
        inner[end] = False
    failed: set[tuple[int, int]] = set()  # (visited bitmask, last node) that led nowhere
    spent = 0

    def place(node: int) -> None:
        left[node] = False
        entries[:] -= arcs[node]
        exits[:] -= arcs[:, node]
        for successor in successors[node]:
            waiting[successor] -= 1

    def unplace(node: int) -> None:
        left[node] = True
        entries[:] += arcs[node]
        exits[:] += arcs[:, node]
        for successor in successors[node]:
            waiting[successor] += 1

    def hopeless(last: int) -> bool:
        """Some node left can no longer be entered or left on usable arcs."""
        if ((entries + arcs[last] < 1) & left).any():
            return True
        stuck = (exits < 1) & left
        if end is not None:
            return bool((stuck & inner).any())
        return int(stuck.sum()) > 1  # an open path: only its last node leaves nothing

    def choices(last: int) -> list[int]:
        """The nodes that may follow ``last``, the one to try first at the end."""
        ready = left & usable[last] & (waiting == 0)
        if end is not None and left.sum() > 1:
            ready[end] = False
        nodes = np.flatnonzero(ready)
        return nodes[np.lexsort((nodes, matrix[last, nodes]))][::-1].tolist()

    path = [int(start)]
    mask = 1 << int(start)
    place(int(start))
    stack = [choices(int(start))]
    while stack:
        if not left.any():
            return path, False
        options = stack[-1]
        if not options:  # every extension of this partial path failed
            stack.pop()
            failed.add((mask, path[-1]))
            node = path.pop()
            mask &= ~(1 << node)
            unplace(node)
            continue
        node = options.pop()
        grown = mask | (1 << node)
        if (grown, node) in failed:
            continue
        spent += 1
        if spent > budget:
            return None, False
        place(node)
        if hopeless(node):
            failed.add((grown, node))
            unplace(node)
            continue
        path.append(node)
        mask = grown
        stack.append(choices(node))
    return None, True


def _repair(
    rule: str, node: int, cost: Any, precedences: Any, start: int, end: int | None
) -> list[int]:
    """The greedy ``rule`` is stuck at ``node``: a backtracking path, or NoOrderError."""
    path, proved = backtrack_order(cost, precedences, start, end)
    if path is not None:
        return path
    why = (
        "no feasible order exists (the backtracking repair searched every partial path)"
        if proved
        else f"the backtracking repair found none within {REPAIR_BUDGET} extensions"
    )
    raise NoOrderError(
        f"{rule} met a dead end (every slot for node {node} needs a forbidden arc) and {why}",
        proved,
    )


# ---------------------------------------------------------------------------------------------
# NIA (5.12)-(5.13)
# ---------------------------------------------------------------------------------------------


def nia_order(
    cost: Any,
    precedences: Iterable[Sequence[int]] = (),
    start: int = 0,
    end: int | None = None,
    repair: bool = True,
) -> list[int]:
    """Nearest inserting algorithm (NIA), thesis (5.12)–(5.13).

    In each iteration pick the viable node c_j and slot q minimising t*(R_l(q), c_j) over
    q in T_a^j = {p, ..., |R_l|} and insert c_j right after R_l(q). The cost of the edge the
    insertion breaks, and of the edge it creates towards R_l(q+1), is ignored (as printed);
    but a slot whose new edge c_j -> R_l(q+1) is forbidden (infinite cost) is not offered,
    so the order never uses a forbidden arc (the thesis's t* has none between customers
    that can follow each other; a TSPLIB SOP file has many).

    Parameters
    ----------
    cost : (N, N) array_like
        Asymmetric travel costs, e.g. the t* matrix D^d of (5.11); ``inf`` marks a forbidden arc.
    precedences : iterable of (before, after) node pairs
        The edges of G^p; ``(r, j)`` means r is visited before j.
    start : int
        The node R_l is initialised with (the depot w0).
    end : int, optional
        A node forced to be last (TSPLIB SOP); nothing is ever inserted after it.
    repair : bool
        At a greedy dead end (a node that no slot takes without a forbidden arc), return
        the path of the backtracking repair :func:`backtrack_order` instead (default);
        False: raise.

    Returns
    -------
    list of int
        The full path, beginning with ``start`` (and ending with ``end`` when given),
        visiting every node once and respecting every precedence.

    Raises
    ------
    InstanceError
        Bad matrix or indices, a precedence cycle, or a pair that cannot hold.
    SolverError
        ``repair=False``: the greedy rule reached a node it cannot insert without a
        forbidden arc (a dead end of the heuristic, not a proof that no order exists).
        ``repair=True``: :class:`NoOrderError`, the repair found no order either (its
        ``proved`` says whether none exists).

    Examples
    --------
    Worked by hand on the matrix (rows = from, columns = to; start 0, pair (1, 2))::

            0  1  2  3
        0 [ 0  6  1  9 ]
        1 [ 5  0  7  3 ]
        2 [ 3  6  0  9 ]
        3 [ 5  1  9  0 ]

    R = [0]; viable {1, 3} (2 waits for 1): t*(0,1) = 6 < t*(0,3) = 9 -> [0, 1].
    R = [0, 1]; viable {2, 3}: 2 only after 1 (p = 1): 7; 3 after 0: 9, after 1: 3
    -> 3 after 1: [0, 1, 3].
    R = [0, 1, 3]; viable {2}: after 1: 7, after 3: 9 -> [0, 1, 2, 3] (path cost 22).

    >>> C = [[0, 6, 1, 9], [5, 0, 7, 3], [3, 6, 0, 9], [5, 1, 9, 0]]
    >>> nia_order(C, [(1, 2)], start=0)
    [0, 1, 2, 3]

    Notes
    -----
    Complexity O(n^3) with numpy (one (viable x slot) array per iteration), against the
    O(n^5) operation count of thesis §5.4.3.

    References
    ----------
    Thesis §5.4.1 (topological sorting) and §5.4.2, equations (5.12)–(5.13).
    """
    matrix, _, pairs = _validate(cost, precedences, start, end)
    state = _PathState(matrix, pairs, start, end)
    while True:
        nodes = state.viable()
        if len(nodes) == 0:
            break
        tail, head = state.slot_ends()
        nearest = matrix[tail[:, None], nodes[None, :]].T  # t*(R_l(q), c_j)
        closed = head >= 0
        if closed.any():  # the edge c_j -> R_l(q+1) the insertion creates must be usable
            onward = matrix[nodes[:, None], head[closed][None, :]]
            nearest[:, closed] = np.where(np.isfinite(onward), nearest[:, closed], np.inf)
        slots = np.arange(len(tail))
        nearest[slots[None, :] < state.earliest_slot(nodes)[:, None]] = np.inf
        row, slot = _argmin_2d(nearest)
        if not np.isfinite(nearest[row, slot]):
            if not repair:
                raise _no_slot("NIA", int(nodes[row]))
            return _repair("NIA", int(nodes[row]), matrix, pairs, start, end)
        state.insert(int(nodes[row]), slot)
    return state.result()


# ---------------------------------------------------------------------------------------------
# MMA (5.14)-(5.16)
# ---------------------------------------------------------------------------------------------


def mma_order(
    cost: Any,
    precedences: Iterable[Sequence[int]] = (),
    start: int = 0,
    end: int | None = None,
    repair: bool = True,
) -> list[int]:
    """Minimum marginal-cost algorithm (MMA), thesis (5.14)–(5.16).

    In each iteration pick the viable node c_j and position minimising the marginal cost
    (5.14) of inserting it, over the slots after its last inserted predecessor (5.15), and
    insert it (5.16). The path is open: appending after the last node costs t*(last, c_j)
    only. With a forced end node the path is [start, ..., end] and every slot is closed.

    Parameters and return value as in :func:`nia_order`.

    Examples
    --------
    Same matrix as :func:`nia_order`, by hand (marginal cost of each slot):

    R = [0]; viable {1, 3}: append 1 costs 6, append 3 costs 9 -> [0, 1].
    R = [0, 1]; viable {2, 3}: 2 after 1: 7; 3 between 0 and 1: 9 + 1 - 6 = 4, after 1: 3
    -> [0, 1, 3].
    R = [0, 1, 3]; viable {2} (after 1): between 1 and 3: 7 + 9 - 3 = 13, after 3: 9
    -> [0, 1, 3, 2] (path cost 18; NIA's was 22).

    >>> C = [[0, 6, 1, 9], [5, 0, 7, 3], [3, 6, 0, 9], [5, 1, 9, 0]]
    >>> mma_order(C, [(1, 2)], start=0)
    [0, 1, 3, 2]

    Notes
    -----
    O(n^3) in total with numpy (all slots of all viable nodes in one array op per iteration).

    References
    ----------
    Thesis §5.4.2, equations (5.14)–(5.16).
    """
    matrix, _, pairs = _validate(cost, precedences, start, end)
    state = _PathState(matrix, pairs, start, end)
    while True:
        nodes = state.viable()
        if len(nodes) == 0:
            break
        marginal = state.marginal_costs(nodes)
        row, slot = _argmin_2d(marginal)
        if not np.isfinite(marginal[row, slot]):
            if not repair:
                raise _no_slot("MMA", int(nodes[row]))
            return _repair("MMA", int(nodes[row]), matrix, pairs, start, end)
        state.insert(int(nodes[row]), slot)
    return state.result()


# ---------------------------------------------------------------------------------------------
# SMMA (5.17)-(5.18)
# ---------------------------------------------------------------------------------------------


def _best_two(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per row: the lowest slot with the minimum value, that value, and the second-best value."""
    best_slot = np.argmin(values, axis=1)
    rows = np.arange(values.shape[0])
    best = values[rows, best_slot]
    if values.shape[1] > 1:
        others = values.copy()
        others[rows, best_slot] = np.inf
        second = others.min(axis=1)
    else:
        second = np.full(values.shape[0], np.inf)
    return best_slot, best, second


def smma_order(
    cost: Any,
    precedences: Iterable[Sequence[int]] = (),
    start: int = 0,
    end: int | None = None,
    lookahead: str = "current",
    repair: bool = True,
) -> list[int]:
    """Second-order minimum marginal-cost algorithm (SMMA), thesis (5.17)–(5.18).

    For every viable c_{j1}, take its best slot q1* under MMA's rule (5.15); on the path
    R' = R_l ⊕_{q1*} c_{j1} find the cheapest insertion (c_{j2}, q2) of a second node. Choose
    the c_{j1} minimising the two-step cost t(R' ⊕_{q2} c_{j2}) - t(R_l), and insert only
    c_{j1} at q1* (5.18). When only one node is viable the two-step rule has no c_{j2}; the
    step then is MMA's (the only candidate at its MMA-best slot).

    Parameters
    ----------
    cost, precedences, start, end, repair
        As in :func:`nia_order`.
    lookahead : {"current", "updated"}
        Which nodes c_{j2} ranges over. ``"current"`` (default) reads (5.17) literally:
        c_{j2} ∈ T^A_{R_l} \\ {c_{j1}}, the viable set *before* inserting c_{j1}.
        ``"updated"`` also admits the successors of c_{j1} that become viable once it is
        inserted (they may only go after c_{j1}).

    Returns
    -------
    list of int
        The full path, as in :func:`nia_order`.

    Examples
    --------
    Same matrix as :func:`nia_order`, by hand (two-step costs m1 + m2):

    R = [0]: c_j1 = 1 (append, 6) then 3 best after 1 (3): 9; c_j1 = 3 (append, 9) then 1
    between 0 and 3 (6 + 3 - 9 = 0): 9. A tie (both reach [0, 1, 3]); lowest index -> [0, 1].
    R = [0, 1]: c_j1 = 2 (after 1, 7) then 3 between 0 and 1 (4): 11; c_j1 = 3 (after 1,
    3) then 2 after 3 (9): 12 -> [0, 1, 2].
    R = [0, 1, 2]; only 3 viable, MMA's rule: between 0 and 1: 4, between 1 and 2: 5,
    after 2: 9 -> [0, 3, 1, 2] (path cost 17; MMA's was 18).

    >>> C = [[0, 6, 1, 9], [5, 0, 7, 3], [3, 6, 0, 9], [5, 1, 9, 0]]
    >>> smma_order(C, [(1, 2)], start=0)
    [0, 3, 1, 2]

    Notes
    -----
    The printed rule costs O(n^6) (§5.4.3). Here a second insertion on R' reuses the
    marginal costs on R_l: every slot of R_l except the broken one keeps its cost, so for
    each c_{j2} the best and second-best old slots are kept, and only the two new slots
    around c_{j1} are evaluated, for all (c_{j1}, c_{j2}) pairs in one array op:
    O(|T^A| |R_l| + |T^A|^2) per iteration, O(n^3) in total (0.1 s for 120 customers,
    against 37.6 s in thesis Table 5.7). Ties: lowest c_{j1}, and q1* the earliest of its
    best slots.

    The look-ahead is greedy and does not guarantee a better order than MMA. On the §5.5
    pairs setup (10 random instances, 120 customers, v_d/v_t = 1.4, L = 0.45 km;
    ``benchmarks/bench_delivery_heuristics.py --instances 10``) the mean makespan was
    13849 for SMMA against 13403 for MMA (13770 with ``lookahead="updated"``), whereas
    thesis Tables 5.5–5.6 report SMMA ahead of MMA.

    References
    ----------
    Thesis §5.4.2, equations (5.17)–(5.18).
    """
    if lookahead not in ("current", "updated"):
        raise InstanceError(f"lookahead must be 'current' or 'updated', got {lookahead!r}")
    matrix, _, pairs = _validate(cost, precedences, start, end)
    state = _PathState(matrix, pairs, start, end)
    while True:
        nodes = state.viable()
        if len(nodes) == 0:
            break
        marginal = state.marginal_costs(nodes)
        if len(nodes) == 1:
            row, slot = _argmin_2d(marginal)
            if not np.isfinite(marginal[row, slot]):
                if not repair:
                    raise _no_slot("SMMA", int(nodes[row]))
                return _repair("SMMA", int(nodes[row]), matrix, pairs, start, end)
            state.insert(int(nodes[row]), slot)
            continue
        first_slot, first_cost, second_best = _best_two(marginal)  # q1*, m(q1*), runner-up
        placeable = np.isfinite(first_cost)  # a node with no usable slot now waits
        if not placeable.any():
            if not repair:
                raise _no_slot("SMMA", int(nodes[0]))
            return _repair("SMMA", int(nodes[0]), matrix, pairs, start, end)
        with np.errstate(invalid="ignore"):  # inf - inf on forbidden arcs: NaN, made inf
            second_cost = _second_step(state, nodes, marginal, first_slot, second_best)
            if lookahead == "updated":
                second_cost = np.minimum(
                    second_cost, _second_step_successors(state, nodes, first_slot)
                )
            total = np.where(placeable, first_cost + second_cost, np.inf)
        if not np.isfinite(total).any():  # no usable second step: MMA's rule
            total = first_cost
        row = int(np.argmin(total))
        state.insert(int(nodes[row]), int(first_slot[row]))
    return state.result()


def _second_step(
    state: _PathState,
    nodes: np.ndarray,
    marginal: np.ndarray,
    first_slot: np.ndarray,
    second_best: np.ndarray,
) -> np.ndarray:
    """min over c_{j2} in T^A \\ {c_{j1}} and slots q2 of the marginal cost on R', per c_{j1}.

    Slots of R' = R_l ⊕_{q1} c_{j1}: the old slots q != q1 with unchanged cost; the slot
    between R_l[q1] and c_{j1}; the slot between c_{j1} and R_l[q1+1] (or the open end).
    The two new slots are allowed for c_{j2} iff q1 >= p(c_{j2}).
    """
    cost = state.cost
    tail, head = state.slot_ends()
    best_slot = np.argmin(marginal, axis=1)  # per j2: lowest best old slot
    best_value = marginal[np.arange(len(nodes)), best_slot]
    # old slots: the best one unless it is the slot c_{j1} breaks, then the runner-up
    old = np.where(
        best_slot[None, :] == first_slot[:, None], second_best[None, :], best_value[None, :]
    )
    q1 = first_slot
    before = tail[q1]  # R_l[q1]
    after = head[q1]  # R_l[q1+1], or -1 on an open end
    j1 = nodes[:, None]
    j2 = nodes[None, :]
    new_left = cost[before[:, None], j2] + cost[j2, j1] - cost[before, nodes][:, None]
    new_right = cost[j1, j2].copy()
    closed = after >= 0
    if closed.any():
        closing = np.where(closed, after, 0)
        extra = cost[j2, closing[:, None]] - cost[nodes, closing][:, None]
        new_right += np.where(closed[:, None], extra, 0.0)
    allowed = q1[:, None] >= state.earliest_slot(nodes)[None, :]
    new = np.where(allowed, np.minimum(new_left, new_right), np.inf)
    second = np.minimum(old, new)
    np.fill_diagonal(second, np.inf)  # c_{j2} != c_{j1}
    second = np.where(np.isnan(second), np.inf, second)
    return second.min(axis=1)


def _second_step_successors(
    state: _PathState, nodes: np.ndarray, first_slot: np.ndarray
) -> np.ndarray:
    """lookahead="updated": best insertion of a successor freed by c_{j1}, per c_{j1}."""
    cost = state.cost
    _, head = state.slot_ends()
    result = np.full(len(nodes), np.inf)
    for row, node in enumerate(nodes):
        freed = [s for s in state.successors[node] if state.pending[s] and state.waiting[s] == 1]
        if not freed:
            continue
        freed_arr = np.asarray(sorted(freed), dtype=np.int64)
        q1 = int(first_slot[row])
        old = state.marginal_costs(freed_arr)[:, q1 + 1 :]  # old slots after c_{j1}
        best_old = old.min(axis=1) if old.shape[1] else np.full(len(freed_arr), np.inf)
        after = head[q1]
        right = cost[node, freed_arr].copy()
        if after >= 0:
            right += cost[freed_arr, after] - cost[node, after]
        earliest = state.earliest_slot(freed_arr)  # old predecessors other than c_{j1}
        right[earliest > q1] = np.inf  # another predecessor sits after c_{j1}
        result[row] = np.minimum(best_old, right).min()
    return result


# ---------------------------------------------------------------------------------------------
# Orders: cost and checks
# ---------------------------------------------------------------------------------------------


def check_order(
    order: Sequence[int],
    n_nodes: int,
    precedences: Iterable[Sequence[int]] = (),
    start: int | None = None,
    end: int | None = None,
) -> None:
    """Raise :class:`InstanceError` unless ``order`` is a precedence-feasible path.

    Checks that every node 0..n_nodes-1 appears exactly once, that ``start``/``end`` are
    first/last when given, and that every pair (r, j) has r before j.
    """
    order = [int(x) for x in order]
    if sorted(order) != list(range(n_nodes)):
        raise InstanceError(f"order {order} is not a permutation of 0..{n_nodes - 1}")
    if start is not None and order[0] != start:
        raise InstanceError(f"order starts at {order[0]}, not at the start node {start}")
    if end is not None and order[-1] != end:
        raise InstanceError(f"order ends at {order[-1]}, not at the end node {end}")
    where = {node: k for k, node in enumerate(order)}
    for before, after in precedences:
        if where[int(before)] > where[int(after)]:
            raise InstanceError(f"precedence ({before}, {after}) violated")


# ---------------------------------------------------------------------------------------------
# The delivery problem: order on t*, schedule exactly
# ---------------------------------------------------------------------------------------------


def delivery_cost_matrix(
    instance: Any,
) -> tuple[np.ndarray, int, list[tuple[int, int]], np.ndarray]:
    """The t* matrix D^d (5.11) of a delivery instance, in the node indexing of this module.

    Returns
    -------
    cost : (n+1, n+1) array
        ``taopt.delivery.costs.drone_cost_matrix(instance)``: node c < n is customer c and
        node n is the depot w0 (``cost[c, n] = inf``: nothing returns to the depot).
    start : int
        The depot's node, n.
    pairs : list of (before, after)
        The instance's precedences (5.7), customer indices = node indices.
    customer_of : (n+1,) int array
        ``customer_of[node]``: the customer index of a node, -1 for the depot.
    """
    from taopt.delivery.costs import drone_cost_matrix

    cost = np.asarray(drone_cost_matrix(instance), dtype=float)
    n = instance.n
    if cost.shape != (n + 1, n + 1):
        raise InstanceError(f"t* matrix has shape {cost.shape}, expected {(n + 1, n + 1)}")
    pairs = [(int(r), int(j)) for r, j in instance.precedences]
    customer_of = np.append(np.arange(n), -1)
    return cost, n, pairs, customer_of


def schedule_order(instance: Any, path: Sequence[int], customer_of: np.ndarray) -> Solution:
    """Map a node path (depot first) to customers and schedule it with :func:`taopt.schedule`.

    The thesis (§5.4.2, last paragraph) recomputes feasible times after ordering with the
    remaining range L_{c_r} = L - d(w_r, c_r); the exact dynamic programme of
    :func:`taopt.delivery.schedule.schedule` supersedes that step: it returns the best
    launch/landing stops and truck path for the order, hence the true makespan (5.1).
    """
    from taopt.delivery.schedule import schedule

    order = [int(customer_of[node]) for node in path if customer_of[node] >= 0]
    return schedule(instance, order)


_RULES: dict[str, Callable[..., list[int]]] = {
    "NIA": nia_order,
    "MMA": mma_order,
    "SMMA": smma_order,
}


def ordered_or_repaired(
    name: str, cost: Any, pairs: Any, start: int, end: int | None, **options: Any
) -> tuple[list[int] | None, dict[str, Any]]:
    """The rule ``name``'s path, the backtracking repair's at a dead end, or None.

    Returns the path and the ``info`` to record: ``{}`` for the rule's own path;
    ``repaired`` (True) and ``dead_end`` (the rule's message) for a repaired one; with
    None, ``error`` (why), ``dead_end`` and ``proved_infeasible`` (whether the repair
    searched every partial path, so that no order exists).
    """
    try:
        return _RULES[name](cost, pairs, start, end, repair=False, **options), {}
    except InstanceError:
        raise
    except SolverError as exc:
        dead_end = str(exc)
    path, proved = backtrack_order(cost, pairs, start, end)
    if path is not None:
        return path, {"repaired": True, "dead_end": dead_end}
    why = (
        "no feasible order exists (the backtracking repair searched every partial path)"
        if proved
        else f"the backtracking repair found none within {REPAIR_BUDGET} extensions"
    )
    return None, {
        "error": f"{name} found no order: {why}",
        "dead_end": dead_end,
        "proved_infeasible": proved,
    }


def no_order_solution(
    problem: Any, name: str, seed: int, began: float, info: dict[str, Any]
) -> Solution:
    """Status "no_solution" (objective inf, no payload): the heuristic found no order."""
    return Solution(
        objective=math.inf,
        status=NO_SOLUTION,
        solution=None,
        runtime=time.perf_counter() - began,
        method=name,
        seed=seed,
        info=info,
    )


def _delivery_method(name: str, instance: Any, seed: int = 0, **options: Any) -> Solution:
    began = time.perf_counter()
    cost, start, pairs, customer_of = delivery_cost_matrix(instance)
    path, info = ordered_or_repaired(name, cost, pairs, start, None, **options)
    if path is None:
        return no_order_solution(instance, name, seed, began, info)
    solution = schedule_order(instance, path, customer_of)
    return solution.replace(
        method=name,
        seed=seed,
        runtime=time.perf_counter() - began,
        info={**solution.info, **info, "tstar_cost": path_cost(cost, path)},
    )


@register_method(DeliveryInstance, "NIA", style=("-", "o"))
def nia_delivery(instance: Any, seed: int = 0, **options: Any) -> Solution:
    """NIA (5.12)–(5.13) on t* from the depot, then the exact schedule of the order.

    The thesis's last step of §5.4.2 (re-timing with L_{c_r} = L - d(w_r, c_r)) is
    superseded by :func:`taopt.schedule`, exact for the order. Deterministic: ``seed`` is
    only recorded. ``info["tstar_cost"]`` is the order's path cost on t*.
    """
    return _delivery_method("NIA", instance, seed, **options)


@register_method(DeliveryInstance, "MMA", style=("--", "s"))
def mma_delivery(instance: Any, seed: int = 0, **options: Any) -> Solution:
    """MMA (5.14)–(5.16) on t* from the depot, then the exact schedule (see NIA)."""
    return _delivery_method("MMA", instance, seed, **options)


@register_method(DeliveryInstance, "SMMA", style=("-.", "D"))
def smma_delivery(instance: Any, seed: int = 0, **options: Any) -> Solution:
    """SMMA (5.17)–(5.18) on t* from the depot, then the exact schedule (see NIA).

    Option ``lookahead`` ("current" or "updated") as in :func:`smma_order`.
    """
    return _delivery_method("SMMA", instance, seed, **options)


def _sop_method(name: str, problem: SopProblem, seed: int = 0, **options: Any) -> Solution:
    """The rule's order (repaired at a dead end), or status "no_solution" with the reason
    in ``info["error"]`` (:func:`ordered_or_repaired`)."""
    began = time.perf_counter()
    path, info = ordered_or_repaired(
        name, problem.cost, problem.precedences, problem.start, problem.end, **options
    )
    if path is None:
        return no_order_solution(problem, name, seed, began, info)
    return make_solution(
        problem,
        Order(path),
        method=name,
        status=FEASIBLE,
        runtime=time.perf_counter() - began,
        seed=seed,
        info=info,
    )


@register_method(SopProblem, "NIA")
def nia_sop(problem: SopProblem, seed: int = 0, **options: Any) -> Solution:
    """NIA (5.12)–(5.13) on the SOP's own cost matrix, from ``start`` to ``end``."""
    return _sop_method("NIA", problem, seed, **options)


@register_method(SopProblem, "MMA")
def mma_sop(problem: SopProblem, seed: int = 0, **options: Any) -> Solution:
    """MMA (5.14)–(5.16) on the SOP's own cost matrix, from ``start`` to ``end``."""
    return _sop_method("MMA", problem, seed, **options)


@register_method(SopProblem, "SMMA")
def smma_sop(problem: SopProblem, seed: int = 0, **options: Any) -> Solution:
    """SMMA (5.17)–(5.18) on the SOP's own cost matrix, from ``start`` to ``end``."""
    return _sop_method("SMMA", problem, seed, **options)
