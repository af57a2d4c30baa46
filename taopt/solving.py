"""``taopt solve FILE`` and ``taopt verify SOLUTION INSTANCE``: files in, certified tables out.

A problem file is one of taopt's JSON kinds (schema_version 1, checked against its JSON
Schema before anything is built; see ``docs/file-formats.md``):

* ``"instance"`` (:class:`taopt.Instance`): vehicles, targets, region, a drift field and
  obstacles; its travel-time matrix is computed by navigation and it becomes the chapter 2
  problem (one capability, one speed, no obstacles) or the chapter 3 problem;
* the kind of any registered family: ``"assignment_problem"``, ``"delivery_instance"``,
  ``"sop_problem"``, ``"capability_problem"``, ``"comm_problem"`` (see
  :func:`taopt.registry.file_kinds`).

Every method is run through :func:`taopt.solve` (which re-scores the result with the
family's one scorer) and printed in one table with its status, proven bound and gap, its
ratio to a valid lower bound and, when an optimum is certified, its true gap.

Example files ship with the package: ``taopt/data/demo.json`` (an instance),
``taopt/data/delivery_example_20.json`` (a delivery instance) and the small examples in
``taopt/data/examples/``.
"""

from __future__ import annotations

import logging
import math
import sys
import time
from pathlib import Path
from typing import IO, Any

import pandas as pd

from taopt import bounds as bound_functions
from taopt.errors import FeasibilityError, InstanceError
from taopt.instance import Instance, load_json
from taopt.pipeline import default_methods, solve
from taopt.registry import family_for_kind, family_of, get_method
from taopt.result import ERROR, OPTIMAL, Solution
from taopt.routing.problem import AssignmentProblem
from taopt.schemas import naming
from taopt.scoring import evaluate

logger = logging.getLogger("taopt")

__all__ = [
    "problem_from_instance",
    "load_problem_file",
    "method_table",
    "solve_file",
    "verify_file",
]


def problem_from_instance(instance: Instance, progress: bool = True) -> Any:
    """The problem of an :class:`Instance`: its travel-time matrix by navigation.

    One capability, one speed and no obstacles give the chapter 2 problem (2.2)–(2.5);
    anything else the chapter 3 problem (3.1)–(3.3), when chapter 3 is installed.
    """
    from taopt.navigation import travel_time_matrix

    speeds = {v.speed for v in instance.vehicles}
    capabilities = {v.capability for v in instance.vehicles}
    if len(speeds) == 1 and len(capabilities) == 1 and not instance.obstacles:
        matrix = travel_time_matrix(
            instance.field, instance.points, speeds.pop(), progress=progress
        )
        return AssignmentProblem(matrix, n_targets=instance.n_targets, name=instance.name)
    try:
        from taopt.capability.instances import capability_problem_from_instance
    except ImportError:
        raise InstanceError(
            "this instance has several capabilities, speeds or obstacles: it needs the "
            "chapter 3 problem (3.1)-(3.3), which this taopt cannot build"
        ) from None
    return capability_problem_from_instance(instance)


def load_problem_file(path: str | Path, progress: bool = True) -> tuple[Any, Instance | None]:
    """(problem, instance) from a JSON file; ``instance`` is None unless it is an instance."""
    data = load_json(path)
    if not isinstance(data, dict):
        raise InstanceError(f"{path}: a problem file holds a JSON object")
    if data.get("kind") == "instance":
        instance = Instance.from_dict(data, source=str(path))
        return problem_from_instance(instance, progress=progress), instance
    family = family_for_kind(data.get("kind"))
    with naming(str(path)):  # the schema's and the constructor's errors name the file
        return family.load(data), None


def _bound(name: str, problem: Any) -> float:
    if name not in family_of(problem).bounds:
        return math.nan
    return float(getattr(bound_functions, name)(problem))


def method_table(
    problem: Any,
    methods: tuple[str, ...] | list[str] | None = None,
    seed: int = 0,
    time_limit: float | None = None,
) -> tuple[pd.DataFrame, dict[str, Solution]]:
    """Solve ``problem`` with each method; a table of objectives, bounds and gaps.

    Columns: method, status, objective, ``bound`` and ``gap`` (what the method proves),
    ``gap_to_optimum`` (f / f_o − 1 against a certified optimum found in this run — the
    true gap the thesis could not measure), ``q_valid`` (f / the family's valid
    arborescence bound), ``q_thesis`` (f / the thesis's Algorithm 1 value, where the family
    has one; not a valid bound on asymmetric costs), ``seconds`` and, when some method
    failed, ``message``.

    A method that raises does not sink the table: its row has status "error", objective
    NaN and the exception's first line in ``message`` (its Solution carries it in
    ``info["error"]``); the other rows stand. An unknown method name is still refused
    (InstanceError) before anything runs. Ctrl-C (KeyboardInterrupt) stops the whole run.
    """
    methods = list(methods) if methods else default_methods(problem)
    for method in methods:  # an unknown name is the user's error: refuse before running any
        get_method(problem, method)
    solutions = {m: _run_method(problem, m, seed, time_limit) for m in methods}
    valid = _bound("arborescence", problem)
    thesis = _bound("thesis_mcga", problem)
    optima = [s.objective for s in solutions.values() if s.status == OPTIMAL]
    optimum = min(optima) if optima else math.nan
    rows = []
    for method, sol in solutions.items():
        rows.append(
            {
                "method": method,
                "status": sol.status.value,
                "objective": sol.objective,
                "bound": math.nan if sol.bound is None else sol.bound,
                "gap": math.nan if sol.gap is None else sol.gap,
                "gap_to_optimum": sol.objective / optimum - 1.0 if optimum > 0 else math.nan,
                "q_valid": sol.objective / valid if valid > 0 else math.nan,
                "q_thesis": sol.objective / thesis if thesis > 0 else math.nan,
                "seconds": sol.runtime,
                "message": _short(sol.info.get("error", "")) if sol.status == ERROR else "",
            }
        )
    table = pd.DataFrame(rows).dropna(axis=1, how="all")
    if not table["message"].astype(bool).any():
        table = table.drop(columns="message")
    return table, solutions


def _short(text: str, width: int = 120) -> str:
    """``text`` cut to ``width`` characters for a table cell (the full text is in ``info``)."""
    return text if len(text) <= width else text[: width - 3] + "..."


def _run_method(problem: Any, method: str, seed: int, time_limit: float | None) -> Solution:
    """``solve(problem, method)``, or an "error" row saying what failed and why.

    Any ``Exception`` of one method (a heuristic's dead end, a solver failure, a bug) is
    caught so the other methods' rows stand; ``KeyboardInterrupt`` is not an
    ``Exception`` and still stops the whole run.
    """
    began = time.perf_counter()
    try:
        return solve(problem, method, seed=seed, time_limit=time_limit)
    except Exception as exc:  # noqa: BLE001 -- one failing method must not sink the table
        text = str(exc).splitlines()[0] if str(exc) else ""
        message = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
        logger.info("method %s failed on %r: %s", method, problem, message)
        return Solution(
            objective=math.nan,
            status=ERROR,
            runtime=time.perf_counter() - began,
            method=method,
            info={"error": message},
        )


def solve_file(
    path: str | Path,
    methods: tuple[str, ...] | None = None,
    seed: int = 0,
    time_limit: float | None = 60.0,
    plot: str | None = None,
    gantt: str | None = None,
    save: str | Path | None = None,
    out: IO[str] | None = None,
    progress: bool = True,
) -> dict[str, Any]:
    """Load ``path``, solve it with ``methods`` and print the gap table.

    Parameters
    ----------
    path : str or Path
        A JSON problem file (see the module docstring).
    methods : tuple of str, optional
        Registered methods of the file's problem type (default: its exact methods and
        heuristics; see :func:`taopt.pipeline.default_methods`).
    seed : int
        For randomised methods.
    time_limit : float, optional
        Seconds for each exact model (and peer); a stopped model reports status
        "time_limit" with its proven bound and gap.
    plot : str, optional
        PNG of the best solution (the family's first plot).
    gantt : str, optional
        PNG of the truck and drone timelines (delivery instances).
    save : path, optional
        Folder: each method's solution is written there as ``<method>.json``, which
        ``taopt verify`` re-checks.

    Returns
    -------
    dict with ``problem``, ``instance``, ``table`` (DataFrame), ``solutions`` and ``failed``
    (the methods whose row has status "error"; ``taopt solve`` exits with 1 when there is
    one). Failed methods are not saved and not plotted.
    """
    out = out or sys.stdout
    tic = time.perf_counter()
    problem, instance = load_problem_file(path, progress=progress)
    family = family_of(problem)
    if gantt and "gantt" not in family.plots:
        raise InstanceError(f"--gantt draws delivery plans; {path} is a {family.kind}")
    if plot and not family.plots:
        raise InstanceError(f"no plot for a {family.kind} file")
    if plot and instance is None and family.kind == "assignment_problem":
        raise InstanceError("--plot needs positions: give an 'instance' file, not a matrix")
    table, solutions = method_table(problem, methods, seed=seed, time_limit=time_limit)
    print(f"{problem!r} from {path}", file=out)
    print(table.to_string(index=False, float_format=lambda v: f"{v:.6g}"), file=out)
    found = [s for s in solutions.values() if s.solution is not None and s.status != ERROR]
    best = min(found, key=lambda s: s.objective) if found else None
    failed = [m for m, s in solutions.items() if s.status == ERROR]
    if save:
        folder = Path(save)
        folder.mkdir(parents=True, exist_ok=True)
        for method, sol in solutions.items():
            if sol.status != ERROR:
                sol.save(folder / f"{method}.json")
        print(f"solutions written to {folder}/<method>.json", file=out)
    if best is None:
        plot = gantt = None  # nothing to draw
    if plot:
        name, draw = next(iter(family.plots.items()))
        draw(problem, best.solution, plot, instance=instance)
        print(f"{name} plot of {best.method} written to {plot}", file=out)
    if gantt:
        family.plots["gantt"](problem, best.solution, gantt, instance=instance)
        print(f"Gantt chart of {best.method} written to {gantt}", file=out)
    if failed:
        print(f"failed: {', '.join(failed)} (see the message column)", file=out)
    print(f"({time.perf_counter() - tic:.2f} s)", file=out)
    return {
        "problem": problem,
        "instance": instance,
        "table": table,
        "solutions": solutions,
        "failed": failed,
    }


def verify_file(
    solution_path: str | Path,
    problem_path: str | Path,
    exact: bool = False,
    time_limit: float | None = None,
    out: IO[str] | None = None,
    progress: bool = False,
) -> bool:
    """Re-score a saved solution from the problem file alone and check every constraint.

    Checks: the payload is of the problem's family; the family's scorer accepts it (every
    constraint, the violated one named otherwise); its value equals the saved objective
    (1e-6 relative); a saved bound is not above the objective; a solution called "optimal"
    has a gap of at most 1e-6. With ``exact=True`` the problem is also solved exactly here
    and an "optimal" claim must match that optimum (small instances).

    Returns
    -------
    bool
        True when every check passes (each check is printed).
    """
    out = out or sys.stdout
    problem, _ = load_problem_file(problem_path, progress=progress)
    solution = Solution.load(solution_path)
    family = family_of(problem)
    ok = True

    def report(passed: bool, text: str) -> None:
        nonlocal ok
        ok = ok and passed
        print(f"  [{'ok' if passed else 'FAIL'}] {text}", file=out)

    print(f"{solution_path}: {solution.summary()}", file=out)
    print(f"against {problem!r} from {problem_path}", file=out)
    expected = getattr(family.payload, "payload_kind", None)
    kind = getattr(solution.solution, "payload_kind", None)
    if kind != expected:
        report(False, f"payload is {kind!r}, but a {family.kind} needs {expected!r}")
        return False
    try:
        value = evaluate(problem, solution.solution)
    except FeasibilityError as exc:
        report(False, f"infeasible: {exc}")
        return False
    report(True, f"feasible: every constraint of this {family.kind} holds")
    close = abs(value - solution.objective) <= 1e-6 * max(1.0, abs(value))
    report(
        close,
        f"objective re-scored from the problem: {value:.10g} (saved {solution.objective:.10g})",
    )
    if solution.bound is not None:
        report(
            solution.bound <= value * (1 + 1e-9) + 1e-9,
            f"saved bound {solution.bound:.10g} is not above the objective",
        )
    if solution.status == OPTIMAL:
        gap = solution.gap
        report(gap is not None and gap <= 1e-6, f"an 'optimal' claim carries a proven gap ({gap})")
    if exact:
        certified = solve(problem, "exact", time_limit=time_limit)
        if certified.status == OPTIMAL:
            if solution.status == OPTIMAL:
                report(
                    abs(certified.objective - value) <= 1e-6 * max(1.0, abs(value)),
                    f"re-solved optimum {certified.objective:.10g} equals the saved objective",
                )
            report(
                value >= certified.objective * (1 - 1e-9) - 1e-9,
                f"objective is not below the re-solved optimum {certified.objective:.10g}",
            )
            if solution.bound is not None:
                report(
                    solution.bound <= certified.objective * (1 + 1e-9) + 1e-9,
                    "saved bound is not above the re-solved optimum",
                )
        else:
            print(f"  [--] exact re-solve not certified: {certified.summary()}", file=out)
    print("VALID" if ok else "NOT VALID", file=out)
    return ok
