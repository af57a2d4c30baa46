"""Chapter 3's corrected model (``solve_capability(problem, "corrected")``, what
``taopt.solve(problem, "exact")`` runs): one certified (2.2)–(2.5) per capability class
(:func:`~taopt.models.capability_corrected.solve_classes`, shared with chapter 4's f_o), joined.

The classes run in this process or in the worker processes of
:mod:`taopt.models.capability`, which imports this module; its pool functions are therefore
looked up there when :func:`~taopt.models.capability_corrected.solve_classes` runs.

References
----------
Thesis §3.4.2 and §3.6 (the split by class), §2.2.1 (2.2)–(2.5), §4.3 (f_o).
"""

from __future__ import annotations

import math
import time
from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any

from taopt.capability.problem import CapabilityProblem, evaluate_capability
from taopt.result import OPTIMAL, Routes, Solution, finish


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


@dataclass
class ClassSolve:
    """The classes of a split problem, each certified by :func:`~taopt.models.routing.solve_routing`.

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
        """Capability -> the class's routes (class indexing), for ``CapabilityProblem.join``;
        a class without routes is left out (none is when :attr:`complete`)."""
        return {cap: r.routes for cap, r in self.results.items() if r.routes is not None}


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
        Passed to :func:`~taopt.models.routing.solve_routing` (``improve`` must be a module-level function when
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
    # the process pool lives in taopt.models.capability, which imports this module: looked up
    # at call time (it is to move to a runtime package of its own, issue 31 item 2)
    from taopt.models.capability import (
        PARALLEL_MIN_SECONDS,
        _auto_workers,
        _class_options,
        _solve_classes_parallel,
        _solve_classes_serial,
    )

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
    """One certified (2.2)–(2.5) per class (:func:`~taopt.models.capability_corrected.solve_classes`), joined."""
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
