"""Exact DP over customer subsets for one drone per truck, c = 1 and no precedence (TSP-D).

With one drone per truck and single-customer sorties, a truck's plan is a sequence of
*operations* between moments its drone is aboard (Agatz, Bouman & Schmidt 2018, generalised to
a street network, τ, service modes and ranges): from stop v (drone aboard, truck free) the
truck drives to stop w serving a set of customers at their stops, while its drone either stays
aboard (a truck-only operation, time ``P(U, v, w)``) or serves one customer d, launched at v and
recovered at w (time ``max(P(U \\ d, v, w), ft(v, d) + τ + ft(d, w)) + τ``, within range). The
earliest schedule of any plan of such a truck splits into operations this way (module
:mod:`taopt.fleet.evaluate`: a launch waits only for the truck, a recovery for both), so

* ``H(U, v, j)``: the shortest truck walk from v serving U, ending at customer j (Held–Karp);
* ``P(U, v, w) = min_j H(U, v, j) + tt(j, w)``, ``C(U, v, w)`` the best operation;
* ``F(T, w) = min_{U ⊆ T, v} F(T \\ U, v) + C(U, v, w)`` (then closed under a plain drive),
  the earliest time a truck stands at w, drone aboard, having served exactly T;

give one truck's optimum serving exactly T: ``F(T, depot)`` under ``"return"``, and under
``"last_service"`` ``min_{U, v} F(T \\ U, v) + E(U, v)`` with E the last service time of a final
operation. Trucks share nothing but the customers (no precedence), so K trucks' optimum is
``min over partitions (T_1..T_K) of max_k f(T_k)``, a DP over subsets.

Time O(3^n s² + 2^n n² s); memory O(2^n s²) floats (n = 12, s = 13: 0.7 M).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from taopt.errors import SolverError
from taopt.fleet.bounds import reach_bound
from taopt.fleet.evaluate import evaluate_fleet
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie
from taopt.runtime import Deadline

#: Largest table cells ``2^n s²`` this DP allocates (8 bytes each, a few copies).
MAX_CELLS = 40_000_000

INF = math.inf


def _bits(mask: int) -> list[int]:
    return [j for j in range(mask.bit_length()) if mask >> j & 1]


def operations_dp(
    problem: FleetProblem, time_limit: float | None = None, fast: bool = True
) -> dict[str, Any]:
    """Optimum of a problem with one drone per truck, c = 1 and no precedence.

    With ``fast`` (the default), a geometric TSP-D (:func:`taopt.fleet.tspd_dp.tspd_applies`)
    goes to the sparse operations DP :func:`taopt.fleet.tspd_dp.tspd_dp` (same optimum, 16
    customers in seconds); ``fast=False`` keeps this full DP (the tests' reference).

    Returns a dict like :func:`taopt.fleet.search.label_search`: ``plan``, ``value``, ``bound``,
    ``stopped_by`` ("optimal", "time_limit" or "size").
    """
    if not (all(d == 1 for d in problem.drones) and problem.capacity == 1):
        raise SolverError("operations_dp needs one drone per truck and c = 1")
    if problem.precedences:
        raise SolverError("operations_dp needs an instance without precedences")
    if fast:
        from taopt.fleet.tspd_dp import tspd_applies, tspd_dp

        if tspd_applies(problem):
            return tspd_dp(problem, time_limit)
    deadline = Deadline(time_limit)
    n, s = problem.n, problem.s
    N = 1 << n
    if N * s * s > MAX_CELLS:
        return _stopped(problem, "size")
    tau = problem.service_time
    tt = np.asarray(problem.truck_time, dtype=float)
    ft = problem.flight_stop / problem.v_drone  # (n, s)
    truck_ok = np.array([problem.truck_servable(j) for j in range(n)])
    drone_ok = np.array([problem.drone_servable(j) for j in range(n)])
    cs = np.array([problem.customer_stop[j] if truck_ok[j] else 0 for j in range(n)])
    ttc = np.where(truck_ok[:, None] & truck_ok[None, :], tt[cs][:, cs], INF)  # (n, n)
    to_stop = np.where(truck_ok[:, None], tt[cs], INF)  # (n, s): customer j's stop -> w
    popcount = np.array([bin(m).count("1") for m in range(N)])
    layers = [np.flatnonzero(popcount == k) for k in range(n + 1)]
    # -- H(U, v, j) --------------------------------------------------------------------------
    H = np.full((N, s, n), INF)
    for j in range(n):
        if truck_ok[j]:
            H[1 << j, :, j] = tt[:, cs[j]]
    for k in range(2, n + 1):
        if deadline.expired():
            return _stopped(problem, "time_limit")
        masks = layers[k]
        for j in range(n):
            sel = masks[(masks >> j) & 1 == 1]
            if not truck_ok[j] or sel.size == 0:
                continue
            prev = sel ^ (1 << j)
            H[sel, :, j] = np.min(H[prev] + ttc[None, None, :, j], axis=2)
    # -- P(U, v, w), C(U, v, w) --------------------------------------------------------------
    P = np.empty((N, s, s))
    P[0] = tt
    for start in range(1, N, 4096):
        if deadline.expired():
            return _stopped(problem, "time_limit")
        stop = min(N, start + 4096)
        P[start:stop] = np.min(H[start:stop, :, :, None] + to_stop[None, None, :, :], axis=2)
    fly = ft[:, :, None] + tau + ft[:, None, :]  # (n, v, w)
    dist = problem.flight_stop[:, :, None] + problem.flight_stop[:, None, :]
    fly = np.where(dist <= problem.flight_limit, fly, INF)
    C = P.copy()
    choice = np.full((N, s, s), -1, dtype=np.int8)  # -1: truck-only, else the drone's customer
    everything = np.arange(N)
    for d in range(n):
        if not drone_ok[d]:
            continue
        if deadline.expired():
            return _stopped(problem, "time_limit")
        sel = everything[(everything >> d) & 1 == 1]
        op = np.maximum(P[sel ^ (1 << d)], fly[d][None, :, :]) + tau
        better = op < C[sel]
        C[sel] = np.where(better, op, C[sel])
        choice[sel] = np.where(better, d, choice[sel])
    if deadline.expired():
        return _stopped(problem, "time_limit")
    # -- F(T, w) -----------------------------------------------------------------------------
    F = np.full((N, s), INF)
    F[0] = tt[problem.depot]
    masks_all = np.arange(N)
    for T in range(1, N):
        if T & 255 == 0 and deadline.expired():
            return _stopped(problem, "time_limit")
        subs = masks_all[1 : T + 1][(masks_all[1 : T + 1] & ~T) == 0]
        best = np.min(F[T ^ subs][:, :, None] + C[subs], axis=(0, 1))
        # then a plain drive (tt is a metric: one step suffices)
        F[T] = np.min(best[:, None] + tt, axis=0)
    # -- one truck's optimum per served set ----------------------------------------------------
    if problem.objective == "return":
        f = F[:, problem.depot].copy()
        f_last = None
    else:
        # E(U, v): last service time of a final operation from v serving U (no recovery)
        Hend = np.min(H, axis=2)  # (N, s)
        Hend[0] = 0.0
        E = Hend.copy()
        e_choice = np.full((N, s), -1, dtype=np.int64)
        reach_ok = (
            problem.flight_stop + problem.flight_stop.min(axis=1)[:, None]
        ) <= problem.flight_limit
        for d in range(n):
            if not drone_ok[d]:
                continue
            sel = everything[(everything >> d) & 1 == 1]
            drone_t = np.where(reach_ok[d], ft[d] + tau, INF)  # (s,)
            op = np.maximum(Hend[sel ^ (1 << d)], drone_t[None, :])
            better = op < E[sel]
            E[sel] = np.where(better, op, E[sel])
            e_choice[sel] = np.where(better, d, e_choice[sel])
        f = np.full(N, INF)
        f_last = np.zeros((N, 2), dtype=np.int64)
        f[0] = 0.0
        for T in range(1, N):
            subs = _submasks(T)
            vals = F[T ^ subs] + E[subs]  # (m, v)
            a = int(np.argmin(vals))
            f[T] = vals.flat[a]
            f_last[T] = (subs[a // s], a % s)
    # -- K trucks --------------------------------------------------------------------------------
    K = problem.K
    g = f.copy()
    splits: list[np.ndarray] = []
    for _ in range(1, K):
        if deadline.expired():
            return _stopped(problem, "time_limit")
        g_new = np.full(N, INF)
        arg_new = np.zeros(N, dtype=np.int64)
        for T in range(N):
            subs = _submasks(T, empty=True)
            vals = np.maximum(g[T ^ subs], f[subs])
            a = int(np.argmin(vals))
            g_new[T] = vals[a]
            arg_new[T] = subs[a]
        splits.append(arg_new)
        g = g_new
    value = float(g[N - 1])
    if not math.isfinite(value):
        return {"plan": None, "value": INF, "bound": INF, "stopped_by": "infeasible"}
    # -- rebuild -------------------------------------------------------------------------------
    sets = []
    T = N - 1
    for arg in reversed(splits):
        U = int(arg[T])
        sets.append(U)
        T ^= U
    sets.append(T)
    sets.reverse()
    routes, served, flights = [], [], []
    for T in sets:
        r, sv, fl = _rebuild_truck(
            problem,
            T,
            F,
            C,
            choice,
            H,
            f_last,
            e_choice if f_last is not None else None,
            tt,
            cs,
        )
        routes.append(r)
        served.append(sv)
        flights.append([fl])
    plan = FleetPlan(routes, served, flights)
    scored = evaluate_fleet(problem, plan)
    if abs(scored - value) > 1e-9 * max(1.0, abs(value)):
        raise SolverError(f"operations_dp: the plan scores {scored!r} but the DP says {value!r}")
    return {"plan": plan, "value": scored, "bound": scored, "stopped_by": "optimal", "subsets": N}


def _submasks(T: int, empty: bool = False) -> np.ndarray:
    """The non-empty submasks of T (the empty one too with ``empty``)."""
    bits = _bits(T)
    subs = np.zeros(1, dtype=np.int64)
    for b in bits:
        subs = np.concatenate([subs, subs | (1 << b)])
    return subs if empty else subs[1:]


def _walk(
    H: np.ndarray, ttc_rows: Any, U: int, v: int, last: int, tt: np.ndarray, cs: np.ndarray
) -> list[int]:
    """The customers of U in walking order, ending at ``last`` (Held–Karp back-pointers
    recomputed from H)."""
    order = [last]
    while U != (1 << last):
        prev = U ^ (1 << last)
        cands = _bits(prev)
        target = H[U, v, last]
        best, arg = INF, -1
        for i in cands:
            val = H[prev, v, i] + tt[cs[i], cs[last]]
            if val < best:
                best, arg = val, i
        U, last = prev, arg
        order.append(last)
        del target
    return order[::-1]


def _last_operation(
    F: np.ndarray, C: np.ndarray, tt: np.ndarray, T: int, w: int
) -> tuple[int, int]:
    """(U, v) of the last step into F[T, w]: an operation U from v (U = 0: a plain drive
    from v), recomputed as the DP chose it."""
    s = tt.shape[0]
    masks = np.arange(1, T + 1)
    subs = masks[(masks & ~T) == 0]
    vals = F[T ^ subs][:, :, None] + C[subs]  # (m, v, w)
    best = vals.min(axis=(0, 1))  # arriving at each w' by an operation
    target = F[T, w]
    if best[w] <= target:
        a = int(np.argmin(vals[:, :, w]))
        return int(subs[a // s]), a % s
    v = int(np.argmin(best + tt[:, w]))
    return 0, v


def _rebuild_truck(
    problem: FleetProblem,
    T: int,
    F: np.ndarray,
    C: np.ndarray,
    choice: np.ndarray,
    H: np.ndarray,
    f_last: np.ndarray | None,
    e_choice: np.ndarray | None,
    tt: np.ndarray,
    cs: np.ndarray,
) -> tuple[list[int], list[tuple[int, int]], list[Sortie]]:
    """One truck's route, truck service and sorties for its set T."""
    ops: list[tuple[int, int, int]] = []  # (U, v, w) from the start; U = 0 a plain drive
    final: tuple[int, int] | None = None
    if f_last is not None:
        U, v = (int(x) for x in f_last[T]) if T else (0, problem.depot)
        final = (U, v)
        T_rest, w = T ^ U, v
    else:
        T_rest, w = T, problem.depot
    for _ in range(4 * problem.n + 8):
        if T_rest == 0:
            if w != problem.depot:
                ops.append((0, problem.depot, w))
            break
        U, v = _last_operation(F, C, tt, T_rest, w)
        if U == 0:
            # a plain drive into w: the operation that reached v (never another drive)
            U2, v2 = _last_operation(F, C, tt, T_rest, v)
            if U2 == 0:
                raise SolverError("operations_dp: the rebuild found two drives in a row")
            ops.append((0, v, w))
            U, v, w = U2, v2, v
        ops.append((U, v, w))
        T_rest ^= U
        w = v
    else:
        raise SolverError("operations_dp: the rebuild did not reach the start")
    ops.reverse()
    route = [problem.depot]
    served: list[tuple[int, int]] = []
    flights: list[Sortie] = []

    def go(stop: int) -> int:
        if route[-1] != stop:
            route.append(stop)
        return len(route) - 1

    def truck_walk(U: int, v: int) -> None:
        if U == 0:
            return
        Hv = H[U, v]
        last = int(np.argmin(Hv))
        for j in _walk(H, None, U, v, last, tt, cs):
            served.append((go(int(cs[j])), j))

    for U, v, w in ops:
        go(v)
        if U == 0:
            go(w)
            continue
        d = int(choice[U, v, w])
        if d < 0:
            # truck-only: walk U ending where P's argmin says, then drive to w
            ends = H[U, v] + tt[cs, w]
            last = int(np.argmin(ends))
            for j in _walk(H, None, U, v, last, tt, cs):
                served.append((go(int(cs[j])), j))
            go(w)
            continue
        launch = len(route) - 1
        rest = U ^ (1 << d)
        if rest:
            ends = H[rest, v] + tt[cs, w]
            last = int(np.argmin(ends))
            for j in _walk(H, None, rest, v, last, tt, cs):
                served.append((go(int(cs[j])), j))
        route.append(w)  # a new position, even at the same stop: the recovery
        flights.append(Sortie(launch, (d,), len(route) - 1))
    if final is not None:
        assert e_choice is not None  # the caller passes it whenever f_last is given
        U, v = final
        go(v)
        if U:
            d = int(e_choice[U, v])
            if d < 0:
                truck_walk(U, v)
            else:
                launch = len(route) - 1
                rest = U ^ (1 << d)
                truck_walk(rest, v)
                stop = int(np.argmin(problem.flight_stop[d]))
                route.append(stop)
                flights.append(Sortie(launch, (d,), len(route) - 1))
    return route, served, flights


def _stopped(problem: FleetProblem, why: str) -> dict[str, Any]:
    from taopt.fleet.search import _simple_plan

    plan = _simple_plan(problem)
    value = evaluate_fleet(problem, plan) if plan is not None else INF
    return {
        "plan": plan,
        "value": value,
        "bound": min(reach_bound(problem), value),
        "stopped_by": why,
    }


__all__ = ["operations_dp", "MAX_CELLS"]
