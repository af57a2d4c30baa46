"""PyVRP and OR-Tools on the chapter 2 problem, side by side with the thesis's methods.

Users compare the thesis's heuristics with the general vehicle-routing
solvers they would otherwise reach for. :func:`pyvrp_solve` and
:func:`ortools_solve` hand a :class:`taopt.AssignmentProblem` (thesis §2.2:
open routes from each vehicle's own start point, objective (2.2) = total
travel time) to `PyVRP <https://pyvrp.org>`_ or the `OR-Tools
<https://developers.google.com/optimization/routing>`_ routing library and
return a :class:`taopt.Solution` whose objective is the float total travel
time re-scored by :func:`taopt.evaluate` (the one scorer), not the solver's
own integer objective (kept in ``info``).

Modelling
---------
Both solvers get the ``(n+m+1)``-point model: targets ``0..n-1``, vehicle
starts ``n..n+m-1`` and one dummy end point ``n+m`` reachable from every point
at cost 0, so a route ends after its last target at no cost (an open route)
and a vehicle that goes straight from its start to the end is idle. PyVRP:
one start depot per vehicle and the free end as every vehicle's end depot;
OR-Tools: a ``RoutingIndexManager`` with per-vehicle starts and the dummy end.

Both solvers take integer arc costs. The travel times are multiplied by
``scale`` (default: the largest entry becomes :data:`LARGEST_ENTRY` = 1e7)
and rounded, so each arc is off by at most ``0.5 / scale`` time units and a
solution's integer objective by at most ``(n + m) * 0.5 / scale``, i.e. a
relative ``5e-8 (n + m)`` of the largest entry. Route sums stay below
``(n + m) * 1e7``, far inside both solvers' int64 limits (PyVRP's
``MAX_VALUE`` is about 1.8e13). Rounding can only make a peer prefer one of
two solutions whose float values differ by less than that.

Worker processes
----------------
The ``ortools`` and ``highspy`` wheels ship incompatible ``libhighs``
libraries with the same soname: whichever is imported second fails to load
(and cvxpy then silently loses its HIGHS solver). So each peer runs in its own
worker process, started on first use and kept alive for later calls (starting
costs about a second), and this module imports neither package. The worker is
the script ``_peer_worker.py`` run by a fresh interpreter
(:class:`taopt.runtime.workers.ScriptWorker`), not a :mod:`multiprocessing` "spawn" child: a spawn child re-runs the
top-level imports of the caller's ``__main__`` script, so a script that
imports ``taopt.models`` (hence highspy) at the top would break OR-Tools in
its own worker. The worker dies with its parent (Linux ``PR_SET_PDEATHSIG``,
a ``getppid`` watch, end of file on its stdin); on Ctrl-C during a call the
caller stops it and re-raises; a worker that crashes or cannot import its
package becomes a :class:`taopt.SolverError` naming the peer.
:func:`shutdown` stops the workers (also done at exit).

Time limits
-----------
A ``time_limit`` is wall-clock from the call (docs/architecture.md, invariant 4), the
worker's start-up included: the caller waits for a starting worker only as
long as the limit allows (a worker still importing its package at the limit
keeps starting, for the next call, and the call answers "no_solution"); the
request carries the seconds left, which the worker counts from when it reads
it (model building included; CP-SAT's is checked as it is built). Each
improving solution the worker finds is sent to the caller at once; a worker
that has not answered :func:`grace` seconds after the limit is stopped and
the call answers with the last of them (or "no_solution"), never an
exception. A call without a time limit waits as long as it takes.

Default stop
------------
A heuristic peer stops by default after :func:`default_no_improvement`
iterations (PyVRP) or solutions (OR-Tools) without a better solution, a count
that grows with ``n + m``; the time limit is the ceiling. An explicit
``max_iterations`` / ``solution_limit`` switches it off.

Determinism
-----------
PyVRP is deterministic for a given ``seed`` when it stops on a count
(``max_iterations`` or the default no-improvement stop; pass
``time_limit=None``); stopped by time it is not (the number of iterations done
in the time varies). OR-Tools' routing search has no random seed: ``seed`` is
recorded but changes nothing; it is deterministic when it stops on a count
(``solution_limit`` or the no-improvement stop; pass ``time_limit=None``), not
when it stops on time.

References
----------
Thesis §2.2.1, (2.2)–(2.5). Wouda, Lan and Kool, "PyVRP: a high-performance
VRP solver package", INFORMS J. Computing 36(4), 2024. Perron and Didier,
OR-Tools routing, Google.
"""

from __future__ import annotations

import atexit
import importlib.util
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from taopt.errors import InstanceError, SolverError, require
from taopt.registry import register_method
from taopt.result import (
    FEASIBLE,
    NO_SOLUTION,
    Order,
    Routes,
    Solution,
    finish,
    make_solution,
)
from taopt.routing.problem import AssignmentProblem
from taopt.runtime import Deadline
from taopt.runtime.workers import ScriptWorker
from taopt.sop.problem import SopProblem
from taopt.status import RAW_OUTCOMES

__all__ = [
    "LARGEST_ENTRY",
    "PEERS",
    "cpsat_routing",
    "cpsat_sop",
    "pyvrp_solve",
    "ortools_solve",
    "shutdown",
]

#: The largest travel time becomes this integer when ``scale`` is not given.
LARGEST_ENTRY = 10**7
#: Integer entries above this are refused (a route of n + m arcs must stay far below 2**63).
MAX_ENTRY = 10**12
#: Peer name -> the package its worker imports.
PEERS = {"pyvrp": "pyvrp", "ortools": "ortools", "cpsat": "ortools"}
INSTALL_HINT = 'pip install "taopt[peers]"'
WORKER_SCRIPT = Path(__file__).with_name("_peer_worker.py")
#: Seconds a worker may take to import its package and say it is ready (a call with a
#: time limit waits at most its limit; the worker then keeps starting for the next call).
STARTUP_TIMEOUT = 120.0
#: A call with a time limit waits for its worker until the limit plus ``GRACE`` seconds
#: plus ``GRACE_SHARE`` of the limit, then stops the worker and answers with the best
#: solution the worker sent so far (or none): the overrun stays within max(1 s, 5 %).
GRACE = 0.3
GRACE_SHARE = 0.02
#: Iterations (PyVRP) or solutions (OR-Tools routing) without a better solution after which
#: a heuristic peer stops by default: ``max(NO_IMPROVEMENT_MIN[peer],
#: NO_IMPROVEMENT_PER_POINT[peer] * (n + m))`` (:func:`default_no_improvement`).
NO_IMPROVEMENT_MIN = {"pyvrp": 1000, "ortools": 100}
NO_IMPROVEMENT_PER_POINT = {"pyvrp": 50, "ortools": 1}


def default_no_improvement(peer: str, n: int, m: int) -> int:
    """The default stop of a heuristic peer on n targets and m vehicles: this many iterations
    (PyVRP's ``NoImprovement``) or solutions (OR-Tools) without a better solution.

    It scales with the instance, so a small one answers in well under a second and a large
    one searches longer; the time limit stays the ceiling.

    Example
    -------
    >>> default_no_improvement("pyvrp", 3, 2), default_no_improvement("pyvrp", 200, 10)
    (1000, 10500)
    >>> default_no_improvement("ortools", 3, 2), default_no_improvement("ortools", 200, 10)
    (100, 210)
    """
    return max(NO_IMPROVEMENT_MIN[peer], NO_IMPROVEMENT_PER_POINT[peer] * (n + m))


def grace(time_limit: float) -> float:
    """Seconds a call waits for its worker beyond ``time_limit`` before stopping it."""
    return GRACE + GRACE_SHARE * time_limit


class _Worker(ScriptWorker):
    """One worker process for one peer (a :class:`~taopt.runtime.workers.ScriptWorker`
    running ``_peer_worker.py``), and the lock its calls hold.

    Starting it does not wait: the worker imports its package while the caller waits for
    its "ready" frame (:meth:`wait_ready`) as long as its time limit allows.
    """

    def __init__(self, peer: str, nice: int = 0) -> None:
        super().__init__(WORKER_SCRIPT, [peer], name=peer, nice=nice)
        self.peer = peer
        self.lock = threading.Lock()
        self.ready = False
        self.version: str | None = None
        self.startup = math.nan

    def wait_ready(self, until: float | None, stop: Callable[[], bool] | None = None) -> bool:
        """Wait (holding :attr:`lock`) for the worker's "ready" frame until ``until``
        (``time.monotonic()``; None: up to :data:`STARTUP_TIMEOUT`) or ``stop()``. False
        when ``until`` or ``stop`` came first: the worker goes on starting and a later call
        finds it ready.

        Raises
        ------
        SolverError
            The package cannot be imported in the worker, the worker died, or it did not
            start within :data:`STARTUP_TIMEOUT` (it is then stopped).
        """
        if self.ready:
            return True
        hung = self.started + STARTUP_TIMEOUT
        try:
            frame = self.next_frame(hung if until is None else min(until, hung), "start", stop)
        except BaseException:  # Ctrl-C while it starts, or it died: do not leave it behind
            self.stop(wait=0.0)
            raise
        if frame is None:
            if time.monotonic() < hung or (stop is not None and stop()):
                return False
            self.stop(wait=0.0)
            raise SolverError(
                f"{self.peer} worker did not start within {STARTUP_TIMEOUT:.0f} s; stopped it"
            )
        kind, payload = frame
        if kind != "ready":
            self.stop()
            raise SolverError(
                f"{self.peer} could not be imported in its worker process ({payload.strip()}); "
                f"install the peers with {INSTALL_HINT}"
            )
        self.ready, self.version = True, payload["version"]
        self.startup = time.monotonic() - self.started
        return True

    def call(
        self,
        request: dict[str, Any],
        until: float | None,
        stop: Callable[[], bool] | None = None,
    ) -> tuple[dict[str, Any] | None, bool]:
        """Send one request (holding :attr:`lock`, the worker ready) and wait for its reply.

        Returns ``(reply, True)``; or, when ``time.monotonic()`` passes ``until`` or
        ``stop()`` is true first, the worker is stopped (killed and reaped) and ``(the last
        "best" frame it sent or None, False)``. Any interruption (Ctrl-C) stops the worker
        and is re-raised.
        """
        best = None
        try:
            self.send(request)
            while True:
                frame = self.next_frame(until, "a solve", stop)
                if frame is None:  # past the deadline: stop it, answer with what it sent
                    self.stop(wait=0.0)
                    return best, False
                kind, payload = frame
                if kind == "best":
                    best = payload
                    continue
                if kind != "ok":
                    raise SolverError(f"{self.peer} failed in its worker:\n{payload}")
                return payload, True
        except (BrokenPipeError, OSError) as exc:
            self.stop()
            raise SolverError(f"{self.peer} worker process is gone ({exc})") from None
        except SolverError:
            raise
        except BaseException:  # Ctrl-C: the reply would be stale
            self.stop(wait=0.0)
            raise


_WORKERS: dict[str, _Worker] = {}
_WORKERS_LOCK = threading.Lock()


def _find_spec(name: str) -> Any:
    """``importlib.util.find_spec`` without importing the package (patched by the tests)."""
    return importlib.util.find_spec(name)


def _worker(peer: str, nice: int = 0) -> _Worker:
    """The live worker of ``peer`` at niceness ``nice`` (one kept per pair: a niced process
    cannot be given its priority back), started (not waited for) if there is none."""
    if _find_spec(PEERS[peer]) is None:
        raise SolverError(f"{peer} is not installed; install the peers with {INSTALL_HINT}")
    key = peer if not nice else f"{peer}+nice{int(nice)}"
    with _WORKERS_LOCK:
        worker = _WORKERS.get(key)
        if worker is None or not worker.alive():
            worker = _WORKERS[key] = _Worker(peer, nice)
        return worker


def shutdown() -> None:
    """Stop every peer worker of this process (they restart on the next call)."""
    with _WORKERS_LOCK:
        for worker in _WORKERS.values():
            worker.stop()
        _WORKERS.clear()


atexit.register(shutdown)


def integer_costs(problem: AssignmentProblem, scale: float | None) -> tuple[np.ndarray, float]:
    """The travel times as int64 (``rint(cost * scale)``) and the scale used.

    The default ``scale`` maps the largest entry to :data:`LARGEST_ENTRY`.

    Raises
    ------
    InstanceError
        ``scale`` not positive, or a scaled entry above :data:`MAX_ENTRY`.
    """
    cost = problem.cost
    largest = float(cost.max())
    if scale is None:
        scale = LARGEST_ENTRY / largest if largest > 0 else 1.0
    scale = float(scale)
    if not np.isfinite(scale) or scale <= 0:
        raise InstanceError(f"scale must be a positive number, got {scale}")
    if largest * scale > MAX_ENTRY:
        raise InstanceError(
            f"scale {scale:g} makes the largest travel time {largest:g} into "
            f"{largest * scale:.3g} > {MAX_ENTRY:.0e} integer units"
        )
    return np.rint(cost * scale).astype(np.int64), scale


def _check(
    problem: Any,
    time_limit: float | None,
    seed: int,
    limit_name: str,
    limit: Any,
    no_improvement: Any = None,
) -> None:
    require(problem, AssignmentProblem, "the routing peers")
    if time_limit is not None and not (np.isfinite(time_limit) and time_limit > 0):
        raise InstanceError(f"time_limit must be a positive number of seconds, got {time_limit}")
    if limit is not None and (isinstance(limit, bool) or int(limit) != limit or limit < 1):
        raise InstanceError(f"{limit_name} must be a positive integer, got {limit}")
    if no_improvement is not None and no_improvement != "auto":
        if (
            isinstance(no_improvement, bool)
            or not isinstance(no_improvement, (int, np.integer))
            or no_improvement < 1
        ):
            raise InstanceError(
                f'no_improvement must be a positive integer, "auto" or None, got {no_improvement!r}'
            )
    if time_limit is None and limit is None and no_improvement is None:
        raise InstanceError(
            f"give time_limit, {limit_name} or no_improvement, or the search never stops"
        )
    if isinstance(seed, bool) or int(seed) != seed or not 0 <= seed < 2**32:
        raise InstanceError(f"seed must be an integer in [0, 2**32), got {seed}")


def stop_options(
    peer: str, problem: Any, limit_name: str, limit: int | None, no_improvement: Any
) -> dict[str, Any]:
    """The worker's count limits: ``limit_name`` (``max_iterations`` or ``solution_limit``)
    and ``no_improvement``, "auto" read as :func:`default_no_improvement` when no explicit
    count limit is given (and as no such stop when one is: a run stopped by ``limit_name``
    stays what it was)."""
    if no_improvement == "auto":
        no_improvement = (
            None if limit is not None else default_no_improvement(peer, problem.n, problem.m)
        )
    return {
        limit_name: None if limit is None else int(limit),
        "no_improvement": None if no_improvement is None else int(no_improvement),
    }


def _solve(
    peer: str,
    problem: AssignmentProblem,
    seed: int,
    scale: float | None,
    options: dict[str, Any],
    deadline: Deadline,
) -> Solution:
    """Run ``peer`` in its worker and turn its routes into a re-scored Solution."""
    cost, scale = integer_costs(problem, scale)
    request = {"cost": cost, "n": problem.n, "m": problem.m, "options": options}
    answer = _call(peer, request, deadline)
    reply = dict(answer.reply or {"routes": None, "objective": None})
    info = {
        "solver_objective": reply.pop("objective", None),
        "scale": scale,
        "version": answer.version,
        "startup": answer.startup,
        **{key: value for key, value in options.items() if key != "seed"},
        **{key: value for key, value in reply.items() if key != "routes"},
    }
    if answer.stopped:
        info["stopped_by"] = "time_limit"
        info["worker"] = answer.stopped
    if reply.get("routes") is None:  # the time limit ended the search before a first solution
        info["error"] = (
            f"{peer} found no route set within time_limit = {options.get('time_limit')} s "
            f"({answer.stopped or 'routing status ' + str(reply.get('routing_status'))}); "
            "not a proof that none exists"
        )
        return Solution(
            math.inf,
            NO_SOLUTION,
            None,
            runtime=deadline.elapsed(),
            method=peer,
            seed=int(seed),
            info=info,
        )
    try:  # the one scorer, once (taopt.solve does not score it again)
        return make_solution(
            problem,
            Routes(reply["routes"]),
            method=peer,
            status=FEASIBLE,
            runtime=deadline.elapsed(),
            seed=int(seed),
            info=info,
        )
    except Exception as exc:
        raise SolverError(f"{peer} returned routes that fail the check: {exc}") from None


@dataclass
class _Answer:
    """What a worker call gave: its reply (None when there is none), the worker's package
    version, the seconds this call waited for the worker to start, and why the call ended
    without the worker's own reply ("" when it replied)."""

    reply: dict[str, Any] | None
    version: str | None
    startup: float
    stopped: str = ""


def _call(peer: str, request: dict[str, Any], deadline: Deadline, nice: int = 0) -> _Answer:
    """Send ``request`` to ``peer``'s worker within ``deadline`` (everything counts: the
    worker's start-up, the request's time in the worker, the reply).

    The worker gets the seconds left when the request is sent as its ``time_limit``. A
    worker still starting when the deadline passes keeps starting (for the next call) and
    the answer has no reply; a worker that has not replied :func:`grace` seconds after the
    deadline is stopped and the answer is the last solution it sent ("best" frame), if any.
    A cancelled deadline (its token: e.g. the SOP portfolio proved the optimum first) stops
    the worker at once in the same way (a starting worker keeps starting). ``nice``: the
    worker's niceness (:func:`_worker`).
    """
    began = time.monotonic()
    left = deadline.remaining()  # None without a limit
    end = None if left is None else began + left
    stop = (lambda: deadline.cancelled) if deadline.token is not None else None
    for _attempt in range(3):
        worker = _worker(peer, nice)
        wait = -1.0 if end is None else max(0.0, end - time.monotonic())
        if not worker.lock.acquire(timeout=wait):  # another thread's call holds it
            why = "its worker was busy with another call until the time limit"
            return _Answer(None, worker.version, 0.0, why)
        try:
            if not worker.alive():  # stopped by another thread's failed call: take a fresh one
                continue
            was_ready = worker.ready
            ready = worker.wait_ready(end, stop)
            startup = 0.0 if was_ready else time.monotonic() - began
            if not ready:
                why = "its worker was still starting (importing its package) at the time limit"
                if deadline.cancelled:
                    why = "cancelled while its worker was starting"
                return _Answer(None, None, startup, why)
            options = dict(request["options"])
            if end is not None:
                left = end - time.monotonic()
                if left <= 0:
                    why = "the time limit was spent before the request was sent"
                    return _Answer(None, worker.version, startup, why)
                options["time_limit"] = left
            until = None if end is None else end + grace(deadline.seconds or 0.0)
            reply, answered = worker.call({**request, "options": options}, until, stop)
            if answered:
                return _Answer(reply, worker.version, startup)
            if deadline.cancelled:
                return _Answer(reply, worker.version, startup, "cancelled; stopped its worker")
            assert until is not None and end is not None  # only a limited call is cut off
            why = (
                f"its worker had not answered {until - end:.2f} s after the time limit; stopped it"
            )
            return _Answer(reply, worker.version, startup, why)
        finally:
            worker.lock.release()
    raise SolverError(f"{peer} worker kept being stopped by other threads; try again")


@register_method(AssignmentProblem, "pyvrp", category="peer", requires="pyvrp")
def pyvrp_solve(
    problem: AssignmentProblem,
    time_limit: float | None = 1.0,
    seed: int = 0,
    *,
    max_iterations: int | None = None,
    no_improvement: int | str | None = "auto",
    scale: float | None = None,
) -> Solution:
    """Solve the open multi-vehicle routing problem (2.2)–(2.5) with PyVRP.

    PyVRP's iterated local search on the model described in the module
    docstring (one start depot per vehicle, a free end depot), run in its
    worker process. By default it stops after
    :func:`default_no_improvement` iterations without a better solution
    (``max(1000, 50 (n + m))``: a few milliseconds on 3 targets), or at the
    time limit if that comes first.

    Parameters
    ----------
    problem : AssignmentProblem
    time_limit : float or None
        Wall-clock seconds for the whole call, the worker's start-up included
        (PyVRP's ``MaxRuntime`` gets what is left); None for no time limit.
        At the limit the worker is asked to stop; one that has not answered
        :func:`grace` seconds later is stopped and the call answers with the
        best solution it reported (or status "no_solution").
    seed : int
        PyVRP's random seed.
    max_iterations : int, optional
        Stop after this many iterations (``MaxIterations``). The search stops
        at whichever limit comes first; with ``time_limit=None`` the result is
        the same for the same seed, bit for bit.
    no_improvement : int, "auto" or None
        Stop after this many iterations without a better solution (PyVRP's
        ``NoImprovement``). "auto" (default): :func:`default_no_improvement`,
        unless ``max_iterations`` is given (then only the limits given stop
        it); None: no such stop.
    scale : float, optional
        Integer units per unit of travel time (default: largest entry -> 1e7).

    Returns
    -------
    Solution
        Status "feasible" (no optimality claim, no bound), method "pyvrp",
        ``routes`` one list per vehicle, ``objective = taopt.evaluate(routes)``;
        ``info`` has ``solver_objective`` (PyVRP's integer cost, about
        ``objective * scale``), ``scale``, ``iterations``, ``solver_runtime``,
        ``startup`` (seconds this call waited for the worker to start) and
        ``version``. ``runtime`` is the call's wall time, ``startup`` included.
        Status "no_solution" (objective ``inf``, ``info["error"]`` says why)
        when the time limit ran out before a first solution, e.g. while the
        worker was still starting (it keeps starting for the next call).

    Raises
    ------
    InstanceError
        Not an AssignmentProblem, or bad limits, seed or scale.
    SolverError
        PyVRP missing (the message says ``pip install "taopt[peers]"``), or
        failed or crashed in its worker.

    Example
    -------
    >>> import numpy as np, taopt
    >>> from taopt.heuristics.peers import pyvrp_solve
    >>> p = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0]]), n_targets=2)
    >>> s = pyvrp_solve(p, time_limit=None, max_iterations=50)
    >>> s.routes, s.objective
    ([[1, 0]], 4.0)

    References
    ----------
    Thesis §2.2.1; Wouda, Lan and Kool (2024), PyVRP.
    """
    deadline = Deadline(time_limit)
    _check(problem, time_limit, seed, "max_iterations", max_iterations, no_improvement)
    options = {
        "time_limit": time_limit,
        **stop_options("pyvrp", problem, "max_iterations", max_iterations, no_improvement),
        "seed": int(seed),
    }
    return _solve("pyvrp", problem, seed, scale, options, deadline)


@register_method(AssignmentProblem, "ortools", category="peer", requires="ortools")
def ortools_solve(
    problem: AssignmentProblem,
    time_limit: float | None = 1.0,
    seed: int = 0,
    *,
    solution_limit: int | None = None,
    no_improvement: int | str | None = "auto",
    first_solution: str = "PATH_CHEAPEST_ARC",
    metaheuristic: str = "GUIDED_LOCAL_SEARCH",
    scale: float | None = None,
) -> Solution:
    """Solve the open multi-vehicle routing problem (2.2)–(2.5) with OR-Tools routing.

    A first solution by ``first_solution``, improved by guided local search
    (by default) until a limit, on the model of the module docstring
    (per-vehicle starts, a dummy end node with zero-cost arcs into it), run in
    its worker process. By default it stops after
    :func:`default_no_improvement` solutions without a better one
    (``max(100, n + m)``), or at the time limit if that comes first.

    Parameters
    ----------
    problem : AssignmentProblem
    time_limit : float or None
        Wall-clock seconds for the whole call, the worker's start-up included
        (see :func:`pyvrp_solve`); None for no time limit. Guided local search
        itself only stops at a limit.
    seed : int
        Recorded only: OR-Tools' routing search has no random seed.
    solution_limit : int, optional
        Stop after this many solutions. With ``time_limit=None`` the result
        is the same on every run; stopped by time it may differ.
    no_improvement : int, "auto" or None
        Stop after this many solutions without a better one (counted by a
        solution callback, which then finishes the search). "auto" (default):
        :func:`default_no_improvement`, unless ``solution_limit`` is given;
        None: no such stop. Counted in solutions, the stop is deterministic.
    first_solution, metaheuristic : str
        Names from OR-Tools' ``FirstSolutionStrategy`` and
        ``LocalSearchMetaheuristic`` enums.
    scale : float, optional
        Integer units per unit of travel time (default: largest entry -> 1e7).

    Returns
    -------
    Solution
        Status "feasible" (no bound), method "ortools", ``routes``,
        ``objective = taopt.evaluate(routes)``; ``info`` has
        ``solver_objective``, ``scale``, ``routing_status``,
        ``solver_runtime``, ``startup`` and ``version``. Status "no_solution"
        (``objective = inf``, no routes, ``info["error"]``) when the time limit
        ends the search before OR-Tools' first solution (e.g. 1 ms).

    Raises
    ------
    InstanceError
        Not an AssignmentProblem, or bad limits, seed or scale.
    SolverError
        OR-Tools missing (the message says ``pip install "taopt[peers]"``),
        an unknown strategy name, or a failure or crash in its worker.

    Example
    -------
    >>> import numpy as np, taopt
    >>> from taopt.heuristics.peers import ortools_solve
    >>> p = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0]]), n_targets=2)
    >>> ortools_solve(p, time_limit=None).objective
    4.0

    References
    ----------
    Thesis §2.2.1; OR-Tools routing library (Google).
    """
    deadline = Deadline(time_limit)
    _check(problem, time_limit, seed, "solution_limit", solution_limit, no_improvement)
    options = {
        "time_limit": time_limit,
        **stop_options("ortools", problem, "solution_limit", solution_limit, no_improvement),
        "first_solution": str(first_solution),
        "metaheuristic": str(metaheuristic),
        "seed": int(seed),
    }
    return _solve("ortools", problem, seed, scale, options, deadline)


# ----------------------------------------------------------------------------- CP-SAT
def _sop_integer_costs(
    problem: SopProblem, scale: float | None
) -> tuple[np.ndarray, np.ndarray, float, bool]:
    """The SOP's arc costs as int64, the forbidden arcs, the scale, and whether it is exact.

    Whole-number costs keep ``scale = 1`` (exact); otherwise the largest finite entry
    becomes :data:`LARGEST_ENTRY`. ``forbidden[i, j]`` is True for an infinite cost and
    for an arc ``i -> j`` with ``j`` required before ``i`` (no feasible path uses it); it
    goes to the worker as its own array, never coded in the sign of a cost (a negative
    cost read as "forbidden" once made CP-SAT prove a wrong optimum).
    """
    cost = problem.cost
    finite = np.isfinite(cost)
    largest = float(np.abs(cost[finite]).max(initial=0.0))
    if scale is None:
        integral = bool(np.all(cost[finite] == np.rint(cost[finite])))
        scale = 1.0 if integral else (LARGEST_ENTRY / largest if largest > 0 else 1.0)
    scale = float(scale)
    if not np.isfinite(scale) or scale <= 0:
        raise InstanceError(f"scale must be a positive number, got {scale}")
    if largest * scale > MAX_ENTRY:
        raise InstanceError(
            f"scale {scale:g} makes the largest cost {largest:g} into "
            f"{largest * scale:.3g} > {MAX_ENTRY:.0e} integer units"
        )
    scaled = np.where(finite, cost * scale, 0.0)
    exact = bool(np.all(scaled == np.rint(scaled)))
    matrix = np.where(finite, np.rint(scaled), 0).astype(np.int64)
    forbidden = ~finite
    for r, j in problem.closure.edges:
        forbidden[j, r] = True
    return matrix, forbidden, scale, exact


def _scaled_bound(reply: dict[str, Any], scale: float, slack_units: float) -> float | None:
    """CP-SAT's proven bound in the problem's units, rounded down (valid after rounding)."""
    bound = reply.get("best_bound")
    if bound is None or not np.isfinite(bound):
        return None
    return (np.floor(bound + 1e-9) - slack_units) / scale


def _cpsat_options(
    problem: Any, expected: type, time_limit: float | None, seed: int, num_workers: int
) -> dict[str, Any]:
    """The worker's common CP-SAT options, checked (InstanceError naming the bad one).

    ``problem`` must be an ``expected`` (each family's CP-SAT function takes its own type;
    ``taopt.solve`` picks the right one).
    """
    require(
        problem,
        expected,
        "this CP-SAT model",
        "taopt.solve(problem, 'cpsat') picks the family's own",
    )
    if time_limit is not None and not (np.isfinite(time_limit) and time_limit > 0):
        raise InstanceError(f"time_limit must be a positive number of seconds, got {time_limit}")
    if isinstance(seed, bool) or int(seed) != seed or not 0 <= seed < 2**31:
        raise InstanceError(f"seed must be an integer in [0, 2**31), got {seed}")
    if isinstance(num_workers, bool) or int(num_workers) != num_workers or num_workers < 1:
        raise InstanceError(f"num_workers must be a positive integer, got {num_workers}")
    return {"time_limit": time_limit, "seed": int(seed), "num_workers": int(num_workers)}


def _cpsat_run(
    problem: SopProblem | AssignmentProblem,
    request: dict[str, Any],
    *,
    scale: float,
    exact: bool,
    slack: float,
    payload_type: type[Order] | type[Routes],
    payload_key: str,
    deadline: Deadline,
    nice: int = 0,
) -> Solution:
    """Send one CP-SAT request to the worker and turn its reply into a Solution.

    Shared by both families' registrations: scored once by taopt's scorer, status by
    :func:`taopt.result.finish`, bound in the problem's units (see :func:`cpsat_sop`).
    """
    options = request["options"]
    time_limit = options["time_limit"]
    answer = _call("cpsat", request, deadline, nice)
    reply = answer.reply or {
        "cpsat_status": "UNKNOWN",
        "objective": None,
        "best_bound": None,
        "branches": 0,
        "solver_runtime": 0.0,
    }
    info = {
        "cpsat_status": reply["cpsat_status"],
        "solver_objective": reply["objective"],
        "best_bound": reply["best_bound"],
        "scale": scale,
        "exact_scaling": exact,
        "branches": reply["branches"],
        "solver_runtime": reply["solver_runtime"],
        "num_workers": options["num_workers"],
        "time_limit": time_limit,
        "version": answer.version,
        "startup": answer.startup,
    }
    if answer.stopped:
        info["worker"] = answer.stopped
    if reply.get("stopped_during"):
        info["stopped_during"] = reply["stopped_during"]
    bound = _scaled_bound(reply, scale, slack)
    found = reply.get(payload_key)
    payload = None if found is None else payload_type(found)
    if reply["cpsat_status"] == "OPTIMAL" and payload is None:
        raise SolverError("cpsat reported OPTIMAL without a solution")
    seed = options["seed"]
    infeasible = RAW_OUTCOMES["cpsat"].get(reply["cpsat_status"]) == "infeasible"
    try:  # scored once by taopt's scorer; the status follows from that objective
        return finish(
            problem,
            payload,
            method="cpsat",
            stop=reply["cpsat_status"],
            solver="cpsat",
            time_limited=time_limit is not None or bool(answer.stopped),
            bound=np.inf if infeasible else bound,
            runtime=deadline.elapsed(),
            seed=seed,
            info=info,
        )
    except Exception as exc:
        raise SolverError(f"cpsat returned a solution that fails the check: {exc}") from None


@register_method(SopProblem, "cpsat", category="peer", requires="ortools")
def cpsat_sop(
    problem: SopProblem,
    time_limit: float | None = 10.0,
    seed: int = 0,
    *,
    num_workers: int = 2,
    scale: float | None = None,
    nice: int = 0,
) -> Solution:
    """OR-Tools CP-SAT on a sequential ordering problem, in its worker process.

    One ``AddCircuit`` over the usable arcs (the forbidden ones passed as their own array)
    plus a dummy ``end -> start`` arc, with position variables for the precedences
    (``_peer_worker.solve_cpsat_sop``).

    Parameters
    ----------
    problem : SopProblem
    time_limit : float or None
        CP-SAT's ``max_time_in_seconds``; None: until it proves the optimum.
    seed : int
        CP-SAT's ``random_seed``.
    num_workers : int
        CP-SAT's ``num_workers`` (default 2: this machine's cores).
    scale : float, optional
        Integer units per unit of cost. Default: 1 when the costs are whole numbers
        (exact), else the largest entry becomes :data:`LARGEST_ENTRY`.
    nice : int
        Niceness added to the worker process (a lower CPU priority; a worker is kept per
        niceness). The SOP portfolio runs CP-SAT beside its own stages this way
        (:func:`taopt.models.sop.solve_sop_problem`).

    Returns
    -------
    Solution
        Method "cpsat". Status by :func:`taopt.status.decide` (the one rule): CP-SAT's
        OPTIMAL -> "optimal" when its bound (in the problem's units) closes the gap,
        else "feasible"; FEASIBLE -> "time_limit"; no solution -> "time_limit" with
        objective ``inf``; INFEASIBLE -> "infeasible".
        ``objective`` is re-scored by taopt's scorer; ``bound`` is CP-SAT's proven bound
        divided by the scale, rounded down and lowered by the rounding error of a path when
        the scaling is not exact (so it stays valid). ``info`` has ``cpsat_status``,
        ``solver_objective``, ``best_bound`` (CP-SAT's units), ``scale``, ``branches``,
        ``solver_runtime``.

    Raises
    ------
    InstanceError
        Bad limits, seed, workers or scale.
    SolverError
        OR-Tools missing (the message says ``pip install "taopt[peers]"``), or a failure
        or crash in the worker.

    Example
    -------
    >>> from taopt.heuristics.peers import cpsat_sop
    >>> s = cpsat_sop(SopProblem.load("ESC07"), time_limit=10)
    >>> str(s.status), s.objective, s.bound
    ('optimal', 2125.0, 2125.0)

    References
    ----------
    Thesis §5.2 (5.7); Perron and Didier, CP-SAT (OR-Tools, Google).
    """
    deadline = Deadline(time_limit)
    options = _cpsat_options(problem, SopProblem, time_limit, seed, num_workers)
    if isinstance(nice, bool) or int(nice) != nice or not 0 <= nice <= 19:
        raise InstanceError(f"nice must be an integer in [0, 19], got {nice!r}")
    cost, forbidden, scale, exact = _sop_integer_costs(problem, scale)
    options.update(
        kind="sop",
        forbidden=forbidden.tolist(),
        start=problem.start,
        end=problem.end,
        precedences=[(int(r), int(j)) for r, j in problem.precedences],
    )
    request = {"cost": cost, "n": problem.n, "m": 0, "options": options}
    slack = 0.0 if exact else 0.5 * (problem.n - 1)
    return _cpsat_run(
        problem, request, scale=scale, exact=exact, slack=slack,
        payload_type=Order, payload_key="order", deadline=deadline, nice=int(nice),
    )  # fmt: skip


@register_method(AssignmentProblem, "cpsat", category="peer", requires="ortools")
def cpsat_routing(
    problem: AssignmentProblem,
    time_limit: float | None = 10.0,
    seed: int = 0,
    *,
    num_workers: int = 2,
    scale: float | None = None,
) -> Solution:
    """OR-Tools CP-SAT on the chapter 2 routing problem (2.2)-(2.5), in its worker process.

    One circuit through a dummy node that chains the vehicles' open routes, targets first
    then the vehicles' start points as in :class:`AssignmentProblem`
    (``_peer_worker.solve_cpsat_routing``). Parameters, result and errors as
    :func:`cpsat_sop`; the default ``scale`` makes the largest entry :data:`LARGEST_ENTRY`.

    Example
    -------
    >>> from taopt.heuristics.peers import cpsat_routing
    >>> cost = np.array([[0, 4, 9], [4, 0, 9], [2, 3, 0.0]])
    >>> s = cpsat_routing(AssignmentProblem(cost, n_targets=2), time_limit=10)
    >>> str(s.status), s.routes
    ('optimal', [[0, 1]])

    References
    ----------
    Thesis §2.2.1; Perron and Didier, CP-SAT (OR-Tools, Google).
    """
    deadline = Deadline(time_limit)
    options = _cpsat_options(problem, AssignmentProblem, time_limit, seed, num_workers)
    cost, scale = integer_costs(problem, scale)
    exact = bool(np.all(problem.cost * scale == cost))
    options["kind"] = "routing"
    request = {"cost": cost, "n": problem.n, "m": problem.m, "options": options}
    slack = 0.0 if exact else 0.5 * problem.n
    return _cpsat_run(
        problem, request, scale=scale, exact=exact, slack=slack,
        payload_type=Routes, payload_key="routes", deadline=deadline,
    )  # fmt: skip
