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

import math
import sys
import time
from pathlib import Path
from typing import IO, Any

import pandas as pd

from taopt import bounds as bound_functions
from taopt.errors import FeasibilityError, InstanceError, OutputError
from taopt.instance import Instance, load_json
from taopt.limits import check_memory, navigation_bytes
from taopt.pipeline import default_methods, no_optimum_note, solve
from taopt.registry import family_for_kind, family_of
from taopt.result import OPTIMAL, Solution
from taopt.routing.problem import AssignmentProblem
from taopt.schemas import naming
from taopt.scoring import evaluate

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

    # the size guard: the matrix and navigation's work arrays, before navigating
    points = instance.n_targets + len(instance.vehicles)
    check_memory(
        navigation_bytes(points),
        f"the travel-time matrix of {instance.name or 'this instance'} "
        f"({instance.n_targets:,} targets + {len(instance.vehicles)} vehicles = "
        f"{points:,} points, {points**2:,} pairs)",
    )
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
        targets, vehicles = data.get("targets"), data.get("vehicles")
        if isinstance(targets, list) and isinstance(vehicles, list):  # before validating
            points = len(targets) + len(vehicles)
            check_memory(
                navigation_bytes(points),
                f"{path}: the travel-time matrix of {len(targets):,} targets + "
                f"{len(vehicles)} vehicles ({points:,} points)",
            )
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
    has one; not a valid bound on asymmetric costs) and ``seconds``.
    """
    methods = list(methods) if methods else default_methods(problem)
    solutions = {m: solve(problem, m, seed=seed, time_limit=time_limit) for m in methods}
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
            }
        )
    table = pd.DataFrame(rows).dropna(axis=1, how="all")
    return table, solutions


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
        PNG of the best solution (the family's first plot): routes over the drift field
        along their minimum-time paths (instance files, as ``taopt demo`` draws them), routes
        on a schematic MDS layout (matrix files, said in the caption), the plan on the
        streets (delivery), the order as a position/cost chart with its precedences (SOP),
        the driven trajectories (comm). The drawn solution is printed under it in the same
        ids.
    gantt : str, optional
        PNG of the truck and drone timelines (delivery instances).

    Raises
    ------
    OutputError
        ``plot`` or ``gantt`` not a ``.png`` file, or a Gantt chart asked of a file that is
        not a delivery instance: raised before the file is loaded or anything solved.
    save : path, optional
        Folder: each method's solution is written there as ``<method>.json``, which
        ``taopt verify`` re-checks.

    Returns
    -------
    dict with ``problem``, ``instance``, ``table`` (DataFrame) and ``solutions``.
    """
    out = out or sys.stdout
    tic = time.perf_counter()
    _check_plot_request(path, plot, gantt)  # before any matrix is computed or model solved
    problem, instance = load_problem_file(path, progress=progress)
    family = family_of(problem)
    table, solutions = method_table(problem, methods, seed=seed, time_limit=time_limit)
    print(f"{problem!r} from {path}", file=out)
    print(table.to_string(index=False, float_format=lambda v: f"{v:.6g}"), file=out)
    note = "" if methods else no_optimum_note(problem)
    if note:
        print(note, file=out)
    best = min(solutions.values(), key=lambda s: s.objective)
    if save:
        folder = Path(save)
        folder.mkdir(parents=True, exist_ok=True)
        for method, sol in solutions.items():
            sol.save(folder / f"{method}.json")
        print(f"solutions written to {folder}/<method>.json", file=out)
    if plot:
        name, draw = next(iter(family.plots.items()))
        draw(problem, best.solution, plot, instance=instance, method=best.method)
        print(f"{name} plot of {best.method} written to {plot}", file=out)
        for line in _route_lines(best, instance, problem):
            print(line, file=out)
    if gantt:
        family.plots["gantt"](problem, best.solution, gantt, instance=instance, method=best.method)
        print(f"Gantt chart of {best.method} written to {gantt}", file=out)
    print(f"({time.perf_counter() - tic:.2f} s)", file=out)
    return {"problem": problem, "instance": instance, "table": table, "solutions": solutions}


def _check_plot_request(path: str | Path, plot: str | None, gantt: str | None) -> None:
    """Refuse a plot request before any work: wrong extension, or a kind with no such plot."""
    from taopt.plot import check_output

    check_output(plot, ".png", "--plot")
    check_output(gantt, ".png", "--gantt")
    if not (plot or gantt):
        return
    data = load_json(path)
    kind = data.get("kind") if isinstance(data, dict) else None
    if kind == "instance":  # becomes a chapter 2 or 3 problem: both draw routes, neither a Gantt
        plots: tuple[str, ...] = ("routes",)
    else:
        try:
            plots = tuple(family_for_kind(kind).plots)
        except InstanceError:  # an unknown kind: the loader says so, with the schema's words
            return
    if gantt and "gantt" not in plots:
        raise OutputError(f"--gantt draws delivery plans (truck and drone); {path} is a {kind}")
    if plot and not plots:
        raise OutputError(f"--plot: no plot for a {kind} file ({path})")


def _route_lines(best: Solution, instance: Instance | None, problem: Any) -> list[str]:
    """The plotted solution spelt with the ids written on the picture.

    Routes as ``v0: v0 -> t2 -> t1``; a delivery plan as one ``#p: customer j, launch s<i>,
    landing s<k>`` line per sortie; an SOP order as its node sequence. Other payloads
    (trajectories) print nothing here.
    """
    payload = best.solution
    if hasattr(payload, "launch") and hasattr(payload, "landing"):  # a delivery Plan
        sorties = zip(payload.order, payload.launch, payload.landing, strict=True)
        return [
            f"  #{p + 1}: customer {j}, launch s{i}, landing s{k}"
            for p, (j, i, k) in enumerate(sorties)
        ]
    if hasattr(payload, "sequence"):  # an SOP Order
        return ["  order: " + " -> ".join(str(v) for v in payload.sequence)]
    routes = getattr(payload, "routes", None)
    if routes is None:
        return []
    from taopt.routing.plot import route_text

    routes = [list(r) for r in routes]
    if instance is not None:
        targets = [t.id for t in instance.targets]
        vehicles = [v.id for v in instance.vehicles]
    else:
        targets = [f"t{k}" for k in range(problem.n_targets)]
        vehicles = [f"v{k}" for k in range(len(routes))]
    return [f"  {route_text(vehicles[k], r, targets)}" for k, r in enumerate(routes)]


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
