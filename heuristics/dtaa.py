"""DTAA: the distributed task assignment algorithm of chapter 3 (§3.5, Algorithm 2).

For each capability class q in turn (in the order of ``problem.capabilities``), every
vehicle of the fleet runs Algorithm 2 on the communication graph:

1. bid (3.6): ``c_jr = min_{k in o_j} t(k, r)`` and ``β_jr = j`` for every unassigned
   ``r in T_q^u``; ``c_jr = inf`` when j lacks capability q (all vehicles take part, as
   §3.5.1 says, so that vehicles of R_q talk through vehicles of other classes);
2. ``|R|`` synchronous rounds (lines 10–17): each vehicle sends ``(c_j, β_j)`` to its
   neighbours, receives theirs and keeps, per target, the smallest bid (3.7);
3. pick (3.8): ``r* = argmin_r c_jr``; the vehicle ``β_jr*`` adds ``r*`` to ``o_j`` (3.9);
   every vehicle removes ``r*`` from its own copy of ``T_q^u``;

until ``T_q^u`` is empty; then each vehicle orders its targets by the marginal-cost
principle (3.10)–(3.11) (:func:`ordering_principle`: cheapest insertion after its start; the
same rule as chapter 2's (2.18), :func:`taopt.heuristics.clustering.marginal_cost_sequence`).

Ties (where the thesis is silent): in (3.7) the smallest ``(c, β)`` pair wins (equal bids go
to the lower vehicle index); in (3.8) the lowest target index. A vehicle wins only a finite
bid (read literally, line 20 would let a vehicle with no vehicle of R_q in reach "win" a
target at infinite cost).

Simulation: state is held per vehicle (its own ``c_j``, ``β_j`` and ``T_q^u``) and rounds
are synchronous. After ``s`` rounds vehicle j holds the smallest ``(c, β)`` within ``s``
hops, so after the largest eccentricity of its component (at most ``|R| - 1``) nothing
changes any more: the remaining rounds of the ``|R|`` are counted, not recomputed.

Byte model: a message from vehicle j carries a header of 8 bytes (sender id and class index,
two 32-bit integers) and, for every target of j's ``T_q^u`` in the common increasing order,
its bid ``c_jr`` (an IEEE-754 double, 8 bytes) and bidder ``β_jr`` (a 32-bit integer,
4 bytes): ``8 + 12 |T_q^u|`` bytes. Every vehicle sends one message to each neighbour in
each round; the counts include every one of Algorithm 2's ``|T_q| |R|`` rounds per class.

Theorem 3.5 says the assignment equals Algorithm 1's ("MCGA") per class on every connected
graph: :mod:`taopt.orchestration.studies.capability_claims` checks it. On a disconnected graph the vehicles of
different components reach different "consensus" values: a component holding vehicles of
class q assigns every target of T_q to its own vehicles, so a target is served once per
such component, and (3.2) fails; :func:`distributed_auction` returns those assignments,
:func:`dtaa` refuses the graph.

References
----------
Thesis §3.5.1 (3.6)–(3.9), Algorithm 2; §3.5.2 (3.10)–(3.11); Theorem 3.5.
"""

from __future__ import annotations

import time
from collections.abc import Hashable
from dataclasses import dataclass, field
from typing import Any

import networkx as nx
import numpy as np

from taopt.capability.problem import CapabilityProblem
from taopt.errors import InstanceError
from taopt.registry import register_method
from taopt.result import FEASIBLE, Routes, Solution, make_solution

#: Header bytes of one message (sender id, class index: two 32-bit integers).
HEADER_BYTES = 8
#: Bytes per target entry of a message (a float64 bid and a 32-bit bidder).
ENTRY_BYTES = 12

__all__ = [
    "HEADER_BYTES",
    "ENTRY_BYTES",
    "ClassAuction",
    "AuctionResult",
    "communication_graph",
    "distributed_auction",
    "ordering_principle",
    "dtaa",
]


@dataclass(frozen=True)
class ClassAuction:
    """Algorithm 2 on one class q.

    Attributes
    ----------
    capability : label
    assigned : list of list of int
        ``assigned[j]``: targets (whole-problem indices) vehicle j added to ``o_j``, in the
        order it won them; empty for vehicles outside R_q.
    picks : list of list of (target, winner)
        ``picks[j]``: the (r*, β_jr*) vehicle j saw at each auction step.
    rounds, messages, bytes : int
        Synchronous rounds (``|T_q| |R|``), messages and bytes of this class's auction.
    computed_rounds : int
        Rounds actually recomputed (``|T_q| min(depth, |R|)``; the others repeat a fixed
        point).
    consensus : bool
        Every vehicle saw the same r* and winner at every step.
    """

    capability: Hashable
    assigned: list[list[int]]
    picks: list[list[tuple[int, int]]]
    rounds: int
    messages: int
    bytes: int
    computed_rounds: int
    consensus: bool


@dataclass(frozen=True)
class AuctionResult:
    """Algorithm 2 on every class, and the communication it took."""

    classes: tuple[ClassAuction, ...]
    connected: bool
    components: list[list[int]] = field(default_factory=list)

    @property
    def rounds(self) -> int:
        return sum(c.rounds for c in self.classes)

    @property
    def messages(self) -> int:
        return sum(c.messages for c in self.classes)

    @property
    def bytes(self) -> int:
        return sum(c.bytes for c in self.classes)

    def served(self) -> dict[tuple[int, Hashable], list[int]]:
        """(target, capability) -> every vehicle that took it (more than one: (3.2) fails)."""
        out: dict[tuple[int, Hashable], list[int]] = {}
        for cls in self.classes:
            for j, targets in enumerate(cls.assigned):
                for r in targets:
                    out.setdefault((r, cls.capability), []).append(j)
        return out


def communication_graph(graph: Any, m: int) -> nx.Graph:
    """The communication topology on vehicles ``0..m-1`` (default: complete).

    Raises
    ------
    InstanceError
        Not a networkx graph, or nodes other than the vehicle indices (named).
    """
    if graph is None:
        return nx.complete_graph(m)
    if not isinstance(graph, nx.Graph):
        raise InstanceError(f"graph must be a networkx graph, got {type(graph).__name__}")
    extra = sorted(set(graph.nodes) - set(range(m)), key=str)
    if extra:
        raise InstanceError(f"graph node {extra[0]!r} is not a vehicle index 0..{m - 1}")
    full = graph.copy()
    full.add_nodes_from(range(m))  # a vehicle missing from the graph is isolated
    return full


def _neighbours(graph: nx.Graph, m: int) -> np.ndarray:
    """(m, D) padded array: vehicle j hears itself and each vehicle it receives from."""
    lists = []
    for j in range(m):
        heard = graph.predecessors(j) if graph.is_directed() else graph.neighbors(j)
        lists.append([j, *sorted(i for i in heard if i != j)])
    width = max(len(x) for x in lists)
    return np.array([x + [x[0]] * (width - len(x)) for x in lists], dtype=int)


def _is_connected(graph: nx.Graph) -> bool:
    if graph.number_of_nodes() <= 1:
        return True
    if graph.is_directed():
        return nx.is_strongly_connected(graph)
    return nx.is_connected(graph)


def _depth(graph: nx.Graph, nodes: list[int]) -> int:
    """Rounds after which min-propagation is stable on a component: its largest eccentricity
    (for a directed graph, the longest shortest path into a vehicle)."""
    if len(nodes) == 1:
        return 0
    sub = graph.subgraph(nodes)
    lengths = dict(nx.all_pairs_shortest_path_length(sub))
    return max(max(d.values()) for d in lengths.values())


def _auction(
    problem: CapabilityProblem,
    cls: Any,
    heard: np.ndarray,
    degree: np.ndarray,
    depth: int,
    shortcut: bool = True,
) -> ClassAuction:
    """Algorithm 2 for class ``cls``, simulated vehicle by vehicle.

    ``depth`` is the largest eccentricity in the graph's components: after that many
    rounds of (3.7) every vehicle holds the smallest bid of its component, and further
    rounds repeat the same messages, so they are counted but not recomputed.
    """
    m, n = problem.m, problem.n
    targets = np.array(cls.targets, dtype=int)
    size = len(targets)
    cost = problem.cost_for(cls.capability)
    between = cost[np.ix_(targets, targets)]
    member = np.array([c == cls.capability for c in problem.vehicle_capability])
    # (3.6) with o_j = {p_j}: c_jr = t(p_j, r) for vehicles of R_q, inf for the others;
    # a target a vehicle has removed from its own T_q^u is masked by `open_`.
    own = np.where(member[:, None], cost[n + np.arange(m)][:, targets], np.inf)  # (m, size)
    open_ = np.ones((m, size), dtype=bool)  # each vehicle's own T_q^u
    ids = np.arange(m)
    self_bidder = np.repeat(ids[:, None], size, axis=1)
    chosen_log = np.empty((size, m), dtype=int)
    winner_log = np.empty((size, m), dtype=int)
    won_log = np.zeros((size, m), dtype=bool)
    computed = min(depth, m)
    heard_ids = np.broadcast_to(heard[:, :, None], heard.shape + (size,))
    if shortcut and computed == 1 and heard.shape[1] == m:
        # every vehicle hears every vehicle (complete graph): after one round of (3.7) all
        # hold the same smallest (c, beta) pairs, computed here once for all of them
        for step in range(size):
            best = own.min(axis=0)
            who = own.argmin(axis=0)  # the lowest vehicle on equal bids
            r = int(np.argmin(best))  # the lowest open target on ties
            finite = bool(np.isfinite(best[r]))
            if not finite:
                r = int(np.argmax(open_[0]))
            chosen_log[step], winner_log[step] = r, who[r]
            open_[:, r] = False
            own[:, r] = np.inf
            if finite:
                winner = int(who[r])
                won_log[step, winner] = True
                own[winner] = np.where(open_[winner], np.minimum(own[winner], between[r]), np.inf)
    for step in range(size if not (shortcut and computed == 1 and heard.shape[1] == m) else 0):
        # own[j] is inf outside j's T_q^u: within a component every vehicle holds the same
        # T_q^u, so a vehicle never hears a bid for a target it has closed
        bid, bidder, bidder_heard = own, self_bidder, heard_ids
        for round_ in range(computed):  # (3.7): keep the smallest (c, beta) heard
            heard_bid = bid[heard]  # (m, D, size)
            bid = heard_bid.min(axis=1)
            bidder = np.where(heard_bid == bid[:, None, :], bidder_heard, m).min(axis=1)
            if round_ + 1 < computed:
                bidder_heard = bidder[heard]
        # (3.8)-(3.9) at every vehicle on its own state: the lowest open target on ties
        chosen = np.argmin(bid, axis=1)
        value = bid[ids, chosen]
        blind = np.isinf(value)  # no finite bid heard (no vehicle of R_q in reach)
        if blind.any():
            chosen[blind] = np.argmax(open_[blind], axis=1)
        winner = bidder[ids, chosen]
        won = (winner == ids) & ~blind
        chosen_log[step], winner_log[step], won_log[step] = chosen, winner, won
        open_[ids, chosen] = False
        own[ids, chosen] = np.inf
        if won.any():  # (3.6): o_j grew, so c_jr = min over o_j includes the new target
            own[won] = np.where(open_[won], np.minimum(own[won], between[chosen[won]]), np.inf)
    assigned = [targets[chosen_log[won_log[:, j], j]].tolist() for j in range(m)]
    picks = [
        list(zip(targets[chosen_log[:, j]].tolist(), winner_log[:, j].tolist(), strict=True))
        for j in range(m)
    ]
    consensus = bool(
        np.all(chosen_log == chosen_log[:, :1]) and np.all(winner_log == winner_log[:, :1])
    )
    # every vehicle removes one target per step, so |T_q^u| = size - step for all of them:
    # each of the m rounds of step s carries sum_j deg_j messages of 8 + 12 (size - s) bytes
    open_counts = size - np.arange(size)
    volume = m * int(degree.sum()) * int((HEADER_BYTES + ENTRY_BYTES * open_counts).sum())
    return ClassAuction(
        capability=cls.capability,
        assigned=assigned,
        picks=picks,
        rounds=size * m,
        messages=size * m * int(degree.sum()),
        bytes=volume,
        computed_rounds=size * computed,
        consensus=consensus,
    )


def distributed_auction(
    problem: CapabilityProblem, graph: Any = None, shortcut: bool = True
) -> AuctionResult:
    """Algorithm 2 for every class on the communication graph (connected or not).

    Parameters
    ----------
    problem : CapabilityProblem
    graph : networkx graph on vehicles ``0..m-1``, optional
        Default: complete. A directed graph means "j receives from its in-neighbours".
    shortcut : bool
        On a complete graph every vehicle holds the same state after one round; compute it
        once instead of per vehicle (the same result, message for message; False forces the
        per-vehicle simulation, for tests).

    Returns
    -------
    AuctionResult
        Per class: each vehicle's won targets, what each vehicle saw, rounds, messages,
        bytes; ``connected`` and the components. On a disconnected graph a target may be
        taken by several vehicles (see :meth:`AuctionResult.served`).
    """
    graph = communication_graph(graph, problem.m)
    heard = _neighbours(graph, problem.m)
    degree = np.array(
        [graph.out_degree(j) if graph.is_directed() else graph.degree(j) for j in range(problem.m)]
    ) - np.array([int(graph.has_edge(j, j)) for j in range(problem.m)])
    connected = _is_connected(graph)
    if graph.is_directed():
        components = [sorted(c) for c in nx.strongly_connected_components(graph)]
    else:
        components = [sorted(c) for c in nx.connected_components(graph)]
    depth = max(_depth(graph, c) for c in components)
    classes = tuple(
        _auction(problem, cls, heard, degree, depth, shortcut)
        for cls in problem.classes
        if cls.targets
    )
    return AuctionResult(classes=classes, connected=connected, components=sorted(components))


def ordering_principle(cost: np.ndarray, start: int, targets: list[int]) -> list[int]:
    """The ordering principle (3.10)–(3.11) for one vehicle: repeated cheapest insertion.

    Starting from ``λ_j = (p_j)``, insert the (target, position) pair with the smallest
    increase ``t(λ_j ⊕_k r) - t(λ_j)`` of the open route's time, positions after the start
    (``1 < k <= |λ_j| + 1``). Ties: lowest target index, then earliest position. The same
    rule as chapter 2's (2.18); here the insertion costs are kept per gap and only the two
    gaps an insertion creates are computed, O(|o_j|^2) numpy work per vehicle.

    Parameters
    ----------
    cost : (N, N) array
    start : int
        Index of the vehicle's start ``p_j`` in ``cost``.
    targets : list of int
        The vehicle's targets ``o_j \\ {p_j}`` (indices into ``cost``).

    Returns
    -------
    list of int
        ``λ_j`` without the start.

    Example
    -------
    >>> import numpy as np
    >>> x = np.array([0.0, 3.0, 1.0, 2.0])           # start at 0, targets at 3, 1, 2
    >>> ordering_principle(abs(x[:, None] - x[None, :]), 0, [1, 2, 3])
    [2, 3, 1]
    """
    if not targets:
        return []
    order = np.array(sorted(targets), dtype=int)
    nodes = np.concatenate([[start], order])
    local = cost[np.ix_(nodes, nodes)]  # point 0 is the start, point p + 1 target order[p]
    size = len(order)
    # rows: the gaps of the route in route order; the last row is the open end
    # table[k, g]: the cost of inserting target k + 1 into gap g of the route (gaps in route
    # order, the last one the open end); rows of inserted targets hold inf
    table = np.empty((size, size + 1))
    table[:, 0] = local[0, 1:]
    route = [0]
    dead = np.zeros(size, dtype=bool)
    for length in range(1, size + 1):  # `length` gaps so far
        flat = int(np.argmin(table[:, :length]))  # target-major: lowest target, earliest gap
        pick, gap = divmod(flat, length)
        point = pick + 1
        before = route[gap]
        dead[pick] = True
        # insertion cost through a gap (a, b): t(a, k) + t(k, b) - t(a, b)
        into = local[before, 1:] + local[1:, point] - local[before, point]
        if gap + 1 < length:  # between before and after: two new gaps replace one
            after = route[gap + 1]
            out = local[point, 1:] + local[1:, after] - local[point, after]
            table[:, gap + 2 : length + 1] = table[:, gap + 1 : length]
        else:  # at the open end: the old end becomes a gap, the new point the end
            out = local[point, 1:]
        table[:, gap] = np.where(dead, np.inf, into)
        table[:, gap + 1] = np.where(dead, np.inf, out)
        table[pick, : length + 1] = np.inf
        route.insert(gap + 1, point)
    return [int(order[p - 1]) for p in route[1:]]


def _order(problem: CapabilityProblem, auction: AuctionResult) -> list[list[int]]:
    """(3.10)–(3.11) for every vehicle."""
    routes: list[list[int]] = [[] for _ in range(problem.m)]
    for result in auction.classes:
        cost = problem.cost_for(result.capability)
        for vehicle, mine in enumerate(result.assigned):
            if mine:  # only vehicles of this class ever win its targets
                routes[vehicle] = ordering_principle(cost, problem.n + vehicle, mine)
    return routes


@register_method(CapabilityProblem, "DTAA", style=("-", "d"))
def dtaa(problem: CapabilityProblem, graph: Any = None, seed: int | None = 0) -> Solution:
    """DTAA: Algorithm 2's auction per class, then the ordering principle (3.10)–(3.11).

    Parameters
    ----------
    problem : CapabilityProblem
    graph : networkx graph on vehicles ``0..m-1``, optional
        Communication topology (default complete); must be connected.
    seed : int
        Recorded only: DTAA is deterministic.

    Returns
    -------
    Solution
        ``info``: ``rounds``, ``messages``, ``bytes`` (byte model in the module notes),
        ``computed_rounds`` (rounds recomputed before the fixed point) and ``per_class``
        counts.

    Raises
    ------
    InstanceError
        The graph is disconnected (the message names the components and a target served
        more than once, or a class whose vehicles cannot be heard).

    Example
    -------
    >>> import numpy as np, networkx as nx
    >>> x = np.array([1.0, 2.0, 8.0, 0.0, 9.0])        # targets 1, 2, 8; vehicles at 0, 9
    >>> p = CapabilityProblem(abs(x[:, None] - x[None, :]), 3, ["a", "a"], [{"a"}] * 3)
    >>> s = dtaa(p, graph=nx.path_graph(2))
    >>> s.routes, s.objective, s.info["rounds"], s.info["messages"]
    ([[0, 1], [2]], 3.0, 6, 12)
    """
    start = time.perf_counter()
    auction = distributed_auction(problem, graph)
    if not auction.connected:
        served = auction.served()
        twice = next(((key, who) for key, who in served.items() if len(who) > 1), None)
        detail = (
            f"target {twice[0][0]} is taken for capability {twice[0][1]!r} by vehicles {twice[1]}"
            if twice
            else "no target was taken twice, but Theorem 3.5's consensus does not hold"
        )
        raise InstanceError(
            f"the communication graph is disconnected (components {auction.components}): "
            f"{detail}; DTAA needs a connected graph"
        )
    routes = _order(problem, auction)
    info = {
        "rounds": auction.rounds,
        "messages": auction.messages,
        "bytes": auction.bytes,
        "computed_rounds": sum(c.computed_rounds for c in auction.classes),
        "per_class": [
            {
                "capability": str(c.capability),
                "rounds": c.rounds,
                "messages": c.messages,
                "bytes": c.bytes,
            }
            for c in auction.classes
        ],
    }
    return make_solution(
        problem,
        Routes(routes),
        method="DTAA",
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        seed=seed,
        info=info,
    )
