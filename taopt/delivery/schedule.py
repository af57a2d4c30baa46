"""Exact truck schedule for a fixed customer order (dynamic programming).

Given the order in which the drone serves the customers, the remaining decisions
of (5.1)–(5.7) are the launch and landing stops of every sortie (σ_ijk) and the
truck path between them (y_ik). Under the timing semantics of
:mod:`taopt.delivery.evaluate` the recovery time R_p after sortie p depends on
the past only through (R_{p-1}, landing stop of sortie p-1), and every later time
is non-decreasing in R_{p-1}. So for each sortie and each landing stop the
earliest recovery time dominates every other partial schedule ending there, and
the dynamic programme over (sortie, landing stop) states below is exact.
"""

from __future__ import annotations

import time
import weakref
from collections.abc import Sequence

import numpy as np

from taopt.delivery.instance import DeliveryInstance, Plan
from taopt.errors import FeasibilityError
from taopt.result import FEASIBLE, Solution


class _SortieData:
    """Per-customer arrays the DP needs, built once per instance on first use.

    For customer j: V_j (viable stops), flight times to them, a penalty matrix equal to
    τ where launch i / landing k satisfy (5.6) and +inf elsewhere, and the truck times
    between the stops of V_j.
    """

    def __init__(self, instance: DeliveryInstance) -> None:
        self.instance = instance
        self.items: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = {}

    def get(self, j: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        item = self.items.get(j)
        if item is None:
            inst = self.instance
            dist = inst.flight_distance[j]
            limit = inst.flight_limit
            viable = np.flatnonzero(dist + dist.min() <= limit)
            near = dist[viable]
            penalty = np.where(near[:, None] + near[None, :] <= limit, inst.service_time, np.inf)
            carry = inst.truck_time[np.ix_(viable, viable)]
            item = (viable, inst.flight_time[j, viable], penalty, carry)
            self.items[j] = item
        return item


_DATA: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _sortie_data(instance: DeliveryInstance) -> _SortieData:
    data = _DATA.get(instance)
    if data is None:
        data = _DATA[instance] = _SortieData(instance)
    return data


def _check_order(instance: DeliveryInstance, order: np.ndarray, complete: bool) -> None:
    n = instance.n
    if order.size and (order.min() < 0 or order.max() >= n):
        bad = int(order[(order < 0) | (order >= n)][0])
        raise FeasibilityError(f"(5.2) customer {bad} in the order does not exist (0..{n - 1})")
    counts = np.bincount(order, minlength=n)
    if (counts > 1).any():
        j = int(np.flatnonzero(counts > 1)[0])
        raise FeasibilityError(f"(5.2) customer {j} appears {int(counts[j])} times in the order")
    if complete and (counts == 0).any():
        j = int(np.flatnonzero(counts == 0)[0])
        raise FeasibilityError(f"(5.2) customer {j} is missing from the order")
    if instance.precedences:
        pairs = np.asarray(instance.precedences, dtype=np.int64)
        position = np.full(n, -1, dtype=np.int64)
        position[order] = np.arange(order.size)
        pr, pj = position[pairs[:, 0]], position[pairs[:, 1]]
        bad = np.flatnonzero((pj >= 0) & ((pr < 0) | (pr > pj)))
        if bad.size:
            r, j = (int(x) for x in pairs[bad[0]])
            if pr[bad[0]] < 0:
                raise FeasibilityError(
                    f"(5.7) precedence ({r}, {j}) violated: customer {j} is in the order but "
                    f"its predecessor {r} is not"
                )
            raise FeasibilityError(
                f"(5.7) precedence ({r}, {j}) violated: customer {r} must be served before "
                f"customer {j} in the order"
            )


def schedule(instance: DeliveryInstance, order: Sequence[int], complete: bool = True) -> Solution:
    """Best launch/landing stops and truck path for a fixed customer order.

    Parameters
    ----------
    instance : DeliveryInstance
    order : sequence of int
        The customers in serving order (a permutation of 0..n-1 respecting (5.7)).
    complete : bool
        If False, ``order`` may list a subset of the customers (used while building
        orders); precedences are then checked among the listed ones and every
        listed customer's predecessors must be listed. The plan is then partial and
        :func:`taopt.evaluate` will reject it.

    Returns
    -------
    Solution
        ``.plan`` the optimal :class:`Plan` for this order, ``.objective`` its makespan
        (5.1) (equal to ``taopt.evaluate(instance, plan)``), ``.status`` "feasible",
        ``.order``, ``.runtime``, ``.method`` "schedule".

    Raises
    ------
    FeasibilityError
        The order is not a permutation of the customers, or violates a precedence.

    Notes
    -----
    States are (sortie p, landing stop k) with value R_p(k), the earliest recovery
    time at k. Transitions, for customer j of sortie p and stops in V_j (the viable
    stops of j, the only possible launch and landing stops)::

        S_p(i)  = min_k' R_{p-1}(k') + truck_time[k', i]
        t_p(i)  = S_p(i) + flight_time[j, i] + τ
        R_p(k)  = min_{i: d(i,j)+d(j,k) <= L} max(t_p(i) + flight_time[j, k],
                                                 S_p(i) + truck_time[i, k]) + τ

    and the last sortie minimises t_p(i) instead. Time O(Σ_p |V_{p-1}| |V_p|) <= O(n s²),
    vectorised with numpy; memory O(n s) for the back-pointers.

    Example
    -------
    >>> from taopt.delivery.instance import DeliveryInstance
    >>> inst = DeliveryInstance.grid([[0, 100], [100, 100]], k=2, side=100, v_drone=10,
    ...                              v_truck=5, flight_range=150)
    >>> sol = schedule(inst, [0, 1])  # customer 0 launched at stop 0, recovered at stop 2
    >>> sol.objective, sol.plan.launch
    (30.0, (0, 2))
    """
    start = time.perf_counter()
    order_arr = np.asarray(list(order), dtype=np.int64).reshape(-1)
    _check_order(instance, order_arr, complete)
    if order_arr.size == 0:
        return Solution(
            0.0,
            FEASIBLE,
            runtime=time.perf_counter() - start,
            method="schedule",
            plan=Plan((), (), ()),
            order=[],
        )
    tt = instance.truck_time
    tau = instance.service_time
    data = _sortie_data(instance)

    prev_stops = np.array([instance.depot], dtype=np.int64)
    ready = np.zeros(1)
    stops_of: list[np.ndarray] = []
    best_prev: list[np.ndarray] = []  # for each launch stop (position in V_p): position in V_{p-1}
    best_launch: list[np.ndarray] = []  # for each landing stop (position in V_p): launch position
    last = order_arr.size - 1
    objective = np.inf
    for p, j in enumerate(order_arr):
        viable, flight, penalty, carry = data.get(int(j))
        # launch times S_p(i): drive from the best previous landing stop
        reach = ready[:, None] + tt[np.ix_(prev_stops, viable)]
        arg = reach.argmin(axis=0)
        launch_time = reach[arg, np.arange(viable.size)]
        served = launch_time + flight + tau
        # R_p(k) = max(t + flight to k, S + truck i -> k) + τ; + inf where (5.6) fails
        recovery = np.maximum(served[:, None] + flight[None, :], launch_time[:, None] + carry)
        recovery += penalty
        if p == last:
            i_pos = int(served.argmin())
            objective = float(served[i_pos])
            k_pos = int(recovery[i_pos].argmin())
        else:
            land_arg = recovery.argmin(axis=0)
            ready = recovery[land_arg, np.arange(viable.size)]
            best_launch.append(land_arg)
        stops_of.append(viable)
        best_prev.append(arg)
        prev_stops = viable

    # backtrack
    m = order_arr.size
    launch = np.empty(m, dtype=np.int64)
    landing = np.empty(m, dtype=np.int64)
    launch[last] = stops_of[last][i_pos]
    landing[last] = stops_of[last][k_pos]
    for p in range(last, 0, -1):
        k_pos = int(best_prev[p][i_pos])  # landing of sortie p-1, a position in V_{p-1}
        i_pos = int(best_launch[p - 1][k_pos])
        landing[p - 1] = stops_of[p - 1][k_pos]
        launch[p - 1] = stops_of[p - 1][i_pos]
    plan = Plan(tuple(order_arr.tolist()), tuple(launch.tolist()), tuple(landing.tolist()))
    return Solution(
        objective=objective,
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        method="schedule",
        plan=plan,
        order=order_arr.tolist(),
    )


def optimal_plan(instance: DeliveryInstance, max_customers: int = 14) -> Solution:
    """Exact optimum of (5.1)–(5.7) for small n by dynamic programming over subsets.

    The future of a partial plan depends only on the set of customers served, the
    landing stop of its last sortie and its recovery time, and every later time is
    non-decreasing in that recovery time. So the states (served set, landing stop)
    with value the earliest recovery time (Held–Karp style, the same transitions as
    :func:`schedule`) give the optimum over all precedence-feasible orders and all
    launch/landing choices at once.

    Parameters
    ----------
    instance : DeliveryInstance
    max_customers : int
        Refuse instances with more customers (time and memory grow as 2^n).

    Returns
    -------
    Solution
        ``.status`` "optimal", ``.objective == .bound`` the optimal makespan,
        ``.plan`` an optimal plan (scored by :func:`taopt.evaluate` to the same value),
        ``.method`` "subset-dp".

    Raises
    ------
    SolverError
        n > max_customers.

    Notes
    -----
    O(2^n · n · s²) time, O(2^n · s) memory. About 0.1 s for n = 8, s = 121.
    """
    from taopt.errors import SolverError
    from taopt.result import OPTIMAL

    start = time.perf_counter()
    n, s = instance.n, instance.s
    if n > max_customers:
        raise SolverError(f"optimal_plan: n = {n} > max_customers = {max_customers}")
    tt = instance.truck_time
    ft = instance.flight_time
    fd = instance.flight_distance
    tau = instance.service_time
    limit = instance.flight_limit
    need = np.zeros(n, dtype=np.int64)  # bit mask of each customer's predecessors
    for r, j in instance.precedences:
        need[j] |= 1 << r
    viable = [np.flatnonzero(fd[j] + fd[j].min() <= limit) for j in range(n)]
    pair_ok = [fd[j, v][:, None] + fd[j, v][None, :] <= limit for j, v in enumerate(viable)]
    full = (1 << n) - 1
    ready = np.full((1 << n, s), np.inf)
    ready[0, instance.depot] = 0.0
    # back-pointers: (customer, launch stop, previous landing stop) per (mask, landing)
    back_customer = np.full((1 << n, s), -1, dtype=np.int64)
    back_launch = np.full((1 << n, s), -1, dtype=np.int64)
    back_prev = np.full((1 << n, s), -1, dtype=np.int64)
    best = (np.inf, -1, -1, -1, -1)  # makespan, last customer, launch, landing, prev landing
    for mask in range(full):
        alive = np.flatnonzero(np.isfinite(ready[mask]))
        if alive.size == 0:
            continue
        for j in range(n):
            if mask >> j & 1 or (need[j] & ~mask):
                continue
            v = viable[j]
            reach = ready[mask, alive][:, None] + tt[np.ix_(alive, v)]
            arg = reach.argmin(axis=0)
            launch_time = reach[arg, np.arange(v.size)]
            served = launch_time + ft[j, v] + tau
            new = mask | 1 << j
            if new == full:
                i_pos = int(served.argmin())
                if served[i_pos] < best[0]:
                    recovery = (
                        np.maximum(served[i_pos] + ft[j, v], launch_time[i_pos] + tt[v[i_pos], v])
                        + tau
                    )
                    recovery[~pair_ok[j][i_pos]] = np.inf
                    k_pos = int(recovery.argmin())
                    best = (
                        float(served[i_pos]),
                        j,
                        int(v[i_pos]),
                        int(v[k_pos]),
                        int(alive[arg[i_pos]]),
                    )
                continue
            recovery = (
                np.maximum(
                    served[:, None] + ft[j, v][None, :], launch_time[:, None] + tt[np.ix_(v, v)]
                )
                + tau
            )
            recovery[~pair_ok[j]] = np.inf
            land_arg = recovery.argmin(axis=0)
            value = recovery[land_arg, np.arange(v.size)]
            better = value < ready[new, v]
            if better.any():
                k = v[better]
                ready[new, k] = value[better]
                back_customer[new, k] = j
                back_launch[new, k] = v[land_arg[better]]
                back_prev[new, k] = alive[arg[land_arg[better]]]
    makespan, j, i, k, prev = best
    order, launch, landing = [j], [i], [k]
    mask = full & ~(1 << j)
    while mask:
        j, i = int(back_customer[mask, prev]), int(back_launch[mask, prev])
        order.append(j)
        launch.append(i)
        landing.append(prev)
        prev = int(back_prev[mask, prev])
        mask &= ~(1 << j)
    plan = Plan(tuple(order[::-1]), tuple(launch[::-1]), tuple(landing[::-1]))
    return Solution(
        objective=makespan,
        status=OPTIMAL,
        bound=makespan,
        runtime=time.perf_counter() - start,
        method="subset-dp",
        plan=plan,
        order=list(plan.order),
    )


__all__ = ["schedule", "optimal_plan"]
