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
  the true optimum; :func:`~taopt.models.capability_printed.decode_printed` shows what went wrong in its arcs.

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

Modules (split by job): :mod:`~taopt.models.capability_printed`,
:mod:`~taopt.models.capability_corrected` and :mod:`~taopt.models.capability_joint` hold
the three formulations, :mod:`~taopt.models.capability_model` the model they build; this
module holds :func:`solve_capability`, :func:`describe` and the worker processes of the
corrected model. Every public name is importable from here.

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
from typing import Any

from taopt.capability.problem import CapabilityProblem
from taopt.errors import InstanceError, SolverError
from taopt.models.capability_corrected import (
    ClassSolve,
    _solve_corrected,
    class_incumbents,
    solve_classes,
)
from taopt.models.capability_joint import (
    COMPILE_PER_BUILD,
    JOINT_SUBTOUR_ELIMINATIONS,
    _solve_joint,
    build_joint,
)
from taopt.models.capability_model import CapabilityModel, _check
from taopt.models.capability_printed import (
    PRINTED_MAX_VARIABLES,
    PrintedArcs,
    _solve_printed,
    build_printed,
    decode_printed,
)
from taopt.models.routing import solve_routing
from taopt.result import Solution
from taopt.runtime import milp_bytes, register_footprint
from taopt.runtime.workers import WorkerPool, drop_pool, shared_pool

logger = logging.getLogger(__name__)  # a child of the "taopt" logger

FORMULATIONS = ("printed", "corrected", "joint")
__all__ = [
    "FORMULATIONS",
    "JOINT_SUBTOUR_ELIMINATIONS",
    "PRINTED_MAX_VARIABLES",
    "COMPILE_PER_BUILD",
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
                try:
                    future = pool.submit(
                        _solve_class, cls.problem, options(share, given), time.time()
                    )
                except BrokenProcessPool as error:  # a worker died before this submission
                    dead = sorted(map(str, running.values())) or [str(cls.capability)]
                    raise SolverError(
                        f"the worker process solving capability class {', '.join(dead)} died "
                        "(killed, or out of memory); run again with workers=1 to see why"
                    ) from error
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
