"""Iterated local search over precedence-feasible orders, each scored by the exact schedule DP.

The thesis's own search for chapter 5 is the topological-sort GA (:mod:`taopt.heuristics.ga_delivery`), which
optimises the path cost on t* (5.11) and only schedules its best order. This module is a
*competent* ordering metaheuristic in the sense of chapter 2's memetic GA
(:mod:`taopt.heuristics.ga_routing`): it starts from the constructive heuristics' orders, improves them by
local search, and judges every candidate order by the quantity that matters, the makespan
(5.1) of the best truck schedule for that order (the exact fixed-order DP of
:func:`taopt.delivery.schedule.schedule`).

Search
------
* **Start**: the orders of SMMA and MMA (§5.4.2); each is improved by local search and the
  better one becomes the incumbent. The result is never worse than SMMA's.
* **Local search** (first improvement, don't-look bits per customer): for the customer at
  position i, (a) relocate the block of 1..``max_block`` customers starting at i forwards or
  backwards by up to ``window`` positions (or-opt), (b) swap it with a customer up to
  ``window`` positions later. Only moves that keep every precedence (5.7) are tried: a block
  never passes one of its successors (forwards) or predecessors (backwards).
* **Perturbation**: ``strength`` random precedence-feasible relocations of one customer
  each, by up to ``2 · window`` positions (a double relocate by default).
* **Acceptance**: the perturbed local optimum replaces the current order if it is no worse,
  or within a factor ``1 + accept_worse`` of the best order found ("better or slightly
  worse"); the best order is always kept.
* **Stop**: after ``iterations`` perturbations, or when ``time_limit`` wall-clock seconds
  (:class:`taopt.runtime.Deadline`) have passed; tests and studies stop on iterations, so
  the same seed gives the same result.

Incremental evaluation
----------------------
:class:`ScheduleStates` keeps, for the current order, the DP's forward states after every
sortie, R_p(k) for the landing stops k of V_{π(p)} (the quantity :func:`_sortie_step`
produces). A move rewrites the order on positions a..b only, so its evaluation restarts the
DP from the stored state before a and runs :func:`_sortie_step` over a..b. After b the two
orders serve the same customers in the same order, and the rest of the DP is a function F
of the state vector, *non-decreasing* in every R(k) and *shift-equivariant*,
F(R + c) = F(R) + c (every operation of the step is +, min or max). Hence with
δ = R'_q − R_q at any common position q ≥ b::

    F(R_q) + min_k δ(k)  <=  F(R'_q)  <=  F(R_q) + max_k δ(k)

so the evaluation stops as soon as min δ >= 0 (the move cannot improve: pruned) or
max δ < 0 (it does), usually a few sorties after b, and runs to the final sortie only in
the remaining cases, where it returns the exact makespan. An accepted move re-runs the DP
from a to store the new states; the makespan kept is always the DP's exact value, and the
returned plan is re-scored by :func:`taopt.delivery.schedule.schedule` (hence
:func:`taopt.delivery.evaluate.evaluate_plan`).

The same search runs on :class:`taopt.SopProblem` with the path cost instead of the DP
(:class:`PathStates`: a move's cost change is read from the arcs around the rewritten
positions).
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Iterator, Sequence
from typing import Any

import numpy as np

from taopt.delivery.instance import DeliveryInstance
from taopt.delivery.schedule import _sortie_data, _sortie_step, schedule
from taopt.errors import InstanceError, SolverError
from taopt.heuristics.sequencing import (
    delivery_cost_matrix,
    no_order_solution,
    ordered_or_repaired,
    path_cost,
)
from taopt.registry import register_method
from taopt.result import FEASIBLE, Order, Solution, make_solution
from taopt.runtime import Deadline
from taopt.sop.problem import SopProblem

__all__ = ["ScheduleStates", "PathStates", "Screen", "ils_search", "forward_states"]

#: Relative tolerance below which two makespans are treated as equal (float rounding of the
#: DP; a move must improve by more than this to be taken).
TOLERANCE = 1e-9

#: Wall-clock checks happen every this many move evaluations.
_CHECK_EVERY = 64


# ---------------------------------------------------------------------------------------------
# Incremental evaluators
# ---------------------------------------------------------------------------------------------


def forward_states(
    instance: DeliveryInstance,
    order: Sequence[int] | np.ndarray,
    start: int = 0,
    states: list[np.ndarray] | None = None,
) -> tuple[list[np.ndarray], float]:
    """The fixed-order DP's states R_p after every sortie p but the last, and the makespan.

    Parameters
    ----------
    instance : DeliveryInstance
    order : sequence of int
        A complete precedence-feasible order (not checked here).
    start : int
        Re-run the DP from sortie ``start`` on, reusing ``states[:start]`` (the prefix
        states of an order that agrees with ``order`` on positions ``< start``).
    states : list of arrays, optional
        Required when ``start > 0``; updated in place from ``start`` on.

    Returns
    -------
    states : list of (|V_{order[p]}|,) arrays
        ``states[p]`` = R_p(k), the earliest recovery time at each viable stop k of
        customer ``order[p]`` (+inf where no launch stop reaches k), p = 0..n-2.
    makespan : float
        The DP's optimal makespan for the order (the value of
        ``schedule(instance, order).info["dp_objective"]``, bit for bit).

    Notes
    -----
    The transitions are :func:`taopt.delivery.schedule._sortie_step`'s, in the order
    :func:`taopt.delivery.schedule.schedule` makes them; time O(Σ_{p >= start}
    |V_{p-1}| |V_p|).
    """
    order_arr = np.asarray(list(order), dtype=np.int64)
    n = order_arr.size
    if states is None:
        if start:
            raise InstanceError("forward_states: start > 0 needs the prefix states")
        states = []
    states += [np.empty(0)] * (max(n - 1, 0) - len(states))
    if n == 0:
        return states, 0.0
    tt, tau = instance.truck_time, instance.service_time
    data = _sortie_data(instance)
    if start == 0:
        ready, stops = np.zeros(1), np.array([instance.depot], dtype=np.int64)
    else:
        ready, stops = states[start - 1], data.get(int(order_arr[start - 1]))[0]
    for p in range(start, n - 1):
        sortie = data.get(int(order_arr[p]))
        _, _, _, ready = _sortie_step(tt, tau, ready, stops, sortie)
        states[p] = ready
        stops = sortie[0]
    sortie = data.get(int(order_arr[n - 1]))
    _, served, i_pos, _ = _sortie_step(tt, tau, ready, stops, sortie, final=True)
    return states, float(served[i_pos])


class ScheduleStates:
    """An order with its DP forward states, evaluating segment moves incrementally.

    A *segment move* ``(a, segment)`` replaces ``order[a : a + len(segment)]`` by
    ``segment``, a permutation of those customers (relocations, or-opt and swaps all are).

    Attributes
    ----------
    order : (n,) int array
        The current order.
    value : float
        Its makespan (the DP's exact value).
    ready : list of arrays
        ``ready[p]`` = R_p on the viable stops of ``order[p]``, p = 0..n-2.
    steps : int
        Sorties run so far (a measure of work).
    """

    def __init__(self, instance: DeliveryInstance, order: Sequence[int]) -> None:
        self.instance = instance
        self.truck_time = instance.truck_time
        self.service_time = instance.service_time
        self.data = _sortie_data(instance)
        self.depot = np.array([instance.depot], dtype=np.int64)
        self.zero = np.zeros(1)
        self.steps = 0
        self.order = np.asarray(list(order), dtype=np.int64)
        self.ready, self.value = forward_states(instance, self.order)
        self.steps = self.order.size

    def _entry(
        self, p: int, ready: list[np.ndarray], order: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        if p == 0:
            return self.zero, self.depot
        return ready[p - 1], self.data.get(int(order[p - 1]))[0]

    def try_segment(self, a: int, segment: Sequence[int], exact: bool = False) -> float | None:
        """Evaluate the move; None when it cannot improve the makespan by more than the
        tolerance, else an upper bound on its makespan (the exact value if ``exact``).

        With ``exact`` the DP runs to the end unless the move is pruned, and the value
        returned is the new order's makespan (equal to a full :func:`schedule`).
        """
        order, old = self.order, self.ready
        n = order.size
        b = a + len(segment) - 1
        tol = TOLERANCE * abs(self.value)
        ready, stops = self._entry(a, old, order)
        tt, tau, data = self.truck_time, self.service_time, self.data
        for q in range(a, n):
            j = int(segment[q - a]) if q <= b else int(order[q])
            sortie = data.get(j)
            if q == n - 1:
                _, served, i_pos, _ = _sortie_step(tt, tau, ready, stops, sortie, final=True)
                self.steps += q - a + 1
                value = float(served[i_pos])
                return value if value < self.value - tol else None
            _, _, _, ready = _sortie_step(tt, tau, ready, stops, sortie)
            stops = sortie[0]
            if q >= b and j == order[q]:
                with np.errstate(invalid="ignore"):
                    delta = ready - old[q]  # inf - inf (no launch reaches k) -> nan, ignored
                finite = delta[~np.isnan(delta)]
                if finite.size and finite.min() >= -tol:
                    self.steps += q - a + 1
                    return None
                if not exact and finite.size and finite.max() < -tol:
                    self.steps += q - a + 1
                    return self.value + float(finite.max())
        raise AssertionError("unreachable")  # pragma: no cover

    def apply(self, a: int, segment: Sequence[int]) -> None:
        """Make the move and re-run the DP from position ``a`` (the states before stay)."""
        self.order = self.order.copy()
        self.order[a : a + len(segment)] = segment
        self.ready, self.value = forward_states(self.instance, self.order, a, list(self.ready))
        self.steps += self.order.size - a

    def snapshot(self) -> tuple[np.ndarray, list[np.ndarray], float]:
        return self.order, self.ready, self.value

    def restore(self, state: tuple[np.ndarray, list[np.ndarray], float]) -> None:
        self.order, self.ready, self.value = state


class PathStates:
    """The same interface as :class:`ScheduleStates` for a path cost (the SOP).

    ``order`` lists the nodes between the fixed ``start`` and ``end`` (None: open path);
    the value is the cost of start → order → end.
    """

    def __init__(self, cost: np.ndarray, start: int, end: int | None, order: Sequence[int]):
        self.cost = np.asarray(cost, dtype=float)
        self.start, self.end = int(start), end
        self.order = np.asarray(list(order), dtype=np.int64)
        self.value = self._total(self.order)
        self.steps = 0

    def _total(self, order: np.ndarray) -> float:
        path = [self.start, *order.tolist()] + ([] if self.end is None else [int(self.end)])
        return path_cost(self.cost, path)

    def _arcs(self, order: np.ndarray, lo: int, hi: int) -> float:
        """Cost of the arcs entering positions lo..hi and leaving hi (within the path)."""
        before = self.start if lo == 0 else int(order[lo - 1])
        nodes = [before, *order[lo : hi + 1].tolist()]
        if hi + 1 < order.size:
            nodes.append(int(order[hi + 1]))
        elif self.end is not None:
            nodes.append(int(self.end))
        return path_cost(self.cost, nodes)

    def try_segment(self, a: int, segment: Sequence[int], exact: bool = False) -> float | None:
        """The new path cost if it improves by more than the tolerance, else None."""
        b = a + len(segment) - 1
        new_order = self.order.copy()
        new_order[a : b + 1] = segment
        self.steps += len(segment)
        old = self._arcs(self.order, a, b)
        if np.isfinite(old):
            value = self.value - old + self._arcs(new_order, a, b)
        else:
            value = self._total(new_order)
        if not np.isfinite(value):
            return None
        return value if value < self.value - TOLERANCE * abs(self.value) else None

    def apply(self, a: int, segment: Sequence[int]) -> None:
        self.order = self.order.copy()
        self.order[a : a + len(segment)] = segment
        self.value = self._total(self.order)

    def snapshot(self) -> tuple[np.ndarray, float]:
        return self.order, self.value

    def restore(self, state: tuple[np.ndarray, float]) -> None:
        self.order, self.value = state


# ---------------------------------------------------------------------------------------------
# The search
# ---------------------------------------------------------------------------------------------


class _Precedence:
    """Direct predecessors/successors of every item (customers or SOP nodes)."""

    def __init__(self, items: Iterable[int], pairs: Iterable[Sequence[int]]) -> None:
        self.preds: dict[int, set[int]] = {int(c): set() for c in items}
        self.succs: dict[int, set[int]] = {c: set() for c in self.preds}
        for before, after in pairs:
            before, after = int(before), int(after)
            if before in self.preds and after in self.preds:
                self.preds[after].add(before)
                self.succs[before].add(after)

    def window(self, order: np.ndarray, position: np.ndarray, i: int) -> tuple[int, int]:
        """Positions the item at ``i`` may take alone: after its last predecessor and
        before its first successor."""
        c = int(order[i])
        lo = max((int(position[p]) for p in self.preds[c]), default=-1) + 1
        hi = min((int(position[s]) for s in self.succs[c]), default=order.size) - 1
        return lo, hi


def _moves(
    order: np.ndarray, i: int, prec: _Precedence, window: int, max_block: int
) -> Iterator[tuple[int, list[int]]]:
    """Precedence-feasible segment moves for the item at position i, nearest first.

    Yields (a, segment) pairs: block relocations (or-opt) of length 1..max_block starting
    at i, forwards and backwards by up to ``window`` positions, and swaps of i with a later
    position up to ``window`` away.
    """
    n = order.size
    items = order.tolist()
    for length in range(1, max_block + 1):
        if i + length > n:
            break
        block = items[i : i + length]
        members = set(block)
        block_succs = set().union(*(prec.succs[c] for c in block)) - members
        block_preds = set().union(*(prec.preds[c] for c in block)) - members
        # forwards: the block goes right after position j
        for j in range(i + length, min(n, i + length + window)):
            if items[j] in block_succs:
                break
            yield i, items[i + length : j + 1] + block
        # backwards: the block goes right before position j
        for j in range(i - 1, max(-1, i - 1 - window), -1):
            if items[j] in block_preds:
                break
            yield j, block + items[j:i]
    # swaps of i with a later j (j = i + 1 is a relocation already)
    first = items[i]
    if i + 1 < n and items[i + 1] in prec.succs[first]:
        return
    for j in range(i + 2, min(n, i + 1 + window)):
        if items[j] in prec.succs[first]:
            break
        other = items[j]
        if any(p in prec.preds[other] for p in items[i:j]):
            continue
        yield i, [other] + items[i + 1 : j] + [first]


class Screen:
    """Granular filter: skip moves that lengthen a surrogate path cost by more than a threshold.

    For the delivery problem the surrogate is the path cost on t* (5.11) from the depot, the
    quantity NIA/MMA/SMMA and the thesis's GA minimise. Measured on dag40 and pairs120 from
    SMMA's orders, the moves whose t* change is in the lowest fifth of all moves held every
    move that shortens the makespan (96 of 96 on pairs120-0 at L/L0 = 0.45, 87 of 87 at 0.9,
    20 of 20 on dag40-0 at 0.3), so the DP is run on those only, best t* change first.
    """

    def __init__(self, cost: np.ndarray, start: int, threshold: float) -> None:
        self.cost, self.start, self.threshold = cost, int(start), float(threshold)
        self.rows = np.asarray(cost, dtype=float).tolist()  # plain floats: ~8 arcs per move

    def delta(self, order: np.ndarray, a: int, segment: Sequence[int]) -> float:
        """Change of the surrogate path cost when ``order[a:a+len(segment)]`` becomes it."""
        b = a + len(segment) - 1
        prev = self.start if a == 0 else int(order[a - 1])
        old, new = [prev, *order[a : b + 1].tolist()], [prev, *segment]
        if b + 1 < order.size:
            old.append(int(order[b + 1]))
            new.append(int(order[b + 1]))
        rows = self.rows
        added = sum(rows[u][v] for u, v in zip(new[:-1], new[1:], strict=True))
        return added - sum(rows[u][v] for u, v in zip(old[:-1], old[1:], strict=True))

    def rank(self, order: np.ndarray, moves: Iterable[tuple[int, list[int]]]) -> list:
        """The moves within the threshold, smallest surrogate change first (stable)."""
        scored = [(self.delta(order, a, seg), k, (a, seg)) for k, (a, seg) in enumerate(moves)]
        return [move for d, _, move in sorted(scored) if d <= self.threshold]


class _Budget:
    """Evaluations counted, and the wall clock read every :data:`_CHECK_EVERY` of them."""

    def __init__(self, deadline: Deadline) -> None:
        self.deadline = deadline
        self.evaluations = 0
        self.expired = False

    def tick(self) -> bool:
        self.evaluations += 1
        if (
            self.deadline.limited
            and self.evaluations % _CHECK_EVERY == 0
            and self.deadline.expired()
        ):
            self.expired = True
        return self.expired


def _local_search(
    states: Any,
    prec: _Precedence,
    look: np.ndarray,
    rng: np.random.Generator,
    window: int,
    max_block: int,
    radius: int,
    budget: _Budget,
    screen: Screen | None = None,
) -> int:
    """First-improvement descent from ``states`` over the items flagged in ``look``
    (don't-look bits by item); returns the number of moves made. A move re-flags the items
    within ``radius`` positions of the rewritten ones."""
    made = 0
    while look.any() and not budget.expired:
        candidates = np.flatnonzero(look)
        item = int(candidates[rng.integers(candidates.size)])
        position = np.empty(look.size, dtype=np.int64)  # item -> position
        position[states.order] = np.arange(states.order.size)
        i = int(position[item])
        improved = False
        moves: Iterable[tuple[int, list[int]]] = _moves(states.order, i, prec, window, max_block)
        if screen is not None:
            moves = screen.rank(states.order, moves)
        for a, segment in moves:
            if budget.tick():
                break
            if states.try_segment(a, segment) is not None:
                states.apply(a, segment)
                made += 1
                lo, hi = max(0, a - radius), min(states.order.size, a + len(segment) + radius)
                look[states.order[lo:hi]] = True
                improved = True
                break
        if not improved:
            look[item] = False
    return made


def _perturb(
    states: Any, prec: _Precedence, rng: np.random.Generator, strength: int, reach: int
) -> list[int]:
    """``strength`` random precedence-feasible single relocations; returns the positions
    touched (for the don't-look bits)."""
    touched = []
    n = states.order.size
    for _ in range(strength):
        position = np.empty(int(states.order.max()) + 1, dtype=np.int64)
        position[states.order] = np.arange(n)
        i = int(rng.integers(n))
        lo, hi = prec.window(states.order, position, i)
        lo, hi = max(lo, i - reach), min(hi, i + reach)
        if hi <= lo:
            continue
        j = int(rng.integers(lo, hi))
        j += j >= i  # a position other than i
        items = states.order.tolist()
        if j > i:
            states.apply(i, items[i + 1 : j + 1] + [items[i]])
        else:
            states.apply(j, [items[i]] + items[j:i])
        touched += [i, j]
    return touched


def ils_search(
    make_states: Any,
    starts: Sequence[Sequence[int]],
    items: Sequence[int],
    pairs: Iterable[Sequence[int]],
    seed: int | np.random.Generator | None = 0,
    iterations: int = 30,
    time_limit: float | None = None,
    window: int = 20,
    max_block: int = 3,
    strength: int = 2,
    accept_worse: float = 0.01,
    radius: int = 2,
    screen: Screen | None = None,
) -> tuple[np.ndarray, float, dict[str, Any]]:
    """Iterated local search over precedence-feasible orders (see the module docstring).

    Parameters
    ----------
    make_states : callable
        ``make_states(order)`` -> an evaluator (:class:`ScheduleStates` or
        :class:`PathStates`) of that order.
    starts : sequence of orders
        Precedence-feasible start orders (each is improved; the best becomes the incumbent).
    items : sequence of int
        The items ordered (customers, or the SOP's free nodes), numbered 0..max.
    pairs : iterable of (before, after)
        Precedences among the items (pairs with other nodes are ignored).
    seed : int or numpy.random.Generator
        Same seed, same result (when the run stops on ``iterations``).
    iterations : int
        Perturbations (ILS iterations) after the start's local search.
    time_limit : float, optional
        Wall-clock seconds; the best order so far is returned when it passes.
    window : int
        Largest shift of a block or distance of a swap in the local search (positions).
    max_block : int
        Longest block relocated (or-opt).
    strength : int
        Random relocations per perturbation.
    accept_worse : float
        A perturbed local optimum within a factor 1 + accept_worse of the best is accepted.
    radius : int
        Don't-look bits: a move or a perturbation re-flags the items within this many
        positions of those it moved.
    screen : Screen, optional
        Evaluate only the moves it passes, in its order (default: every move, nearest
        first).

    Returns
    -------
    order : (m,) int array
        The best order found.
    value : float
        Its value (makespan or path cost) as the evaluator computed it.
    info : dict
        ``start_value`` (best start before the search), ``iterations`` done, ``evaluations``
        (moves evaluated), ``steps`` (DP sorties or arcs evaluated), ``moves`` made,
        ``stopped_by`` ("iterations" or "time_limit").

    Notes
    -----
    One move evaluation costs O(b - a + d) sorties of the DP (|V|² each) where d is the
    number of sorties after the rewritten positions needed to decide (see the module
    docstring); a local search pass tries O(m · window · (max_block + 1)) moves per
    flagged item. Hand-written: no library offers local search over linear extensions
    scored by a custom DP.
    """
    for name, value, low in (
        ("iterations", iterations, 0),
        ("window", window, 1),
        ("max_block", max_block, 1),
        ("strength", strength, 1),
        ("radius", radius, 0),
    ):
        if int(value) != value or value < low:
            raise InstanceError(f"{name} must be an integer >= {low}, got {value!r}")
    if not accept_worse >= 0:
        raise InstanceError(f"accept_worse must be >= 0, got {accept_worse!r}")
    deadline = Deadline(time_limit)
    budget = _Budget(deadline)
    rng = np.random.default_rng(seed)
    prec = _Precedence(items, pairs)
    size = max([int(c) for c in items], default=-1) + 1
    window, max_block, strength, radius = int(window), int(max_block), int(strength), int(radius)

    best = None
    start_value = np.inf
    made = 0
    for start in starts:
        states = make_states(start)
        start_value = min(start_value, states.value)
        look = np.zeros(size, dtype=bool)
        look[states.order] = True
        made += _local_search(states, prec, look, rng, window, max_block, radius, budget, screen)
        if best is None or states.value < best.value:
            best, current = states, states.snapshot()
    if best is None:
        raise SolverError("ILS: no start order given")
    incumbent = best.snapshot()
    done = 0
    stopped_by = "iterations"
    if len(items) >= 2:
        for done in range(1, int(iterations) + 1):
            if budget.expired or (deadline.limited and deadline.expired()):
                done -= 1
                stopped_by = "time_limit"
                break
            best.restore(current)
            touched = _perturb(best, prec, rng, strength, 2 * window)
            look = np.zeros(size, dtype=bool)
            for p in touched:
                lo, hi = max(0, p - radius), min(best.order.size, p + radius + 1)
                look[best.order[lo:hi]] = True
            made += _local_search(best, prec, look, rng, window, max_block, radius, budget, screen)
            if best.value < incumbent[-1] - TOLERANCE * abs(incumbent[-1]):
                incumbent = best.snapshot()
            if best.value <= current[-1] or best.value <= incumbent[-1] * (1 + accept_worse):
                current = best.snapshot()
        else:
            done = int(iterations)
        if budget.expired:
            stopped_by = "time_limit"
    best.restore(incumbent)
    info = {
        "start_value": float(start_value),
        "iterations": done,
        "evaluations": budget.evaluations,
        "steps": best.steps,
        "moves": made,
        "stopped_by": stopped_by,
    }
    return best.order.copy(), float(best.value), info


# ---------------------------------------------------------------------------------------------
# Registered methods
# ---------------------------------------------------------------------------------------------


def _start_orders(
    cost: np.ndarray, pairs: Any, start: int, end: int | None
) -> tuple[list[list[int]], dict[str, Any]]:
    """SMMA's and MMA's paths (repaired at a greedy dead end), without the fixed nodes.

    Returns the orders (none when both rules and the repair found nothing) and the
    ``info`` of the last rule that failed (:func:`ordered_or_repaired`; ``{}`` if none did).
    """
    fixed = {start} if end is None else {start, end}
    starts, failure = [], {}
    for name in ("SMMA", "MMA"):
        path, info = ordered_or_repaired(name, cost, pairs, start, end)
        if path is None:
            reason = info["error"].split(": ", 1)[-1]  # "no feasible order exists (...)"
            failure = {**info, "error": f"ILS found no start order: {reason}"}
        else:
            starts.append([c for c in path if c not in fixed])
    return starts, failure


@register_method(
    DeliveryInstance,
    "ILS",
    default=False,
    not_default="ILS runs only when named (--methods ILS): a search with a budget",
    style=(":", "P"),
)
def ils_delivery(
    instance: Any,
    seed: int = 0,
    time_limit: float | None = None,
    iterations: int = 30,
    window: int = 20,
    max_block: int = 3,
    strength: int = 2,
    accept_worse: float = 0.01,
    tstar_screen: float | None = 1.5,
) -> Solution:
    """Iterated local search over orders, each scored by the exact schedule DP.

    Starts from SMMA's and MMA's orders (§5.4.2) and returns an order at least as good as
    SMMA's; options as in :func:`ils_search`, and ``tstar_screen``: the DP evaluates only
    moves that lengthen the t* path by at most ``tstar_screen`` times the mean t* leg of the
    better start order, best t* change first (:class:`Screen`; None: every move, nearest
    first). ``info``: ``tstar_cost`` (the order's path
    cost on t*), ``start_objective`` (the better start), ``iterations``, ``evaluations``,
    ``steps`` (DP sorties run), ``moves``, ``stopped_by``.

    References
    ----------
    Thesis §5.4–5.5 (the orders, the GA it stands beside); the schedule DP of
    :func:`taopt.delivery.schedule.schedule`.
    """
    began = time.perf_counter()
    cost, start, pairs, _ = delivery_cost_matrix(instance)
    starts, failure = _start_orders(cost, pairs, start, None)
    if not starts:
        return no_order_solution(instance, "ILS", seed, began, failure)
    screen = None
    if tstar_screen is not None:
        if not tstar_screen >= 0:
            raise InstanceError(f"tstar_screen must be >= 0 or None, got {tstar_screen!r}")
        legs = min(path_cost(cost, [start, *order]) for order in starts) / max(instance.n, 1)
        screen = Screen(cost, start, tstar_screen * legs)
    order, _, info = ils_search(
        lambda o: ScheduleStates(instance, o),
        starts,
        range(instance.n),
        pairs,
        seed,
        iterations,
        time_limit,
        window,
        max_block,
        strength,
        accept_worse,
        screen=screen,
    )
    solution = schedule(instance, order.tolist())
    return solution.replace(
        method="ILS",
        seed=seed,
        runtime=time.perf_counter() - began,
        info={
            **solution.info,
            "tstar_cost": path_cost(cost, [start, *order.tolist()]),
            "start_objective": info.pop("start_value"),
            **info,
        },
    )


@register_method(
    SopProblem,
    "ILS",
    default=False,
    not_default="ILS runs only when named (--methods ILS): a search with a budget",
)
def ils_sop(
    problem: SopProblem,
    seed: int = 0,
    time_limit: float | None = None,
    iterations: int = 30,
    window: int = 20,
    max_block: int = 3,
    strength: int = 2,
    accept_worse: float = 0.01,
) -> Solution:
    """The same iterated local search on the SOP's path cost (start/end nodes fixed).

    Starts from SMMA's and MMA's paths, each repaired by backtracking at a greedy dead end
    (:func:`~taopt.heuristics.sequencing.ordered_or_repaired`); when neither gives one,
    status "no_solution" with the reason in ``info["error"]``.
    """
    began = time.perf_counter()
    start, end = problem.start, problem.end
    fixed = {start} if end is None else {start, end}
    starts, failure = _start_orders(problem.cost, problem.precedences, start, end)
    if not starts:
        return no_order_solution(problem, "ILS", seed, began, failure)
    items = [c for c in range(len(problem.cost)) if c not in fixed]
    order, _, info = ils_search(
        lambda o: PathStates(problem.cost, start, end, o),
        starts,
        items,
        problem.precedences,
        seed,
        iterations,
        time_limit,
        window,
        max_block,
        strength,
        accept_worse,
    )
    path = [start, *order.tolist()] + ([] if end is None else [end])
    return make_solution(
        problem,
        Order(path),
        method="ILS",
        status=FEASIBLE,
        runtime=time.perf_counter() - began,
        seed=seed,
        info=info,
    )
