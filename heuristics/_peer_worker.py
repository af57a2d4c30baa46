"""Worker process that runs one peer solver (PyVRP, OR-Tools routing or CP-SAT) for :mod:`taopt.heuristics.peers`
and :mod:`taopt.heuristics.budgeted_peers` (the same routing models plus capacity and
route-time limits when a request carries them).

This file is started as a script (``python _peer_worker.py <peer> <parent pid>
<die with parent>``) in a fresh interpreter, never imported into a process
that uses the exact models: the ``ortools`` and ``highspy`` wheels ship
incompatible ``libhighs`` libraries with one soname, so whichever is imported
second fails to load. It imports only the standard library, numpy and its
peer; it never imports taopt, which is why the caller sends it an integer
matrix and re-scores the routes it returns.

Protocol (pickle frames; the parent is the only peer on the pipes)

* worker -> parent, once at start: ``("ready", {"peer": ..., "version": ...})``
  or ``("error", message)`` when the peer package cannot be imported;
* parent -> worker: ``{"cost": int64 (n+m, n+m) array, "n": n, "m": m,
  "options": {...}}``; worker -> parent: any number of ``("best", {...})`` frames, one per
  improving solution found (the same keys as the final reply: the parent keeps the last one
  and answers with it if it has to stop the worker at the deadline), then ``("ok",
  {"routes": [[...], ...], "objective": int, ...})`` or ``("error", traceback text)``;
* end of file on stdin: the worker exits.

Time. ``options["time_limit"]`` is the seconds left of the caller's wall-clock limit when
the request was sent; the worker takes its own deadline from the moment it reads the
request, checks it while it builds a model (CP-SAT's is built in Python and can take
seconds), and gives the solver what is left less :data:`REPLY_MARGIN` (the reply still has
to be decoded and sent). ``options["no_improvement"]``, when set, stops a heuristic search
after that many iterations (PyVRP's ``NoImprovement``) or solutions (OR-Tools routing)
without a better one.

The worker dies with its parent: it ignores Ctrl-C (the parent handles it and
stops the worker), asks Linux for SIGKILL when the parent dies
(``PR_SET_PDEATHSIG``, when the parent says the spawning thread is its main
thread), watches ``os.getppid()`` from a thread, and exits on end of file.
"""

from __future__ import annotations

import os
import pickle
import signal
import sys
import threading
import time
import traceback
from typing import Any

_HERE = os.path.dirname(os.path.abspath(__file__))

#: Seconds of a request's time limit kept back for decoding and sending the reply.
REPLY_MARGIN = 0.05
#: The least time limit handed to a solver (a limit of 0 is refused by some of them).
MIN_LIMIT = 1e-3


def seconds_left(options: dict[str, Any]) -> float | None:
    """Seconds the solver may still use (at least :data:`MIN_LIMIT`), None without a limit.

    ``options["deadline"]`` is set by :func:`serve` when the request is read
    (``time.monotonic()`` + the request's ``time_limit``)."""
    deadline = options.get("deadline")
    if deadline is None:
        return None
    return max(deadline - time.monotonic() - REPLY_MARGIN, MIN_LIMIT)


def out_of_time(options: dict[str, Any]) -> bool:
    """Whether the request's deadline (less :data:`REPLY_MARGIN`) has passed."""
    deadline = options.get("deadline")
    return deadline is not None and time.monotonic() + REPLY_MARGIN >= deadline


def report(options: dict[str, Any], payload: dict[str, Any]) -> None:
    """Send an improving solution to the parent as a ``("best", payload)`` frame (if the
    request's sender listens: :func:`serve` sets ``options["report"]``)."""
    send = options.get("report")
    if send is not None:
        send(payload)


def open_routes_matrix(cost: Any) -> Any:
    """The ``(n+m+1)``-square integer matrix with a free dummy end point ``n+m``.

    Rows and columns ``0..n+m-1`` are ``cost``; the last column is 0, so any
    route may finish anywhere at no cost (open routes, thesis §2.2); the last
    row is never used by a route and is 0 too.
    """
    import numpy as np

    size = cost.shape[0] + 1
    matrix = np.zeros((size, size), dtype=np.int64)
    matrix[:-1, :-1] = cost
    return matrix


def _limits(options: dict[str, Any], key: str, m: int, default: int) -> list[int]:
    """``options[key]`` (one integer or None per vehicle) with None as ``default``."""
    values = options.get(key) or [None] * m
    return [default if value is None else int(value) for value in values]


def _limited(options: dict[str, Any]) -> bool:
    """Whether the request carries the budgeted family's limits (``capacity``,
    ``max_time``; :mod:`taopt.heuristics.budgeted_peers`)."""
    return "capacity" in options or "max_time" in options


def solve_pyvrp(cost: Any, n: int, m: int, options: dict[str, Any]) -> dict[str, Any]:
    """Solve with PyVRP's iterated local search: one depot per vehicle start, one free end depot.

    Locations ``0..n-1`` are the clients (targets), ``n..n+m-1`` the start
    depots, ``n+m`` the shared end depot; vehicle type ``k`` (one vehicle)
    starts at depot ``k`` and ends at depot ``m``. The distance and duration
    matrices are both the scaled travel times; only distance is charged.

    With the budgeted family's limits (``options["capacity"]``, ``options["max_time"]``,
    one integer or None per vehicle): every target has a load of ``unit`` (the largest
    arc cost; PyVRP's penalties are bounded, so a load of 1 beside arc costs near 1e10
    would never be worth repairing) and vehicle k ``capacity=[Q_k unit]`` and
    ``max_distance=T_k``. PyVRP penalises violations during its search and its best may
    still break a limit: the reply then says ``solver_feasible=False`` (and ``routes``
    is None when the solution is incomplete) instead of raising.
    """
    import pyvrp
    from pyvrp import IteratedLocalSearchParams, SolveParams
    from pyvrp.IteratedLocalSearch import IteratedLocalSearchCallbacks
    from pyvrp.stop import MaxIterations, MaxRuntime, MultipleCriteria, NoImprovement

    matrix = open_routes_matrix(cost)
    limited = _limited(options)
    locations = [pyvrp.Location(0, 0, name=f"point {i}") for i in range(n + m + 1)]
    depots = [pyvrp.Depot(location=n + k, name=f"start {k}") for k in range(m)]
    depots.append(pyvrp.Depot(location=n + m, name="free end"))
    if limited:
        unit = max(1, int(matrix.max()))
        capacity = _limits(options, "capacity", m, n)
        max_time = _limits(options, "max_time", m, int(matrix.sum()) + 1)
        clients = [pyvrp.Client(location=j, delivery=[unit], name=f"target {j}") for j in range(n)]
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
    else:
        clients = [pyvrp.Client(location=j, name=f"target {j}") for j in range(n)]
        vehicle_types = [
            pyvrp.VehicleType(num_available=1, start_depot=k, end_depot=m, name=f"vehicle {k}")
            for k in range(m)
        ]
    data = pyvrp.ProblemData(locations, clients, depots, vehicle_types, [matrix], [matrix])
    criteria: list[Any] = []
    left = seconds_left(options)
    if left is not None:
        criteria.append(MaxRuntime(left))
    if options.get("max_iterations") is not None:
        criteria.append(MaxIterations(int(options["max_iterations"])))
    if options.get("no_improvement") is not None:
        criteria.append(NoImprovement(int(options["no_improvement"])))
    stop = criteria[0] if len(criteria) == 1 else MultipleCriteria(criteria)

    def answer(best: Any) -> dict[str, Any]:
        routes: list[list[int]] = [[] for _ in range(m)]
        for route in best.routes():
            routes[route.vehicle_type()] = [int(act.idx) for act in route if act.is_client()]
        found = {
            "routes": routes if best.is_complete() else None,
            "objective": int(best.distance_cost()) if best.is_feasible() else None,
        }
        if limited:
            found["solver_feasible"] = bool(best.is_feasible())
        return found

    class Reporter(IteratedLocalSearchCallbacks):
        """Sends each new feasible best to the parent (kept if the worker is stopped)."""

        def on_start(self, ils: Any) -> None:
            start = getattr(ils, "_init", None)  # its first local optimum, if it shows it
            if start is not None:
                self.on_best(start)

        def on_best(self, best: Any) -> None:
            if best.is_feasible() and best.is_complete():
                report(options, answer(best))

    params = SolveParams(ils=IteratedLocalSearchParams(callbacks=Reporter()))
    started = time.perf_counter()
    result = pyvrp.solve(
        data, stop, seed=int(options["seed"]), collect_stats=False, display=False, params=params
    )
    runtime = time.perf_counter() - started
    best = result.best
    if not limited and (not best.is_feasible() or not best.is_complete()):
        raise RuntimeError(f"PyVRP returned an incomplete or infeasible solution: {best!r}")
    reply = answer(best)
    if best.is_feasible():
        reply["objective"] = int(result.cost())
    reply.update(iterations=int(result.num_iterations), solver_runtime=runtime)
    return reply


def solve_ortools(cost: Any, n: int, m: int, options: dict[str, Any]) -> dict[str, Any]:
    """Solve with the OR-Tools routing library: per-vehicle starts, one free dummy end node.

    Nodes ``0..n-1`` are targets, ``n..n+m-1`` the vehicle starts, ``n+m`` the
    dummy end shared by every vehicle (zero-cost arcs into it, so routes are
    open and a vehicle may go straight from its start to the end: idle).

    With the budgeted family's limits (``options["capacity"]``, ``options["max_time"]``):
    a "Load" dimension (demand 1 per target, capacity Q_k) and a "Time" dimension
    (transit = travel time, capacity T_k, no slack; the free arc into the dummy end makes
    the cumul at a vehicle's end its route's travel time). When the first-solution
    strategy finds nothing under limits, or the time limit ends the search before a first
    solution, the reply has ``routes = None`` and ``solver_feasible = False`` instead of
    raising.
    """
    from ortools.constraint_solver import pywrapcp, routing_enums_pb2

    strategies = routing_enums_pb2.FirstSolutionStrategy.Value  # name <-> number
    metaheuristics = routing_enums_pb2.LocalSearchMetaheuristic.Value
    first = options["first_solution"]
    meta = options["metaheuristic"]
    if first not in strategies.keys():
        raise ValueError(
            f"unknown first_solution {first!r}; OR-Tools has {list(strategies.keys())}"
        )
    if meta not in metaheuristics.keys():
        raise ValueError(
            f"unknown metaheuristic {meta!r}; OR-Tools has {list(metaheuristics.keys())}"
        )
    matrix = open_routes_matrix(cost)
    end = n + m
    manager = pywrapcp.RoutingIndexManager(n + m + 1, m, [n + k for k in range(m)], [end] * m)
    routing = pywrapcp.RoutingModel(manager)
    transit = routing.RegisterTransitMatrix(matrix.tolist())
    routing.SetArcCostEvaluatorOfAllVehicles(transit)
    limited = _limited(options)
    if any(value is not None for value in options.get("capacity") or []):
        demand = routing.RegisterUnaryTransitVector([1] * n + [0] * (m + 1))
        capacity = _limits(options, "capacity", m, n)
        routing.AddDimensionWithVehicleCapacity(demand, 0, capacity, True, "Load")
    if any(value is not None for value in options.get("max_time") or []):
        max_time = _limits(options, "max_time", m, int(matrix.sum()) + 1)
        routing.AddDimensionWithVehicleCapacity(transit, 0, max_time, True, "Time")
    params = pywrapcp.DefaultRoutingSearchParameters()
    params.first_solution_strategy = strategies.Value(first)
    params.local_search_metaheuristic = metaheuristics.Value(meta)
    left = seconds_left(options)
    if left is not None:
        params.time_limit.FromNanoseconds(int(round(left * 1e9)))
    if options.get("solution_limit") is not None:
        params.solution_limit = int(options["solution_limit"])

    def current_routes(value: Any) -> list[list[int]]:
        routes = []
        for vehicle in range(m):
            index = routing.Start(vehicle)
            route = []
            while not routing.IsEnd(index):
                node = manager.IndexToNode(index)
                if node < n:
                    route.append(int(node))
                index = value(routing.NextVar(index))
            routes.append(route)
        return routes

    patience = options.get("no_improvement")
    state: dict[str, Any] = {"best": None, "since": 0, "solutions": 0}

    def at_solution() -> None:
        """Each solution of the search: report a new best; stop after ``no_improvement``
        solutions without one (OR-Tools' routing search has no such limit of its own)."""
        cost = routing.CostVar().Value()
        state["solutions"] += 1
        if state["best"] is None or cost < state["best"]:
            state["best"], state["since"] = cost, 0
            found = {"routes": current_routes(lambda var: var.Value()), "objective": int(cost)}
            if limited:
                found["solver_feasible"] = True
            report(options, found)
        else:
            state["since"] += 1
            if patience is not None and state["since"] >= int(patience):
                routing.solver().FinishCurrentSearch()

    routing.AddAtSolutionCallback(at_solution)
    started = time.perf_counter()
    assignment = routing.SolveWithParameters(params)
    runtime = time.perf_counter() - started
    if assignment is None and (limited or options.get("deadline") is not None):
        # nothing within the limits, or the time ran out before a first solution: an
        # outcome of the run (status "no_solution" in taopt), not a failure
        return {
            "routes": None,
            "objective": None,
            "solver_feasible": False,
            "routing_status": int(routing.status()),
            "solver_runtime": runtime,
        }
    if assignment is None:
        raise RuntimeError(f"OR-Tools found no solution (routing status {routing.status()})")
    reply = {
        "routes": current_routes(assignment.Value),
        "objective": int(assignment.ObjectiveValue()),
        "routing_status": int(routing.status()),
        "solutions": state["solutions"],
        "solver_runtime": runtime,
    }
    if limited:
        reply["solver_feasible"] = True
    return reply


def _cpsat_solver(options: dict[str, Any]) -> Any:
    """A CP-SAT solver with the time left of the request, its seed and number of workers."""
    from ortools.sat.python import cp_model

    solver = cp_model.CpSolver()
    left = seconds_left(options)
    if left is not None:
        solver.parameters.max_time_in_seconds = left
    solver.parameters.random_seed = int(options["seed"])
    solver.parameters.num_workers = int(options["num_workers"])
    return solver


def _cpsat_reply(solver: Any, status: int, started: float) -> dict[str, Any]:
    from ortools.sat.python import cp_model

    found = status in (cp_model.OPTIMAL, cp_model.FEASIBLE)
    return {
        "cpsat_status": solver.status_name(status),
        "objective": int(round(solver.objective_value)) if found else None,
        "best_bound": float(solver.best_objective_bound)
        if found or status == cp_model.UNKNOWN
        else None,
        "solver_runtime": time.perf_counter() - started,
        "branches": int(solver.num_branches),
    }


def _cpsat_unsolved(started: float, why: str) -> dict[str, Any]:
    """The reply of a CP-SAT request whose time ran out before the search (status UNKNOWN,
    no solution, no bound)."""
    return {
        "cpsat_status": "UNKNOWN",
        "objective": None,
        "best_bound": None,
        "solver_runtime": time.perf_counter() - started,
        "branches": 0,
        "stopped_during": why,
    }


def _cpsat_solve(model: Any, options: dict[str, Any], used: dict, decode: Any) -> dict[str, Any]:
    """Solve ``model`` within the request's time, reporting every solution to the parent.

    ``used`` maps each arc ``(i, j)`` to its literal; ``decode(successor)`` turns the chosen
    arcs (``successor[i] = j``) into the reply's payload entries (``{"routes": ...}`` or
    ``{"order": ...}``). Each solution CP-SAT finds is sent as a ``("best", ...)`` frame
    with its objective and CP-SAT's bound at that moment, so a worker stopped at the
    deadline still answers with the best it found.
    """
    import numpy as np
    from ortools.sat.python import cp_model

    arcs = list(used)
    index = np.array([literal.Index() for literal in used.values()], dtype=np.int64)

    def successors(values: Any) -> dict[int, int]:
        chosen = np.flatnonzero(np.asarray(values, dtype=np.int64)[index] == 1)
        return {arcs[k][0]: arcs[k][1] for k in chosen}

    class Reporter(cp_model.CpSolverSolutionCallback):
        def on_solution_callback(self) -> None:
            found = {
                "cpsat_status": "FEASIBLE",
                "objective": int(round(self.objective_value)),
                "best_bound": float(self.best_objective_bound),
                "solver_runtime": time.perf_counter() - started,
                "branches": int(self.num_branches),
            }
            found.update(decode(successors(self.response_proto.solution)))
            report(options, found)

    solver = _cpsat_solver(options)
    started = time.perf_counter()
    status = solver.Solve(model, Reporter() if options.get("report") else None)
    reply = _cpsat_reply(solver, status, started)
    if reply["objective"] is None:
        reply.update(decode(None))
    else:
        reply.update(decode(successors(solver.response_proto.solution)))
    return reply


def solve_cpsat_sop(cost: Any, options: dict[str, Any]) -> dict[str, Any]:
    """Sequential ordering as one circuit: the arcs of ``cost`` not marked in
    ``options["forbidden"]`` (an n x n list of booleans; a cost's sign means nothing) plus a
    dummy ``end -> start`` arc, and position variables for the precedences.

    ``add_circuit`` over every node makes the chosen arcs one Hamiltonian cycle; with the
    dummy arc as the only way into ``start`` and out of ``end`` it is a path start -> end.
    ``position[start] = 0``, an arc ``i -> j`` (not the dummy) forces
    ``position[j] = position[i] + 1``, and each precedence ``(r, j)`` adds
    ``position[r] < position[j]``.
    """
    from ortools.sat.python import cp_model

    received = time.perf_counter()
    n = cost.shape[0]
    forbidden = options["forbidden"]
    start, end = int(options["start"]), int(options["end"])
    model = cp_model.CpModel()
    position = [model.new_int_var(0, n - 1, f"position {v}") for v in range(n)]
    model.add(position[start] == 0)
    model.add(position[end] == n - 1)
    arcs, terms, used = [], [], {}
    for i in range(n):
        for j in range(n):
            if i == j or forbidden[i][j] or j == start or i == end:
                continue
            literal = model.new_bool_var(f"{i}->{j}")
            arcs.append((i, j, literal))
            terms.append(int(cost[i, j]) * literal)
            used[(i, j)] = literal
            model.add(position[j] == position[i] + 1).only_enforce_if(literal)
    arcs.append((end, start, model.new_constant(1)))
    model.add_circuit(arcs)
    for r, j in options["precedences"]:
        model.add(position[int(r)] < position[int(j)])
    model.minimize(sum(terms))
    if out_of_time(options):  # the model took the time: no search, no solution
        return {**_cpsat_unsolved(received, "model building"), "order": None}

    def decode(successor: dict[int, int] | None) -> dict[str, Any]:
        if successor is None:
            return {"order": None}
        order = [start]
        while order[-1] != end and len(order) <= n:
            order.append(successor[order[-1]])
        return {"order": order}

    return _cpsat_solve(model, options, used, decode)


def solve_cpsat_routing(cost: Any, n: int, m: int, options: dict[str, Any]) -> dict[str, Any]:
    """Open multi-vehicle routing (2.2)-(2.5) as one circuit through a dummy node.

    Nodes: targets ``0..n-1``, vehicle starts ``n..n+m-1``, dummy ``D = n+m``. The circuit
    runs ``D -> start 0 -> (vehicle 0's targets) -> start 1 -> ... -> start m-1 -> ...
    -> D``: an arc into ``start k`` (from ``start k-1`` or a target of vehicle k-1) or into
    ``D`` (from vehicle m-1) ends a route at no cost, so routes are open and a vehicle that
    goes straight to the next start is idle. ``vehicle[v]`` labels each node with its
    vehicle (``vehicle[start k] = k``; an arc between a node and a target keeps the label),
    which fixes the order of the vehicles along the circuit (no symmetric copies).
    """
    from ortools.sat.python import cp_model

    model = cp_model.CpModel()
    dummy = n + m
    vehicle = [model.new_int_var(0, m - 1, f"vehicle {v}") for v in range(n)]
    vehicle += [model.new_constant(k) for k in range(m)]
    arcs, terms, used = [], [], {}

    def arc(i: int, j: int, charge: int) -> Any:
        literal = model.new_bool_var(f"{i}->{j}")
        arcs.append((i, j, literal))
        used[(i, j)] = literal
        if charge:
            terms.append(charge * literal)
        return literal

    received = time.perf_counter()
    arc(dummy, n, 0)  # the circuit leaves D into vehicle 0's start
    for i in range(n + m):
        if out_of_time(options):  # building in Python is slow: stop when the time is spent
            return {**_cpsat_unsolved(received, "model building"), "routes": None}
        for j in range(n):  # into a target: same vehicle, cost charged
            if i != j:
                literal = arc(i, j, int(cost[i, j]))
                model.add(vehicle[j] == vehicle[i]).only_enforce_if(literal)
        for k in range(1, m):  # into start k: the route of vehicle k-1 ends here
            if i < n or i == n + k - 1:
                literal = arc(i, n + k, 0)
                model.add(vehicle[i] == k - 1).only_enforce_if(literal)
        literal = arc(i, dummy, 0)  # back to D: the last vehicle's route ends
        model.add(vehicle[i] == m - 1).only_enforce_if(literal)
    model.add_circuit(arcs)
    model.minimize(sum(terms))
    if out_of_time(options):
        return {**_cpsat_unsolved(received, "model building"), "routes": None}

    def decode(successor: dict[int, int] | None) -> dict[str, Any]:
        if successor is None:
            return {"routes": None}
        routes: list[list[int]] = [[] for _ in range(m)]
        at, current = successor[dummy], -1
        while at != dummy:
            if at >= n:
                current = at - n
            else:
                routes[current].append(int(at))
            at = successor[at]
        return {"routes": routes}

    return _cpsat_solve(model, options, used, decode)


def solve_cpsat(cost: Any, n: int, m: int, options: dict[str, Any]) -> dict[str, Any]:
    """CP-SAT on an SOP (``options["kind"] == "sop"``) or on the routing problem."""
    if options.get("kind") == "sop":
        return solve_cpsat_sop(cost, options)
    return solve_cpsat_routing(cost, n, m, options)


SOLVERS = {"pyvrp": solve_pyvrp, "ortools": solve_ortools, "cpsat": solve_cpsat}
PACKAGES = {"pyvrp": "pyvrp", "ortools": "ortools", "cpsat": "ortools"}


def _load(peer: str) -> str:
    """Import the peer's package (the slow part of starting); return its version."""
    from importlib.metadata import version

    if peer == "pyvrp":
        import pyvrp  # noqa: F401
    elif peer == "cpsat":
        from ortools.sat.python import cp_model  # noqa: F401
    else:
        from ortools.constraint_solver import pywrapcp  # noqa: F401
    return version(PACKAGES[peer])


def _die_with_parent(parent_pid: int, use_pdeathsig: bool) -> None:
    """Exit as soon as the parent is gone, even if it was killed.

    The steps of :func:`taopt.runtime.workers.die_with_parent`, written out here because
    this script does not import taopt (the parent is :class:`taopt.runtime.workers.ScriptWorker`).
    """
    if use_pdeathsig and sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG = 1
        except (OSError, AttributeError):  # pragma: no cover - exotic libc
            pass

    def watch() -> None:
        while True:
            if os.getppid() != parent_pid:
                os._exit(0)
            time.sleep(0.5)

    if os.getppid() != parent_pid:  # the parent died before we could watch it
        os._exit(0)
    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def serve(peer: str, parent_pid: int, use_pdeathsig: bool) -> None:
    """Answer requests on stdin/stdout until end of file (see the module docstring)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    _die_with_parent(parent_pid, use_pdeathsig)
    # The channel is the original stdout; anything else written to fd 1 (a C
    # library's log, a stray print) goes to stderr so it cannot corrupt a frame.
    channel_out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    channel_in = sys.stdin.buffer

    sending = threading.Lock()  # a solver's callback thread may report while we reply

    def send(message: Any) -> None:
        with sending:
            pickle.dump(message, channel_out, protocol=pickle.HIGHEST_PROTOCOL)
            channel_out.flush()

    def send_best(payload: dict[str, Any]) -> None:
        try:
            send(("best", payload))
        except (BrokenPipeError, OSError):  # the parent stopped listening: it will stop us
            pass

    try:
        send(("ready", {"peer": peer, "version": _load(peer), "pid": os.getpid()}))
    except ImportError as exc:
        send(("error", f"{type(exc).__name__}: {exc}"))
        return
    solver = SOLVERS[peer]
    while True:
        try:
            request = pickle.load(channel_in)
        except EOFError:
            return
        reply: tuple[str, Any]
        options = request["options"]
        if options.get("time_limit") is not None:  # the worker's clock starts on reading it
            options["deadline"] = time.monotonic() + float(options["time_limit"])
        options["report"] = send_best if options.get("report_best", True) else None
        try:
            reply = ("ok", solver(request["cost"], request["n"], request["m"], request["options"]))
        except Exception:
            reply = ("error", traceback.format_exc(limit=6))
        try:
            send(reply)
        except (BrokenPipeError, OSError):
            return


def main(argv: list[str]) -> None:
    """Entry point: ``<peer> <parent pid> <1 to ask for SIGKILL when the parent dies, else 0>``."""
    peer, parent_pid, use_pdeathsig = argv[0], int(argv[1]), argv[2] == "1"
    if peer not in SOLVERS:
        raise SystemExit(f"unknown peer {peer!r}; choose from {sorted(SOLVERS)}")
    serve(peer, parent_pid, use_pdeathsig)


if __name__ == "__main__":
    # Run as a script, this folder is sys.path[0]; drop it so its modules
    # (registry.py, peers.py, ...) cannot shadow anything the peers import.
    if sys.path and os.path.abspath(sys.path[0] or os.curdir) == _HERE:
        del sys.path[0]
    main(sys.argv[1:])
