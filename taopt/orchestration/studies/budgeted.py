"""The chapter-6 study: do chapter 2's algorithms keep their performance when limits bite?

Thesis §6.2 leaves open what happens to the task-assignment algorithms when "each vehicle
can visit a maximum number of target locations" or "has a maximum travel time"; it says
their performance "might no longer be guaranteed". This study measures it on the drift
scenarios of Table 2.1 (:func:`taopt.routing.scenarios.drift_scenario`, the generator of
:mod:`taopt.orchestration.studies.drift`), with the limits tightened step by step.

Tightness levels
----------------
A level is a name (``--levels``), the same limit for every vehicle:

* ``"none"`` — no limit (chapter 2's problem; the reference row);
* ``"Q<s>"`` — capacity ``Q = ceil(s · n / m)`` targets per vehicle; ``s = 1`` is the
  tightest feasible one (``m Q >= n``);
* ``"T<τ>"`` — maximum travel time ``T = τ · T*``, where ``T*`` is the longest route of
  the scenario's *unlimited* certified optimum (chapter 2's exact model, computed once per
  scenario and cached). ``τ = 1`` does not bite (that optimum stays feasible: a check that
  ``f_o`` is unchanged); below 1 it does, and some scenarios become infeasible (the exact
  method says so);
* ``"Q<s>T<τ>"`` — both.

Rows and summary
----------------
Rows are the study runner's (:func:`taopt.orchestration.study.run_study`: resumable CSV
``<out>/budgeted.csv``, jobs, seeds) keyed by (size, level, scenario, method), with the
scenario's ``n, m, Q, T`` and references ``T_star`` (``T*``) and ``f_unlimited`` (the
unlimited optimum). :func:`summarize` gives per (size, level, method): the mean true gap
``f / f_o − 1`` (in %) over scenarios whose optimum is certified by the "exact" method, its
upper bound ``f / exact bound − 1`` over all answered scenarios, the fraction of
scenarios *not proven infeasible* where the method gave no feasible answer, and the mean
runtime with its ratio to the same method's "none" level.

Example
-------
>>> df = budgeted_study(["n8m2"], ["none", "Q1"], 2, out_dir=tmp)  # doctest: +SKIP
>>> summarize(df)  # doctest: +SKIP

References
----------
Thesis §2.5 (the scenarios, Table 2.1), §6.2 (the question).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from taopt.budgeted.problem import BudgetedProblem
from taopt.defaults import SEED, TIME_LIMIT
from taopt.errors import InstanceError, SolverError
from taopt.io import save_json
from taopt.orchestration.cli import terminal_width
from taopt.orchestration.study import Scenario, StudySpec, check_integer, run_study, with_optimum
from taopt.routing.scenarios import drift_scenario, scenario_seed

#: The study's methods when every one is installed (the defaults are those installed here).
METHODS = ("MC", "EVM", "GA", "pyvrp", "ortools", "exact")
LEVELS = ("none", "Q2", "Q1.5", "Q1.2", "Q1", "T1", "T0.8", "T0.6", "T0.5")
SIZES = ("n50m10", "n120m10")
#: Seconds for the unlimited optimum that defines ``T*`` (computed once per scenario).
REFERENCE_TIME_LIMIT = 600.0

__all__ = [
    "METHODS",
    "LEVELS",
    "default_methods",
    "SPEC",
    "parse_level",
    "parse_size",
    "budgeted_study",
    "summarize",
    "plot_study",
    "add_arguments",
    "run",
]


def parse_size(text: str) -> tuple[int, int]:
    """``"n50m10"`` -> ``(50, 10)``."""
    match = re.fullmatch(r"n(\d+)m(\d+)", str(text).strip())
    if not match or int(match[1]) < 1 or int(match[2]) < 1:
        raise InstanceError(f"a size is written nNmM with N, M >= 1 (e.g. n50m10), got {text!r}")
    return int(match[1]), int(match[2])


def parse_level(text: str) -> tuple[float, float]:
    """A level name -> ``(s, τ)``, ``inf`` for "no such limit".

    >>> parse_level("none"), parse_level("Q1.5"), parse_level("Q1T0.8")
    ((inf, inf), (1.5, inf), (1.0, 0.8))
    """
    text = str(text).strip()
    if text == "none":
        return math.inf, math.inf
    match = re.fullmatch(r"(?:Q(\d+(?:\.\d+)?))?(?:T(\d+(?:\.\d+)?))?", text)
    if not text or not match:
        raise InstanceError(
            f"a level is 'none', 'Q<s>', 'T<tau>' or 'Q<s>T<tau>' (e.g. Q1.5, T0.8), got {text!r}"
        )
    s = float(match[1]) if match[1] else math.inf
    tau = float(match[2]) if match[2] else math.inf
    if s < 1.0:
        raise InstanceError(f"level {text!r}: s = {s:g} < 1 makes m Q < n (always infeasible)")
    if tau <= 0:
        raise InstanceError(f"level {text!r}: tau must be > 0")
    return s, tau


def default_methods() -> list[str]:
    """The study's default methods: :data:`METHODS` that are installed here (pyvrp and
    ortools only with ``taopt[peers]``; :func:`taopt.available_methods`)."""
    from taopt.orchestration.study import available_defaults

    return available_defaults(BudgetedProblem, METHODS)


def level_order(level: str) -> tuple[int, float, float]:
    """Sort key of a level: "none", then Q levels, T levels and both, each loosest first."""
    s, tau = parse_level(level)
    kind = 0 if level == "none" else 1 if math.isinf(tau) else 2 if math.isinf(s) else 3
    return kind, -s, -tau


def _items(values: str | Sequence[str], what: str) -> list[str]:
    if isinstance(values, str):
        values = [v.strip() for v in values.split(",") if v.strip()]
    values = list(dict.fromkeys(str(v) for v in values))
    if not values:
        raise InstanceError(f"no {what} given")
    return values


# -- scenarios ----------------------------------------------------------------------------------


def unlimited_reference(problem: Any, seed: int, cache_dir: str | None) -> dict[str, Any]:
    """The scenario's unlimited optimum (chapter 2's "exact"): objective, status, ``T*``.

    Cached as JSON in ``cache_dir`` (written atomically; parallel tasks may race to write the
    same numbers). If the exact model stops on :data:`REFERENCE_TIME_LIMIT` its best routes
    define ``T*`` and ``status`` says so.
    """
    path = None
    if cache_dir:
        path = Path(cache_dir) / f"unlimited_n{problem.n}m{problem.m}_s{seed}.json"
        if path.exists():
            return json.loads(path.read_text())
    from taopt.orchestration.pipeline import solve

    solution = solve(problem, "exact", time_limit=REFERENCE_TIME_LIMIT)
    if solution.routes is None:  # the unlimited problem always has routes; none in time
        raise SolverError(f"{problem!r}: no unlimited reference routes ({solution.status})")
    times = [problem.route_cost(j, route) for j, route in enumerate(solution.routes)]
    reference = {
        "objective": solution.objective,
        "status": str(solution.status),
        "T_star": max(times),
    }
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        save_json(reference, path)  # atomic; a failed write leaves no temporary file
    return reference


def make_scenario(key: dict, settings: dict) -> Scenario:
    """Scenario ``key`` = (size, level, scenario): the drift scenario with the level's limits."""
    n, m = parse_size(key["size"])
    s, tau = parse_level(key["level"])
    seed = scenario_seed(settings["seed"], key["scenario"])
    cache = settings.get("context", {}).get("cache_dir")
    routing = drift_scenario(n, m, seed, field="thesis", cache_dir=cache, jobs=1).problem
    reference = unlimited_reference(routing, seed, cache)  # every level: f_unlimited, T*
    capacity = math.ceil(s * n / m - 1e-9) if math.isfinite(s) else math.inf
    max_time = tau * reference["T_star"] if math.isfinite(tau) else math.inf
    problem = BudgetedProblem.from_routing(
        routing,
        capacity=None if not math.isfinite(capacity) else [capacity] * m,
        max_time=None if not math.isfinite(max_time) else [max_time] * m,
        name=f"{key['size']} {key['level']} scenario {key['scenario']}",
    )
    return Scenario(
        problem,
        columns={"n": n, "m": m, "Q": capacity, "T": max_time},
        references={"T_star": reference["T_star"], "f_unlimited": reference["objective"]},
    )


def method_seed(key: dict, settings: dict) -> int:
    """Scenario k's own seed for every level (as the drift study), so levels are paired."""
    return scenario_seed(settings["seed"], key["scenario"])


SPEC = StudySpec(
    name="budgeted",
    problem_type=BudgetedProblem,
    key_columns=("size", "level", "scenario"),
    make_scenario=make_scenario,
    scenario_columns=("n", "m", "Q", "T"),
    reference_columns=("T_star", "f_unlimited"),
    info_columns=("unassigned", "violation_count", "first_feasible", "startup"),
    method_seed=method_seed,
)


def budgeted_study(
    sizes: str | Sequence[str] = SIZES,
    levels: str | Sequence[str] = LEVELS,
    scenarios: int = 10,
    methods: str | Sequence[str] | None = None,
    seed: int = SEED,
    out_dir: str | os.PathLike = "budgeted-study",
    jobs: int = 1,
    time_limit: float | None = TIME_LIMIT,
    peer_iterations: int = 2000,
    method_options: dict[str, dict] | None = None,
    progress: bool = True,
    dask: str | None = None,
) -> pd.DataFrame:
    """Run the chapter-6 study: sizes × levels × ``scenarios`` × methods.

    Parameters
    ----------
    sizes : str or list of str
        "nNmM" names (Table 2.1: n50m10, n120m10).
    levels : str or list of str
        Level names (module docstring), in the order they should be plotted.
    scenarios : int
        Scenarios per (size, level); scenario k is the same drift scenario at every level.
    methods : str or list of str, optional
        Registered methods of BudgetedProblem ("MC", "EVM", "GA", "pyvrp", "ortools",
        "exact"; case-insensitive). Default: those of :data:`METHODS` installed here
        (:func:`default_methods`: the peers only with ``taopt[peers]``).
    seed : int
        Study seed (scenario k has seed ``scenario_seed(seed, k)``).
    out_dir : path
        Folder for ``budgeted.csv``, its settings and the cached matrices and references.
    jobs : int
        Worker processes.
    time_limit : float or None
        Seconds per method run (the study runner's limit): it stops the "exact" method
        (leaving the scenario's optimum uncertified; its bound still bounds the gap); the
        heuristics and peers end far sooner on their own budgets.
    peer_iterations : int
        The peers' budget, so that they are deterministic (same seed, same rows): PyVRP's
        ``max_iterations`` and OR-Tools' ``solution_limit = peer_iterations // 10``
        (about 1 s each at n50m10 on this machine).
    method_options : dict, optional
        More options per method, e.g. ``{"GA": {"generations": 100}}``.
    progress : bool
        A progress bar.
    dask : str, optional
        As :func:`taopt.orchestration.study.run_study`.

    Returns
    -------
    pandas.DataFrame
        The rows, plus ``optimum`` and ``exact_bound`` per scenario
        (:func:`taopt.orchestration.study.with_optimum`).

    Raises
    ------
    InstanceError
        A bad size, level, count or method (nothing is written).
    """
    sizes = _items(sizes, "sizes")
    levels = _items(levels, "levels")
    for size in sizes:
        parse_size(size)
    for level in levels:
        parse_level(level)
    methods = default_methods() if methods is None else _items(methods, "methods")
    from taopt.orchestration.pipeline import register_methods
    from taopt.registry import get_method

    register_methods()
    methods = list(dict.fromkeys(get_method(BudgetedProblem, m).name for m in methods))
    scenarios = check_integer("scenarios", scenarios, 1)
    seed = check_integer("seed", seed, 0)
    peer_iterations = check_integer("peer_iterations", peer_iterations, 10)
    options = {k: dict(v) for k, v in (method_options or {}).items()}
    if "pyvrp" in methods:
        options.setdefault("pyvrp", {}).setdefault("max_iterations", peer_iterations)
    if "ortools" in methods:
        options.setdefault("ortools", {}).setdefault("solution_limit", peer_iterations // 10)
    # scenario-major: a study stopped early has every level of its first scenarios
    keys = [
        {"size": size, "level": level, "scenario": k}
        for size in sizes
        for k in range(int(scenarios))
        for level in levels
    ]
    df = run_study(
        SPEC,
        keys,
        methods,
        {"seed": int(seed), "field": "thesis"},
        out_dir,
        jobs=jobs,
        dask=dask,
        time_limit=time_limit,
        method_options=options,
        context={"cache_dir": str(Path(out_dir) / "cache")},
        progress=progress,
    )
    return with_optimum(df, SPEC)


# -- summary and plot ---------------------------------------------------------------------------


def _with_measures(df: pd.DataFrame) -> pd.DataFrame:
    if "optimum" not in df.columns:
        df = with_optimum(df, SPEC)
    keys = list(SPEC.key_columns)
    exact = df[df["method"] == "exact"].set_index(keys)["status"]
    index = pd.MultiIndex.from_frame(df[keys])
    exact_status = exact.reindex(index).to_numpy(dtype=object)
    answered = (df["status"].isin(["feasible", "optimal", "time_limit"])) & np.isfinite(
        df["objective"].to_numpy(float)
    )
    objective = df["objective"].where(answered, np.nan)
    best_known = objective.groupby([df[k] for k in keys]).transform("min")
    return df.assign(
        known_feasible=np.isfinite(best_known.to_numpy(float)),
        vs_best_pct=100 * (objective / best_known - 1),
        proven_infeasible=exact_status == "infeasible",
        answered=answered.to_numpy(),
        gap_pct=100 * (df["objective"] / df["optimum"] - 1),
        gap_ub_pct=100 * (df["objective"] / df["exact_bound"] - 1),
        # a peer's first call in a worker process starts its solver process: not its work
        work_s=df["runtime"] - df.get("startup", pd.Series(0.0, index=df.index)).fillna(0.0),
    )


def summarize(df: pd.DataFrame) -> pd.DataFrame:
    """Per (size, level, method): gaps, answers and time.

    Columns: ``scenarios``; ``proven_infeasible`` (scenarios the exact method proved
    infeasible); ``unknown`` (scenarios neither proven infeasible nor answered by any
    method); ``no_answer_pct`` (% of the scenarios known to be feasible, i.e. answered by
    some method, where this method gave no feasible answer); ``certified`` (scenarios with
    a certified optimum, answered by the method); ``gap_pct`` (mean ``100 (f / f_o − 1)`` over those); ``gap_ub_pct`` (mean
    ``100 (f / bound − 1)`` over the answered scenarios with an exact bound: an upper bound
    on the gap); ``vs_best_pct`` (mean ``100 (f / f_best − 1)`` over the answered
    scenarios, ``f_best`` the best answer of any method on the scenario: the measure left
    where the exact method certifies nothing); ``time_s`` (mean runtime, without a peer's
    one-off worker start-up) and ``time_vs_none`` (its ratio to the same
    method's mean time at level "none", when that level was run).
    """
    data = _with_measures(df)
    rows = []
    keys = ["size", "level", "method"]
    for (size, level, method), group in data.groupby(keys, sort=False):
        known = group[group["known_feasible"]]
        unknown = group[~group["known_feasible"] & ~group["proven_infeasible"]]
        answered = group[group["answered"]]
        certified = answered.dropna(subset=["gap_pct"])
        bounded = answered[np.isfinite(answered["gap_ub_pct"].to_numpy(float))]
        rows.append(
            {
                "size": size,
                "level": level,
                "method": method,
                "scenarios": group["scenario"].nunique(),
                "proven_infeasible": int(group["proven_infeasible"].sum()),
                "unknown": unknown["scenario"].nunique(),
                "no_answer_pct": 100 * float((~known["answered"]).mean()) if len(known) else np.nan,
                "certified": len(certified),
                "gap_pct": float(certified["gap_pct"].mean()) if len(certified) else np.nan,
                "gap_ub_pct": float(bounded["gap_ub_pct"].mean()) if len(bounded) else np.nan,
                "vs_best_pct": float(answered["vs_best_pct"].mean()) if len(answered) else np.nan,
                "time_s": float(group["work_s"].mean()),
            }
        )
    table = pd.DataFrame(rows)
    if table.empty:
        return table
    order = {level: level_order(level) for level in table["level"]}
    table = table.assign(_order=table["level"].map(order), _size=table["size"].map(parse_size))
    methods = {name: i for i, name in enumerate(dict.fromkeys(df["method"]))}
    table = table.assign(_method=table["method"].map(methods))
    table = table.sort_values(["_size", "_order", "_method"], kind="stable")
    table = table.drop(columns=["_order", "_size", "_method"]).reset_index(drop=True)
    none = table[table["level"] == "none"].set_index(["size", "method"])["time_s"]
    reference = none.reindex(pd.MultiIndex.from_frame(table[["size", "method"]])).to_numpy()
    table["time_vs_none"] = table["time_s"].to_numpy() / reference
    return table


def plot_study(table: pd.DataFrame, path: str | None = None, exclude: Sequence[str] = ()) -> Any:
    """True gap, gap to the best answer and no-answer fraction vs tightness, one line per
    method, one row of panels per size.

    Each panel is titled by its measure (and its size when there are several); each method
    keeps its own line style and marker (:func:`taopt.plot.method_style`) and is shifted
    sideways a little (:func:`taopt.plot.dodge`), so methods with equal values (MC and EVM
    at the same gap, every method at 0 % no answer) stay visible.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`summarize`'s table.
    path : str, optional
        Save the figure as PNG there.
    exclude : sequence of str
        Methods left out (e.g. "exact", whose gap is 0 by definition).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    from taopt.plot import dodge, legend_outside, method_style

    sizes = list(dict.fromkeys(table["size"]))
    panels = (
        ("gap_pct", "true gap to the certified optimum", "true gap 100 (f / f_o - 1) (%)"),
        (
            "vs_best_pct",
            "gap to the best answer found",
            "gap to the best answer 100 (f / f_best - 1) (%)",
        ),
        (
            "no_answer_pct",
            "no feasible answer",
            "no feasible answer (% of scenarios known feasible)",
        ),
    )
    methods = [m for m in dict.fromkeys(table["method"]) if m not in exclude]
    figure = Figure(figsize=(16, 4.2 * len(sizes) + 0.6))
    axes = figure.subplots(len(sizes), len(panels), squeeze=False)
    for row, size in zip(axes, sizes, strict=True):
        part = table[table["size"] == size]
        levels = list(dict.fromkeys(part["level"]))
        x = np.arange(len(levels), dtype=float)
        for k, method in enumerate(methods):
            line = part[part["method"] == method].set_index("level").reindex(levels)
            shift = dodge(k, len(methods), max(len(levels) - 1, 1), share=0.03)
            for ax, (column, _title, _label) in zip(row, panels, strict=True):
                ax.plot(
                    x + shift,
                    line[column],
                    label=method,
                    ms=6,
                    mfc="white" if k % 2 else None,
                    **method_style(method, k),
                )
        for ax, (_column, title, label) in zip(row, panels, strict=True):
            ax.set_xticks(x, levels)
            ax.set_xlabel("tightness level (Q<s>: Q = ceil(s n / m); T<tau>: T = tau T*)")
            ax.set_ylabel(label, fontsize=9)
            ax.set_title(title if len(sizes) == 1 else f"{title}, {size}", fontsize=10)
            ax.grid(alpha=0.3)
        top = part.loc[part["method"].isin(methods), "no_answer_pct"].max()
        row[-1].set_ylim(-2.0, max(10.0, 1.1 * float(top)) if pd.notna(top) else 10.0)
    if methods:
        legend_outside(axes[0, -1])
    counts = table["scenarios"].max() if "scenarios" in table and len(table) else 0
    figure.suptitle(
        f"{', '.join(methods)} against the tightness of the limits: "
        f"{', '.join(sizes)}, {int(counts)} scenarios per size and level "
        "(methods shifted sideways a little)",
        fontsize=11,
    )
    figure.tight_layout()
    if path:
        figure.savefig(path, dpi=110, bbox_inches="tight")
    return figure


# -- command line -------------------------------------------------------------------------------

#: One line for ``taopt study --help``.
HELP = "chapter 6 (§6.2 future work): capacities and travel-time limits, true gap to f_o"
#: The file the study writes in ``--out``.
CSV = "budgeted.csv"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's own flags (the CLI adds the common ones: --out, --seed, --jobs, --plot,
    --time-limit (per exact run), --dask)."""
    parser.add_argument("--sizes", default="n50m10", help="comma-separated nNmM sizes")
    parser.add_argument(
        "--levels",
        default=",".join(LEVELS),
        metavar="LIST",
        help="comma-separated tightness levels: none, Q<s> (Q = ceil(s n/m)), T<tau> "
        "(T = tau x the longest route of the unlimited optimum), Q<s>T<tau>",
    )
    parser.add_argument(
        "--scenarios", type=int, default=10, help="scenarios per (size, level) (a count)"
    )
    parser.add_argument(
        "--methods",
        default=None,
        metavar="LIST",
        help="comma-separated, case-insensitive: MC,EVM,GA,pyvrp,ortools,exact (default: "
        "those installed here: MC,EVM,GA,exact, plus pyvrp,ortools with taopt[peers])",
    )
    parser.add_argument(
        "--peer-iterations",
        type=int,
        default=2000,
        help="PyVRP max_iterations (OR-Tools: solution_limit = this / 10): deterministic peers",
    )
    parser.add_argument(
        "--ga-generations",
        type=int,
        default=None,
        help="GA generations (default: none: the GA's own, the thesis's 350)",
    )


def run(args: argparse.Namespace) -> int:
    """Body of ``taopt study budgeted``: run, print and save the summary, plot."""
    options = (
        {"GA": {"generations": args.ga_generations}}
        if getattr(args, "ga_generations", None) is not None
        else None
    )
    df = budgeted_study(
        args.sizes,
        args.levels,
        args.scenarios,
        methods=args.methods,
        seed=getattr(args, "seed", SEED),
        out_dir=args.out,
        jobs=getattr(args, "jobs", 1),
        time_limit=getattr(args, "time_limit", TIME_LIMIT),
        peer_iterations=args.peer_iterations,
        method_options=options,
        progress=not getattr(args, "quiet", False),
        dask=getattr(args, "dask", None),
    )
    table = summarize(df)
    with pd.option_context("display.width", 160, "display.max_columns", 20):
        print(table.round(3).to_string(index=False, line_width=terminal_width()))
    Path(args.out).mkdir(parents=True, exist_ok=True)
    table.to_csv(Path(args.out) / "summary.csv", index=False)
    if getattr(args, "plot", None):
        plot_study(table, path=args.plot, exclude=("exact",))
        print(f"plot written to {args.plot}")
    return 0
