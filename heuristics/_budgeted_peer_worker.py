"""Worker process that runs PyVRP or OR-Tools routing on a budgeted problem (§6.2).

Started as a script (``python _budgeted_peer_worker.py <peer> <parent pid> <die with
parent>``) by :mod:`taopt.heuristics.budgeted_peers`, for the same reason as
``_peer_worker.py`` (the ``ortools`` and ``highspy`` wheels cannot share a process). The
protocol, the start-up handshake and the dying-with-the-parent machinery are
``_peer_worker.py``'s own: this script loads that file and serves with its :func:`serve`,
swapping in the two solvers below (peer names ``"pyvrp"`` and ``"ortools"``). It imports
only the standard library, numpy and the peer, never taopt.

A request is ``{"cost": int64 (n+m, n+m), "n": n, "m": m, "options": {...}}`` as for the
chapter-2 peers, plus ``options["capacity"]`` and ``options["max_time"]``: one integer or
None (no limit) per vehicle, ``max_time`` already in the matrix's integer units. The reply
has ``routes`` (None when the solver found nothing), ``objective`` and
``solver_feasible`` (the solver's own word; the caller re-checks the limits anyway).
"""

from __future__ import annotations

import functools
import importlib.util
import os
import sys
import time
from typing import Any

_HERE = os.path.dirname(os.path.abspath(__file__))


@functools.lru_cache(maxsize=1)
def _base() -> Any:
    """``_peer_worker.py`` (next to this file) as a module, loaded by path."""
    spec = importlib.util.spec_from_file_location(
        "_taopt_peer_worker", os.path.join(_HERE, "_peer_worker.py")
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _limits(options: dict[str, Any], key: str, m: int, default: int) -> list[int]:
    values = options.get(key) or [None] * m
    return [default if value is None else int(value) for value in values]


def solve_pyvrp(cost: Any, n: int, m: int, options: dict[str, Any]) -> dict[str, Any]:
    """PyVRP with a load dimension (demand 1 per target, capacity Q_k) and ``max_distance``.

    The model of ``_peer_worker.solve_pyvrp`` (a start depot per vehicle, one free end
    depot; open routes via zero-cost arcs into it) with ``Client(delivery=[1])``,
    ``VehicleType(capacity=[Q_k], max_distance=T_k)`` (demand and capacity both multiplied
    by the largest arc cost, so that a target too many weighs as much as a long arc in
    PyVRP's bounded penalties; with a demand of 1 its search returns infeasible answers on
    a 3-target instance): distance is the scaled travel time,
    so ``max_distance`` is the maximum route travel time. PyVRP penalises violations during
    its search; its best solution may still violate a limit, and is returned as it is.
    """
    import pyvrp
    from pyvrp.stop import MaxIterations, MaxRuntime, MultipleCriteria

    matrix = _base().open_routes_matrix(cost)
    capacity = _limits(options, "capacity", m, n)
    max_time = _limits(options, "max_time", m, int(matrix.sum()) + 1)
    locations = [pyvrp.Location(0, 0, name=f"point {i}") for i in range(n + m + 1)]
    # One target is ``unit`` load units: PyVRP's penalties are bounded, so a load of 1 next
    # to arc costs near 1e7 would never be worth repairing (it warns and returns infeasible).
    unit = max(1, int(matrix.max()))
    clients = [pyvrp.Client(location=j, delivery=[unit], name=f"target {j}") for j in range(n)]
    depots = [pyvrp.Depot(location=n + k, name=f"start {k}") for k in range(m)]
    depots.append(pyvrp.Depot(location=n + m, name="free end"))
    vehicle_types = [
        pyvrp.VehicleType(
            num_available=1,
            capacity=[min(capacity[k], n) * unit],
            start_depot=k,
            end_depot=m,
            max_distance=max_time[k],
            name=f"vehicle {k}",
        )
        for k in range(m)
    ]
    data = pyvrp.ProblemData(locations, clients, depots, vehicle_types, [matrix], [matrix])
    criteria = []
    if options.get("time_limit") is not None:
        criteria.append(MaxRuntime(float(options["time_limit"])))
    if options.get("max_iterations") is not None:
        criteria.append(MaxIterations(int(options["max_iterations"])))
    stop = criteria[0] if len(criteria) == 1 else MultipleCriteria(criteria)
    started = time.perf_counter()
    result = pyvrp.solve(data, stop, seed=int(options["seed"]), collect_stats=False, display=False)
    runtime = time.perf_counter() - started
    best = result.best
    routes: list[list[int]] = [[] for _ in range(m)]
    for route in best.routes():
        routes[route.vehicle_type()] = [int(act.idx) for act in route if act.is_client()]
    return {
        "routes": routes if best.is_complete() else None,
        "objective": int(result.cost()) if best.is_feasible() else None,
        "solver_feasible": bool(best.is_feasible()),
        "iterations": int(result.num_iterations),
        "solver_runtime": runtime,
    }


def solve_ortools(cost: Any, n: int, m: int, options: dict[str, Any]) -> dict[str, Any]:
    """OR-Tools routing with a "Load" dimension (demand 1, capacity Q_k) and a "Time"
    dimension (transit = travel time, capacity T_k, no slack).

    The model of ``_peer_worker.solve_ortools`` (per-vehicle starts, a shared dummy end with
    zero-cost arcs into it). The time dimension's cumul at a vehicle's end is its route's
    travel time (the arc into the dummy end is free), bounded by T_k. When the first
    solution strategy finds nothing the reply has ``routes = None``.
    """
    from ortools.constraint_solver import pywrapcp, routing_enums_pb2

    strategies = routing_enums_pb2.FirstSolutionStrategy.Value
    metaheuristics = routing_enums_pb2.LocalSearchMetaheuristic.Value
    first, meta = options["first_solution"], options["metaheuristic"]
    if first not in strategies.keys():
        raise ValueError(
            f"unknown first_solution {first!r}; OR-Tools has {list(strategies.keys())}"
        )
    if meta not in metaheuristics.keys():
        raise ValueError(
            f"unknown metaheuristic {meta!r}; OR-Tools has {list(metaheuristics.keys())}"
        )
    matrix = _base().open_routes_matrix(cost)
    end = n + m
    manager = pywrapcp.RoutingIndexManager(n + m + 1, m, [n + k for k in range(m)], [end] * m)
    routing = pywrapcp.RoutingModel(manager)
    transit = routing.RegisterTransitMatrix(matrix.tolist())
    routing.SetArcCostEvaluatorOfAllVehicles(transit)
    capacity = _limits(options, "capacity", m, n)
    if any(value is not None for value in options.get("capacity") or []):
        demand = routing.RegisterUnaryTransitVector([1] * n + [0] * (m + 1))
        routing.AddDimensionWithVehicleCapacity(demand, 0, capacity, True, "Load")
    if any(value is not None for value in options.get("max_time") or []):
        horizon = int(matrix.sum()) + 1
        max_time = _limits(options, "max_time", m, horizon)
        routing.AddDimensionWithVehicleCapacity(transit, 0, max_time, True, "Time")
    params = pywrapcp.DefaultRoutingSearchParameters()
    params.first_solution_strategy = strategies.Value(first)
    params.local_search_metaheuristic = metaheuristics.Value(meta)
    if options.get("time_limit") is not None:
        params.time_limit.FromNanoseconds(int(round(float(options["time_limit"]) * 1e9)))
    if options.get("solution_limit") is not None:
        params.solution_limit = int(options["solution_limit"])
    started = time.perf_counter()
    assignment = routing.SolveWithParameters(params)
    runtime = time.perf_counter() - started
    reply: dict[str, Any] = {
        "routing_status": int(routing.status()),
        "solver_runtime": runtime,
        "routes": None,
        "objective": None,
        "solver_feasible": assignment is not None,
    }
    if assignment is None:
        return reply
    routes = []
    for vehicle in range(m):
        index = routing.Start(vehicle)
        route = []
        while not routing.IsEnd(index):
            node = manager.IndexToNode(index)
            if node < n:
                route.append(int(node))
            index = assignment.Value(routing.NextVar(index))
        routes.append(route)
    reply.update(routes=routes, objective=int(assignment.ObjectiveValue()))
    return reply


SOLVERS = {"pyvrp": solve_pyvrp, "ortools": solve_ortools}


def main(argv: list[str]) -> None:
    """Entry point: ``<peer> <parent pid> <1 to ask for SIGKILL when the parent dies, else 0>``."""
    peer, parent_pid, use_pdeathsig = argv[0], int(argv[1]), argv[2] == "1"
    if peer not in SOLVERS:
        raise SystemExit(f"unknown peer {peer!r}; choose from {sorted(SOLVERS)}")
    base = _base()
    base.SOLVERS = SOLVERS  # serve() looks its solver up here
    base.serve(peer, parent_pid, use_pdeathsig)


if __name__ == "__main__":
    # as _peer_worker.py: this folder must not shadow anything the peers import
    if sys.path and os.path.abspath(sys.path[0] or os.curdir) == _HERE:
        del sys.path[0]
    main(sys.argv[1:])
