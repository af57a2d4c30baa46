"""Exact models of chapter 3: (3.1)–(3.3) as printed, corrected per class, and joint.

Sets and data (thesis §3.2.1): targets ``T = {0..n-1}``, vehicle start points
``V = {n..n+m-1}`` (vehicle k starts at ``n + k``), vehicle k has capability ``a_k``, the
class ``R_q`` holds the vehicles of capability q, ``y_jq = 1`` when target j demands q,
``T_q`` the targets demanding q; ``t_q(i, j)`` the travel time of class q's vehicles
(one matrix, or one per capability).

Three formulations (``solve_capability(problem, formulation=...)``):

* ``"printed"`` — (3.1)–(3.3) literally. Binary ``σ_ijk`` for ``i ∈ T ∪ V``, ``j ∈ T``,
  ``k ∈ R`` (``i ≠ j``, as chapter 2's ``σ_ii = 0``; arcs that cannot be travelled,
  ``t = inf``, are left out, never given a big number):

  - (3.1) ``min Σ t(i, j) σ_ijk``;
  - (3.2) ``Σ_{i ∈ T∪V, k ∈ R_q} σ_ijk = y_jq`` for every target j and class q (when
    ``y_jq = 0`` it fixes those σ to 0, so they are not created);
  - (3.3) ``Σ_{j ∈ T, k ∈ R_q} σ_ijk <= 1`` for every point i and class q.

  Nothing ties σ to routes: there is no subtour elimination (a class can serve a cluster
  of targets by a cycle among them), no flow conservation (a vehicle may leave a target it
  never entered, or another vehicle's start, or a target its class does not visit), and
  nothing keeps the label k along a route (a route may "change vehicle" mid-way). Every
  feasible routing satisfies (3.2)–(3.3), so the printed optimum is a **lower bound** on
  the true optimum; :func:`decode_printed` shows what went wrong in its arcs.

* ``"corrected"`` — the problem splits exactly by class (§3.4.2, §3.6: classes share no
  vehicle and no (target, capability) demand, and (3.1) is the sum of the classes' totals),
  so the optimum is the sum of one chapter 2 model (2.2)–(2.5) per class on ``T_q`` and
  ``R_q``, each solved and certified by :func:`taopt.models.solve_routing`. In the
  printed notation, class q's block is (3.2) restricted to ``i ∈ T_q ∪ V_q`` (the class's
  own targets and starts), (3.3), and (2.5) ``Σ_{i,j∈S} σ_ijq <= |S| - 1`` for every
  ``S ⊆ T_q``; the label k is dropped (a route belongs to the vehicle at its start). This
  is what ``taopt.solve(problem, "exact")`` runs.

* ``"joint"`` — the same corrected model written as ONE MILP over all classes (for
  teaching): binary ``σ_ijq`` on class q's arcs, (3.1), (3.2) per (j, q), (3.3) per (i, q),
  and (2.5) per class, by DFJ cuts added in a loop (``sec="dfj"``) or by MTZ order
  variables (``sec="mtz"``).

Example
-------
>>> import numpy as np
>>> from taopt.capability import CapabilityProblem
>>> x = np.array([10.0, 11.0, 0.0])                  # targets at 10, 11; one vehicle at 0
>>> p = CapabilityProblem(abs(x[:, None] - x[None, :]), 2, ["a"], [{"a"}, {"a"}])
>>> solve_capability(p, "printed").objective        # the 2-cycle 10 <-> 11 costs 2
2.0
>>> solve_capability(p, "corrected").objective      # 0 -> 10 -> 11
11.0
"""

from __future__ import annotations

import inspect
import logging
import math
import os
import time
from collections.abc import Hashable
from concurrent.futures import FIRST_COMPLETED, Future, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp
import networkx as nx
import numpy as np
import scipy.sparse as sp

from taopt.bounds import arborescence as arborescence_lower
from taopt.capability.problem import CapabilityProblem, evaluate_capability
from taopt.errors import InstanceError, SolverError, require
from taopt.models.highs import solve_highs
from taopt.models.routing import solve_routing
from taopt.result import OPTIMAL, RELAXATION, Routes, Solution, finish, make_solution
from taopt.runtime import MARGIN, milp_bytes, register_footprint
from taopt.runtime.workers import WorkerPool, drop_pool, shared_pool

logger = logging.getLogger(__name__)  # a child of the "taopt" logger

FORMULATIONS = ("printed", "corrected", "joint")
JOINT_SUBTOUR_ELIMINATIONS = ("dfj", "mtz")
#: The printed model is meant for small instances (teaching); refuse to build beyond this.
PRINTED_MAX_VARIABLES = 400_000

__all__ = [
    "FORMULATIONS",
    "CapabilityModel",
    "PrintedArcs",
    "build_printed",
    "build_joint",
    "decode_printed",
    "describe",
    "solve_capability",
    "solve_exact",
    "class_incumbents",
    "ClassSolve",
    "solve_classes",
]


@dataclass
class CapabilityModel:
    """A built chapter 3 model: the cvxpy problem and the meaning of each σ.

    Attributes
    ----------
    problem : cvxpy.Problem
    arc_use : cvxpy.Variable
        One binary per arc.
    tails, heads : (A,) int arrays
        Arc ``a`` runs from point ``tails[a]`` to target ``heads[a]``.
    labels : (A,) int array
        "printed": the vehicle k of ``σ_ijk``; "joint": the class index q (position in
        ``problem.capabilities``).
    formulation : str
    order : cvxpy.Variable or None
        MTZ positions (joint, ``sec="mtz"``).
    cuts : list of (q, subset)
        DFJ cuts present (joint, ``sec="dfj"``).
    """

    problem: cp.Problem
    arc_use: cp.Variable
    tails: np.ndarray
    heads: np.ndarray
    labels: np.ndarray
    formulation: str
    order: cp.Variable | None = None
    cuts: list[tuple[int, tuple[int, ...]]] = field(default_factory=list)


def _class_index(problem: CapabilityProblem) -> dict[Hashable, int]:
    return {cap: q for q, cap in enumerate(problem.capabilities)}


def _check(problem: Any) -> None:
    require(
        problem,
        CapabilityProblem,
        "solve_capability",
        "chapter 2 problems are solved by taopt.models.solve_routing",
    )


# ----------------------------------------------------------------------------- printed
def _printed_arcs(problem: CapabilityProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    n, m = problem.n, problem.m
    size = n + m
    tails, heads, vehicles = [], [], []
    for k, cap in enumerate(problem.vehicle_capability):
        cost = problem.cost_for(cap)
        demanded = np.array([cap in problem.demands[j] for j in range(n)])
        i, j = np.nonzero((~np.eye(size, n, dtype=bool)) & demanded[None, :])
        keep = np.isfinite(cost[i, j])
        tails.append(i[keep])
        heads.append(j[keep])
        vehicles.append(np.full(int(keep.sum()), k))
    return np.concatenate(tails), np.concatenate(heads), np.concatenate(vehicles)


def build_printed(problem: CapabilityProblem, relax: bool = False) -> CapabilityModel:
    """Build (3.1)–(3.3) literally (see the module notes).

    Parameters
    ----------
    problem : CapabilityProblem
    relax : bool
        ``0 <= σ <= 1`` instead of binary.

    Returns
    -------
    CapabilityModel
        ``labels`` are the vehicles k of ``σ_ijk``.

    Raises
    ------
    InstanceError
        More than :data:`PRINTED_MAX_VARIABLES` variables (the printed model has
        ``(n + m - 1) n m`` of them at most; it is for small instances).
    """
    _check(problem)
    n, m = problem.n, problem.m
    size = n + m
    tails, heads, vehicles = _printed_arcs(problem)
    count = len(tails)
    if count > PRINTED_MAX_VARIABLES:
        raise InstanceError(
            f"the printed model would have {count} variables (> {PRINTED_MAX_VARIABLES}); "
            "it is meant for small instances"
        )
    index = _class_index(problem)
    arc_class = np.array([index[problem.vehicle_capability[k]] for k in vehicles], dtype=int)
    n_classes = len(problem.capabilities)
    arcs = np.arange(count)
    travel_time = np.array(
        [
            problem.cost_for(problem.vehicle_capability[k])[i, j]
            for i, j, k in zip(tails, heads, vehicles, strict=True)
        ]
    )
    sigma = (
        cp.Variable(count, name="sigma_ijk", nonneg=True)
        if relax
        else cp.Variable(count, name="sigma_ijk", boolean=True)
    )
    # (3.2): one row per (j, q) with y_jq = 1 (rows with y_jq = 0 have no variable left).
    demand_rows = {
        (j, q): r
        for r, (j, q) in enumerate(
            (j, index[cap])
            for j in range(n)
            for cap in sorted(problem.demands[j], key=lambda c: index[c])
        )
    }
    row = np.array([demand_rows[j, q] for j, q in zip(heads, arc_class, strict=True)])
    into = sp.csr_matrix((np.ones(count), (row, arcs)), shape=(len(demand_rows), count))
    # (3.3): one row per (i, q).
    out_of = sp.csr_matrix(
        (np.ones(count), (tails * n_classes + arc_class, arcs)), shape=(size * n_classes, count)
    )
    constraints = [
        (into @ sigma == 1).set_label("(3.2) sum_{i, k in R_q} sigma_ijk = y_jq (y_jq = 1 rows)"),
        (out_of @ sigma <= 1).set_label("(3.3) sum_{j, k in R_q} sigma_ijk <= 1 per point, class"),
    ]
    if relax:
        constraints.append((sigma <= 1).set_label("0 <= sigma_ijk <= 1 (LP relaxation)"))
    objective = cp.Minimize(travel_time @ sigma)  # (3.1)
    return CapabilityModel(
        problem=cp.Problem(objective, constraints),
        arc_use=sigma,
        tails=tails,
        heads=heads,
        labels=vehicles,
        formulation="printed",
    )


@dataclass(frozen=True)
class PrintedArcs:
    """The arcs chosen by the printed model and what makes them not a routing.

    Attributes
    ----------
    arcs : list of (i, j, k)
        ``σ_ijk = 1``: "vehicle k travels from point i to target j".
    subtours : list of (capability, [targets])
        Cycles among targets in one class's arcs (no vehicle ever reaches them).
    foreign_tails : list of (i, j, k)
        Arcs leaving a point class ``a_k`` never visits: another class's start or a
        target that does not demand ``a_k`` (no flow conservation).
    vehicle_switches : list of (i, j, k, other)
        Arcs whose label k differs from the vehicle ``other`` that is at i: the vehicle
        whose start i is, or the vehicle that entered target i in the same class.
    routes : Routes or None
        When there are no subtours and no foreign tails, the arcs are routes from the
        class starts (relabelled by the start's vehicle): the printed optimum is then
        feasible, hence optimal.
    """

    arcs: list[tuple[int, int, int]]
    subtours: list[tuple[Hashable, list[int]]]
    foreign_tails: list[tuple[int, int, int]]
    vehicle_switches: list[tuple[int, int, int, int]]
    routes: Routes | None

    @property
    def is_routing(self) -> bool:
        return self.routes is not None

    def to_dict(self) -> dict[str, Any]:
        return {
            "arcs": [list(a) for a in self.arcs],
            "subtours": [[str(c), t] for c, t in self.subtours],
            "foreign_tails": [list(a) for a in self.foreign_tails],
            "vehicle_switches": [list(a) for a in self.vehicle_switches],
        }


def decode_printed(
    problem: CapabilityProblem, model: CapabilityModel, values: np.ndarray | None = None
) -> PrintedArcs:
    """Read the printed model's arcs and name every way they fail to be routes."""
    values = model.arc_use.value if values is None else values
    if values is None:
        raise SolverError("the printed model has no solution values to decode")
    n = problem.n
    used = np.flatnonzero(np.asarray(values) > 0.5)
    arcs = [(int(model.tails[a]), int(model.heads[a]), int(model.labels[a])) for a in used]
    subtours: list[tuple[Hashable, list[int]]] = []
    foreign: list[tuple[int, int, int]] = []
    switches: list[tuple[int, int, int, int]] = []
    routes: list[list[int]] = [[] for _ in range(problem.m)]
    clean = True
    for cls in problem.classes:
        cap = cls.capability
        mine = [(i, j, k) for i, j, k in arcs if problem.vehicle_capability[k] == cap]
        own = set(cls.targets) | {n + k for k in cls.vehicles}
        entered_by = {j: k for _, j, k in mine}
        successor = {}
        for i, j, k in mine:
            successor[i] = j
            if i not in own:
                foreign.append((i, j, k))
            holder = i - n if i >= n else entered_by.get(i)
            if holder is not None and holder != k:
                switches.append((i, j, k, holder))
        graph = nx.DiGraph(list(successor.items()))
        for cycle in nx.simple_cycles(graph):
            if all(c < n for c in cycle):
                subtours.append((cap, sorted(cycle)))
        if any(i not in own for i, _, _ in mine) or any(c for c_cap, c in subtours if c_cap == cap):
            clean = False
            continue
        for k in cls.vehicles:
            point, route = n + k, []
            while point in successor:
                point = successor[point]
                route.append(point)
            routes[k] = route
    return PrintedArcs(
        arcs=arcs,
        subtours=subtours,
        foreign_tails=foreign,
        vehicle_switches=switches,
        routes=Routes(routes) if clean else None,
    )


def _solve_printed(
    problem: CapabilityProblem, time_limit: float | None, verbose: bool, start: float
) -> Solution:
    model = build_printed(problem)
    run = solve_highs(model.problem, time_limit=time_limit, verbose=verbose)
    if not run.has_point:
        raise SolverError(f"HiGHS found no point of the printed model ({run.solver_status})")
    decoded = decode_printed(problem, model)
    value = float(run.objective)
    bound = value if run.status == OPTIMAL else run.bound
    info = {
        "formulation": "printed",
        "variables": len(model.tails),
        "solver_status": run.solver_status,
        "stopped_by": run.stopped_by,
        **decoded.to_dict(),
    }
    if decoded.is_routing and run.status == OPTIMAL:
        # the relaxation's optimum is a feasible routing: it is the true optimum
        solution = make_solution(
            problem,
            decoded.routes,
            method="exact-printed",
            status=OPTIMAL,
            runtime=time.perf_counter() - start,
            info=info,
        )
        return solution.replace(bound=solution.objective)
    return make_solution(
        problem,
        None,
        method="exact-printed",
        status=RELAXATION,
        objective=value,
        bound=bound,
        runtime=time.perf_counter() - start,
        info=info,
    )


# --------------------------------------------------------------------------- corrected
def class_incumbents(
    problem: CapabilityProblem, incumbent: Any
) -> dict[Hashable, list[list[int]] | None]:
    """Restrict whole-problem routes (or a Solution carrying them) to each class's indexing."""
    result: dict[Hashable, list[list[int]] | None] = {c.capability: None for c in problem.classes}
    if incumbent is None:
        return result
    routes = getattr(incumbent, "solution", incumbent)
    routes = Routes(routes).as_lists()
    evaluate_capability(problem, routes)  # a bad incumbent is the caller's error, named
    for cls in problem.classes:
        if cls.problem is None:
            continue
        position = {t: p for p, t in enumerate(cls.targets)}
        result[cls.capability] = [[position[t] for t in routes[k]] for k in cls.vehicles]
    return result


def _routing_takes_incumbent() -> bool:
    return "incumbent" in inspect.signature(solve_routing).parameters


# ------------------------------------------------------------- classes in worker processes
#: Seconds a worker may run past its class's time limit before the pool is killed and the
#: class counted as unfinished (``solve_routing`` keeps its limit within about 0.5 s).
WORKER_GRACE = 5.0

#: A class counts towards the default number of workers from this many targets (smaller
#: ones are certified in milliseconds: not worth starting a process for).
PARALLEL_MIN_TARGETS = 20

#: A time limit below this many seconds solves the classes in this process (default
#: ``workers``): starting worker processes takes 1-3 s, more on a loaded machine.
PARALLEL_MIN_SECONDS = 10.0


def available_cores() -> int:
    """Cores this process may run on (``os.sched_getaffinity``; ``os.cpu_count`` elsewhere)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _auto_workers(classes: list[Any]) -> int:
    """Worker processes for these classes: one per core, at most one per class of at least
    :data:`PARALLEL_MIN_TARGETS` targets; 1 (in this process) when fewer than two classes are
    that large, and inside a study's task.

    A study's worker runs with ``TAOPT_SOLVER_THREADS=1`` (its scenarios already share the
    cores), as do this module's own workers: there the classes are solved in turn. Small
    classes take milliseconds, less than the workers' first start-up (about 1-3 s).
    """
    if os.environ.get("TAOPT_SOLVER_THREADS") == "1":
        return 1
    large = sum(len(c.targets) >= PARALLEL_MIN_TARGETS for c in classes)
    return 1 if large < 2 else min(large, available_cores())


def _pool_key(workers: int) -> tuple[str, int]:
    """The key of the capability model's pool of ``workers`` processes
    (:func:`taopt.runtime.workers.shared_pool`)."""
    return ("capability", workers)


def _class_pool(workers: int) -> WorkerPool:
    """A pool of ``workers`` spawned processes, created on first use and kept for reuse.

    "spawn", not "fork": HiGHS's threads do not survive a fork. One HiGHS / BLAS thread each
    (the workers are the parallelism, and a nested ``solve_capability`` inside a worker stays
    serial); ``__main__`` hidden while they start, so a caller's script without a
    ``__main__`` guard is not run again by them. The first call pays the workers' start-up
    (the imports, about a second each); later calls reuse them.
    """
    return shared_pool(_pool_key(workers), workers, hide_main=True)


def _solve_class(problem: Any, options: dict[str, Any], submitted: float) -> Solution:
    """In a worker: ``solve_routing`` with the time limit less the wait since submission."""
    options = dict(options)
    if "time_limit" in options:  # time.time(): the one clock the processes share
        options["time_limit"] = max(options["time_limit"] - (time.time() - submitted), 0.01)
    return solve_routing(problem, **options)


def _class_options(
    sec: str, mip_gap: float, verbose: bool, share: float | None, given: Any, improve: Any = None
) -> dict[str, Any]:
    options: dict[str, Any] = {"sec": sec, "mip_gap": mip_gap, "verbose": verbose}
    if improve is not None:
        options["improve"] = improve
    if share is not None:
        options["time_limit"] = max(share, 0.01)
    if given is not None and _routing_takes_incumbent():
        options["incumbent"] = given
    return options


def _solve_classes_serial(
    jobs: list[tuple[Any, Any]], left: Any, options: Any, least: float = -math.inf
) -> dict[Hashable, Solution]:
    """Classes one after another, each with an equal share of the time left; the classes
    still to come when less than ``least`` seconds are left are not started."""
    results = {}
    for index, (cls, given) in enumerate(jobs):
        if left() < least:
            break
        share = left() / (len(jobs) - index) if math.isfinite(left()) else None
        results[cls.capability] = solve_routing(cls.problem, **options(share, given))
    return results


def _solve_classes_parallel(
    jobs: list[tuple[Any, Any]], left: Any, options: Any, workers: int
) -> dict[Hashable, Solution]:
    """Classes in ``workers`` processes, largest first; a class missing from the answer
    ran past its limit by more than :data:`WORKER_GRACE` (the pool is then killed).

    At most ``workers`` classes run at once; a class is given the time left divided by the
    number of waves still to come (``ceil(r / workers)`` for ``r`` classes not started), so
    with no more classes than workers each gets all the time left.
    """
    pool = _class_pool(workers)
    waiting = sorted(jobs, key=lambda job: -len(job[0].targets))
    running: dict[Future, Hashable] = {}
    results: dict[Hashable, Solution] = {}
    try:
        while waiting or running:
            while waiting and len(running) < workers:
                cls, given = waiting.pop(0)
                waves = math.ceil((len(waiting) + 1) / workers)
                share = left() / waves if math.isfinite(left()) else None
                future = pool.submit(_solve_class, cls.problem, options(share, given), time.time())
                running[future] = cls.capability
            done, _ = wait(running, timeout=0.2, return_when=FIRST_COMPLETED)
            for future in done:
                capability = running.pop(future)
                try:
                    results[capability] = future.result()
                except BrokenProcessPool as error:
                    raise SolverError(
                        f"the worker process solving capability class {capability!r} died "
                        "(killed, or out of memory); run again with workers=1 to see why"
                    ) from error
            if running and left() < -WORKER_GRACE:
                logger.warning(
                    "capability classes %s ran %.0f s past the time limit: workers killed",
                    sorted(map(str, running.values())),
                    WORKER_GRACE,
                )
                drop_pool(_pool_key(workers))
                break
    except BaseException:  # Ctrl-C or a class's error: stop every worker, then raise
        drop_pool(_pool_key(workers))
        raise
    return results


@dataclass
class ClassSolve:
    """The classes of a split problem, each certified by :func:`solve_routing`.

    Attributes
    ----------
    results : dict
        Capability -> the class's :class:`Solution` (routes in the class problem's
        indexing); only classes with targets.
    per_class : list of dict
        One row per class (empty ones included): capability, targets, vehicles, status,
        objective, bound, runtime.
    bound : float
        Σ of the classes' proven bounds (0 for a class without one).
    stopped_by : str
        "optimal" when every class is; else the first unfinished class's reason.
    workers : int
        Processes used (1: in this process).
    """

    results: dict[Hashable, Solution]
    per_class: list[dict[str, Any]]
    bound: float
    stopped_by: str
    workers: int

    @property
    def complete(self) -> bool:
        """Whether every class has routes (a class may have none at a time limit)."""
        return all(r.routes is not None for r in self.results.values())

    def class_routes(self) -> dict[Hashable, list[list[int]]]:
        """Capability -> the class's routes (class indexing), for ``CapabilityProblem.join``."""
        return {cap: r.routes for cap, r in self.results.items()}


def solve_classes(
    classes: Any,
    *,
    time_limit: float | None,
    start: float,
    incumbents: Any = None,
    sec: str = "dfj",
    mip_gap: float = 1e-6,
    verbose: bool = False,
    workers: int | None = None,
    improve: Any = None,
) -> ClassSolve:
    """One certified (2.2)–(2.5) per class; a wall-clock limit shared between the classes.

    Parameters
    ----------
    classes : sequence of CapabilityClass
        The exact split (§3.6): ``capability``, ``targets``, ``vehicles`` and the class's
        chapter 2 ``problem`` (None for a class without targets).
    time_limit : float, optional
        Seconds for all classes together, counted from ``start``.
    start : float
        ``time.perf_counter()`` when the caller's clock started.
    incumbents : mapping, optional
        Capability -> routes in the class's indexing (or None), offered to each class.
    sec, mip_gap, verbose, improve
        Passed to :func:`solve_routing` (``improve`` must be a module-level function when
        the classes run in worker processes).
    workers : int, optional
        Processes (default: :func:`_auto_workers`).

    Returns
    -------
    ClassSolve

    Notes
    -----
    Serially (``workers == 1``) classes are solved smallest first, each with an equal share
    of the time left (so a hard class cannot starve the others); in worker processes,
    largest first, each with the time left over the waves still to come. With time to
    spare, classes stopped by their share are solved again with the rest (their best routes
    and largest proven bound are kept). A class killed past its limit keeps its incumbent
    (if any) with bound 0 and status "time_limit". Shared by chapter 3's corrected model
    and chapter 4's certified optimum f_o.

    References
    ----------
    Thesis §3.4.2 and §3.6 (the split by class); §4.3 (f_o).
    """
    classes = list(classes)
    starts = dict(incumbents or {})
    solvable = sorted((c for c in classes if c.problem), key=lambda c: len(c.targets))
    if workers is None:
        # a limit shorter than the workers' start-up (seconds, more under load) is kept only
        # in this process: the wall-clock limit counts the start-up too
        short = time_limit is not None and time_limit < PARALLEL_MIN_SECONDS
        workers = 1 if short else _auto_workers(solvable)
    workers = min(workers, max(len(solvable), 1))

    def left() -> float:
        return time_limit - (time.perf_counter() - start) if time_limit is not None else math.inf

    def options(share: float | None, given: Any) -> dict[str, Any]:
        return _class_options(sec, mip_gap, verbose, share, given, improve)

    def solve(jobs: list[tuple[Any, Any]], least: float = -math.inf) -> dict[Hashable, Solution]:
        if workers > 1 and len(jobs) > 1:
            return _solve_classes_parallel(jobs, left, options, workers)
        return _solve_classes_serial(jobs, left, options, least)

    results = solve([(cls, starts.get(cls.capability)) for cls in solvable])
    for cls in solvable:  # a class killed past its limit: its incumbent (if any), bound 0
        if cls.capability not in results:
            given = starts.get(cls.capability)
            results[cls.capability] = finish(
                cls.problem,
                None if given is None else Routes(given),
                method="exact-dfj",
                stop="time_limit",
                bound=0.0,
                runtime=time.perf_counter() - start,
                info={"killed": True},
            )
    unfinished = [c for c in solvable if results[c.capability].status != OPTIMAL]
    if unfinished and left() >= 0.05:
        again_all = solve([(cls, results[cls.capability].routes) for cls in unfinished], 0.05)
        for cls in unfinished:
            first, again = results[cls.capability], again_all.get(cls.capability)
            if again is None:
                continue
            best = again if again.objective < first.objective else first
            proven = max(b for b in (first.bound, again.bound, 0.0) if b is not None)
            results[cls.capability] = finish(
                cls.problem,
                best.solution,
                method=best.method,
                stop="time_limit",
                bound=proven,
                runtime=first.runtime + again.runtime,
                info={**best.info, "passes": 2},
            )
    stopped_by = "optimal"
    bound = 0.0
    per_class = []
    for cls in classes:
        if cls.problem is None:
            per_class.append({"capability": str(cls.capability), "targets": 0})
            continue
        result = results[cls.capability]
        bound += result.bound if result.bound is not None else 0.0
        if result.status != OPTIMAL and stopped_by == "optimal":
            stopped_by = result.info.get("stopped_by", str(result.status))
        per_class.append(
            {
                "capability": str(cls.capability),
                "targets": len(cls.targets),
                "vehicles": len(cls.vehicles),
                "status": str(result.status),
                "objective": result.objective,
                "bound": result.bound,
                "runtime": result.runtime,
            }
        )
    return ClassSolve(results, per_class, bound, stopped_by, workers)


def _solve_corrected(
    problem: CapabilityProblem,
    time_limit: float | None,
    incumbent: Any,
    sec: str,
    mip_gap: float,
    verbose: bool,
    start: float,
    workers: int | None = None,
    improve: Any = None,
) -> Solution:
    """One certified (2.2)–(2.5) per class (:func:`solve_classes`), joined."""
    split = solve_classes(
        problem.classes,
        time_limit=time_limit,
        start=start,
        incumbents=class_incumbents(problem, incumbent),
        sec=sec,
        mip_gap=mip_gap,
        verbose=verbose,
        workers=workers,
        improve=improve,
    )
    info = {
        "formulation": "corrected",
        "sec": sec,
        "workers": split.workers,
        "classes": split.per_class,
    }
    if not split.complete:  # a class has no plan in time
        return finish(
            problem,
            None,
            method="exact-corrected",
            stop="time_limit",
            bound=split.bound,
            runtime=time.perf_counter() - start,
            info=info,
        )
    return finish(  # certified on the scored objective (gap 0 when bound >= it)
        problem,
        Routes(problem.join(split.class_routes())),
        method="exact-corrected",
        stop=split.stopped_by,
        bound=split.bound,
        runtime=time.perf_counter() - start,
        info=info,
    )


# ------------------------------------------------------------------------------- joint
def _joint_arcs(problem: CapabilityProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    n = problem.n
    tails, heads, classes = [], [], []
    for q, cls in enumerate(problem.classes):
        if cls.problem is None:
            continue
        points = list(cls.targets) + [n + k for k in cls.vehicles]
        cost = problem.cost_for(cls.capability)
        for i in points:
            for j in cls.targets:
                if i != j and math.isfinite(cost[i, j]):
                    tails.append(i)
                    heads.append(j)
                    classes.append(q)
    return np.array(tails, int), np.array(heads, int), np.array(classes, int)


def build_joint(
    problem: CapabilityProblem,
    sec: str = "dfj",
    cuts: list[tuple[int, tuple[int, ...]]] | None = None,
    relax: bool = False,
) -> CapabilityModel:
    """Build the corrected model as one MILP over all classes (see the module notes).

    Parameters
    ----------
    problem : CapabilityProblem
    sec : {"dfj", "mtz"}
        How (2.5) is written per class; for "dfj" only ``cuts`` are present.
    cuts : list of (class index q, subset of targets), optional
    relax : bool

    Returns
    -------
    CapabilityModel
        ``labels`` are class indices q.
    """
    _check(problem)
    if sec not in JOINT_SUBTOUR_ELIMINATIONS:
        raise InstanceError(f"sec must be one of {JOINT_SUBTOUR_ELIMINATIONS}, got {sec!r}")
    n, m = problem.n, problem.m
    size = n + m
    n_classes = len(problem.capabilities)
    tails, heads, classes = _joint_arcs(problem)
    count = len(tails)
    arcs = np.arange(count)
    travel_time = np.array(
        [
            problem.cost_for(problem.capabilities[q])[i, j]
            for i, j, q in zip(tails, heads, classes, strict=True)
        ]
    )
    sigma = (
        cp.Variable(count, name="sigma_ijq", nonneg=True)
        if relax
        else cp.Variable(count, name="sigma_ijq", boolean=True)
    )
    demand_keys = sorted({(int(j), int(q)) for j, q in zip(heads, classes, strict=True)})
    demand_rows = {key: r for r, key in enumerate(demand_keys)}
    row = np.array([demand_rows[int(j), int(q)] for j, q in zip(heads, classes, strict=True)])
    into = sp.csr_matrix((np.ones(count), (row, arcs)), shape=(len(demand_rows), count))
    out_of = sp.csr_matrix(
        (np.ones(count), (tails * n_classes + classes, arcs)), shape=(size * n_classes, count)
    )
    constraints = [
        (into @ sigma == 1).set_label("(3.2) every demanded (target, class) entered once"),
        (out_of @ sigma <= 1).set_label("(3.3) every point left at most once per class"),
    ]
    if relax:
        constraints.append((sigma <= 1).set_label("0 <= sigma_ijq <= 1 (LP relaxation)"))
    order = None
    cuts = list(cuts or [])
    if sec == "dfj" and cuts:
        rows, cols = [], []
        for r, (q, subset) in enumerate(cuts):
            inside = np.isin(tails, subset) & np.isin(heads, subset) & (classes == q)
            cols.extend(np.flatnonzero(inside))
            rows.extend([r] * int(inside.sum()))
        lhs = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(cuts), count))
        rhs = np.array([len(s) - 1 for _, s in cuts], dtype=float)
        constraints.append(
            (lhs @ sigma <= rhs).set_label("(2.5) DFJ per class: sum_{i,j in S} sigma_ijq <= |S|-1")
        )
    elif sec == "mtz":
        # u[q, j] in [1, |T_q|]: target j's position on its class-q route. For a target arc
        # i -> j of class q: u_qi - u_qj + |T_q| sigma_ijq <= |T_q| - 1. Big-M: sigma = 1
        # forces u_qj >= u_qi + 1 (no cycle); sigma = 0 leaves u_qi - u_qj <= |T_q| - 1,
        # always true for positions in [1, |T_q|], so M = |T_q| cuts no route.
        order = cp.Variable(n_classes * n, name="u_qj")
        sizes = np.array([len(c.targets) for c in problem.classes], dtype=float)
        target_arcs = np.flatnonzero(tails < n)
        k = len(target_arcs)
        tail_of = sp.csr_matrix(
            (np.ones(k), (np.arange(k), classes[target_arcs] * n + tails[target_arcs])),
            shape=(k, n_classes * n),
        )
        head_of = sp.csr_matrix(
            (np.ones(k), (np.arange(k), classes[target_arcs] * n + heads[target_arcs])),
            shape=(k, n_classes * n),
        )
        big = sizes[classes[target_arcs]]
        upper = np.repeat(np.maximum(sizes, 1.0), n)
        constraints += [
            (order >= 1).set_label("MTZ: 1 <= u_qj"),
            (order <= upper).set_label("MTZ: u_qj <= |T_q|"),
            (
                tail_of @ order - head_of @ order + cp.multiply(big, sigma[target_arcs]) <= big - 1
            ).set_label("(2.5) MTZ per class: u_qi - u_qj + |T_q| sigma_ijq <= |T_q| - 1"),
        ]
    objective = cp.Minimize(travel_time @ sigma)  # (3.1)
    return CapabilityModel(
        problem=cp.Problem(objective, constraints),
        arc_use=sigma,
        tails=tails,
        heads=heads,
        labels=classes,
        formulation="joint",
        order=order,
        cuts=cuts,
    )


def _joint_decode(
    problem: CapabilityProblem, model: CapabilityModel, values: np.ndarray
) -> tuple[list[list[int]], list[tuple[int, tuple[int, ...]]]]:
    """Routes from the class starts and the cycles among targets, per class."""
    n = problem.n
    used = np.flatnonzero(np.asarray(values) > 0.5)
    routes: list[list[int]] = [[] for _ in range(problem.m)]
    cycles: list[tuple[int, tuple[int, ...]]] = []
    for q, cls in enumerate(problem.classes):
        if cls.problem is None:
            continue
        successor = {int(model.tails[a]): int(model.heads[a]) for a in used if model.labels[a] == q}
        seen: set[int] = set()
        for k in cls.vehicles:
            point, route = n + k, []
            while point in successor:
                point = successor[point]
                route.append(point)
            routes[k] = route
            seen.update(route)
        left = [t for t in cls.targets if t not in seen]
        while left:
            cycle, point = [], left[0]
            while point not in cycle:
                cycle.append(point)
                point = successor[point]
            cycles.append((q, tuple(sorted(cycle))))
            left = [t for t in left if t not in cycle]
    return routes, cycles


def _repair(
    problem: CapabilityProblem, routes: list[list[int]], cycles: list[tuple[int, tuple[int, ...]]]
) -> list[list[int]]:
    """A feasible solution from routes plus subtours: each cycle appended to a class route."""
    routes = [list(r) for r in routes]
    for q, cycle in cycles:
        vehicle = problem.classes[q].vehicles[0]
        routes[vehicle].extend(cycle)
    return routes


def _solve_joint(
    problem: CapabilityProblem,
    time_limit: float | None,
    incumbent: Any,
    sec: str,
    mip_gap: float,
    verbose: bool,
    start: float,
    max_rounds: int = 10_000,
) -> Solution:
    if sec not in JOINT_SUBTOUR_ELIMINATIONS:
        raise InstanceError(f"sec must be one of {JOINT_SUBTOUR_ELIMINATIONS}, got {sec!r}")
    best_routes: list[list[int]] | None = None
    best_value = math.inf
    if incumbent is not None:
        best_routes = Routes(getattr(incumbent, "solution", incumbent)).as_lists()
        best_value = evaluate_capability(problem, best_routes)
    best_bound = 0.0
    cuts: list[tuple[int, tuple[int, ...]]] = []
    rounds = 0
    stopped_by = "optimal"
    solver_status = ""
    while True:
        rounds += 1
        left = None if time_limit is None else time_limit - (time.perf_counter() - start)
        if left is not None and left <= 0:
            stopped_by = "time_limit"
            break
        building = time.perf_counter()
        model = build_joint(problem, sec, cuts)
        if left is not None:  # cvxpy compiles outside HiGHS's clock: about 4-8x the build
            left = time_limit - (time.perf_counter() - start)
            left -= COMPILE_PER_BUILD * (time.perf_counter() - building) + MARGIN
            if left <= 0:
                stopped_by = "time_limit"
                break
        run = solve_highs(model.problem, time_limit=left, mip_rel_gap=mip_gap, verbose=verbose)
        solver_status = run.solver_status
        if run.status in ("error", "infeasible"):
            raise SolverError(f"HiGHS returned {run.solver_status!r} on the joint model")
        if run.bound is not None:
            best_bound = max(best_bound, run.bound)
        if not run.has_point:
            stopped_by = run.stopped_by
            break
        routes, cycles = _joint_decode(problem, model, model.arc_use.value)
        candidate = _repair(problem, routes, cycles) if cycles else routes
        value = evaluate_capability(problem, candidate)
        if value < best_value:
            best_routes, best_value = candidate, value
        if cycles:
            if sec != "dfj":
                raise SolverError(f"the MTZ joint model returned a subtour {cycles[0]}")
            cuts.extend(cycles)
            if run.stopped_by == "time_limit" or rounds >= max_rounds:
                stopped_by = "time_limit" if run.stopped_by == "time_limit" else "max_rounds"
                break
            continue
        stopped_by = run.stopped_by
        break

    def joint_info(stopped: str) -> dict:
        return {
            "formulation": "joint",
            "sec": sec,
            "rounds": rounds,
            "cuts": len(cuts),
            "solver_status": solver_status,
            "stopped_by": stopped,
        }

    if best_routes is None:
        if stopped_by != "time_limit":
            raise SolverError(f"the joint model found no feasible solution ({solver_status})")
        # no plan in time: status time_limit, objective inf, the bound stands
        return finish(
            problem,
            None,
            method="exact-joint",
            stop="time_limit",
            bound=max(best_bound, float(arborescence_lower(problem))),
            runtime=time.perf_counter() - start,
            info=joint_info("time_limit"),
        )
    if stopped_by == "time_limit":  # a valid bound of the family keeps the gap honest
        best_bound = max(best_bound, float(arborescence_lower(problem)))
    bound = best_bound
    info = joint_info(stopped_by)
    return finish(
        problem,
        Routes(best_routes),
        method="exact-joint",
        stop=stopped_by,
        bound=bound,
        runtime=time.perf_counter() - start,
        info=info,
    )


# ------------------------------------------------------------------------------ public
def solve_capability(
    problem: CapabilityProblem,
    formulation: str = "corrected",
    time_limit: float | None = None,
    incumbent: Any = None,
    sec: str = "dfj",
    mip_gap: float = 1e-6,
    verbose: bool = False,
    workers: int | None = None,
    improve: Any = None,
) -> Solution:
    """Solve chapter 3's problem (3.1)–(3.3) with one of three formulations.

    Parameters
    ----------
    problem : CapabilityProblem
    formulation : {"printed", "corrected", "joint"}
        "printed": (3.1)–(3.3) literally, a relaxation (status "relaxation", no routes,
        ``info`` lists its arcs, subtours, foreign tails and vehicle switches; status
        "optimal" with routes in the rare case its arcs are a routing). "corrected": one
        certified (2.2)–(2.5) per capability class (:func:`taopt.models.solve_routing`),
        summed. "joint": the corrected model as one MILP.
    time_limit : float, optional
        Seconds for the whole solve; a limited run returns its best routes with status
        "time_limit" and the proven bound.
    incumbent : routes or Solution, optional
        A feasible solution of the whole problem (e.g. DTAA's); passed on per class
        ("corrected", when ``solve_routing`` takes one) or kept as the first incumbent
        ("joint"). Never computed here: :func:`taopt.solve` supplies it.
    sec : str
        Subtour elimination: "dfj" (default), "mtz" (both formulations) or "flow"
        ("corrected" only).
    mip_gap : float
        HiGHS ``mip_rel_gap``.
    verbose : bool
        HiGHS log.
    workers : int, optional
        "corrected": worker processes solving the classes at the same time (spawned once
        and kept for the next call). Default: one per core this process may use
        (``os.sched_getaffinity``), at most one per class of at least
        :data:`PARALLEL_MIN_TARGETS` targets, so 1 when fewer than two classes are that
        large, and 1 inside a study's task (``TAOPT_SOLVER_THREADS=1``); 1 solves the
        classes one after another in this process. The optimum does not depend on it.
    improve : callable, optional
        "corrected": passed to each class's :func:`taopt.models.solve_routing`
        (``improve(class_problem, routes) -> routes`` on the class's chapter-2 problem).
        Never computed here: :func:`taopt.solve` passes the registered improver
        (:func:`taopt.registry.improver`).

    Returns
    -------
    Solution
        Routes (one per vehicle), objective = ``evaluate(routes)``, status by the one rule
        of :func:`taopt.status.decide`, ``bound`` the sum of the proven class bounds
        (corrected) or the MIP bound (joint); ``info["classes"]`` has each class's status,
        objective, bound and time, ``info["workers"]`` the processes used (corrected).

    Raises
    ------
    InstanceError
        Not a CapabilityProblem, unknown formulation or ``sec``, a non-positive time limit.
    FeasibilityError
        An incumbent that is not a feasible solution (named by the scorer).
    SolverError
        HiGHS failed.

    References
    ----------
    Thesis §3.2.1 (3.1)–(3.3), §3.4.2 and §3.6 (the split by class), §2.2.1 (2.2)–(2.5).
    """
    _check(problem)
    if formulation not in FORMULATIONS:
        raise InstanceError(f"formulation must be one of {FORMULATIONS}, got {formulation!r}")
    if time_limit is not None and not time_limit > 0:
        raise InstanceError(f"time_limit must be positive, got {time_limit}")
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
    ):
        raise InstanceError(f"workers must be a positive integer, got {workers!r}")
    start = time.perf_counter()
    if formulation == "printed":
        return _solve_printed(problem, time_limit, verbose, start)
    if formulation == "corrected":
        return _solve_corrected(
            problem, time_limit, incumbent, sec, mip_gap, verbose, start, workers, improve
        )
    return _solve_joint(problem, time_limit, incumbent, sec, mip_gap, verbose, start)


#: cvxpy's compile for HiGHS takes about 4-8x the time of building a model (see
#: :data:`taopt.models.sop.COMPILE_PER_BUILD`); a round under a limit keeps that in hand.
COMPILE_PER_BUILD = 8.0


def _footprint(problem: CapabilityProblem, options: dict[str, Any]) -> tuple[float, str]:
    """A routing model per capability class (corrected), or all of them in one MILP
    (joint): (n_q + m_q)^2 arcs per class q, the flow version n_q more per arc."""
    flow = options.get("sec", "dfj") == "flow"
    columns = 0.0
    for cls in problem.classes:
        if cls.problem is not None:
            arcs = float(len(cls.targets) + len(cls.vehicles)) ** 2
            columns += arcs * (len(cls.targets) + 1) if flow else arcs
    return milp_bytes(columns), (
        f"the exact models of {problem.n:,} targets, {problem.m} vehicles and "
        f"{len(problem.capabilities)} capabilities (up to {columns:,.0f} columns)"
    )


register_footprint(CapabilityProblem, "exact")(_footprint)
register_footprint(CapabilityProblem, "joint")(_footprint)


def solve_exact(
    problem: CapabilityProblem,
    time_limit: float | None = None,
    incumbent: Any = None,
    sec: str = "dfj",
    workers: int | None = None,
    improve: Any = None,
) -> Solution:
    """Certified optimum of (3.1)–(3.3): the corrected model, one (2.2)–(2.5) per class,
    the classes in ``workers`` processes (default: one per core), each class's incumbents
    improved by ``improve`` (see :func:`solve_capability`)."""
    return solve_capability(
        problem,
        "corrected",
        time_limit=time_limit,
        incumbent=incumbent,
        sec=sec,
        workers=workers,
        improve=improve,
    )


def solve_joint(
    problem: CapabilityProblem,
    time_limit: float | None = None,
    incumbent: Any = None,
    sec: str = "dfj",
) -> Solution:
    """The corrected model as one MILP over all classes (for teaching)."""
    return solve_capability(problem, "joint", time_limit=time_limit, incumbent=incumbent, sec=sec)


def describe(
    problem: CapabilityProblem, formulation: str = "joint", sec: str = "dfj", show: bool = True
) -> list[dict[str, Any]]:
    """Variable and constraint families of the printed or joint model, with equations.

    With ``show`` the table is logged at INFO on the ``taopt`` logger too.

    Returns
    -------
    list of dict
        ``family``, ``equation``, ``rows`` per family.
    """
    if formulation == "printed":
        model = build_printed(problem)
        families = [
            {
                "family": "variables sigma_ijk (binary)",
                "equation": "(3.1)",
                "rows": len(model.tails),
            }
        ]
    elif formulation == "joint":
        model = build_joint(problem, sec)
        families = [
            {
                "family": "variables sigma_ijq (binary)",
                "equation": "(3.1)",
                "rows": len(model.tails),
            }
        ]
        if model.order is not None:
            families.append(
                {
                    "family": "variables u_qj (MTZ order)",
                    "equation": "(2.5)",
                    "rows": int(model.order.size),
                }
            )
    else:
        raise InstanceError("describe() shows the 'printed' or 'joint' model")
    for constraint in model.problem.constraints:
        label = constraint.label or str(constraint)
        equation = label.split(" ")[0] if label.startswith("(") else "bounds"
        families.append({"family": label, "equation": equation, "rows": int(constraint.size)})
    if formulation == "joint" and sec == "dfj":
        families.append(
            {
                "family": "(2.5) DFJ subtour cuts per class, added lazily",
                "equation": "(2.5)",
                "rows": 0,
            }
        )
    if show:
        lines = [
            f"{formulation} model: n={problem.n} targets, m={problem.m} vehicles, "
            f"|A|={len(problem.capabilities)}"
        ]
        lines += [f"  {family['rows']:>8}  {family['family']}" for family in families]
        logger.info("\n".join(lines))
    return families
