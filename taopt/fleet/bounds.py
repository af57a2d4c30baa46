"""A fast valid lower bound of the fleet family (the stronger ``lower`` builds on it).

:func:`reach_bound` prices every customer with the fastest way any vehicle can reach it from
the depot; Proposition 5.3's idea (the last customer is served no earlier than it can be
reached) carried to the fleet.
"""

from __future__ import annotations

import numpy as np

from taopt.fleet.problem import FleetProblem


def earliest_service(problem: FleetProblem) -> np.ndarray:
    """(n,) a time no plan serves customer j before: ``min`` of a truck's drive to its stop
    (truck-servable j) and ``min_w tt[depot, w] + ft(w, j) + τ`` over stops w with
    ``2 d(w, j) <= range`` (drone-servable j); ``inf`` when neither exists.

    Proof: a truck serving j is at ``customer_stop[j]``, reached no sooner than by the street
    shortest path; a drone serving j was launched at some stop w its truck reached no sooner
    than ``tt[depot, w]``, flew at least the straight line ``d(w, j)`` and lands τ; its sortie
    flies at least ``d(w, j)`` out and, by the triangle inequality, at least ``d(j, w')`` back to
    some stop w', and ``d(w, j) <= range`` at least — we use only ``d(w, j) <= range``.
    """
    tt = problem.truck_time[problem.depot]
    out = np.full(problem.n, np.inf)
    fs = problem.flight_stop
    for j in range(problem.n):
        if problem.truck_servable(j):
            out[j] = float(tt[problem.customer_stop[j]])
        if problem.drone_servable(j) and problem.D > 0:
            ok = fs[j] <= problem.flight_limit
            if ok.any():
                drone = float(np.min((tt + fs[j] / problem.v_drone)[ok])) + problem.service_time
                out[j] = min(out[j], drone)
    return out


def reach_bound(problem: FleetProblem) -> float:
    """Every customer reached as fast as any vehicle can: ``max_j earliest_service(j)``.

    Valid for both objectives: under ``"return"`` every customer is served before every truck
    is back (the vehicle serving it still has to come home), so the return time is at least
    the last service time. ``inf`` when some customer cannot be served at all.
    """
    return float(np.max(earliest_service(problem)))


# -- the family's ``lower`` (issue 32, item 3): Proposition 5.3 generalised --------------------


def _earliest_by_mode(problem: FleetProblem) -> tuple[np.ndarray, np.ndarray]:
    """(n,) earliest truck service and (n,) earliest drone service of each customer (``inf``
    where that mode cannot serve it); :func:`earliest_service` is their minimum."""
    tt = problem.truck_time[problem.depot]
    truck = np.full(problem.n, np.inf)
    drone = np.full(problem.n, np.inf)
    fs = problem.flight_stop
    for j in range(problem.n):
        if problem.truck_servable(j):
            truck[j] = float(tt[problem.customer_stop[j]])
        if problem.drone_servable(j) and problem.D > 0:
            ok = fs[j] <= problem.flight_limit
            if ok.any():
                drone[j] = float(np.min((tt + fs[j] / problem.v_drone)[ok])) + problem.service_time
    return truck, drone


def return_reach_bound(problem: FleetProblem) -> float:
    """Under ``"return"``: every customer served as early as possible, then its vehicle home.

    ``max_j min(truck_j + tt[stop_j, depot], drone_j + min_w (d(j, w) / v_d + τ + tt[w,
    depot]))`` with the earliest services of :func:`earliest_service` by mode. Proof: the
    vehicle serving j is back at the depot no sooner: a truck drives home from j's stop (street
    shortest path), a drone flies on to some recovery stop w (at least the straight line), is
    recovered (τ) and its truck then drives from w home. For ``"last_service"`` it is the
    plain :func:`reach_bound`.
    """
    if problem.objective != "return":
        return reach_bound(problem)
    truck, drone = _earliest_by_mode(problem)
    home = problem.truck_time[:, problem.depot]
    fs = problem.flight_stop
    out = 0.0
    for j in range(problem.n):
        best = np.inf
        if np.isfinite(truck[j]):
            best = truck[j] + float(home[problem.customer_stop[j]])
        if np.isfinite(drone[j]):
            back = float(np.min(fs[j] / problem.v_drone + home)) + problem.service_time
            best = min(best, drone[j] + back)
        out = max(out, best)
    return float(out)


def work_bound(problem: FleetProblem, grid: int = 101) -> float:
    """The fleet's work: the drones share the drone customers' flying, the trucks the truck
    customers' stops (Proposition 5.3's "sum of the legs", spread over the vehicles).

    Each customer j served by a drone costs that drone at least ``a_j``: its in-leg (the
    shortest flight into j, from a stop within range or, when c > 1, from another
    drone-servable customer) over v_d, plus τ at j; under ``"return"`` the mean of the
    shortest in- and out-leg plus τ and τ/c (each sortie's recovery, shared by at most c
    customers). A truck serving at stop w costs it ``b_w``: the shortest street into w
    (0 at the depot), under ``"return"`` the mean of the shortest in and out.

    Proof: one drone flies one leg at a time; the in-legs (and τ) of its customers are
    disjoint intervals that end by the customers' service times, so they fit before f
    (``"last_service"``); under ``"return"`` every leg and every recovery ends before f, and
    each leg is counted at most half for each end. So ``W_d <= f`` for each drone and ``Σ_d
    W_d <= D f``; the same for trucks over the distinct stops they serve (a stop shared by
    m truck-servable customers is charged ``b_w / m`` to each). For any split of the
    customers, ``f >= max(A / D, B / K)`` with A, B the two sums, and ``max(P, Q) >= λ P +
    (1 − λ) Q`` for every λ in [0, 1]; minimising over the split customer by customer gives
    ``f >= λ A_0 / D + (1 − λ) B_0 / K + Σ_j min(λ a_j / D, (1 − λ) b_j / K)`` (A_0, B_0:
    customers only a drone, only a truck may serve), maximised over a grid of λ. When some
    customer must go by drone, the drone serving it starts its first in-leg no sooner than
    ``δ_D = min_j (e_j − a_j) >= 0`` (e_j the earliest drone service), so ``δ_D`` is added to
    the drone term (every drone that serves anything pays it: ``max_d W_d + δ_D >= A / D +
    δ_D``); likewise ``δ_T`` for trucks (``"last_service"`` only).
    """
    n, K, D = problem.n, problem.K, problem.D
    vd, tau, c = problem.v_drone, problem.service_time, problem.capacity
    ret = problem.objective == "return"
    fs, fc, limit = problem.flight_stop, problem.flight_customer, problem.flight_limit
    truck_e, drone_e = _earliest_by_mode(problem)
    a = np.full(n, np.inf)
    drone_ok = [problem.drone_servable(j) and D > 0 for j in range(n)]
    for j in range(n):
        if not drone_ok[j] or not np.isfinite(drone_e[j]):
            continue
        legs = fs[j][fs[j] <= limit]
        shortest = float(legs.min())
        if c > 1:
            others = [fc[i, j] for i in range(n) if i != j and drone_ok[i]]
            shortest = min([shortest, *others])
        if ret:
            a[j] = shortest / vd + tau + tau / c
        else:
            a[j] = shortest / vd + tau
    tt = problem.truck_time
    s = problem.s
    b = np.full(n, np.inf)
    sharing: dict[int, int] = {}
    for j in range(n):
        if problem.truck_servable(j):
            w = problem.truck_stop(j)
            sharing[w] = sharing.get(w, 0) + 1
    for j in range(n):
        if not problem.truck_servable(j):
            continue
        w = problem.truck_stop(j)
        if w == problem.depot or s == 1:
            cost = 0.0
        else:
            into = float(np.min(np.delete(tt[:, w], w)))
            cost = (into + float(np.min(np.delete(tt[w], w)))) / 2.0 if ret else into
        b[j] = cost / sharing[w]
    only_drone = np.isfinite(a) & ~np.isfinite(b)
    only_truck = np.isfinite(b) & ~np.isfinite(a)
    if (~np.isfinite(a) & ~np.isfinite(b)).any():
        return float("inf")
    delta_d = 0.0
    if only_drone.any() and not ret:
        ok = np.isfinite(a)
        delta_d = max(0.0, float(np.min(drone_e[ok] - a[ok])))
    delta_t = 0.0
    if only_truck.any() and not ret:
        ok = np.isfinite(b)
        delta_t = max(
            0.0,
            float(
                np.min(
                    truck_e[ok]
                    - b[ok]
                    * np.array([sharing[problem.truck_stop(int(j))] for j in np.flatnonzero(ok)])
                )
            ),
        )
    best = 0.0
    for lam in np.linspace(0.0, 1.0, grid):
        value = 0.0
        if D > 0:
            value += lam * (float(a[only_drone].sum()) / D + (delta_d if only_drone.any() else 0))
        if K > 0:
            value += (1 - lam) * (
                float(b[only_truck].sum()) / K + (delta_t if only_truck.any() else 0)
            )
        for j in np.flatnonzero(~only_drone & ~only_truck).tolist():
            value += min(lam * a[j] / max(D, 1), (1 - lam) * b[j] / K)
        best = max(best, value)
    return float(best)


def chapter5_bound(problem: FleetProblem, strength: str = "auto") -> float:
    """Chapter 5's own bound when the fleet *is* chapter 5's problem: one drone in the whole
    fleet, c = 1 and every customer drone-only (trucks without a drone can do nothing, so the
    optimum is chapter 5's with the drone's truck). Then
    :func:`taopt.delivery.bounds.delivery_lower` (Proposition 5.3 and its strengthenings) bounds the last service, hence
    also the return time. 0 when the fleet is not of that form.
    """
    if problem.D != 1 or problem.capacity != 1:
        return 0.0
    if any(problem.service[j] != "drone" for j in range(problem.n)):
        return 0.0
    from taopt.delivery.bounds import delivery_lower
    from taopt.errors import InstanceError

    try:
        instance = problem.to_delivery()
    except InstanceError:
        return 0.0
    return float(delivery_lower(instance, strength))


def fleet_lower(problem: FleetProblem, strength: str = "auto") -> float:
    """:func:`taopt.lower` for the fleet: the largest of :func:`return_reach_bound` (which is
    :func:`reach_bound` under ``"last_service"``), :func:`work_bound` and, unless ``strength
    == "fast"``, :func:`chapter5_bound`. ``inf`` when some customer cannot be served.

    Example
    -------
    >>> import networkx as nx
    >>> g = nx.Graph(); g.add_edge(0, 1, length=100.0)
    >>> p = FleetProblem([[100, 50], [100, -50]], [[0, 0], [100, 0]], g, depot=0,
    ...                  flight_range=500, v_truck=10, v_drone=10)
    >>> fleet_lower(p) >= reach_bound(p)
    True

    References
    ----------
    Thesis §5.3.2, Proposition 5.3 (f_a <= f_o); §6.2.
    """
    value = max(return_reach_bound(problem), work_bound(problem))
    if strength != "fast" and np.isfinite(value):
        value = max(value, chapter5_bound(problem, strength))
    return float(value)


__all__ = [
    "chapter5_bound",
    "earliest_service",
    "fleet_lower",
    "reach_bound",
    "return_reach_bound",
    "work_bound",
]
