"""An incumbent for one truck with several drones: the best *synchronised* plan, by a DP over
(served set, stop).

A synchronised plan is a sequence of *operations*: the truck stands at stop a with every drone
aboard, launches up to D sorties there (each at most c customers), drives straight to stop b
(b = a: it waits) and recovers every drone there; then it may drive on before the next
operation. This is the shape the iterated local search cannot build when the truck drives
ahead and meets its drones (issue 32): the truck's walk and the drones' flights are chosen
together, per operation.

With every drone aboard between operations, the earliest schedule of such a plan
(:mod:`taopt.fleet.evaluate`) splits into operations: launched at t, a drone flying sortie σ
lands at b at ``t + fly(σ, a, b)`` (its legs and τ per customer), the truck arrives at
``t + tt(a, b)``, each drone is recovered at ``max(both) + τ``, so the truck leaves b at
``t + max(tt(a, b), max_σ fly(σ, a, b)) + τ``. A customer's predecessors are served in earlier
operations or earlier on its own sortie (so no service ever waits). Hence

* ``g_D[X][a, b]``: the least ``max_σ fly(σ, a, b)`` over the splits of X into at most D
  sorties (each ordered, within range), a recursion over the sortie holding X's lowest
  customer;
* ``F[S, b]``: the earliest time the truck stands at b, every drone aboard, having served
  exactly S: ``F[S ∪ X, b] = min_a G[S, a] + max(tt(a, b), g_D[X][a, b]) + τ`` with
  ``G[S, a] = min_q F[S, q] + tt(q, a)`` (a plain drive);
* under ``"last_service"`` the value is ``min G[S, a] + e_D[X][a]`` over final operations
  (``e_D``: the least last service time of X's sorties launched at a); under ``"return"``,
  ``min_b F[full, b] + tt(b, depot)``.

This restricts the plans (every drone recovered before the next launch), so its value is an
upper bound only: it is scored by :func:`~taopt.fleet.evaluate.evaluate_fleet` and used as an
incumbent (:func:`taopt.fleet.search.label_search`, :func:`taopt.models.fleet.solve_fleet`).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from taopt.errors import FeasibilityError
from taopt.fleet.evaluate import evaluate_fleet
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie
from taopt.runtime import Deadline

#: Largest ``2^n * operation sets * s^2`` the DP takes on (float operations, about 1 s per 2e8).
MAX_WORK = 4e8

INF = math.inf


def synced_applies(problem: FleetProblem) -> bool:
    """One truck carrying at least one drone, every customer drone-servable (the DP's shape)."""
    return (
        problem.K == 1
        and problem.drones[0] >= 1
        and all(problem.drone_servable(j) for j in range(problem.n))
    )


def _closure(problem: FleetProblem) -> list[int]:
    """``before[j]``: bitmask of every customer that must be served no later than j."""
    import networkx as nx

    g = problem.precedence_graph
    before = [0] * problem.n
    for j in nx.topological_sort(g):
        for r in g.predecessors(j):
            before[j] |= before[r] | 1 << r
    return before


class _Ops:
    """The operation tables: per customer set X (at most D·c customers, no precedence pair
    across its sorties), ``g`` (s, s) and ``e`` (s,), with the sorties' sequences kept for
    the rebuild."""

    def __init__(self, problem: FleetProblem, before: list[int]) -> None:
        p = problem
        n, s, c, D = p.n, p.s, p.capacity, p.drones[0]
        tau, vd, limit = p.service_time, p.v_drone, p.flight_limit
        fs, fc = p.flight_stop, p.flight_customer
        self.s = s
        # one sortie: per unordered set Y (|Y| <= c) the best order's (fly (s, s), last (s,))
        self.fly: dict[int, np.ndarray] = {}
        self.last: dict[int, np.ndarray] = {}
        self.order: dict[tuple[int, int, int], tuple[int, ...]] = {}
        self.seqs: dict[int, list[tuple[tuple[int, ...], np.ndarray, np.ndarray]]] = {}
        for size in range(1, c + 1):
            for seq in itertools.permutations(range(n), size):
                mask = sum(1 << j for j in seq)
                if any(before[seq[i]] & (1 << seq[k]) for i in range(size) for k in range(i, size)):
                    continue  # a predecessor later on the same sortie
                inner = sum(float(fc[a, b]) for a, b in zip(seq[:-1], seq[1:], strict=False))
                dist = fs[seq[0]][:, None] + inner + fs[seq[-1]][None, :]  # (s launch, s rec)
                fly = np.where(dist <= limit, dist / vd + size * tau, INF)
                ok = np.isfinite(fly).any(axis=1)
                inner_time = inner / vd + (size - 1) * tau
                last = np.where(ok, fs[seq[0]] / vd + tau + inner_time, INF)
                self.seqs.setdefault(mask, []).append((seq, fly, last))
        for mask, options in self.seqs.items():
            self.fly[mask] = np.min(np.stack([f for _, f, _ in options]), axis=0)
            self.last[mask] = np.min(np.stack([e for _, _, e in options]), axis=0)
        # D sorties: per set X the least max over a split (recursion on X's lowest customer)
        self.g: dict[int, np.ndarray] = dict(self.fly)
        self.e: dict[int, np.ndarray] = dict(self.last)
        singles = sorted(self.fly)
        for _ in range(D - 1):
            g2: dict[int, np.ndarray] = dict(self.fly)
            e2: dict[int, np.ndarray] = dict(self.last)
            for Y in singles:
                low = Y & -Y
                for Z, gz in self.g.items():
                    if Z & Y or Z & -Z < low:
                        continue  # Y holds the lowest customer of Y | Z
                    if any(before[j] & Z for j in _bits(Y)) or any(before[j] & Y for j in _bits(Z)):
                        continue  # a precedence pair across two sorties of one operation
                    X = Y | Z
                    gx = np.maximum(self.fly[Y], gz)
                    ex = np.maximum(self.last[Y], self.e[Z])
                    if X in g2:
                        g2[X] = np.minimum(g2[X], gx)
                        e2[X] = np.minimum(e2[X], ex)
                    else:
                        g2[X], e2[X] = gx, ex
            self.g, self.e = g2, e2
        self.sets = np.array(sorted(self.g), dtype=np.int64)
        tt = np.asarray(p.truck_time, dtype=float)
        self.dur = np.stack([np.maximum(tt, self.g[int(X)]) + tau for X in self.sets])  # (m,s,s)
        self.ends = np.stack([self.e[int(X)] for X in self.sets])  # (m, s)
        self.D = D

    def split(
        self, X: int, a: int, b: int | None, target: float, drones: int
    ) -> list[tuple[int, ...]]:
        """Sorties (at most ``drones``) serving X from a (to b, or open when b is None) whose
        largest flight (or last service) is ``target``."""
        Y = X & -X
        options = []
        for mask, seqs in self.seqs.items():
            if not mask & Y or mask & ~X:
                continue
            for seq, fly, last in seqs:
                v = float(fly[a, b]) if b is not None else float(last[a])
                if v <= target * (1 + 1e-12) + 1e-12:
                    options.append((mask, seq))
        for mask, seq in options:
            rest = X & ~mask
            if not rest:
                return [seq]
            if drones > 1:
                try:
                    return [seq, *self.split(rest, a, b, target, drones - 1)]
                except LookupError:
                    continue
        raise LookupError(X)


def _bits(mask: int) -> list[int]:
    return [j for j in range(mask.bit_length()) if mask >> j & 1]


def synced_plan(
    problem: FleetProblem, time_limit: float | None = None
) -> tuple[float, FleetPlan | None]:
    """The best synchronised plan (module docstring) and its value by
    :func:`~taopt.fleet.evaluate.evaluate_fleet`; ``(inf, None)`` when the DP does not apply
    (:func:`synced_applies`), is too large (:data:`MAX_WORK`) or the time limit passes first."""
    if not synced_applies(problem):
        return INF, None
    deadline = Deadline(time_limit)
    n, s = problem.n, problem.s
    before = _closure(problem)
    ops = _Ops(problem, before)
    m = len(ops.sets)
    if float(1 << n) * m * s * s > MAX_WORK or m == 0:
        return INF, None
    tt = np.asarray(problem.truck_time, dtype=float)
    full = (1 << n) - 1
    N = 1 << n
    F = np.full((N, s), INF)
    F[0, problem.depot] = 0.0
    par_s = np.full((N, s), -1, dtype=np.int64)
    par_x = np.full((N, s), -1, dtype=np.int64)
    par_a = np.full((N, s), -1, dtype=np.int64)
    G = np.full((N, s), INF)
    drive = np.full((N, s), -1, dtype=np.int64)  # G's stop before the drive
    need = np.array(
        [int(np.bitwise_or.reduce([before[j] for j in _bits(int(X))])) for X in ops.sets]
    )
    best, best_at = INF, None
    ret = problem.objective == "return"
    for S in range(N):
        row = F[S]
        if not np.isfinite(row).any():
            continue
        if S & 15 == 0 and deadline.expired():
            return INF, None
        reach = row[:, None] + tt
        G[S] = reach.min(axis=0)
        drive[S] = reach.argmin(axis=0)
        free = ((ops.sets & S) == 0) & ((need & ~(S | ops.sets)) == 0)
        idx = np.flatnonzero(free)
        if not len(idx):
            continue
        if not ret:
            finals = idx[(ops.sets[idx] | S) == full]
            if len(finals):
                vals = G[S][None, :] + ops.ends[finals]
                k = int(np.argmin(vals))
                v = float(vals.flat[k])
                if v < best:
                    best, best_at = v, (S, int(finals[k // s]), k % s)
        cand = G[S][None, :, None] + ops.dur[idx]  # (m, a, b)
        a_best = cand.argmin(axis=1)
        v_best = np.take_along_axis(cand, a_best[:, None, :], axis=1)[:, 0, :]
        for r, x in enumerate(idx):
            T = S | int(ops.sets[x])
            better = v_best[r] < F[T]
            if better.any():
                F[T][better] = v_best[r][better]
                par_s[T][better] = S
                par_x[T][better] = x
                par_a[T][better] = a_best[r][better]
    if ret:
        home = F[full] + tt[:, problem.depot]
        b = int(np.argmin(home))
        if np.isfinite(home[b]):
            best, best_at = float(home[b]), (full, -1, b)
    if best_at is None:
        return INF, None
    plan = _rebuild(problem, ops, tt, F, G, drive, par_s, par_x, par_a, best_at)
    try:
        return evaluate_fleet(problem, plan), plan
    except FeasibilityError:  # not expected: the DP's plans are feasible by construction
        return INF, None


def _rebuild(
    problem: FleetProblem,
    ops: _Ops,
    tt: np.ndarray,
    F: np.ndarray,
    G: np.ndarray,
    drive: np.ndarray,
    par_s: np.ndarray,
    par_x: np.ndarray,
    par_a: np.ndarray,
    best_at: tuple[int, int, int],
) -> FleetPlan:
    """The plan of the DP's best path: per operation (launch stop a, sorties, recovery stop b)."""
    S, x, a = best_at
    steps: list[tuple[int, list[tuple[int, ...]], int | None]] = []
    if x >= 0:  # last_service: a final operation from (S, a), sorties left open
        X = int(ops.sets[x])
        target = float(ops.e[X][a])
        steps.append((a, ops.split(X, a, None, target, ops.D), None))
        b = int(drive[S, a])
    else:
        b = a  # return: the stop where every drone is aboard at the end
    while S:
        Sp, xp, ap = int(par_s[S, b]), int(par_x[S, b]), int(par_a[S, b])
        X = int(ops.sets[xp])
        target = float(ops.g[X][ap, b])
        steps.append((ap, ops.split(X, ap, b, target, ops.D), b))
        S, b = Sp, int(drive[Sp, ap])
    steps.reverse()
    route = [problem.depot]
    D = problem.drones[0]
    sorties: list[list[Sortie]] = [[] for _ in range(D)]
    for launch_stop, seqs, rec_stop in steps:
        if route[-1] != launch_stop:
            route.append(launch_stop)
        lpos = len(route) - 1
        if rec_stop is None:  # open sorties: each recovered at the stop nearest its last customer
            for d, seq in enumerate(seqs):
                q = int(np.argmin(problem.flight_stop[seq[-1]]))
                if route[-1] != q:
                    route.append(q)
                sorties[d].append(Sortie(lpos, seq, len(route) - 1))
            continue
        if route[-1] != rec_stop:
            route.append(rec_stop)
        rpos = len(route) - 1
        for d, seq in enumerate(seqs):
            sorties[d].append(Sortie(lpos, seq, rpos))
    return FleetPlan([route], [[]], [sorties])


__all__ = ["MAX_WORK", "synced_applies", "synced_plan"]
