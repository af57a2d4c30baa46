"""The chapter 2 gap study (§2.5, Tables 2.1–2.2), resumable and parallel.

For each random scenario (§2.5 setup, :mod:`taopt.routing.scenarios`) every
method is run and one row per method is appended to ``<out>/results.csv`` as
soon as the scenario finishes (a scenario's rows in one write), through
:class:`taopt.studyio.ResultsStore`: the settings that change the numbers (n, m,
seed, field, time_limit, method_options) are kept in ``<out>/config.json`` and a
re-run with other settings is refused; torn lines are dropped. A re-run computes
only the (scenario, method) rows that are missing: a scenario that lacks some
requested methods is re-run for those methods only (its matrix comes from the
cache, its heuristics use the same seed, so the rows are those of a full run).
Rows of methods not asked for now are kept on disk. So an interrupted study
resumes without losing anything, and the same seed gives the same table.

Each row also carries, per scenario, the three reference values:

* ``f_a`` — the thesis's Algorithm 1 value ("MCGA", :func:`thesis_mcga`), the
  denominator of the thesis's quality ratio ``q = f / f_a`` (2.26). On an
  asymmetric matrix it is *not* a valid lower bound (see
  :mod:`taopt.routing.bounds`), so q can dip below 1.
* ``valid_bound`` — the minimum-cost arborescence (Edmonds), a valid bound.
* ``optimum`` — the exact optimum of (2.2)–(2.5) (``solve_routing``), when it
  was proven (NaN otherwise), and ``exact_bound`` its proven bound.

:func:`summarize` gives, per method, the mean of ``q_thesis = f / f_a``
(Table 2.1's measure), ``q_valid = f / valid_bound`` and the true gap
``q_exact = f / optimum``, the mean runtime (Table 2.2); :func:`wilcoxon_pairs`
the pairwise two-tailed Wilcoxon signed-rank tests at 5 % (§2.5).

Example
-------
>>> df = drift_study(6, 2, 3, methods=["MC", "exact"], seed=1, out_dir=tmp)  # doctest: +SKIP
>>> summarize(df)  # doctest: +SKIP
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from itertools import combinations
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from taopt.errors import InstanceError
from taopt.studyio import ResultsStore

METHODS = ("VN", "VM", "EVN", "EVM", "MC", "GA", "exact")
COLUMNS = [
    "scenario",
    "seed",
    "n",
    "m",
    "method",
    "objective",
    "runtime",
    "status",
    "f_a",
    "valid_bound",
    "optimum",
    "exact_bound",
    "complete",  # last column: a torn (half-written) line lacks it and is discarded
]
RESULTS = "results.csv"
CONFIG = "config.json"

__all__ = ["METHODS", "drift_study", "summarize", "wilcoxon_pairs", "register_cli", "run_scenario"]


def _parse_methods(methods: str | Sequence[str]) -> list[str]:
    if isinstance(methods, str):
        methods = [m.strip() for m in methods.split(",") if m.strip()]
    methods = list(dict.fromkeys(methods))
    unknown = [m for m in methods if m not in METHODS]
    if unknown or not methods:
        raise InstanceError(f"unknown method(s) {unknown}; choose from {list(METHODS)}")
    return methods


def run_scenario(
    n: int,
    m: int,
    k: int,
    seed: int,
    methods: Sequence[str],
    cache_dir: str | None = None,
    time_limit: float | None = None,
    method_options: dict[str, dict] | None = None,
    field: Any = "thesis",
) -> list[dict[str, Any]]:
    """Run every method on scenario ``k`` of a study with seed ``seed``; return its rows."""
    from taopt.heuristics import run as run_heuristic
    from taopt.models import solve_routing
    from taopt.routing.bounds import arborescence_bound, thesis_mcga
    from taopt.routing.problem import evaluate_routes
    from taopt.routing.scenarios import drift_scenario, scenario_seed

    method_options = method_options or {}
    scenario_rng_seed = scenario_seed(seed, k)
    scenario = drift_scenario(n, m, scenario_rng_seed, field=field, cache_dir=cache_dir, jobs=1)
    problem = scenario.problem
    f_a = thesis_mcga(problem)
    valid_bound = arborescence_bound(problem)
    results = {}
    for method in methods:
        started = time.perf_counter()
        if method == "exact":
            solution = solve_routing(
                problem, time_limit=time_limit, **method_options.get(method, {})
            )
        else:
            solution = run_heuristic(
                method, problem, seed=scenario_rng_seed, **method_options.get(method, {})
            )
        elapsed = time.perf_counter() - started
        objective = evaluate_routes(problem, solution.routes)  # the one scorer
        if abs(objective - solution.objective) > 1e-6 * max(1.0, abs(objective)):
            raise InstanceError(
                f"{method} reported {solution.objective} but evaluate gives {objective} "
                f"(scenario {k})"
            )
        results[method] = (solution, objective, elapsed)
    optimum = exact_bound = np.nan
    if "exact" in results:
        exact = results["exact"][0]
        exact_bound = float(exact.bound) if exact.bound is not None else np.nan
        if exact.status == "optimal":
            optimum = results["exact"][1]
    rows = []
    for method, (solution, objective, elapsed) in results.items():
        rows.append(
            {
                "scenario": k,
                "seed": scenario_rng_seed,
                "n": n,
                "m": m,
                "method": method,
                "objective": objective,
                "runtime": solution.runtime or elapsed,
                "status": solution.status,
                "f_a": f_a,
                "valid_bound": valid_bound,
                "optimum": optimum,
                "exact_bound": exact_bound,
                "complete": 1,
            }
        )
    return rows


def drift_study(
    n: int,
    m: int,
    scenarios: int,
    methods: str | Sequence[str] = METHODS,
    seed: int = 1,
    out_dir: str | os.PathLike = "drift-study",
    jobs: int = 1,
    progress: bool = True,
    time_limit: float | None = None,
    method_options: dict[str, dict] | None = None,
    field: Any = "thesis",
) -> pd.DataFrame:
    """Run the §2.5 study: ``scenarios`` random scenarios × ``methods``.

    Parameters
    ----------
    n, m : int
        Targets and vehicles (the thesis's "n50m10" is n=50, m=10).
    scenarios : int
        Number of scenarios (the thesis: 400); scenario k has seed
        ``scenario_seed(seed, k)``.
    methods : str or list of str
        Any of ``VN, VM, EVN, EVM, MC, GA, exact`` (comma-separated string allowed).
    seed : int
        Study seed.
    out_dir : path
        Folder for ``results.csv``, ``config.json`` and the cached matrices.
    jobs : int
        Scenarios solved in parallel (processes).
    progress : bool
        A tqdm progress bar over scenarios.
    time_limit : float, optional
        Seconds per exact solve; a limit leaves ``optimum`` NaN for that scenario.
    method_options : dict, optional
        Keyword options per method, e.g. ``{"GA": {"generations": 50}}``.
    field : Field, None or "thesis"
        The drift (default: the thesis's §2.5 field).

    Returns
    -------
    pandas.DataFrame
        One row per (scenario, method) for the requested methods and the
        scenarios ``0..scenarios-1`` that have all of them (rows finished by
        earlier runs included), columns :data:`COLUMNS` without ``complete``,
        sorted. ``optimum`` and ``exact_bound`` are filled from the scenario's
        ``exact`` row whenever one is on disk.

    Raises
    ------
    InstanceError
        Bad sizes or methods, or ``out_dir`` holds a study with other settings
        (the message names the differing keys).
    """
    methods = _parse_methods(methods)
    if int(n) < 1 or int(m) < 1 or int(scenarios) < 0:
        raise InstanceError(f"need n >= 1, m >= 1, scenarios >= 0; got {n}, {m}, {scenarios}")
    if int(jobs) < 1:
        raise InstanceError(f"jobs must be >= 1, got {jobs}")
    scenarios = int(scenarios)
    field_description = field if isinstance(field, str) or field is None else field.to_dict()
    # everything that changes a row; the methods and the number of scenarios are not here:
    # they are the rows' key, so asking for other methods or more scenarios extends the file
    settings = {
        "n": int(n),
        "m": int(m),
        "seed": int(seed),
        "field": field_description,
        "time_limit": None if time_limit is None else float(time_limit),
        "method_options": method_options or {},
    }
    store = ResultsStore(out_dir, RESULTS, COLUMNS, ["scenario", "method"], settings, CONFIG)
    done = store.done_keys()
    todo = []  # (scenario, the requested methods it still lacks)
    for k in range(scenarios):
        missing = [name for name in methods if store.key(k, name) not in done]
        if missing:
            todo.append((k, missing))
    cache = str(Path(out_dir) / "matrices")
    arguments = [
        (n, m, k, seed, missing, cache, time_limit, method_options, field) for k, missing in todo
    ]

    from tqdm import tqdm

    bar = tqdm(
        total=scenarios,
        initial=scenarios - len(todo),
        disable=not progress,
        desc=f"drift n{n}m{m}",
        unit="scenario",
    )
    try:
        if jobs == 1 or len(todo) <= 1:
            for args in arguments:
                store.append(run_scenario(*args))  # a scenario's rows in one write
                bar.update(1)
        else:
            with ProcessPoolExecutor(max_workers=int(jobs)) as pool:
                futures = [pool.submit(run_scenario, *args) for args in arguments]
                for future in as_completed(futures):
                    store.append(future.result())
                    bar.update(1)
    finally:
        bar.close()
    return _study_table(store.read(), methods, scenarios)


def _study_table(df: pd.DataFrame, methods: Sequence[str], scenarios: int) -> pd.DataFrame:
    """The rows of scenarios ``0..scenarios-1`` that have every method in ``methods``.

    ``optimum`` and ``exact_bound`` are per-scenario references: they are taken
    from the scenario's ``exact`` row whenever one is on disk, so rows written in
    separate runs (a method added later) carry the same values.
    """
    df = df.copy()
    exact = df[df["method"] == "exact"].set_index("scenario")
    if len(exact):
        has = df["scenario"].isin(exact.index)
        for column in ("optimum", "exact_bound"):
            df.loc[has, column] = df.loc[has, "scenario"].map(exact[column])
    df = df[df["method"].isin(methods) & (df["scenario"] < scenarios)]
    counts = df.groupby("scenario")["method"].nunique()
    df = df[df["scenario"].isin(counts[counts == len(methods)].index)]
    order = {name: i for i, name in enumerate(METHODS)}
    df = df.assign(_order=df["method"].map(order)).sort_values(["scenario", "_order"])
    return df.drop(columns=["_order"]).reset_index(drop=True)


def _with_ratios(df: pd.DataFrame) -> pd.DataFrame:
    return df.assign(
        q_thesis=df["objective"] / df["f_a"],
        q_valid=df["objective"] / df["valid_bound"],
        q_exact=df["objective"] / df["optimum"],
    )


def summarize(df: pd.DataFrame) -> pd.DataFrame:
    """Per method: mean ratios and runtime (Tables 2.1 and 2.2, plus the true gap).

    Columns: ``scenarios``, ``q_thesis`` (mean f / f_a, Table 2.1's q),
    ``q_valid`` (mean f / arborescence bound), ``q_exact`` (mean f / optimum
    over scenarios with a proven optimum), ``gap_exact_pct`` (mean
    ``100 (f − f_o) / f_o``), ``below_f_a`` (scenarios where f < f_a, i.e. the
    thesis's bound is exceeded by a real solution), ``time_s`` (mean runtime),
    ``optimal`` (how many runs were proven optimal).
    """
    data = _with_ratios(df)
    grouped = data.groupby("method", sort=False)
    table = pd.DataFrame(
        {
            "scenarios": grouped["scenario"].nunique(),
            "q_thesis": grouped["q_thesis"].mean(),
            "q_valid": grouped["q_valid"].mean(),
            "q_exact": grouped["q_exact"].mean(),
            "gap_exact_pct": grouped["q_exact"].apply(lambda q: 100 * (q - 1).mean()),
            "below_f_a": grouped.apply(
                lambda g: int((g["objective"] < g["f_a"] * (1 - 1e-9)).sum()), include_groups=False
            ),
            "time_s": grouped["runtime"].mean(),
            "optimal": grouped["status"].apply(lambda s: int((s == "optimal").sum())),
        }
    )
    order = [m for m in METHODS if m in table.index]
    return table.loc[order]


def wilcoxon_pairs(df: pd.DataFrame, column: str = "q_thesis", alpha: float = 0.05) -> pd.DataFrame:
    """Pairwise two-tailed Wilcoxon signed-rank tests on paired scenarios (§2.5).

    Returns one row per pair (a, b): the p-value, whether the difference is
    significant at ``alpha``, and which method is better (lower mean) when it is
    (``"same"`` otherwise).
    """
    from scipy.stats import wilcoxon

    data = _with_ratios(df)
    wide = data.pivot(index="scenario", columns="method", values=column)
    methods = [m for m in METHODS if m in wide.columns]
    rows = []
    for a, b in combinations(methods, 2):
        pair = wide[[a, b]].dropna()
        diff = (pair[a] - pair[b]).to_numpy()
        if len(diff) == 0 or np.allclose(diff, 0.0, rtol=0, atol=1e-12):
            p_value = 1.0
        else:
            p_value = float(wilcoxon(pair[a], pair[b], alternative="two-sided").pvalue)
        significant = p_value < alpha
        better = (a if pair[a].mean() < pair[b].mean() else b) if significant else "same"
        rows.append(
            {
                "a": a,
                "b": b,
                "n": len(diff),
                "p_value": p_value,
                "significant": significant,
                "better": better,
            }
        )
    return pd.DataFrame(rows, columns=["a", "b", "n", "p_value", "significant", "better"])


# ------------------------------------------------------------------------------ CLI
def register_cli(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``drift`` subcommand (``taopt study drift ...``) to ``subparsers``.

    The parser's default ``func`` is :func:`run_cli`; call ``args.func(args)``.
    """
    parser = subparsers.add_parser(
        "drift",
        help="chapter 2 gap study (§2.5): heuristics vs f_a, a valid bound and the exact optimum",
        description=__doc__.split("\n\n")[0],
    )
    parser.add_argument("--n", type=int, required=True, help="number of targets")
    parser.add_argument("--m", type=int, required=True, help="number of vehicles")
    parser.add_argument("--scenarios", type=int, default=400)
    parser.add_argument(
        "--methods", default=",".join(METHODS), help="comma list of " + ",".join(METHODS)
    )
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", required=True, help="output folder (results.csv; resumable)")
    parser.add_argument("--jobs", type=int, default=1, help="scenarios in parallel")
    parser.add_argument("--time-limit", type=float, default=None, help="seconds per exact solve")
    parser.add_argument(
        "--ga-generations", type=int, default=None, help="GA iterations (thesis 350)"
    )
    parser.add_argument("--plot", default=None, help="write a boxplot of q to this PNG")
    parser.add_argument("--no-progress", action="store_true")
    parser.set_defaults(func=run_cli)
    return parser


def run_cli(args: argparse.Namespace) -> int:
    """Body of ``taopt study drift``: run, print the summary and the tests, plot."""
    options = {"GA": {"generations": args.ga_generations}} if args.ga_generations else None
    df = drift_study(
        args.n,
        args.m,
        args.scenarios,
        methods=args.methods,
        seed=args.seed,
        out_dir=args.out,
        jobs=args.jobs,
        progress=not args.no_progress,
        time_limit=args.time_limit,
        method_options=options,
    )
    table = summarize(df)
    with pd.option_context("display.width", 160, "display.max_columns", 20):
        print(table.round(4).to_string())
        print()
        print(wilcoxon_pairs(df).round(4).to_string(index=False))
    table.to_csv(Path(args.out) / "summary.csv")
    if args.plot:
        from taopt.routing.plot import plot_gaps

        plot_gaps(df, path=args.plot)
        print(f"plot written to {args.plot}")
    return 0
