"""SOP-3-exchange local search and an iterated local search for sequential ordering.

The SOP portfolio (:func:`taopt.models.sop.solve_sop_problem`) hands its DP and cut engine
the best order it knows; their pruning is only as good as that order's cost, and a stopped run
reports it (issue 33: prob.42's insertion orders cost 428 against the optimum 243). The
portfolio improves its first DP stage's order before the later stages
(``taopt.models.sop.ILS_SHARE``) with the large neighbourhood search of
:mod:`taopt.models.sop_lns`, which descends with this module's move and kicks with its
:func:`kick`; the iterated search below is kept as the simpler alternative (it stays in its
start's basin more often: from a width-64 beam's order, ry48p.1 16,321 on every seed).

The move (Gambardella and Dorigo, 2000). For an order ``o_0 = start, ..., o_{n-1} = end`` and
positions ``h < i < j <= n - 2``, the *path-preserving 3-exchange* swaps the two consecutive
segments ``L = o_{h+1..i}`` and ``R = o_{i+1..j}``::

    o_0 .. o_h  o_{i+1} .. o_j  o_{h+1} .. o_i  o_{j+1} .. o_{n-1},

keeping each segment's direction (costs are asymmetric). Its change of cost is::

    Δ(h, i, j) = c[o_h, o_{i+1}] + c[o_j, o_{h+1}] + c[o_i, o_{j+1}]
                 - c[o_h, o_{h+1}] - c[o_i, o_{i+1}] - c[o_j, o_{j+1}].

Feasibility: only the relative order of a node of L and a node of R changes, so the new order
keeps every precedence (5.7) if and only if no node of L precedes (in the closure) a node of
R. With ``R[k, i]`` the first position after i holding a successor of ``o_k`` and ``M[h, i] =
min_{h < k <= i} R[k, i]``, the swap is feasible exactly when ``j < M[h, i]`` (the
lexicographic search of Gambardella and Dorigo, which extends R while no successor of L is
met, found here for every (h, i) at once). Moving a run of one to three nodes forwards or
backwards (or-opt) is such a swap, so the neighbourhood holds or-opt.

:func:`local_search` applies the best move of the whole neighbourhood until none lowers the
cost (O(n^3) numpy work a scan, in chunks of h so memory stays O(n^2) per chunk).
:func:`iterated_local_search` perturbs the current order by :data:`KICKS` random feasible
segment swaps (segments of at most :data:`KICK_LENGTH_SHARE` of the nodes), descends again
(first with the moves inside the perturbed stretch widened by that length, then with every
move, so each descent ends at a local optimum of the whole neighbourhood), accepts an
order within :data:`ACCEPT_SHARE` of the best one, and goes back to the best after
:data:`STALL` iterations without a new best; seeded, stopped by a deadline or an iteration
count. Every order it returns keeps the precedences (each move and each kick does).

References
----------
Thesis §5.4 (the insertion orders improved here), (5.7) (precedence). L. M. Gambardella and
M. Dorigo, "An ant colony system hybridized with a new local search for the sequential
ordering problem", INFORMS J. Computing 12(3), 2000 (SOP-3-exchange). H. R. Lourenço,
O. C. Martin and T. Stützle, "Iterated local search", Handbook of Metaheuristics, 2003.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from taopt.runtime import Deadline
from taopt.sop.problem import SopProblem

__all__ = [
    "ACCEPT_SHARE",
    "CHUNK_CELLS",
    "KICK_LENGTH_SHARE",
    "KICKS",
    "STALL",
    "before_matrix",
    "best_exchange",
    "iterated_local_search",
    "kick",
    "local_search",
    "order_cost",
]

#: Cells of one chunk of the (h, i, j) move table (memory: 8 bytes a cell, a few arrays).
CHUNK_CELLS = 1 << 18

#: Random segment swaps per perturbation (one let the search fall back into the same local
#: optimum: prob.42 257-259 in 3 s from a width-64 beam's 276; two gave 247-248).
KICKS = 2

#: A kick's segments hold at most this share of the nodes (at least 2).
KICK_LENGTH_SHARE = 0.125

#: An order within this relative share of the best one's cost is accepted as the current one.
ACCEPT_SHARE = 0.01

#: Iterations without a new best order after which the search goes back to the best one.
STALL = 50


def before_matrix(problem: SopProblem) -> np.ndarray:
    """``B[u, v]``: u precedes v in the precedence closure (start and end included)."""
    before = np.zeros((problem.n, problem.n), dtype=bool)
    for u, v in problem.closure.edges():
        before[u, v] = True
    return before


def _limits(on_path: np.ndarray) -> np.ndarray:
    """``M[h, i]`` of the module docstring, for the order's precedence matrix ``on_path``
    (``on_path[a, b]``: the node at position a precedes the node at position b)."""
    n = len(on_path)
    pos = np.arange(n)
    # first position >= l holding a successor of the node at k, then R[k, i] = that at i + 1
    found = np.where(on_path, pos[None, :], n)
    first = np.minimum.accumulate(found[:, ::-1], axis=1)[:, ::-1]
    after = np.hstack([first[:, 1:], np.full((n, 1), n)])  # R[k, i]
    after = np.where(pos[:, None] <= pos[None, :], after, n)  # only k <= i
    least = np.minimum.accumulate(after[::-1], axis=0)[::-1]  # min over k >= row
    return np.vstack([least[1:], np.full((1, n), n)])  # k in (h, i]


def best_exchange(
    cost: np.ndarray,
    before: np.ndarray,
    order: Sequence[int] | np.ndarray,
    span: tuple[int, int] | None = None,
    deadline: Deadline | None = None,
) -> tuple[float, int, int, int]:
    """The best feasible SOP-3-exchange of ``order``: ``(Δ, h, i, j)`` of the module
    docstring (Δ = inf when there is none); with ``span = (lo, hi)`` only the moves with
    ``lo <= h`` and ``j < hi`` (both segments and their ends inside the span). An expired
    ``deadline`` stops the scan between chunks (the best move of the chunks scanned: a scan
    of a 380-node order takes about a second under load)."""
    o = np.asarray(order, dtype=np.intp)
    n = len(o)
    lo, hi = (0, n - 1) if span is None else (max(0, span[0]), min(n - 1, span[1]))
    if hi - lo < 3:
        return np.inf, lo, lo + 1, lo + 2
    x = cost[np.ix_(o, o)]
    limit = _limits(before[np.ix_(o, o)])
    arcs = np.append(x[np.arange(n - 1), np.arange(1, n)], 0.0)
    firsts = np.arange(lo + 1, hi - 1)
    seconds = np.arange(lo + 2, hi)
    i = firsts[None, :, None]
    j = seconds[None, None, :]
    step = max(1, CHUNK_CELLS // max(1, len(firsts) * len(seconds)))
    best = (np.inf, lo, lo + 1, lo + 2)
    for low in range(lo, hi - 2, step):
        if deadline is not None and low > lo and deadline.expired():
            break
        h = np.arange(low, min(low + step, hi - 2))[:, None, None]
        with np.errstate(invalid="ignore"):
            delta = x[h, i + 1] + x[j, h + 1] + x[i, j + 1] - arcs[h] - arcs[i] - arcs[j]
        valid = (h < i) & (i < j) & (j < limit[h, i])
        delta = np.where(valid & ~np.isnan(delta), delta, np.inf)
        at = int(np.argmin(delta))
        a, b, c = np.unravel_index(at, delta.shape)
        if delta[a, b, c] < best[0]:
            best = (float(delta[a, b, c]), low + int(a), int(firsts[b]), int(seconds[c]))
    return best


def _swapped(order: np.ndarray, h: int, i: int, j: int) -> np.ndarray:
    """``order`` with its segments ``h+1..i`` and ``i+1..j`` swapped."""
    return np.concatenate(
        [order[: h + 1], order[i + 1 : j + 1], order[h + 1 : i + 1], order[j + 1 :]]
    )


def local_search(
    cost: np.ndarray,
    before: np.ndarray,
    order: Sequence[int] | np.ndarray,
    deadline: Deadline | None = None,
    span: tuple[int, int] | None = None,
) -> np.ndarray:
    """``order`` improved by the best SOP-3-exchange (:func:`best_exchange`) until none lowers
    its cost (or ``deadline`` expires); precedence-feasible when ``order`` is. With ``span``,
    the moves inside it first (those a perturbation there opened), then every move."""
    current = np.asarray(order, dtype=np.intp)
    tolerance = 1e-9 * max(1.0, float(np.nanmax(np.where(np.isfinite(cost), cost, 0.0))))
    for where in (span, None) if span is not None else (None,):
        while deadline is None or not deadline.expired():
            delta, h, i, j = best_exchange(cost, before, current, where, deadline)
            if not delta < -tolerance:
                break
            current = _swapped(current, h, i, j)
    return current


def kick(
    before: np.ndarray, order: np.ndarray, rng: np.random.Generator, longest: int
) -> tuple[np.ndarray, int, int]:
    """A random feasible segment swap of segments of at most ``longest`` nodes, with the first
    and last positions it changed (``order`` itself, ``(0, 0)``, when 100 draws find none)."""
    n = len(order)
    for _ in range(100):
        h = int(rng.integers(0, n - 3))
        i = h + int(rng.integers(1, longest + 1))
        j = i + int(rng.integers(1, longest + 1))
        if j <= n - 2 and not before[np.ix_(order[h + 1 : i + 1], order[i + 1 : j + 1])].any():
            return _swapped(order, h, i, j), h, j + 1
    return order, 0, 0


def order_cost(cost: np.ndarray, order: np.ndarray) -> float:
    """The cost of the path ``order`` under ``cost``."""
    return float(cost[order[:-1], order[1:]].sum())


def iterated_local_search(
    problem: SopProblem,
    order: Sequence[int],
    deadline: Deadline | None = None,
    iterations: int | None = None,
    seed: int = 0,
    patience: int | None = None,
) -> tuple[float, list[int], dict[str, Any]]:
    """An iterated SOP-3-exchange local search from a feasible ``order`` (module docstring).

    Parameters
    ----------
    problem : SopProblem
    order : sequence of int
        A precedence-feasible order from ``start`` to ``end``.
    deadline : Deadline, optional
        Stops the search (checked between moves).
    iterations : int, optional
        Perturbations at most (None: until the deadline; with neither, one descent only).
    seed : int
        Seed of the perturbations.
    patience : int, optional
        Stop after this many iterations in a row without a new best order.

    Returns
    -------
    tuple
        ``(cost, order, info)``: the best order found (never costlier than ``order`` after
        its first descent) and its cost; ``info`` has ``iterations`` and ``start`` (the
        first descent's cost).
    """
    cost = problem.cost
    before = before_matrix(problem)
    rng = np.random.default_rng(seed)
    current = local_search(cost, before, order, deadline)
    current_cost = order_cost(cost, current)
    best, best_cost = current, current_cost
    info: dict[str, Any] = {"start": best_cost, "iterations": 0}
    if problem.n < 5 or (iterations is None and deadline is None):
        return best_cost, [int(v) for v in best], info
    longest = max(2, int(KICK_LENGTH_SHARE * problem.n))
    since = 0  # iterations since the last new best or the last return to it
    idle = 0  # iterations since the last new best
    done = 0
    while (iterations is None or done < iterations) and (
        deadline is None or not deadline.expired()
    ):
        if patience is not None and idle >= patience:
            break
        done += 1
        candidate, first, last = current, problem.n, 0
        for _ in range(KICKS):
            candidate, low, high = kick(before, candidate, rng, longest)
            first, last = min(first, low), max(last, high)
        span = (first - longest, last + longest)
        candidate = local_search(cost, before, candidate, deadline, span)
        value = order_cost(cost, candidate)
        if value < best_cost:
            best, best_cost, since, idle = candidate, value, 0, 0
        else:
            since += 1
            idle += 1
        if value <= current_cost or value <= best_cost * (1.0 + ACCEPT_SHARE):
            current, current_cost = candidate, value
        if since >= STALL:
            current, current_cost, since = best, best_cost, 0
    info["iterations"] = done
    return best_cost, [int(v) for v in best], info
