"""A position-window Lagrangian bound for the SOP under dense precedence (issue 33).

Problem: the SOP of :mod:`taopt.models.sop` (cheapest Hamiltonian path ``start -> ... ->
end`` through all ``n`` nodes, every precedence pair ``(r, j)`` with r before j).

Windows. In a feasible order node ``v`` sits at position ``p(v)`` (``start`` at 0, ``end``
at ``n - 1``) with every ancestor of ``v`` in the precedence closure before it and every
descendant after it, so ``p(v)`` lies in ``[a_v, b_v] = [#ancestors(v), n-1-#descendants(v)]``
(and in ``[1, n-2]`` for the inner nodes). Position ``k`` can hold only the nodes whose
window contains ``k``: a *layer* of a few dozen nodes under the dense precedence of the rbg
files (``benchmarks/bench_sop.py``), whatever ``n``.

Relaxed walks (a state-space relaxation, Christofides, Mingozzi and Toth 1981). A *walk* is
``x_0 = start, x_1, ..., x_{n-1} = end`` with ``x_k`` in layer ``k``, every step
``x_k -> x_{k+1}`` a usable arc (:func:`taopt.sop.problem.usable_arcs`) and no immediate
return ``x_{k+1} != x_{k-1}``; nodes may repeat or be missed otherwise. Every feasible order
is such a walk (its positions are in their windows, its arcs usable, it repeats nothing).
For prices ``lam`` (one per node) the walk's *priced cost* is
``Σ_k c[x_k, x_{k+1}] - Σ_k lam[x_k]``. A feasible order visits every node exactly once, so
its priced cost is its cost minus ``Σ_v lam_v``, and

    opt >= L(lam) = min over walks of the priced cost + Σ_v lam_v

for *any* ``lam`` (the Lagrangian relaxation of "visit every node once"). The minimum is a
shortest path over (position, node, previous node); with the no-return rule it suffices to
keep, per (position, node), the cheapest walk and the cheapest whose previous node differs
from the cheapest's (Houck et al. 1980, the 2-cycle elimination of q-routes): a walk to
``(k+1, w)`` through ``(k, v)`` may use the cheapest walk to ``(k, v)`` unless that one came
from ``w``, and then the second is the cheapest that did not. Each layer step is one dense
``layer x layer`` block in numpy (:func:`_sweep`).

Prices. ``lam`` is improved at the root by subgradient steps with Polyak's step length
towards a target (the incumbent's cost): ``lam_v += step (1 - visits_v)``, ``visits_v`` the
number of times the cheapest walk visits ``v`` (:func:`window_prices`; the direction deflected
by half the previous one). Every ``lam`` gives a valid bound; the best one seen is kept. The
portfolio starts from the assignment relaxation's dual prices (:func:`start_prices`), where the
bound is at least the assignment bound.

Completion tables. For fixed ``lam`` the same sweep run from ``end`` backwards gives
``H(k, v)``: the cheapest priced cost of a walk ``x_k = v, ..., x_{n-1} = end`` counting the
prices of ``x_{k+1} ... x_{n-1}`` (not of ``v``), with no return inside it. A DP state
``(I, v)`` of :mod:`taopt.models.sop_dp` (an order ideal ``I``, ``v`` its last node) has
``v`` at position ``k = |I| - 1``, and any completion of it is an order of ``U = V \\ I``
after ``v``: a walk from ``(k, v)`` to ``(n-1, end)`` visiting every node of ``U`` exactly
once and nothing else. Its cost is its priced cost plus ``Σ_{u ∈ U} lam_u``, so

    completion(I, v) >= H(k, v) + Σ_{u ∈ U} lam_u.

The sweep also keeps ``H2(k, v)``, the cheapest such walk whose first step is not to the
first step ``s(k, v)`` of the cheapest; a completion never steps into ``I``, so when
``s(k, v)`` is in ``I`` the bound is ``H2(k, v) + Σ_{u ∈ U} lam_u``
(:class:`WindowCompletion`). On the reversed problem (:func:`taopt.models.sop_dp.reversed_problem`)
the walks are the same walks reversed and the priced cost is the same (every node's price
is counted once wherever it sits), so the backward DP's table is this one on the reversed
problem with the same ``lam``.

References
----------
Christofides, Mingozzi and Toth, "State-space relaxation procedures for the computation of
bounds to routing problems", Networks 11(2), 1981. Houck, Picard, Queyranne and Vemuganti,
"The travelling salesman problem as a constrained shortest path problem", Opsearch 17, 1980
(2-cycle elimination). Held and Karp, "The traveling-salesman problem and minimum spanning
trees: Part II", Math. Programming 1, 1971 (subgradient on node prices).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from taopt.ideals import runs, words
from taopt.runtime import Deadline
from taopt.sop.problem import SopProblem, usable_arcs

__all__ = [
    "WindowCompletion",
    "WindowPrices",
    "start_prices",
    "window_bound",
    "window_prices",
    "windows",
]

#: Subgradient steps at most (:func:`window_prices`); the deadline usually ends it first on
#: the large files.
ITERATIONS = 1000

#: Polyak's step factor at the start; halved after ``PATIENCE`` steps without a better
#: bound, the loop ends below ``MIN_FACTOR``.
FACTOR = 1.0
PATIENCE = 30
MIN_FACTOR = 1e-3

#: Steps before the bound is compared with ``floor`` (:func:`window_prices`): three halvings of
#: the step. From the assignment's prices the first steps overshoot: rbg-atsp-255's bound stayed
#: at the assignment bound 2,263 for 50 steps, then rose to 2,293 at 100 and 2,311 at 200.
TRIAL = 4 * PATIENCE

#: The subgradient stops when its best bound rose by less than ``STALL_SHARE`` of the gap
#: left to its target over the last ``STALL_STEPS`` steps (:func:`window_prices`). Reason:
#: at that rate the gap would take more than ``STALL_STEPS / STALL_SHARE`` = 60,000 steps to
#: close, far past ``ITERATIONS``; a bound that creeps up by a unit every few steps (each
#: small rise resets ``PATIENCE``, so the step is never halved to ``MIN_FACTOR``) kept a run
#: without a time limit going (the stand-in rbg-atsp-380: 694 steps in 24.7 s and a bound of
#: 3,312.2 without the rule, 444 steps in 7.8 s and 3,309.1 with it, load 3.5). The window
#: is ``TRIAL`` steps (three halvings of the step: a slower rise is the plateau), and it is
#: not checked in the first two windows: from the assignment's prices the first steps overshoot
#: and the bound stays flat (rbg-atsp-255 for 50 steps; checked from the first window,
#: ftv70-0.15 stopped at step 121 with 2,185 against 2,228 after 495 steps without the rule).
STALL_STEPS = TRIAL
STALL_SHARE = 0.002

#: States per chunk of ``WindowCompletion.__call__``.
CHUNK = 50_000

#: Share of the previous direction added to the subgradient (a deflected subgradient).
DEFLECTION = 0.5


def windows(problem: SopProblem) -> tuple[np.ndarray, np.ndarray]:
    """``(a, b)``: per node, the first and last position it can hold in a feasible order
    (module docstring): ``a_v`` its ancestors in the closure, ``b_v = n - 1 -`` its
    descendants, ``start`` at 0, ``end`` at ``n - 1``, the inner nodes in ``[1, n-2]``."""
    n = problem.n
    closure = problem.closure
    before = np.zeros(n, dtype=np.int64)
    after = np.zeros(n, dtype=np.int64)
    for r, j in closure.edges:
        after[r] += 1
        before[j] += 1
    low = np.maximum(before, 1)
    high = np.minimum(n - 1 - after, n - 2)
    low[problem.start] = high[problem.start] = 0
    low[problem.end] = high[problem.end] = n - 1
    return low, high


@dataclass
class _Walks:
    """Per position ``k``: the nodes of layer ``k`` and, per node, the cheapest and second
    cheapest priced cost of a walk reaching it and the index (in layer ``k - 1``) of the
    previous node of each (-1: none)."""

    layers: list[np.ndarray]
    best: list[np.ndarray]
    second: list[np.ndarray]
    by: list[np.ndarray]
    by_second: list[np.ndarray]


def _layers(low: np.ndarray, high: np.ndarray) -> list[np.ndarray]:
    """The nodes whose window holds position ``k``, per ``k``."""
    n = len(low)
    return [np.flatnonzero((low <= k) & (high >= k)) for k in range(n)]


def _sweep(layers: list[np.ndarray], blocks: list[np.ndarray], lam: np.ndarray) -> _Walks:
    """The cheapest walks (module docstring) through ``layers``, ``blocks[k]`` the arc costs
    from layer ``k`` to layer ``k + 1`` (``inf``: no arc), every visit priced ``-lam``.

    A walk to ``(k, v)`` came from one node, so in the block from layer ``k`` at most one
    entry per row, the step back to that node, takes the second cheapest walk instead: the
    block is summed with the cheapest and those entries are mended."""
    first = layers[0]
    best = [-lam[first]]
    second = [np.full(len(first), np.inf)]
    by = [np.full(len(first), -1, dtype=np.int64)]
    by_second = [np.full(len(first), -1, dtype=np.int64)]
    slot = np.full(len(lam), -1, dtype=np.int64)  # a node's index in the next layer
    for k, block in enumerate(blocks):
        there = layers[k + 1]
        columns = np.arange(len(there))
        value = best[k][:, None] + block
        if k:
            # the cheapest walk to (k, v) unless it came from w: then the second cheapest
            slot[there] = columns
            rows = np.flatnonzero(by[k] >= 0)
            back = slot[layers[k - 1][by[k][rows]]]
            rows, back = rows[back >= 0], back[back >= 0]
            value[rows, back] = second[k][rows] + block[rows, back]
            slot[there] = -1
        one = np.argmin(value, axis=0)
        low = value[one, columns]
        value[one, columns] = np.inf
        two = np.argmin(value, axis=0)
        low2 = value[two, columns]
        price = lam[there]
        best.append(low - price)
        second.append(low2 - price)
        by.append(np.where(np.isfinite(low), one, -1))
        by_second.append(np.where(np.isfinite(low2), two, -1))
    return _Walks(layers, best, second, by, by_second)


def _visits(walks: _Walks, n: int) -> np.ndarray:
    """How many times the cheapest walk to the last layer's first node visits each node."""
    count = np.zeros(n)
    k = len(walks.layers) - 1
    at, which = 0, 1  # index in layer k, and which of its two walks
    while True:
        node = int(walks.layers[k][at])
        count[node] += 1
        if k == 0:
            return count
        previous = int((walks.by if which == 1 else walks.by_second)[k][at])
        # the walk to (k-1, previous) is its cheapest unless that one came from ``node``
        came = int(walks.by[k - 1][previous])
        came_node = int(walks.layers[k - 2][came]) if k >= 2 and came >= 0 else -1
        which = 2 if came_node == node else 1
        at, k = previous, k - 1


def start_prices(alpha: np.ndarray, beta: np.ndarray, start: int, end: int) -> np.ndarray:
    """Node prices from an assignment relaxation's dual prices (``alpha`` of the tails,
    ``beta`` of the heads, reduced costs ``c[u, w] - alpha_u - beta_w >= 0`` on the usable
    arcs, :func:`taopt.models.sop_dp.assignment_potentials`): ``lam_v = alpha_v + beta_v``,
    without ``alpha_end`` and ``beta_start``.

    A walk leaves ``x_0 .. x_{n-2}`` (never ``end``, which only position ``n - 1`` holds) and
    enters ``x_1 .. x_{n-1}`` (never ``start``), so its priced cost is the sum of its arcs'
    reduced costs (at least 0): ``L(lam) = min walk reduced cost + Σ_v lam_v``, and
    ``Σ_v lam_v`` is the assignment bound. The window bound from these prices is never below
    the assignment bound, and the subgradient keeps the best it sees."""
    lam = np.asarray(alpha, float) + np.asarray(beta, float)
    lam[end] -= alpha[end]
    lam[start] -= beta[start]
    return lam


def _usable(problem: SopProblem) -> np.ndarray:
    """``n x n``: the cost of each usable arc (:func:`taopt.sop.problem.usable_arcs`), ``inf``
    elsewhere."""

    n = problem.n
    tails, heads = usable_arcs(problem.cost, problem.closure)
    usable = np.full((n, n), np.inf)
    usable[tails, heads] = problem.cost[tails, heads]
    return usable


def _blocks(usable: np.ndarray, layers: list[np.ndarray]) -> list[np.ndarray]:
    """``usable[layer k, layer k+1]`` per position (costs, ``inf`` off the usable arcs)."""
    return [usable[np.ix_(layers[k], layers[k + 1])] for k in range(len(layers) - 1)]


def window_bound(problem: SopProblem, lam: np.ndarray) -> float:
    """``L(lam)`` of the module docstring: a lower bound on every feasible order's cost
    (``inf`` when no walk exists, so no order either)."""
    low, high = windows(problem)
    layers = _layers(low, high)
    walks = _sweep(layers, _blocks(_usable(problem), layers), np.asarray(lam, float))
    return float(walks.best[-1][0] + np.sum(lam))


@dataclass
class WindowPrices:
    """The root's prices and bound (:func:`window_prices`).

    Attributes
    ----------
    lam : ndarray
        One price per node, the best seen.
    bound : float
        ``L(lam)``, a lower bound on every feasible order's cost.
    iterations : int
        Subgradient steps made.
    seconds : float
    """

    lam: np.ndarray
    bound: float
    iterations: int
    seconds: float


def window_prices(
    problem: SopProblem,
    target: float,
    deadline: Deadline | None = None,
    iterations: int = ITERATIONS,
    lam: np.ndarray | None = None,
    floor: float = -np.inf,
) -> WindowPrices:
    """Subgradient on the window relaxation's prices (module docstring), from ``lam`` (zeros
    by default), towards ``target`` (an incumbent's cost: Polyak's step
    ``FACTOR (target - L) / ||1 - visits||²``), until ``iterations`` steps, the deadline, a
    walk that visits every node once (then ``L`` is that order's cost), a factor below
    ``MIN_FACTOR``, or, after ``TRIAL`` steps, a bound still at most ``floor`` (a bound
    known elsewhere: this one is not the stronger), or a best bound that rose by less than
    ``STALL_SHARE`` of the gap left to ``target`` over the last ``STALL_STEPS`` steps (the
    plateau). Every step's bound is valid; the best is returned with its prices."""
    began = time.perf_counter()
    n = problem.n
    low, high = windows(problem)
    layers = _layers(low, high)
    blocks = _blocks(_usable(problem), layers)
    lam = np.zeros(n) if lam is None else np.asarray(lam, float).copy()
    best_lam, best = lam.copy(), -np.inf
    factor, stale, done = FACTOR, 0, 0
    direction = np.zeros(n)
    history: list[float] = []  # the best bound after each step
    for done in range(1, iterations + 1):
        walks = _sweep(layers, blocks, lam)
        value = float(walks.best[-1][0] + lam.sum())
        if not np.isfinite(value):
            return WindowPrices(lam, value, done, time.perf_counter() - began)  # no walk
        if value > best + 1e-9:
            best, best_lam, stale = value, lam.copy(), 0
        else:
            stale += 1
            if stale >= PATIENCE:
                factor, stale = factor / 2, 0
        gradient = 1.0 - _visits(walks, n)
        if not gradient.any() or factor < MIN_FACTOR or best >= target - 1e-9:
            break
        if done >= TRIAL and best <= floor:
            break
        history.append(best)
        if _stalled(history, target):
            break
        if deadline is not None and deadline.expired():
            break
        direction = gradient + DEFLECTION * direction
        norm = float(direction @ direction)
        lam = lam + factor * max(target - value, 1e-6 * max(1.0, abs(target))) / norm * direction
    return WindowPrices(best_lam, best, done, time.perf_counter() - began)


def _stalled(history: list[float], target: float) -> bool:
    """Whether the best bounds ``history`` (one per step) rose by less than
    ``STALL_SHARE`` of the gap left to ``target`` over the last ``STALL_STEPS``
    steps (:func:`window_prices`); never within the first ``2 * STALL_STEPS`` steps."""
    if len(history) <= 2 * STALL_STEPS:
        return False
    then, now = history[-1 - STALL_STEPS], history[-1]
    if not np.isfinite(then):
        return False
    return bool(now - then < STALL_SHARE * (target - then))


class WindowCompletion:
    """The completion bound ``H(k, v) + Σ_{u ∈ U} lam_u`` of the module docstring for the DP
    states ``(I, v)`` of ``problem`` (masks as in :mod:`taopt.ideals`).

    ``table[k, v]``, ``spare[k, v]``: ``H`` and ``H2`` (``inf`` off the windows), ``step[k, v]``
    the first step of the cheapest (-1: none).
    """

    def __init__(
        self, problem: SopProblem, lam: np.ndarray, usable: np.ndarray | None = None
    ) -> None:
        n = problem.n
        self.n = n
        self.lam = np.asarray(lam, float)
        low, high = windows(problem)
        layers = _layers(low, high)
        blocks = _blocks(_usable(problem) if usable is None else usable, layers)
        # from end backwards: the reversed layers, the blocks transposed
        walks = _sweep(layers[::-1], [b.T for b in blocks[::-1]], self.lam)
        self.table = np.full((n, n), np.inf)
        self.spare = np.full((n, n), np.inf)
        self.step = np.full((n, n), -1, dtype=np.int64)
        for r in range(n):
            k = n - 1 - r
            nodes = walks.layers[r]
            # the sweep priced v itself: H counts the nodes after it only
            self.table[k, nodes] = walks.best[r] + self.lam[nodes]
            self.spare[k, nodes] = walks.second[r] + self.lam[nodes]
            if r:
                chosen = walks.by[r]
                self.step[k, nodes] = np.where(chosen >= 0, walks.layers[r - 1][chosen], -1)
        self.total = float(self.lam.sum())
        # byte i of a mask's words (little-endian) holds nodes 8i .. 8i+7
        width = 8 * words(n)
        padded = np.zeros(8 * width)
        padded[:n] = self.lam
        self._byte_sums = ((np.arange(256)[:, None] >> np.arange(8)[None, :]) & 1) @ padded.reshape(
            width, 8
        ).T  # (256, width)

    def _held_prices(self, mask: np.ndarray) -> np.ndarray:
        """``Σ_{u ∈ I} lam_u`` per mask, by one table look-up per byte."""
        as_bytes = np.ascontiguousarray(mask).view(np.uint8).reshape(len(mask), -1)
        columns = np.arange(as_bytes.shape[1])
        return self._byte_sums[as_bytes, columns[None, :]].sum(axis=1)

    def __call__(self, mask: np.ndarray, last: np.ndarray) -> np.ndarray:
        """A lower bound on the cheapest completion of each state ``(mask[i], last[i])``, in
        chunks of ``CHUNK`` states (the byte look-ups are ``states x bytes`` tables)."""
        if len(last) <= CHUNK:
            return self._chunk(mask, last)
        return np.concatenate(
            [
                self._chunk(mask[lo : lo + CHUNK], last[lo : lo + CHUNK])
                for lo in range(0, len(last), CHUNK)
            ]
        )

    def _chunk(self, mask: np.ndarray, last: np.ndarray) -> np.ndarray:
        """The bound of one chunk of states. The set size and the held prices depend on the
        ideal alone: they are computed once per run of equal consecutive masks
        (:func:`taopt.ideals.runs`; a DP layer is sorted by mask, a few last nodes per
        ideal), and whether the cheapest walk's first step is held is one bit read per
        state."""
        if len(last) == 0:
            return np.zeros(0)
        group, unique = runs(mask)
        k = (_popcount(unique) - 1)[group]
        step = self.step[k, last]
        into = _holds_node(mask, step)
        head = np.where(into, self.spare[k, last], self.table[k, last])
        return head + self.total - self._held_prices(unique)[group]


def _holds_node(mask: np.ndarray, node: np.ndarray) -> np.ndarray:
    """Per mask, whether it holds its own ``node`` (False where ``node`` is negative): one
    bit read per mask (1-D uint64 masks or rows of words)."""
    at = np.maximum(node, 0).astype(np.uint64)
    if mask.ndim == 1:
        word = mask
    else:
        word = mask[np.arange(len(mask)), (at // np.uint64(64)).astype(np.int64)]
    return (node >= 0) & (((word >> (at % np.uint64(64))) & np.uint64(1)) != 0)


def _popcount(mask: np.ndarray) -> np.ndarray:
    """Nodes per mask (1-D uint64 masks or rows of words)."""
    as_bytes = np.ascontiguousarray(mask).view(np.uint8).reshape(len(mask), -1)
    return np.unpackbits(as_bytes, axis=1).sum(axis=1).astype(np.int64)
