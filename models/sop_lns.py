"""Exact reinsertion of removed nodes: a large neighbourhood for sequential ordering orders.

The SOP-3-exchange search (:mod:`taopt.models.sop_search`) moves whole segments; its local
optima are deep (an iterated run on ry48p.1 or ft53.1 stays on one cost for seconds). This
module gives a second, complementary neighbourhood: remove ``k`` nodes from a feasible order
and put them back *optimally* into the ``m + 1 = n - k`` nodes kept in their order (a
destroy-and-repair step of a large neighbourhood search whose repair is exact).

The repair is a dynamic programme over the gaps of the kept sequence ``f_0 = start, ...,
f_m = end``. Its states at gap ``p`` (after ``f_p``, before ``f_{p+1}``) are ``(S, l)``: ``S``
the removed nodes placed so far, ``l`` the last node placed (``f_p`` or one of ``S``)::

    V_p(S, r)      = min_l V_p(S - r, l) + c[l, r]            (r inserted in gap p)
    V_{p+1}(S, f)  = min_l V_p(S, l) + c[l, f_{p+1}]            (f_{p+1} placed next)

with ``V_0({}, f_0) = 0`` and the repaired order's cost ``V_m(R, f_m)``. Precedence (5.7)
holds exactly when (i) a removed node ``r`` goes in a gap ``p`` with ``lo(r) <= p < hi(r)``,
``lo(r)`` the last kept position holding a closure predecessor of ``r`` and ``hi(r)`` the
first holding a closure successor (the kept nodes keep their relative order, which was
feasible), and (ii) ``r`` is inserted only after every removed closure predecessor of ``r``
(``S`` contains them). The kept order with the removed nodes in their old places is one of
the paths of the programme, so the repaired order never costs more than the order it came
from. It is computed along the new order (after ``t`` nodes, a state's gap is ``t - |S|``),
each step vectorised over the subsets reached: work ``O(n 2^k k^2)``.

:func:`repair` is one such step; :func:`large_neighbourhood_search` alternates it with the
SOP-3-exchange descent and, when repairs stop improving, the iterated search's random segment
swaps (kicks) with a strength that doubles while they find nothing better, then restarts from
a random greedy order (:func:`random_order`); seeded, stopped by a
:class:`~taopt.runtime.Deadline`, an iteration count or a patience. The portfolio runs it on
its first DP stage's order (``taopt.models.sop.ILS_SHARE``): from a width-64 beam's order the
iterated search alone stayed in that order's basin (ry48p.1 16,321 on seeds 0-4 after 5
CPU-seconds), this search left it (15,805, the optimum, on each of them).

References
----------
Thesis (5.7) (precedence). P. Shaw, "Using constraint programming and local search methods to
solve vehicle routing problems", CP 1998 (large neighbourhood search, related removal).
E. Balas and N. Simonetti, "Linear time dynamic-programming algorithms for new classes of
restricted TSPs", INFORMS J. Computing 13(1), 2001 (exact neighbourhoods by dynamic
programming).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from taopt.models.sop_search import (
    ACCEPT_SHARE,
    KICK_LENGTH_SHARE,
    KICKS,
    before_matrix,
    kick,
    local_search,
    order_cost,
)
from taopt.runtime import Deadline
from taopt.sop.problem import SopProblem

__all__ = [
    "GREEDY_CHOICES",
    "REACH",
    "REMOVE",
    "REPAIR_PATIENCE",
    "RESTART_KICKS",
    "large_neighbourhood_search",
    "random_order",
    "repair",
]

#: Nodes removed by one repair step (``2^k`` subsets per gap: 8 keeps a step at a few
#: milliseconds on 50 nodes).
REMOVE = 8

#: A removed node goes back at most this many gaps from where it was (:func:`repair`'s
#: ``reach``; None: anywhere its precedences allow). Off: at 10 gaps a repair took 3.9 ms
#: instead of 6.1 ms on ry48p.1, but from a width-64 beam's order 5 s of the search ended
#: prob.42 at 256-260 on seeds 0-4 (247-248 without), load 5-6.
REACH: int | None = None

#: Repair steps in a row without improving the current order after which the search kicks it
#: (the iterated search's segment swaps, :func:`~taopt.models.sop_search.kick`).
REPAIR_PATIENCE = 15

#: Kicks of the largest strength in a row without a better order after which the search
#: restarts from a random greedy order (:func:`random_order`).
RESTART_KICKS = 3

#: A random greedy order draws each next node among this many cheapest arcs.
GREEDY_CHOICES = 3


class _Subsets:
    """The subsets of ``k`` removed nodes grouped by size, with their bit masks."""

    def __init__(self, k: int) -> None:
        every = np.arange(1 << k, dtype=np.int64)
        sizes = np.array([bin(s).count("1") for s in range(1 << k)])
        self.k = k
        self.layers = [every[sizes == size] for size in range(k)]
        self.bits = np.left_shift(1, np.arange(k, dtype=np.int64))
        # has[s, r]: subset s holds removed node r
        self.has = (every[:, None] & self.bits[None, :]) != 0


_SUBSETS: dict[int, _Subsets] = {}


def _subsets(k: int) -> _Subsets:
    if k not in _SUBSETS:
        _SUBSETS[k] = _Subsets(k)
    return _SUBSETS[k]


def repair(
    cost: np.ndarray,
    before: np.ndarray,
    order: Sequence[int] | np.ndarray,
    removed: Sequence[int] | np.ndarray,
    reach: int | None = None,
) -> tuple[float, np.ndarray]:
    """The cheapest order that keeps ``order``'s other nodes in their order and reinserts the
    nodes at positions ``removed`` (module docstring).

    Parameters
    ----------
    cost : (n, n) ndarray
        Arc costs (``inf`` forbids an arc).
    before : (n, n) bool ndarray
        The precedence closure (:func:`~taopt.models.sop_search.before_matrix`).
    order : sequence of int
        A precedence-feasible order from start to end.
    removed : sequence of int
        Distinct inner positions (neither the first nor the last).
    reach : int, optional
        Each removed node goes back at most this many gaps from the gap it came from (None:
        anywhere its precedences allow).

    Returns
    -------
    tuple
        ``(cost, order)``: the repaired order, never costlier than ``order``, and its cost
        (``order`` itself when it is already the cheapest).
    """
    o = np.asarray(order, dtype=np.intp)
    n = len(o)
    at = sorted({int(i) for i in removed if 0 < int(i) < n - 1})
    k = len(at)
    if k == 0:
        return order_cost(cost, o), o
    keep = np.ones(n, dtype=bool)
    keep[at] = False
    fixed = o[keep]
    moved = o[at]
    m = len(fixed) - 1
    # lo(r): last kept position with a predecessor of r; hi(r): first with a successor
    pred = before[np.ix_(fixed, moved)]  # fixed node precedes moved node
    succ = before[np.ix_(moved, fixed)]  # moved node precedes fixed node
    positions = np.arange(m + 1)
    lo = np.where(pred, positions[:, None], -1).max(axis=0)
    hi = np.where(succ, positions[None, :], m + 1).min(axis=1)
    if reach is not None:  # at most ``reach`` gaps from the gap each node came from
        came = np.searchsorted(np.flatnonzero(keep), at) - 1  # the gap each node left
        lo = np.maximum(lo, came - reach)
        hi = np.minimum(hi, came + reach + 1)
    sub = _subsets(k)
    size = 1 << k
    inner = before[np.ix_(moved, moved)]  # inner[a, b]: moved a precedes moved b
    needs = (inner * sub.bits[:, None]).sum(axis=0)  # mask of r's removed predecessors
    every = np.arange(size, dtype=np.int64)
    # ready[s, r]: r is not in s and all its removed predecessors are
    ready = ~sub.has & ((every[:, None] & needs[None, :]) == needs[None, :])
    placed = sub.has.sum(axis=1)  # |S|
    # must[q]: the removed nodes placed before the kept node f_q (their hi <= q)
    must = np.array([sub.bits[hi <= q].sum() for q in range(m + 1)], dtype=np.int64)
    among = cost[np.ix_(moved, moved)]  # r' -> r
    into = cost[np.ix_(fixed, moved)]  # f_p -> r
    out_moved = cost[np.ix_(moved, fixed)]  # r -> f_q
    kept_arcs = np.append(cost[fixed[:-1], fixed[1:]], np.inf)  # f_p -> f_{p+1}
    full = size - 1
    # step t: t nodes after the start are placed; a state (S, l) has p = t - |S| kept ones
    values = np.full((n, size, k + 1), np.inf)
    values[0, 0, k] = 0.0
    for t in range(n - 1):
        live = np.flatnonzero(np.isfinite(values[t]).any(axis=1))  # the reached subsets
        now = values[t, live]
        p = t - placed[live]  # the gap of each reached subset (0 <= p <= m)
        nxt = values[t + 1]
        # the kept node f_{p+1} next, once every removed node due before it is placed
        ahead = np.minimum(p + 1, m)
        leave = np.hstack([out_moved[:, ahead].T, kept_arcs[p][:, None]])
        ok = (p < m) & ((live & must[ahead]) == must[ahead])
        nxt[live[ok], k] = (now[ok] + leave[ok]).min(axis=1)
        # a removed node r next, in gap p
        cand = np.minimum(
            (now[:, :k, None] + among[None, :, :]).min(axis=1), now[:, k, None] + into[p]
        )
        ok = ready[live] & (lo[None, :] <= p[:, None]) & (p[:, None] < hi[None, :])
        rows, cols = np.nonzero(ok & np.isfinite(cand))
        if len(rows):
            nxt[live[rows] | sub.bits[cols], cols] = cand[rows, cols]
    value = float(values[n - 1, full, k])
    if not np.isfinite(value):  # cannot happen from a feasible order; kept safe
        return order_cost(cost, o), o
    # backtrack from (every removed node, f_m) at the last step
    path: list[int] = [int(fixed[m])]
    s, last = full, k
    for t in range(n - 1, 0, -1):
        gap = t - int(placed[s])
        before_t = values[t - 1]
        if last == k:  # f_gap came from (s, l) in the gap before
            arcs = np.append(out_moved[:, gap], kept_arcs[gap - 1])
            last = int(np.argmin(before_t[s] + arcs))
        else:  # moved[last] came from (s - r, l) in this gap
            r = last
            s ^= 1 << r
            arcs = np.append(among[:, r], into[gap, r])
            last = int(np.argmin(before_t[s] + arcs))
        path.append(int(fixed[t - 1 - int(placed[s])]) if last == k else int(moved[last]))
    repaired = np.array(path[::-1], dtype=np.intp)
    new = order_cost(cost, repaired)
    old = order_cost(cost, o)
    if not new < old:
        return old, o
    return new, repaired


def _removal(cost: np.ndarray, order: np.ndarray, k: int, rng: np.random.Generator) -> np.ndarray:
    """Inner positions to remove: a random window of ``k`` consecutive positions, ``k``
    random positions, or a random node with the ``k - 1`` nodes joined to it by the cheapest
    arcs (either way), each a third of the time."""
    n = len(order)
    inner = n - 2
    k = min(k, inner)
    kind = int(rng.integers(0, 3))
    if kind == 0:
        first = 1 + int(rng.integers(0, inner - k + 1))
        return np.arange(first, first + k)
    if kind == 1:
        return 1 + rng.choice(inner, size=k, replace=False)
    seed = 1 + int(rng.integers(0, inner))
    u = order[seed]
    near = np.minimum(cost[u, order[1:-1]], cost[order[1:-1], u])
    near[seed - 1] = -np.inf  # the node itself first
    near = near + rng.random(inner) * 1e-9  # ties broken at random
    return 1 + np.argsort(near, kind="stable")[:k]


def random_order(problem: SopProblem, before: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A random greedy precedence-feasible order: from the start, each next node drawn among
    the (at most) :data:`GREEDY_CHOICES` cheapest arcs into nodes whose predecessors are all
    placed (the end last)."""
    n = problem.n
    waiting = before.sum(axis=0).astype(np.int64)  # unplaced predecessors of each node
    placed = np.zeros(n, dtype=bool)
    order = [problem.start]
    placed[problem.start] = True
    waiting -= before[problem.start]
    for _ in range(n - 1):
        free = np.flatnonzero((waiting == 0) & ~placed)
        if len(free) > 1:
            free = free[free != problem.end]
        arcs = problem.cost[order[-1], free]
        cheapest = free[np.argsort(arcs, kind="stable")[:GREEDY_CHOICES]]
        node = int(rng.choice(cheapest))
        order.append(node)
        placed[node] = True
        waiting -= before[node]
    return np.array(order, dtype=np.intp)


def large_neighbourhood_search(
    problem: SopProblem,
    order: Sequence[int],
    deadline: Deadline | None = None,
    iterations: int | None = None,
    seed: int = 0,
    remove: int = REMOVE,
    restarts: bool = True,
    patience: int | None = None,
) -> tuple[float, list[int], dict[str, Any]]:
    """Exact-repair large neighbourhood search with SOP-3-exchange descents, escalating
    kicks and restarts.

    From a feasible ``order``: descend with the SOP-3-exchange
    (:func:`~taopt.models.sop_search.local_search`), then repeat: remove ``remove`` nodes
    (a random window of consecutive positions, random positions, or a random node and the
    nodes joined to it by the cheapest arcs, a third of the time each) and reinsert them
    optimally (:func:`repair`); an improved order is descended again. After :data:`REPAIR_PATIENCE` repairs in a row without improvement, the
    current order is kicked by random feasible segment swaps
    (:func:`~taopt.models.sop_search.kick`) and descended: :data:`~taopt.models.sop_search.KICKS`
    of them, doubled after each kick that found no better order since the last restart (at
    most a quarter of the nodes). The kicked order is kept when it is within
    :data:`~taopt.models.sop_search.ACCEPT_SHARE` of the best since the last restart, else the
    search goes back to that best. After :data:`RESTART_KICKS` kicks of the largest strength
    in a row without a better order, the search restarts from a new random greedy order
    (:func:`random_order`) when ``restarts``.

    Parameters
    ----------
    problem : SopProblem
    order : sequence of int
        A precedence-feasible order from ``start`` to ``end``.
    deadline : Deadline, optional
        Stops the search (checked between steps).
    iterations : int, optional
        Repair steps at most (None: until the deadline; with neither, one descent only).
    seed : int
        Seed of the removals, kicks and restarts.
    remove : int
        Nodes removed per repair step (:data:`REMOVE`).
    restarts : bool
        Restart from random greedy orders when the kicks stall.
    patience : int, optional
        Stop after this many repair steps in a row without a new best order.

    Returns
    -------
    tuple
        ``(cost, order, info)``: the best order found (never costlier than ``order``) and
        its cost; ``info`` has ``iterations`` (repair steps), ``repaired`` (those that lowered
        the current order's cost), ``kicks``, ``restarts``,
        ``start`` (the first descent's cost) and ``trace`` (seconds and cost of each new best).
    """
    began = time.perf_counter()
    cost = problem.cost
    before = before_matrix(problem)
    rng = np.random.default_rng(seed)
    first = np.asarray(order, dtype=np.intp)
    first_cost = order_cost(cost, first)
    current = local_search(cost, before, first, deadline)
    current_cost = order_cost(cost, current)
    if not current_cost <= first_cost:  # cannot happen (each move lowers the cost); kept safe
        current, current_cost = first, first_cost
    best, best_cost = current, current_cost
    trace = [(time.perf_counter() - began, best_cost)]
    info: dict[str, Any] = {"start": best_cost, "iterations": 0, "kicks": 0, "restarts": 0}
    info["repaired"] = 0  # repair steps that lowered the current order's cost
    info["trace"] = trace
    if problem.n < 5 or (iterations is None and deadline is None):
        return best_cost, [int(v) for v in best], info
    longest = max(2, int(KICK_LENGTH_SHARE * problem.n))
    strongest = max(KICKS, problem.n // 4)
    levels = int(np.ceil(np.log2(strongest / KICKS)))  # doublings up to the strongest kick
    local, local_cost = current, current_cost  # the best since the last restart
    idle = 0  # repairs in a row without improving the current order
    shaken = 0  # kicks in a row without a better order since the last restart
    done = 0
    found = 0  # the step of the last new best
    while (iterations is None or done < iterations) and (
        deadline is None or not deadline.expired()
    ):
        if patience is not None and done - found >= patience:
            break
        done += 1
        removal = _removal(cost, current, remove, rng)
        value, candidate = repair(cost, before, current, removal, REACH)
        if value < current_cost:
            candidate = local_search(cost, before, candidate, deadline)
            current, current_cost = candidate, order_cost(cost, candidate)
            idle = 0
            info["repaired"] += 1
        else:
            idle += 1
        if current_cost < local_cost:
            local, local_cost, shaken = current, current_cost, 0
        elif idle >= REPAIR_PATIENCE:
            idle = 0
            if restarts and shaken >= levels + RESTART_KICKS:
                info["restarts"] += 1
                current = local_search(cost, before, random_order(problem, before, rng), deadline)
                current_cost = order_cost(cost, current)
                local, local_cost, shaken = current, current_cost, 0
            else:
                info["kicks"] += 1
                strength = min(KICKS << min(shaken, 30), strongest)
                candidate, low, high = current, problem.n, 0
                for _ in range(strength):
                    candidate, a, b = kick(before, candidate, rng, longest)
                    low, high = min(low, a), max(high, b)
                span = (low - longest, high + longest)
                candidate = local_search(cost, before, candidate, deadline, span)
                value = order_cost(cost, candidate)
                if value < local_cost:
                    local, local_cost, shaken = candidate, value, 0
                else:
                    shaken += 1
                if value <= local_cost * (1.0 + ACCEPT_SHARE):
                    current, current_cost = candidate, value
                else:
                    current, current_cost = local, local_cost
        if local_cost < best_cost:
            best, best_cost, found = local, local_cost, done
            trace.append((time.perf_counter() - began, best_cost))
    info["iterations"] = done
    return best_cost, [int(v) for v in best], info
