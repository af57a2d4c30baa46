"""``taopt solve FILE`` and ``taopt verify SOLUTION INSTANCE``: files in, certified tables out.

A problem file is one of taopt's JSON kinds (schema_version 1, checked against its JSON
Schema before anything is built; see ``docs/file-formats.md``):

* ``"instance"`` (:class:`taopt.Instance`): vehicles, targets, region, a drift field and
  obstacles; its travel-time matrix is computed by navigation and it becomes the chapter 2
  problem (one capability, one speed, no obstacles) or the chapter 3 problem;
* the kind of any registered family (:func:`taopt.registry.file_kinds`; each family's spec
  names its kind, schema and loader).

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
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import pandas as pd

import taopt.heuristics  # noqa: F401  (registers the heuristics: get_method below)
import taopt.models  # noqa: F401  (registers the exact models)
from taopt.bounds import lower
from taopt.defaults import SEED, TIME_LIMIT
from taopt.errors import FeasibilityError, InstanceError, OutputError, TaoptError
from taopt.examples import resolve as resolve_example
from taopt.fields import FIELD_KINDS
from taopt.instance import Instance
from taopt.io import atomic_path, check_writable, check_writable_file, load_json
from taopt.orchestration.pipeline import (
    available_methods,
    certifying_method,
    default_methods,
    no_optimum_note,
    solve,
)
from taopt.registry import (
    families,
    family_for_kind,
    family_of,
    file_kinds,
    get_method,
)
from taopt.result import ERROR, NO_SOLUTION, OPTIMAL, Solution, Status
from taopt.runtime import check_memory, navigation_bytes
from taopt.runtime.interrupt import OutOfTime, alarm_after
from taopt.schemas import naming
from taopt.scoring import evaluate

logger = logging.getLogger("taopt")

__all__ = [
    "problem_from_instance",
    "load_problem_file",
    "method_table",
    "solve_file",
    "verify_file",
    "load_certificate",
    "Verdict",
]


def problem_from_instance(instance: Instance, progress: bool = True) -> Any:
    """The problem of an :class:`Instance`, built by the family whose spec accepts it.

    Each family with an ``adapter`` (:class:`taopt.registry.Family`) is asked in turn; e.g.
    one capability, one speed and no obstacles give the chapter 2 problem (2.2)–(2.5) (travel
    times by navigation), anything else the chapter 3 problem (3.1)–(3.3).

    Raises
    ------
    InstanceError
        No family accepts the instance.
    """
    for family in families():
        if family.adapter is not None:
            problem = family.adapter(instance, progress=progress)
            if problem is not None:
                return problem
    raise InstanceError(
        f"no problem family accepts the instance {instance.name or ''!r}: "
        "none of the installed families builds a problem from it"
    )


def load_problem_file(path: str | Path, progress: bool = True) -> tuple[Any, Instance | None]:
    """(problem, instance) from a JSON file (or ``example:NAME``, :mod:`taopt.examples`);
    ``instance`` is None unless it is an instance."""
    path = resolve_example(path)
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
        with naming(str(path)):  # e.g. a target inside an obstacle: name the file
            return problem_from_instance(instance, progress=progress), instance
    kind = data.get("kind")
    if kind == "solution":  # e.g. `taopt verify PROBLEM SOLUTION`, swapped
        raise InstanceError(
            f"{path} is a solution file (kind 'solution'), not a problem; `taopt verify` takes "
            "the solution first, then the problem it solves"
        )
    if kind in FIELD_KINDS:
        raise InstanceError(
            f"{path} is a drift field file (kind {kind!r}), not a problem; use it as "
            f"`taopt navigate --field {path} --from X,Y --to X,Y`, or as the field of an "
            "instance file"
        )
    if kind not in file_kinds():
        known = ", ".join(["instance", *sorted(file_kinds())])
        raise InstanceError(
            f"{path}: unknown file kind {kind!r}; a problem file's kind is one of: {known} "
            "('taopt kinds' describes them)"
        )
    with naming(str(path)):  # the schema's and the constructor's errors name the file
        family = family_for_kind(kind)
        return family.load(data), None


def _ratio_columns(problem: Any) -> dict[str, float]:
    """Denominators of the table's ratio columns, from the family's spec.

    ``q_valid``: the family's fast valid lower bound (:func:`taopt.bounds.lower`); then one
    column per bound whose spec names a ``column`` (e.g. ``q_thesis``, the thesis's
    Algorithm 1 value as printed).
    """
    columns = {"q_valid": lower(problem, "fast")}
    for bound in family_of(problem).bounds.values():
        if bound.column:
            columns[bound.column] = float(bound.func(problem))
    return columns


def method_table(
    problem: Any,
    methods: tuple[str, ...] | list[str] | None = None,
    seed: int = SEED,
    time_limit: float | None = TIME_LIMIT,
    progress: bool = False,
    trace: bool = False,
) -> tuple[pd.DataFrame, dict[str, Solution]]:
    """Solve ``problem`` with each method; a table of objectives, bounds and gaps.

    Columns: method, status, objective, ``bound`` and ``gap`` (what the method proves),
    ``gap_to_optimum`` (f / f_o − 1 against a certified optimum found in this run — the
    true gap the thesis could not measure), ``q_valid`` (f / the family's fast valid lower
    bound, :func:`taopt.bounds.lower`), one ratio per bound the family's spec gives a column
    (``q_thesis``: f / the thesis's Algorithm 1 value, not a valid bound on asymmetric costs),
    ``seconds`` and, when some method failed, ``message``.

    A method that raises does not sink the table: its row has status "error", objective
    NaN and the exception's first line in ``message`` (its Solution carries it in
    ``info["error"]``); the other rows stand. An unknown method name is still refused
    (InstanceError) before anything runs. Ctrl-C (KeyboardInterrupt) stops the whole run.

    ``progress``: a bar on stderr over the methods, naming the one running and, for an exact
    method or a peer, the time limit it may take (a peer stops sooner once it stops improving).

    ``trace``: the methods that keep a trace are run with ``trace=True`` (their rounds in
    ``info["trace"]``, :func:`taopt.plot.trace`); the others as usual.
    """
    methods = resolve_methods(problem, methods)  # an unknown name: refused first
    specs = {m: get_method(problem, m) for m in methods}
    from tqdm.auto import tqdm

    solutions = {}
    with tqdm(methods, unit="method", disable=not progress, leave=False) as bar:
        for method in bar:
            limited = time_limit is not None and specs[method].category in ("exact", "peer")
            bar.set_description(method + (f" (up to {time_limit:g} s)" if limited else ""))
            traced = trace and specs[method].accepts("trace")
            solutions[method] = _run_method(problem, method, seed, time_limit, traced)
    ratios = _ratio_columns(problem)
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
                **{
                    column: sol.objective / value if value > 0 else math.nan
                    for column, value in ratios.items()
                },
                "seconds": sol.runtime,
                "message": (
                    _short(sol.info.get("error", "")) if sol.status in (ERROR, NO_SOLUTION) else ""
                ),
            }
        )
    table = pd.DataFrame(rows).dropna(axis=1, how="all")
    if not table["message"].astype(bool).any():
        table = table.drop(columns="message")
    return table, solutions


def resolve_methods(problem: Any, methods: Any = None) -> list[str]:
    """The registered names of ``methods`` for ``problem``, in order, duplicates dropped.

    None or empty: :func:`~taopt.orchestration.pipeline.default_methods`; ``"all"`` (alone
    or in the list): every method available here (:func:`taopt.available_methods`, what
    ``taopt kinds`` lists). Names are case-insensitive (``"mc"`` is ``"MC"``).

    Raises
    ------
    InstanceError
        An unknown name (the message lists the family's methods), or a method whose package
        is not installed here.
    """
    if not methods:
        return default_methods(problem)
    if isinstance(methods, str):
        methods = [m.strip() for m in methods.split(",") if m.strip()]
    names: list[str] = []
    for name in methods:
        if str(name).strip().lower() == "all":
            names.extend(available_methods(problem))
            continue
        spec = get_method(problem, name)
        if not spec.available:
            raise InstanceError(
                f"method {spec.name!r} needs {', '.join(spec.requires)}, not installed here "
                f"(pip install 'taopt[peers]'); available: "
                f"{', '.join(available_methods(problem))}"
            )
        names.append(spec.name)
    return list(dict.fromkeys(names))


def default_set_note(problem: Any) -> str:
    """What ``taopt solve`` runs when no methods are named, and what it leaves out and why.

    E.g. "default methods: exact, NIA, MMA, SMMA, GA (...); run only when named (--methods
    NAME, or --methods all): ILS (a search with a budget), subset-dp, milp (other exact
    models: the same optimum, slower)".
    """
    chosen = default_methods(problem)
    left = [m for m in available_methods(problem) if m not in chosen]
    text = (
        f"default methods: {', '.join(chosen)} (the certified optimum where affordable, then "
        "the heuristics)"
    )
    if not left:
        return text
    groups: dict[str, list[str]] = {}
    for name in left:
        category = get_method(problem, name).category
        why = {
            "exact": "other exact models: the same optimum, slower",
            "peer": "peers: external solvers, no proof",
            "relaxation": "relaxations: bounds, not solutions",
        }.get(category, "variants and budgeted searches")
        groups.setdefault(why, []).append(name)
    parts = [f"{', '.join(names)} ({why})" for why, names in groups.items()]
    return f"{text}; run only when named (--methods NAME, or --methods all): {'; '.join(parts)}"


#: What the ratio and gap columns of ``taopt solve``'s table mean (printed under it).
COLUMN_NOTES = {
    "gap": "gap = the gap the method proves (objective / its bound - 1)",
    "gap_to_optimum": "gap_to_optimum = objective / the certified optimum of this run - 1",
    "q_valid": "q_valid = objective / the family's fast valid lower bound (>= 1; 1 proves the "
    "objective optimal)",
}


def column_notes(table: pd.DataFrame, problem: Any) -> list[str]:
    """One line per gap or ratio column present in ``table``: what it divides by."""
    notes = [text for column, text in COLUMN_NOTES.items() if column in table.columns]
    for name, bound in family_of(problem).bounds.items():
        if bound.column and bound.column in table.columns:
            kind = f"a valid {bound.side} bound" if bound.valid else "as printed, not a valid bound"
            notes.append(f"{bound.column} = objective / {name}: {bound.description} ({kind})")
    return notes


def format_table(table: pd.DataFrame, width: int | None = None) -> tuple[str, list[str]]:
    """The table as text no wider than ``width`` (the terminal's by default), and its notes.

    Messages (the ``message`` column) leave the table: the cell says ``[k]`` and note k
    holds the message. A table still wider than ``width`` is wrapped into blocks of columns
    (pandas' ``line_width``).
    """
    import shutil

    width = width or shutil.get_terminal_size((100, 24)).columns
    notes: list[str] = []
    shown = table.copy()
    if "message" in shown.columns:
        refs = []
        for method, message in zip(shown["method"], shown["message"], strict=True):
            if message:
                notes.append(f"[{len(notes) + 1}] {method}: {message}")
                refs.append(f"[{len(notes)}]")
            else:
                refs.append("")
        shown["message"] = refs
        shown = shown.rename(columns={"message": "note"})
    text = shown.to_string(index=False, float_format=lambda v: f"{v:.6g}", line_width=width)
    return text, notes


def wrap_notes(lines: list[str], width: int | None = None) -> list[str]:
    """Each line wrapped to ``width`` (the terminal's by default), continuations indented."""
    import shutil
    import textwrap

    width = width or shutil.get_terminal_size((100, 24)).columns
    out: list[str] = []
    for line in lines:
        out.extend(textwrap.wrap(line, width=max(width, 20), subsequent_indent="    ") or [line])
    return out


def _short(text: str, width: int = 120) -> str:
    """``text`` cut to ``width`` characters for a table cell (the full text is in ``info``)."""
    return text if len(text) <= width else text[: width - 3] + "..."


def _run_method(
    problem: Any, method: str, seed: int, time_limit: float | None, trace: bool = False
) -> Solution:
    """``solve(problem, method)``, or an "error" row saying what failed and why.

    Any ``Exception`` of one method (a heuristic's dead end, a solver failure, a bug) is
    caught so the other methods' rows stand; ``KeyboardInterrupt`` is not an
    ``Exception`` and still stops the whole run.
    """
    began = time.perf_counter()
    try:
        options: dict[str, Any] = {"trace": True} if trace else {}
        return solve(problem, method, seed=seed, time_limit=time_limit, **options)
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
    seed: int = SEED,
    time_limit: float | None = TIME_LIMIT,
    plot: str | None = None,
    gantt: str | None = None,
    save: str | Path | None = None,
    out: IO[str] | None = None,
    progress: bool = True,
    trace: str | Path | None = None,
) -> dict[str, Any]:
    """Load ``path``, solve it with ``methods`` and print the gap table.

    Parameters
    ----------
    path : str or Path
        A JSON problem file (see the module docstring).
    methods : tuple of str, optional
        Registered methods of the file's problem type (default: its exact methods and
        heuristics; see :func:`taopt.orchestration.pipeline.default_methods`).
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
    save : path, optional
        Folder: each method's solution is written there as ``<method>.json``, which
        ``taopt verify`` re-checks.
    progress : bool
        Progress bars on stderr: the travel-time matrix of an instance file, and the
        methods (:func:`method_table`).
    trace : str or Path, optional
        A ``.gif``: the first method that keeps a trace (``exact`` on chapter 2's routing,
        the DFJ loop; on chapter 5's delivery, the ideal DP) is run with ``trace=True`` and
        its rounds written as an animation, one frame per round (per layer for the DP):
        :func:`taopt.trace.animate_trace`. Refused (InstanceError) before anything is
        solved when none of the methods keeps one.

    Raises
    ------
    OutputError
        ``plot`` or ``gantt`` not a ``.png`` file, ``trace`` not a ``.gif``, or a Gantt chart
        asked of a file that is not a delivery instance: raised before the file is loaded or
        anything solved.
    InstanceError
        ``trace`` asked and none of the methods keeps a trace.

    Returns
    -------
    dict with ``problem``, ``instance``, ``table`` (DataFrame), ``solutions`` and ``failed``
    (the methods whose row has status "error"; ``taopt solve`` exits with 1 when there is
    one). Failed methods are not saved and not plotted.
    """
    out = out or sys.stdout
    tic = time.perf_counter()
    path = resolve_example(path)
    _check_plot_request(path, plot, gantt)  # before any matrix is computed or model solved
    # output folders writable before the solve, not after it (a full disk, a read-only folder)
    if save:
        check_writable(save, "--out folder", create=False)
    check_writable_file(plot, "--plot")
    check_writable_file(gantt, "--gantt")
    if trace is not None:
        from taopt.plot import check_output

        check_output(trace, ".gif", "--trace")
        check_writable_file(trace, "--trace")
    problem, instance = load_problem_file(path, progress=progress)
    family = family_of(problem)
    if trace is not None and not any(
        get_method(problem, m).accepts("trace") for m in resolve_methods(problem, methods)
    ):
        raise InstanceError(
            f"--trace: none of the methods {', '.join(resolve_methods(problem, methods))} keeps "
            "a trace (the exact DFJ loop of chapter 2 and the exact ideal DP of chapter 5 do: "
            "add --methods exact)"
        )
    table, solutions = method_table(
        problem, methods, seed=seed, time_limit=time_limit, progress=progress,
        trace=trace is not None,
    )  # fmt: skip
    print(f"{problem!r} from {path}", file=out)
    text, message_notes = format_table(table)
    print(text, file=out)
    notes = [*message_notes, *column_notes(table, problem)]
    if not methods:
        notes.append(default_set_note(problem))
        if no_optimum_note(problem):
            notes.append(no_optimum_note(problem))
    for line in wrap_notes(notes):
        print(line, file=out)
    found = [s for s in solutions.values() if s.solution is not None and s.status != ERROR]
    best = min(found, key=lambda s: s.objective) if found else None
    failed = [m for m, s in solutions.items() if s.status == ERROR]
    unanswered = [m for m, s in solutions.items() if s.status == NO_SOLUTION]
    if save:
        folder = check_writable(save, "--out folder")
        for method, sol in solutions.items():
            if sol.status != ERROR:
                sol.save(folder / f"{method}.json")
        print(f"solutions written to {folder}/<method>.json", file=out)
    if best is None:
        plot = gantt = None  # nothing to draw
    if plot and best is not None:
        name, draw = next(iter(family.plots.items()))
        with atomic_path(plot) as tmp:  # no half-written PNG; an error names the path
            draw(problem, best.solution, str(tmp), instance=instance, method=best.method)
        print(f"{name} plot of {best.method} written to {plot}", file=out)
        for line in _route_lines(best, instance, problem):
            print(line, file=out)
    if gantt and best is not None:
        with atomic_path(gantt) as tmp:
            family.plots["gantt"](
                problem, best.solution, str(tmp), instance=instance, method=best.method
            )
        print(f"Gantt chart of {best.method} written to {gantt}", file=out)
    if trace is not None:
        traced = [(m, s) for m, s in solutions.items() if "trace" in s.info]
        if traced:
            from taopt.trace import animate_trace

            method, sol = traced[0]
            frames = animate_trace(sol, problem, trace, instance=instance)
            unit = "layer" if sol.info["trace"]["kind"] == "ideal_dp" else "round"
            print(
                f"trace of {method} written to {trace} ({frames} frames, one per {unit})",
                file=out,
            )
        else:
            print("no trace written: the tracing method failed (see the table)", file=out)
    if unanswered:
        print(
            f"no feasible answer: {', '.join(unanswered)} (their outcome, not a proof that "
            "none exists; see the notes under the table)",
            file=out,
        )
    if failed:
        print(f"failed: {', '.join(failed)} (see the notes under the table)", file=out)
    print(f"({time.perf_counter() - tic:.2f} s)", file=out)
    return {
        "problem": problem,
        "instance": instance,
        "table": table,
        "solutions": solutions,
        "failed": failed,
    }


#: Relative tolerance of verify's comparisons (objective re-scored, bound against value).
VERIFY_TOLERANCE = 1e-6

#: ``taopt verify`` exit codes: every claim checked and true / a check failed / bad input
#: (a malformed file) / every check passed but some claims could not be checked.
EXIT_VALID, EXIT_NOT_VALID, EXIT_BAD_INPUT, EXIT_UNCHECKED = 0, 1, 2, 3

#: Statuses that claim the payload is a solution (the others contradict a feasible one).
_SOLUTION_STATUSES = (Status.OPTIMAL, Status.TIME_LIMIT, Status.FEASIBLE)


@dataclass
class Verdict:
    """What ``taopt verify`` checked: each claim passed, failed or not checked.

    Attributes
    ----------
    passed, failed, unchecked : list of str
        One line per claim, as printed (``[ok]``, ``[FAIL]``, ``[not checked]``).

    ``bool(verdict)`` is True when no check failed; :attr:`exit_code` tells the three
    outcomes apart (see :data:`EXIT_VALID`).
    """

    passed: list[str] = field(default_factory=list)
    failed: list[str] = field(default_factory=list)
    unchecked: list[str] = field(default_factory=list)

    def __bool__(self) -> bool:
        return not self.failed

    @property
    def exit_code(self) -> int:
        """0 every claim checked and true, 1 a check failed, 3 some claims not checked."""
        if self.failed:
            return EXIT_NOT_VALID
        return EXIT_UNCHECKED if self.unchecked else EXIT_VALID

    @property
    def final_line(self) -> str:
        """``VALID``, ``VALID (k claims not checked)`` or ``NOT VALID``."""
        if self.failed:
            return "NOT VALID"
        if self.unchecked:
            k = len(self.unchecked)
            return f"VALID ({k} claim{'s' if k > 1 else ''} not checked)"
        return "VALID"


def _close(a: float, b: float) -> bool:
    return abs(a - b) <= VERIFY_TOLERANCE * max(1.0, abs(a), abs(b))


def _not_above(a: float, b: float) -> bool:
    """a <= b up to the verify tolerance."""
    return a <= b + VERIFY_TOLERANCE * max(1.0, abs(b))


def load_certificate(path: str | Path) -> Solution:
    """A saved solution, or an :class:`InstanceError` naming the file and what is wrong.

    The solution schema and the payload classes catch most faults; anything else a
    malformed file can raise while its payload is built (a ``KeyError`` for a payload of
    the wrong shape, a ``TypeError`` for a wrong type) is turned into the same clear error.
    """
    try:
        return Solution.load(path)
    except TaoptError as exc:
        text = str(exc)
        if str(path) in text:
            raise
        raise type(exc)(f"{path}: {text}") from None
    except (LookupError, TypeError, ValueError, AttributeError) as exc:
        detail = f"{type(exc).__name__}: {exc}"
        raise InstanceError(
            f"{path}: malformed solution: its payload does not match its payload_kind ({detail})"
        ) from None


def _valid_lower_bound(problem: Any) -> float:
    """The family's fast valid lower bound (NaN without one, or when it cannot be built)."""
    try:
        return lower(problem, "fast")
    except (TaoptError, ValueError, ArithmeticError):
        return math.nan


def _run_within(problem: Any, method: str, time_limit: float | None) -> Solution:
    """``solve(problem, method)`` within ``time_limit`` wall-clock seconds.

    A method that takes ``time_limit`` gets it; one that does not (a pure-Python
    method) is stopped by a SIGALRM timer when it runs on the main thread, and comes back
    as status "time_limit" without a solution or bound.
    """
    spec = get_method(problem, method)
    if time_limit is None or spec.accepts("time_limit"):
        return solve(problem, method, time_limit=time_limit)
    began = time.perf_counter()
    try:
        with alarm_after(float(time_limit)):
            return solve(problem, method)
    except OutOfTime:
        return Solution(
            objective=math.nan,
            status=Status.TIME_LIMIT,
            runtime=time.perf_counter() - began,
            method=method,
        )


def _check_plot_request(path: str | Path, plot: str | None, gantt: str | None) -> None:
    """Refuse a plot request before any work: wrong extension, or a kind with no such plot."""
    from taopt.plot import check_output

    check_output(plot, ".png", "--plot")
    check_output(gantt, ".png", "--gantt")
    if not (plot or gantt):
        return
    data = load_json(path)
    kind = data.get("kind") if isinstance(data, dict) else None
    if kind == "instance":  # becomes the problem of a family with an adapter: what can it draw?
        plots: tuple[str, ...] = tuple(
            {name for f in families() if f.adapter is not None for name in f.plots}
        )
    else:
        try:
            plots = tuple(family_for_kind(kind).plots)
        except InstanceError:  # an unknown kind: the loader says so, with the schema's words
            return
    if gantt and "gantt" not in plots:
        drawn = ", ".join(f.kind for f in families() if "gantt" in f.plots)
        raise OutputError(f"--gantt draws a Gantt chart of a {drawn} only; {path} is a {kind}")
    if plot and not plots:
        raise OutputError(f"--plot: no plot for a {kind} file ({path})")


def _route_lines(best: Solution, instance: Instance | None, problem: Any) -> list[str]:
    """The plotted solution spelt with the ids written on the picture: the family's
    ``describe`` hook (:class:`taopt.registry.Family`), nothing when it has none."""
    describe = family_of(problem).describe
    return [] if describe is None else list(describe(problem, best.solution, instance))


def verify_file(
    solution_path: str | Path,
    problem_path: str | Path,
    exact: bool = False,
    time_limit: float | None = TIME_LIMIT,
    out: IO[str] | None = None,
    progress: bool = False,
) -> Verdict:
    """Re-check a saved solution from the problem file alone; say what could not be checked.

    Always checked: the payload is of the problem's family and parses; the family's
    scorer accepts it (every constraint, the violated one named otherwise); the status
    agrees with it (a feasible payload saved as "infeasible", "error" or "relaxation" is
    rejected); its value equals the saved objective (relative 1e-6); a saved bound is not
    above the objective; an "optimal" status carries a bound within 1e-6 of it.

    Checked only with ``exact=True`` (else reported ``[not checked]``): that an "optimal"
    solution is optimal, that a saved bound is a valid lower bound (not above the optimum)
    and that an "infeasible" problem has no solution. The problem is re-solved with the
    family's certifying method (:func:`taopt.orchestration.pipeline.certifying_method`: the DP over
    order ideals for a delivery instance with affordable ideals, the exact model otherwise), within
    ``time_limit`` seconds; a re-solve stopped by the limit still refutes a claim its
    incumbent beats, and proves one its bound reaches, and leaves the rest
    ``[not checked]``. Without ``exact``, a bound (or an optimum) at most the family's
    fast valid lower bound (:func:`taopt.bounds.lower`) is proven by it.

    Returns
    -------
    Verdict
        Each claim passed, failed or not checked; ``bool(verdict)`` is True when no check
        failed, ``verdict.exit_code`` is what ``taopt verify`` exits with (0 every claim
        checked, 1 a check failed, 3 some claims not checked). The last line printed is
        ``VALID``, ``VALID (k claims not checked)`` or ``NOT VALID``.

    Raises
    ------
    InstanceError
        A malformed problem or solution file (named), e.g. a payload that does not match
        its ``payload_kind``.
    """
    out = out or sys.stdout
    solution_path = resolve_example(solution_path)
    problem_path = resolve_example(problem_path)
    problem, _ = load_problem_file(problem_path, progress=progress)
    solution = load_certificate(solution_path)
    family = family_of(problem)
    verdict = Verdict()

    def report(passed: bool | None, text: str) -> None:
        """passed True/False: a check; None: a claim that could not be checked."""
        if passed is None:
            verdict.unchecked.append(text)
            print(f"  [not checked] {text}", file=out)
        else:
            (verdict.passed if passed else verdict.failed).append(text)
            print(f"  [{'ok' if passed else 'FAIL'}] {text}", file=out)

    def finish() -> Verdict:
        print(verdict.final_line, file=out)
        return verdict

    print(f"{solution_path}: {solution.summary()}", file=out)
    print(f"against {problem!r} from {problem_path}", file=out)
    status = solution.status
    payload = solution.solution
    value = math.nan
    if payload is None:
        if status not in (Status.INFEASIBLE, Status.TIME_LIMIT, Status.NO_SOLUTION):
            report(False, f"a solution with status {status.value!r} carries no payload to check")
            return finish()
        report(True, f"no payload, as status {status.value!r} allows")
    else:
        expected = getattr(family.payload, "payload_kind", None)
        kind = getattr(payload, "payload_kind", None)
        if kind != expected:
            report(False, f"payload is {kind!r}, but a {family.kind} needs {expected!r}")
            return finish()
        try:
            value = evaluate(problem, payload)
        except FeasibilityError as exc:
            report(False, f"infeasible: {exc}")
            return finish()
        except (TaoptError, LookupError, TypeError, ValueError) as exc:
            report(False, f"the payload cannot be scored: {type(exc).__name__}: {exc}")
            return finish()
        report(True, f"feasible: every constraint of this {family.kind} holds")
        if status not in _SOLUTION_STATUSES:
            report(False, f"status {status.value!r} contradicts a feasible payload")
        report(
            _close(value, solution.objective),
            f"objective re-scored from the problem: {value:.10g} (saved {solution.objective:.10g})",
        )
    bound = solution.bound
    if bound is not None and payload is not None:
        report(_not_above(bound, value), f"saved bound {bound:.10g} is not above the objective")
    if status == Status.OPTIMAL:
        gap = solution.gap
        report(
            gap is not None and gap <= VERIFY_TOLERANCE,
            f"an 'optimal' claim carries a proven gap ({gap})",
        )

    # the claims about the optimum: optimality, the bound's validity, infeasibility
    claims = []
    if status == Status.OPTIMAL and payload is not None:
        claims.append("optimality")
    if bound is not None:
        claims.append("bound")
    if status == Status.INFEASIBLE and payload is None:
        claims.append("infeasibility")
    if not claims and not (exact and payload is not None):
        return finish()  # with --exact a payload still gets its gap to the re-solved optimum
    if not exact:
        lower = _valid_lower_bound(problem)
        for claim in claims:
            if claim == "optimality" and _not_above(value, lower):
                report(True, f"optimality: the objective reaches the valid bound {lower:.10g}")
            elif claim == "bound" and bound is not None and _not_above(bound, lower):
                report(True, f"bound {bound:.10g} is below the valid bound {lower:.10g}")
            else:
                report(None, f"{_CLAIM_TEXT[claim]}: needs --exact")
        return finish()

    method = certifying_method(problem)
    if method is None:
        for claim in claims:
            report(None, f"{_CLAIM_TEXT[claim]}: no exact method for a {family.kind}")
        return finish()
    began = time.perf_counter()
    try:
        certified = _run_within(problem, method, time_limit)
    except Exception as exc:  # noqa: BLE001 -- the re-solve failing leaves claims unchecked
        reason = f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"
        print(f"  re-solve with {method!r} failed: {reason}", file=out)
        for claim in claims:
            report(None, f"{_CLAIM_TEXT[claim]}: the re-solve with {method!r} failed")
        return finish()
    seconds = time.perf_counter() - began
    print(f"  re-solved with {method!r} in {seconds:.2f} s: {certified.summary()}", file=out)
    line = _gap_line(certified, value)
    if line:
        print(f"  {line}", file=out)
    _judge(report, claims, certified, value, bound)
    return finish()


def _gap_line(certified: Solution, value: float) -> str:
    """The checked solution's gap to the optimum the re-solve found ("" with nothing to say).

    Against a proven optimum f_o: ``f / f_o - 1``; against a stopped re-solve, the range
    between its proven bound and its incumbent.
    """
    if not math.isfinite(value):
        return ""
    if certified.status == Status.OPTIMAL and math.isfinite(certified.objective):
        optimum = certified.objective
        if optimum > 0:
            return (
                f"gap of the checked solution to the re-solved optimum {optimum:.10g}: "
                f"{100 * (value / optimum - 1):.4g} %"
            )
        return f"the checked solution's value {value:.10g}, the re-solved optimum {optimum:.10g}"
    parts = []
    if certified.bound is not None and certified.bound > 0:
        parts.append(f"at most {100 * (value / certified.bound - 1):.4g} % (to its bound)")
    if certified.solution is not None and math.isfinite(certified.objective):
        parts.append(f"at least {100 * (value / certified.objective - 1):.4g} % (to its incumbent)")
    if not parts:
        return ""
    return "gap of the checked solution to the optimum: " + ", ".join(parts)


_CLAIM_TEXT = {
    "optimality": "optimality",
    "bound": "the saved bound is a valid lower bound",
    "infeasibility": "infeasibility",
}


def _judge(report: Any, claims: list[str], certified: Solution, value: float, bound: Any) -> None:
    """Judge each claim against a re-solve: optimal, stopped with an incumbent or a bound."""
    stopped = "the re-solve stopped before proving it (raise --time-limit)"
    if certified.status == Status.INFEASIBLE:
        for claim in claims:
            if claim == "infeasibility":
                report(True, "infeasibility: the re-solve proves no solution exists")
            else:
                report(False, f"{_CLAIM_TEXT[claim]}: the re-solve says the problem is infeasible")
        return
    has_incumbent = certified.solution is not None and math.isfinite(certified.objective)
    incumbent = certified.objective if has_incumbent else math.inf
    proven = certified.objective if certified.status == Status.OPTIMAL else certified.bound
    if certified.status == Status.OPTIMAL and not has_incumbent:
        proven = None
    for claim in claims:
        if claim == "infeasibility":
            if has_incumbent:
                report(False, f"infeasibility: the re-solve found a solution ({incumbent:.10g})")
            else:
                report(None, f"infeasibility: {stopped}")
        elif claim == "optimality":
            if not _not_above(value, incumbent):
                report(False, f"optimality: the re-solve found {incumbent:.10g} < {value:.10g}")
            elif proven is not None and _not_above(value, proven):
                report(True, f"optimality: the re-solve proves the optimum is {proven:.10g}")
            else:
                report(None, f"optimality: {stopped}")
        elif claim == "bound":
            if not _not_above(bound, incumbent):
                report(
                    False,
                    f"the saved bound {bound:.10g} is above a solution the re-solve found "
                    f"({incumbent:.10g})",
                )
            elif proven is not None and _not_above(bound, proven):
                report(True, f"the saved bound {bound:.10g} is not above the proven {proven:.10g}")
            else:
                report(None, f"the saved bound is a valid lower bound: {stopped}")
