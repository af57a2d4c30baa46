"""Exact truck schedule for a fixed customer order (dynamic programming).

Given the order in which the drone serves the customers, the remaining decisions
of (5.1)–(5.7) are the launch and landing stops of every sortie (σ_ijk) and the
truck path between them (y_ik). Under the timing semantics of
:mod:`taopt.delivery.evaluate` the recovery time R_p after sortie p depends on
the past only through (R_{p-1}, landing stop of sortie p-1), and every later time
is non-decreasing in R_{p-1}. So for each sortie and each landing stop the
earliest recovery time dominates every other partial schedule ending there, and
the dynamic programme over (sortie, landing stop) states below is exact.

Both dynamic programmes, :func:`schedule` (fixed order) and :func:`optimal_plan`
(subsets of customers), make their transitions with the one vectorised step
:func:`_sortie_step`, and both score the plan they return with the one scorer
:func:`taopt.delivery.evaluate.evaluate_plan` (docs/architecture.md, invariant 1), checking that the
DP's own value agrees (relative :data:`MATCH_TOLERANCE`).
"""

from __future__ import annotations

import time
import weakref
from collections.abc import Sequence
from typing import Any

import numpy as np

from taopt.delivery.instance import DeliveryInstance, Plan
from taopt.errors import FeasibilityError, InstanceError, SolverError
from taopt.result import FEASIBLE, Solution, finish, make_solution
from taopt.runtime import Deadline

#: Largest relative difference allowed between a DP's own makespan and the scorer's (5.1).
MATCH_TOLERANCE = 1e-9


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


def _sortie_step(
    truck_time: np.ndarray,
    service_time: float,
    ready: np.ndarray,
    prev_stops: np.ndarray,
    sortie: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    final: bool = False,
) -> tuple[np.ndarray, np.ndarray, Any, Any]:
    """One DP transition: launch, serve, recover at the cheapest landing (vectorised).

    Shared by :func:`schedule` (fixed order) and :func:`optimal_plan` (subsets). From the
    previous sortie's states (landing stop k', earliest recovery R_{p-1}(k')) and customer
    j's data from :class:`_SortieData`, for every launch i and landing k in V_j::

        S_p(i) = min_k' R_{p-1}(k') + truck_time[k', i]
        t_p(i) = S_p(i) + flight_time[j, i] + τ
        R_p(k) = min_{i: (5.6)} max(t_p(i) + flight_time[j, k], S_p(i) + truck_time[i, k]) + τ

    with the floating-point operations of :func:`taopt.delivery.evaluate.timeline`, in
    the same order, so the DP's values are the scorer's.

    Parameters
    ----------
    truck_time : (s, s) array
    service_time : float
        τ.
    ready : (a,) array
        R_{p-1} at the stops ``prev_stops`` (finite).
    prev_stops : (a,) int array
        The possible landing stops of the previous sortie (the depot before the first).
    sortie : tuple
        ``_SortieData.get(j)``: V_j, flight_time[j, V_j], the (5.6) penalty (τ or +inf),
        truck times on V_j x V_j.
    final : bool
        The last sortie: minimise t_p instead of R_p.

    Returns
    -------
    prev_pos : (|V_j|,) int array
        For each launch stop (position in V_j), the position in ``prev_stops`` of the
        previous landing stop it is reached from.
    served : (|V_j|,) array
        t_p(i) for each launch stop.
    launch_pos, recovery
        If not ``final``: (|V_j|,) arrays, for each landing stop the position of its best
        launch stop and R_p(k) (+inf if no launch stop reaches it within L).
        If ``final``: two ints, the launch position with the earliest t_p and, for it, the
        landing position with the earliest recovery (one satisfies (5.6): every launch stop
        of V_j may land at the stop of V_j nearest to j).
    """
    viable, flight, penalty, carry = sortie
    reach = ready[:, None] + truck_time[np.ix_(prev_stops, viable)]
    prev_pos = reach.argmin(axis=0)
    columns = np.arange(viable.size)
    launch_time = reach[prev_pos, columns]
    served = launch_time + flight + service_time
    if final:
        i_pos = int(served.argmin())
        row = np.maximum(served[i_pos] + flight, launch_time[i_pos] + carry[i_pos])
        row += penalty[i_pos]
        return prev_pos, served, i_pos, int(row.argmin())
    recovery = np.maximum(served[:, None] + flight[None, :], launch_time[:, None] + carry)
    recovery += penalty  # + τ where (5.6) holds, +inf elsewhere
    launch_pos = recovery.argmin(axis=0)
    return prev_pos, served, launch_pos, recovery[launch_pos, columns]


def _matches(value: float, dp_value: float, who: str, plan: Plan) -> None:
    """Raise :class:`SolverError` when the scorer's ``value`` and the DP's differ."""
    if abs(value - dp_value) > MATCH_TOLERANCE * max(abs(value), abs(dp_value)):
        raise SolverError(
            f"{who}: the DP's makespan {dp_value!r} differs from evaluate_plan's {value!r} "
            f"by more than {MATCH_TOLERANCE:g} relative (order {list(plan.order)})"
        )


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
        late = np.flatnonzero((pj >= 0) & ((pr < 0) | (pr > pj)))
        if late.size:
            r, j = (int(x) for x in pairs[late[0]])
            if pr[late[0]] < 0:
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
        listed customer's predecessors must be listed. The plan is then partial,
        :func:`taopt.evaluate` would reject it, and ``.objective`` is the DP's own
        makespan of the listed sorties (the same timing semantics, not re-scored).

    Returns
    -------
    Solution
        ``.plan`` the optimal :class:`Plan` for this order, ``.objective`` its makespan
        (5.1) as scored by ``taopt.delivery.evaluate.evaluate_plan(instance, plan)`` (for
        a complete order), ``.info["dp_objective"]`` the DP's own value, ``.status``
        "feasible", ``.order``, ``.runtime``, ``.method`` "schedule".

    Raises
    ------
    FeasibilityError
        The order is not a permutation of the customers, or violates a precedence.
    SolverError
        The DP's makespan and the scorer's differ by more than :data:`MATCH_TOLERANCE`
        relative (a bug, never expected).

    Notes
    -----
    States are (sortie p, landing stop k) with value R_p(k), the earliest recovery
    time at k. Transitions, for customer j of sortie p and stops in V_j (the viable
    stops of j, the only possible launch and landing stops)::

        S_p(i)  = min_k' R_{p-1}(k') + truck_time[k', i]
        t_p(i)  = S_p(i) + flight_time[j, i] + τ
        R_p(k)  = min_{i: d(i,j)+d(j,k) <= L} max(t_p(i) + flight_time[j, k],
                                                 S_p(i) + truck_time[i, k]) + τ

    (one call of :func:`_sortie_step` per sortie) and the last sortie minimises t_p(i)
    instead. Time O(Σ_p |V_{p-1}| |V_p|) <= O(n s²),
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
    m = order_arr.size
    launch = np.empty(m, dtype=np.int64)
    landing = np.empty(m, dtype=np.int64)
    dp_value = 0.0
    if m:
        tt = instance.truck_time
        tau = instance.service_time
        data = _sortie_data(instance)
        prev_stops = np.array([instance.depot], dtype=np.int64)
        ready = np.zeros(1)
        stops_of: list[np.ndarray] = []
        from_prev: list[np.ndarray] = []  # per launch stop (position in V_p): position in V_{p-1}
        from_launch: list[np.ndarray] = []  # per landing stop (position in V_p): launch position
        last = m - 1
        for p in range(last):
            sortie = data.get(int(order_arr[p]))
            prev_pos, _, launch_pos, ready = _sortie_step(tt, tau, ready, prev_stops, sortie)
            stops_of.append(sortie[0])
            from_prev.append(prev_pos)
            from_launch.append(launch_pos)
            prev_stops = sortie[0]
        sortie = data.get(int(order_arr[last]))
        prev_pos, served, i_pos, k_pos = _sortie_step(
            tt, tau, ready, prev_stops, sortie, final=True
        )
        dp_value = float(served[i_pos])
        stops_of.append(sortie[0])
        from_prev.append(prev_pos)
        # backtrack
        launch[last] = stops_of[last][i_pos]
        landing[last] = stops_of[last][k_pos]
        for p in range(last, 0, -1):
            k_pos = int(from_prev[p][i_pos])  # landing of sortie p-1, a position in V_{p-1}
            i_pos = int(from_launch[p - 1][k_pos])
            landing[p - 1] = stops_of[p - 1][k_pos]
            launch[p - 1] = stops_of[p - 1][i_pos]
    plan = Plan(tuple(order_arr.tolist()), tuple(launch.tolist()), tuple(landing.tolist()))
    if not complete:  # a partial plan: the DP's value, not a plan the scorer accepts
        return Solution(
            objective=dp_value,
            status=FEASIBLE,
            runtime=time.perf_counter() - start,
            method="schedule",
            solution=plan,
            info={"dp_objective": dp_value},
        )
    solution = make_solution(
        instance,
        plan,
        method="schedule",
        status=FEASIBLE,
        runtime=time.perf_counter() - start,
        info={"dp_objective": dp_value},
    )
    _matches(solution.objective, dp_value, "schedule", plan)
    return solution


def _dp_stopped(instance: DeliveryInstance, incumbent: Any, start: float, info: dict) -> Solution:
    """Status "time_limit": the incumbent plan (or none, objective inf) and Proposition
    5.3's arborescence bound (the DP's partial table proves nothing tighter)."""
    from taopt.delivery.bounds import arborescence_bound

    plan = getattr(incumbent, "plan", incumbent)
    return finish(
        instance,
        plan,
        method="subset-dp",
        stop="time_limit",
        bound=arborescence_bound(instance),
        runtime=time.perf_counter() - start,
        info=info,
    )


def optimal_plan(
    instance: DeliveryInstance,
    max_customers: int = 14,
    time_limit: float | None = None,
    incumbent: Any = None,
) -> Solution:
    """Exact optimum of (5.1)–(5.7) for small n by dynamic programming over subsets.

    The future of a partial plan depends only on the set of customers served, the
    landing stop of its last sortie and its recovery time, and every later time is
    non-decreasing in that recovery time. So the states (served set, landing stop)
    with value the earliest recovery time (Held–Karp style, the same transitions as
    :func:`schedule`, made by the same :func:`_sortie_step`) give the optimum over all
    precedence-feasible orders and all launch/landing choices at once.

    Parameters
    ----------
    instance : DeliveryInstance
    max_customers : int
        Refuse instances with more customers (time and memory grow as 2^n).
    time_limit : float, optional
        Wall-clock seconds. When the table is not finished in time, the result has status
        "time_limit", the incumbent (or no plan, objective inf) and the arborescence bound
        of Proposition 5.3.
    incumbent : Plan or Solution, optional
        A feasible plan kept for a time limit (``taopt.solve`` passes the best of NIA, MMA
        and SMMA).

    Returns
    -------
    Solution
        ``.status`` "optimal", ``.objective == .bound`` the optimal makespan (5.1) as
        scored by ``taopt.delivery.evaluate.evaluate_plan(instance, .plan)``,
        ``.info["dp_objective"]`` the DP's own value (checked equal within
        :data:`MATCH_TOLERANCE` relative), ``.plan`` an optimal plan, ``.method``
        "subset-dp".

    Raises
    ------
    InstanceError
        n > max_customers (the size guard: 2^n states).
    SolverError
        The DP's makespan and the scorer's differ by more than
        :data:`MATCH_TOLERANCE` relative (a bug, never expected).

    Notes
    -----
    O(2^n · n · s²) time, O(2^n · s) memory. About 0.1 s for n = 8, s = 121.
    """
    start = time.perf_counter()
    n, s = instance.n, instance.s
    if n > max_customers:
        raise InstanceError(
            f"optimal_plan: n = {n} customers > max_customers = {max_customers} "
            f"(2^n = {2**n:.3g} states); pass max_customers to raise it"
        )
    deadline = Deadline(time_limit)
    tt = instance.truck_time
    tau = instance.service_time
    data = _sortie_data(instance)
    need = np.zeros(n, dtype=np.int64)  # bit mask of each customer's predecessors
    for r, j in instance.precedences:
        need[j] |= 1 << r
    full = (1 << n) - 1
    ready = np.full((1 << n, s), np.inf)
    ready[0, instance.depot] = 0.0
    # back-pointers: (customer, launch stop, previous landing stop) per (mask, landing)
    back_customer = np.full((1 << n, s), -1, dtype=np.int64)
    back_launch = np.full((1 << n, s), -1, dtype=np.int64)
    back_prev = np.full((1 << n, s), -1, dtype=np.int64)
    best = (np.inf, -1, -1, -1, -1)  # makespan, last customer, launch, landing, prev landing
    for mask in range(full):
        if deadline.limited and deadline.expired():
            return _dp_stopped(instance, incumbent, start, {"states_done": mask})
        alive = np.flatnonzero(np.isfinite(ready[mask]))
        if alive.size == 0:
            continue
        values = ready[mask, alive]
        for j in range(n):
            if mask >> j & 1 or (need[j] & ~mask):
                continue
            sortie = data.get(j)
            v = sortie[0]
            new = mask | 1 << j
            if new == full:
                prev_pos, served, i_pos, k_pos = _sortie_step(
                    tt, tau, values, alive, sortie, final=True
                )
                if served[i_pos] < best[0]:
                    best = (
                        float(served[i_pos]),
                        j,
                        int(v[i_pos]),
                        int(v[k_pos]),
                        int(alive[prev_pos[i_pos]]),
                    )
                continue
            prev_pos, _, launch_pos, value = _sortie_step(tt, tau, values, alive, sortie)
            better = value < ready[new, v]
            if better.any():
                k = v[better]
                ready[new, k] = value[better]
                back_customer[new, k] = j
                back_launch[new, k] = v[launch_pos[better]]
                back_prev[new, k] = alive[prev_pos[launch_pos[better]]]
    makespan, j, i, k, prev = best
    if j < 0:
        raise SolverError("optimal_plan: no complete plan found (no customers?)")
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
    # every subset expanded: the DP's optimum, its own bound
    solution = finish(
        instance,
        plan,
        method="subset-dp",
        stop="optimal",
        bound=makespan,
        runtime=time.perf_counter() - start,
        info={"dp_objective": makespan},
    )
    _matches(solution.objective, makespan, "optimal_plan", plan)
    return solution.replace(bound=solution.objective)


__all__ = ["schedule", "optimal_plan"]
