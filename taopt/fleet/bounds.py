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


__all__ = ["earliest_service", "reach_bound"]
