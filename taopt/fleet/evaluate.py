"""The fleet family's one scorer: check a :class:`FleetPlan` and build its earliest schedule.

Timing rules (shared by every fleet method; chapter 5's (5.1)–(5.7) when K = D = c = 1).
Truck k's stop sequence is ``w_0 = depot, w_1, ...``; ``A[k, p]`` is its arrival at position
p, ``Dep[k, p]`` its departure, τ the landing/loading time, ``tt`` street times and ``ft`` drone
flight times (straight lines over ``v_drone``). The earliest schedule is the smallest solution
of::

    A[k, 0] = 0,   A[k, p + 1] = Dep[k, p] + tt[w_p, w_{p+1}],   Dep[k, p] >= A[k, p]
    truck-served j at (k, p):   t_j >= A[k, p],                Dep[k, p] >= t_j
    sortie σ of drone (k, d) launched at p, customers c_1..c_m, recovered at q >= p:
        L_σ >= A[k, p],   L_σ >= R_σ' (the drone's previous sortie),   Dep[k, p] >= L_σ
        t_{c_1} >= L_σ + ft(w_p, c_1) + τ,   t_{c_{i+1}} >= t_{c_i} + ft(c_i, c_{i+1}) + τ
        B_σ = t_{c_m} + ft(c_m, w_q),   R_σ = max(B_σ, A[k, q]) + τ,   Dep[k, q] >= R_σ
    precedence (r, j):   t_j >= t_r

i.e. vehicles may wait: a truck for its drone at the recovery stop, a drone (at the customer)
or a truck (at the stop) until a predecessor served by any vehicle is served. The objective is
``max_j t_j`` (``"last_service"``, (5.1)) or ``max_k Dep[k, last] + tt[w_last, depot]``
(``"return"``). The times are longest paths in the DAG of these inequalities; a cycle (a
precedence that can only be met by waiting for itself) makes the plan infeasible.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

from taopt.errors import FeasibilityError
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie


@dataclass(frozen=True)
class FleetSchedule:
    """The earliest schedule of a feasible plan.

    Attributes
    ----------
    arrival, departure : list of K lists of float
        ``arrival[k][p]``, ``departure[k][p]``: truck k at position p of its sequence.
    service : (n,) float array
        t_j, when customer j is served.
    sorties : list of (truck, drone, index, launch_time, back_time, recovery_time)
        One row per sortie: the launch, the drone's arrival at the recovery stop (before τ)
        and the recovery (drone aboard, τ paid).
    returned : list of K float
        When truck k is back at the depot (its last departure plus the drive home).
    last_service, return_time : float
        ``max_j t_j`` and ``max_k returned[k]``.
    objective : float
        The problem's objective (one of the two above).
    """

    arrival: list[list[float]]
    departure: list[list[float]]
    service: np.ndarray
    sorties: list[tuple[int, int, int, float, float, float]]
    returned: list[float]
    last_service: float
    return_time: float
    objective: float


def as_plan(plan: Any) -> FleetPlan:
    """A :class:`FleetPlan` from a plan, a Solution carrying one, or its dict."""
    if isinstance(plan, FleetPlan):
        return plan
    if hasattr(plan, "solution") and hasattr(plan, "objective"):
        plan = plan.solution
        if isinstance(plan, FleetPlan):
            return plan
    if isinstance(plan, dict):
        return FleetPlan.from_dict(plan)
    raise FeasibilityError(f"expected a FleetPlan, got {type(plan).__name__}")


def sortie_distance(problem: FleetProblem, launch_stop: int, customers: Any, stop: int) -> float:
    """Total flight distance of a sortie: launch stop -> customers in order -> recovery stop."""
    fs, fc = problem.flight_stop, problem.flight_customer
    distance = float(fs[customers[0], launch_stop])
    for a, b in zip(customers[:-1], customers[1:], strict=True):
        distance += float(fc[a, b])
    return distance + float(fs[customers[-1], stop])


def check_structure(problem: FleetProblem, plan: FleetPlan) -> None:
    """Raise :class:`FeasibilityError` naming the first violated rule that needs no times:
    the shape (K routes from the depot, D_k drones), stop and position indices, each customer
    served exactly once by a vehicle allowed to serve it, a truck serving at the customer's
    stop, sortie sizes (1..c), the flight range, and each drone's sorties in order (the next
    launched no earlier in the sequence than the previous is recovered)."""
    K, n, s = problem.K, problem.n, problem.s
    if len(plan.routes) != K:
        raise FeasibilityError(
            f"the plan has {len(plan.routes)} truck routes, the fleet {K} trucks"
        )
    if len(plan.truck_service) != K:
        raise FeasibilityError(
            f"truck_service has {len(plan.truck_service)} entries, the fleet {K} trucks"
        )
    if len(plan.sorties) != K:
        raise FeasibilityError(f"sorties has {len(plan.sorties)} entries, the fleet {K} trucks")
    for k, route in enumerate(plan.routes):
        if not route or route[0] != problem.depot:
            raise FeasibilityError(
                f"truck {k}'s sequence must start at the depot {problem.depot}, got {list(route)}"
            )
        for p, w in enumerate(route):
            if not 0 <= w < s:
                raise FeasibilityError(
                    f"truck {k} position {p}: stop {w} is not a stop (0..{s - 1})"
                )
        if len(plan.sorties[k]) != problem.drones[k]:
            raise FeasibilityError(
                f"truck {k} carries {problem.drones[k]} drones but the plan gives "
                f"{len(plan.sorties[k])} sortie lists"
            )
    served_by: dict[int, str] = {}

    def serve(j: int, who: str) -> None:
        if not 0 <= j < n:
            raise FeasibilityError(f"{who}: customer {j} does not exist (0..{n - 1})")
        if j in served_by:
            raise FeasibilityError(f"customer {j} is served twice: by {served_by[j]} and by {who}")
        served_by[j] = who

    for k, items in enumerate(plan.truck_service):
        route = plan.routes[k]
        for p, j in items:
            who = f"truck {k} at position {p}"
            serve(j, who)
            if not 0 <= p < len(route):
                raise FeasibilityError(
                    f"{who}: position {p} is not in its sequence (0..{len(route) - 1})"
                )
            if not problem.truck_servable(j):
                raise FeasibilityError(f"{who}: customer {j} may only be served by a drone")
            if route[p] != problem.customer_stop[j]:
                raise FeasibilityError(
                    f"{who}: customer {j} is served at stop {problem.customer_stop[j]}, "
                    f"but the truck is at stop {route[p]}"
                )
    limit = problem.flight_limit
    for k, drones in enumerate(plan.sorties):
        route = plan.routes[k]
        for d, flights in enumerate(drones):
            previous: Sortie | None = None
            for i, f in enumerate(flights):
                who = f"sortie {i} of drone ({k}, {d})"
                for p, what in ((f.launch, "launch"), (f.recovery, "recovery")):
                    if not 0 <= p < len(route):
                        raise FeasibilityError(
                            f"{who}: {what} position {p} is not in truck {k}'s sequence "
                            f"(0..{len(route) - 1})"
                        )
                if f.recovery < f.launch:
                    raise FeasibilityError(
                        f"{who}: recovered at position {f.recovery}, before its launch at "
                        f"position {f.launch}"
                    )
                if not 1 <= len(f.customers) <= problem.capacity:
                    raise FeasibilityError(
                        f"{who} serves {len(f.customers)} customers; a sortie serves 1 to "
                        f"c = {problem.capacity}"
                    )
                for j in f.customers:
                    serve(j, who)
                    if not problem.drone_servable(j):
                        raise FeasibilityError(f"{who}: customer {j} may only be served by a truck")
                flown = sortie_distance(problem, route[f.launch], f.customers, route[f.recovery])
                if flown > limit:
                    raise FeasibilityError(
                        f"{who}: flies {flown:.6g} (stop {route[f.launch]} -> customers "
                        f"{list(f.customers)} -> stop {route[f.recovery]}) > flight range "
                        f"{problem.flight_range:.6g}"
                    )
                if previous is not None and f.launch < previous.recovery:
                    raise FeasibilityError(
                        f"{who}: launched at position {f.launch} before the drone's sortie "
                        f"{i - 1} is recovered at position {previous.recovery}"
                    )
                previous = f
    missing = [j for j in range(n) if j not in served_by]
    if missing:
        raise FeasibilityError(
            f"customer {missing[0]} is never served ({len(missing)} of {n} customers missing)"
        )


def schedule(problem: FleetProblem, plan: Any, check: bool = True) -> FleetSchedule:
    """The earliest schedule of ``plan`` under the module's timing rules.

    Parameters
    ----------
    check : bool
        Run :func:`check_structure` first (default). With False the plan must still be
        well-formed (indices in range); customers it does not serve get ``t_j = nan`` and
        precedences touching them are skipped (partial plans).

    Raises
    ------
    FeasibilityError
        A structural violation (see :func:`check_structure`), or a deadlock: the precedences
        and the plan's order make some event wait for itself (named, with the precedence
        pairs on the cycle).
    """
    plan = as_plan(plan)
    if check:
        check_structure(problem, plan)
    tt = problem.truck_time
    fs = problem.flight_stop / problem.v_drone
    fc = problem.flight_customer / problem.v_drone
    tau = problem.service_time
    names: list[tuple[str, tuple[Any, ...]]] = []  # formatted only for a deadlock message
    succ: list[list[tuple[int, float]]] = []

    def node(template: str, *args: Any) -> int:
        names.append((template, args))
        succ.append([])
        return len(names) - 1

    def edge(a: int, b: int, w: float) -> None:
        succ[a].append((b, w))

    arr: list[list[int]] = []
    dep: list[list[int]] = []
    for k, route in enumerate(plan.routes):
        arr.append([node("truck {} arrives at position {}", k, p) for p in range(len(route))])
        dep.append([node("truck {} leaves position {}", k, p) for p in range(len(route))])
        for p in range(len(route)):
            edge(arr[k][p], dep[k][p], 0.0)
            if p + 1 < len(route):
                edge(dep[k][p], arr[k][p + 1], float(tt[route[p], route[p + 1]]))
    cust = [-1] * problem.n
    for k, items in enumerate(plan.truck_service):
        for p, j in items:
            cust[j] = node("customer {} served by truck {}", j, k)
            edge(arr[k][p], cust[j], 0.0)
            edge(cust[j], dep[k][p], 0.0)
    rows: list[tuple[int, int, int, int, int, int]] = []
    for k, drones in enumerate(plan.sorties):
        route = plan.routes[k]
        for d, flights in enumerate(drones):
            prev_rec = -1
            for i, f in enumerate(flights):
                launch = node("sortie {} of drone ({}, {}) launched", i, k, d)
                edge(arr[k][f.launch], launch, 0.0)
                edge(launch, dep[k][f.launch], 0.0)
                if prev_rec >= 0:
                    edge(prev_rec, launch, 0.0)
                here, last = launch, -1
                for j in f.customers:
                    cust[j] = node("customer {} served by drone ({}, {})", j, k, d)
                    if last < 0:
                        edge(here, cust[j], float(fs[j, route[f.launch]]) + tau)
                    else:
                        edge(here, cust[j], float(fc[last, j]) + tau)
                    here, last = cust[j], j
                back = node("sortie {} of drone ({}, {}) back at position {}", i, k, d, f.recovery)
                edge(here, back, float(fs[last, route[f.recovery]]))
                rec = node("sortie {} of drone ({}, {}) recovered", i, k, d)
                edge(back, rec, tau)
                edge(arr[k][f.recovery], rec, tau)
                edge(rec, dep[k][f.recovery], 0.0)
                rows.append((k, d, i, launch, back, rec))
                prev_rec = rec
    prec_edges: dict[tuple[int, int], tuple[int, int]] = {}
    for r, j in problem.precedences:
        if cust[r] >= 0 and cust[j] >= 0:
            edge(cust[r], cust[j], 0.0)
            prec_edges[(cust[r], cust[j])] = (r, j)
    # longest paths (Kahn)
    size = len(names)
    indeg = [0] * size
    for a in range(size):
        for b, _ in succ[a]:
            indeg[b] += 1
    time = [0.0] * size
    queue = deque(v for v in range(size) if indeg[v] == 0)
    done = 0
    while queue:
        a = queue.popleft()
        done += 1
        ta = time[a]
        for b, w in succ[a]:
            if ta + w > time[b]:
                time[b] = ta + w
            indeg[b] -= 1
            if indeg[b] == 0:
                queue.append(b)
    if done < size:
        raise FeasibilityError(_deadlock(names, succ, indeg, prec_edges))
    service = np.array([time[c] if c >= 0 else np.nan for c in cust])
    returned = [
        time[dep[k][-1]] + float(tt[route[-1], problem.depot])
        for k, route in enumerate(plan.routes)
    ]
    served = service[~np.isnan(service)]
    last_service = float(served.max()) if served.size else 0.0
    return_time = float(max(returned))
    return FleetSchedule(
        arrival=[[time[v] for v in row] for row in arr],
        departure=[[time[v] for v in row] for row in dep],
        service=service,
        sorties=[(k, d, i, time[a], time[b], time[c]) for k, d, i, a, b, c in rows],
        returned=returned,
        last_service=last_service,
        return_time=return_time,
        objective=last_service if problem.objective == "last_service" else return_time,
    )


def _deadlock(
    templates: list[tuple[str, tuple[Any, ...]]],
    succ: list[list[tuple[int, float]]],
    indeg: list[int],
    prec_edges: dict[tuple[int, int], tuple[int, int]],
) -> str:
    """A message naming one cycle of waits among the events Kahn's algorithm left."""

    def names(v: int) -> str:
        template, args = templates[v]
        return template.format(*args)

    left = {v for v in range(len(templates)) if indeg[v] > 0}
    start = min(left)
    # walk inside the remaining subgraph until a node repeats (every node left has a
    # predecessor left, so walk backwards along predecessors)
    pred: dict[int, int] = {}
    for a in left:
        for b, _ in succ[a]:
            if b in left and b not in pred:
                pred[b] = a
    seen: dict[int, int] = {}
    v = start
    path: list[int] = []
    while v not in seen:
        seen[v] = len(path)
        path.append(v)
        v = pred[v]
    cycle = path[seen[v] :][::-1]
    pairs = [
        prec_edges[(a, b)]
        for a, b in zip(cycle, cycle[1:] + cycle[:1], strict=True)
        if (a, b) in prec_edges
    ]
    where = " -> ".join(names(x) for x in cycle[:6]) + (" -> ..." if len(cycle) > 6 else "")
    which = ", ".join(f"({r}, {j})" for r, j in pairs) or "none"
    return (
        f"the plan deadlocks: precedence pair(s) {which} can only be met by waiting in a "
        f"cycle: {where}"
    )


def evaluate_fleet(problem: FleetProblem, plan: Any) -> float:
    """The one scorer of the fleet family: the objective of a feasible plan.

    Parameters
    ----------
    problem : FleetProblem
    plan : FleetPlan, a Solution carrying one, or its dict

    Returns
    -------
    float
        The earliest schedule's ``max_j t_j`` (``"last_service"``, the thesis's f (5.1)) or
        the time every truck is back at the depot (``"return"``); see the module docstring.

    Raises
    ------
    FeasibilityError
        Naming the item: a customer missing or served twice, a vehicle not allowed to serve a
        customer, a truck serving away from the customer's stop, a sortie of more than c
        customers or longer than the flight range, a drone launched before it is recovered,
        a bad position, or a deadlock naming the precedence pair(s) that cannot be met.

    Example
    -------
    >>> import networkx as nx
    >>> g = nx.Graph(); g.add_edge(0, 1, length=100.0)
    >>> p = FleetProblem([[100, 50]], [[0, 0], [100, 0]], g, depot=0, flight_range=500,
    ...                  v_truck=10, v_drone=10)
    >>> evaluate_fleet(p, FleetPlan([[0, 1]], [[]], [[[[1, [0], 1]]]]))  # drive 10, fly 5
    15.0
    """
    return schedule(problem, plan, check=True).objective


def best_of(problem: FleetProblem, candidates: Any) -> tuple[float, FleetPlan | None]:
    """The best feasible plan among ``candidates`` (plans, Solutions or dicts; None and
    infeasible ones skipped) and its value by :func:`evaluate_fleet`; ``(inf, None)`` when
    none is feasible."""
    best, best_plan = math.inf, None
    for candidate in candidates:
        if candidate is None:
            continue
        try:
            plan = as_plan(candidate)
            value = evaluate_fleet(problem, plan)
        except FeasibilityError:
            continue
        if value < best:
            best, best_plan = value, plan
    return best, best_plan


__all__ = [
    "FleetSchedule",
    "as_plan",
    "best_of",
    "check_structure",
    "evaluate_fleet",
    "schedule",
    "sortie_distance",
]
