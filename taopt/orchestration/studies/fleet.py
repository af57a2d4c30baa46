"""The fleet study (thesis §6.2, recommendations 2 and 3): how far are the heuristics from the
optimum when several trucks carry several multi-parcel drones under precedence, and what does
a second truck, a second drone or a larger drone capacity buy?

Scenarios
---------
Chapter 5's style (the ``dag40`` setup): :func:`taopt.fleet.instances.residential_fleet`, n
drone-only houses beside the streets of a residential network (≈ 1 km across), a layered
precedence DAG (:func:`taopt.delivery.dags.layered_dag`) of one of two densities
(:data:`DENSITIES`), with a fleet ``K<k>D<d>c<c>``: k trucks, d drones each, capacity c.
Scenario s of a size has the same houses, streets and DAG for every fleet (paired
comparisons).

Rows and summary
----------------
The study runner's resumable CSV ``<out>/fleet.csv`` keyed by (n, fleet, density, scenario,
method), with ``K, D, c`` and the reference ``lower`` (:func:`taopt.lower`, fast strength, and
chapter 5's bound on K = D = c = 1). :func:`summarize` gives per (n, fleet, density, method):
``gap_pct`` (mean ``100 (f / f_o − 1)`` over scenarios whose optimum the ``"exact"`` method
certified), ``gap_lb_pct`` (mean ``100 (f / LB − 1)`` over all scenarios, LB the larger of the
exact run's proven bound and ``lower``: an upper bound on the true gap), ``f_mean`` and
``time_s``. :func:`fleet_value` gives, per (n, density), the mean best-known makespan of each
fleet relative to ``K1D1c1`` (what a second truck, drone or more capacity buys).

References
----------
Thesis §5.5 (the dag40 setup), §6.2; Bai et al. (IEEE T-RO 2025) for 3P.
"""

from __future__ import annotations

import argparse
import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from taopt.errors import InstanceError
from taopt.fleet.instances import residential_fleet
from taopt.fleet.problem import FleetProblem
from taopt.orchestration.study import Scenario, StudySpec, check_integer, run_study, with_optimum
from taopt.routing.scenarios import scenario_seed

METHODS = ("NIA", "MMA", "SMMA", "3P", "ILS", "exact")
SIZES = (10, 20, 40)
FLEETS = tuple(f"K{k}D{d}c{c}" for k in (1, 2, 3) for d in (1, 2) for c in (1, 2, 3))
#: Extra-edge probabilities of the layered DAG (chapter 5's dag40 uses 0.1).
DENSITIES = {"sparse": 0.05, "dense": 0.3}
#: Deterministic budgets of the searches (iterations, not seconds: same seed, same rows).
SEARCH_OPTIONS = {"3P": {"iterations": 3}, "ILS": {"iterations": 10}}

HELP = "chapter 6 (§6.2): trucks with multi-parcel drones under precedence, heuristics' gaps"
#: The file the study writes in ``--out``.
CSV = "fleet.csv"

__all__ = [
    "CSV",
    "DENSITIES",
    "FLEETS",
    "HELP",
    "METHODS",
    "SPEC",
    "add_arguments",
    "fleet_study",
    "fleet_value",
    "parse_fleet",
    "plot_study",
    "run",
    "summarize",
]


def parse_fleet(text: str) -> tuple[int, int, int]:
    """``"K2D1c3"`` -> (2, 1, 3).

    Raises
    ------
    InstanceError
        Not of the form ``K<k>D<d>c<c>`` with k, c >= 1 and d >= 1.
    """
    match = re.fullmatch(r"K(\d+)D(\d+)c(\d+)", str(text).strip())
    if not match or min(int(g) for g in match.groups()) < 1:
        raise InstanceError(f"fleet {text!r} must be K<trucks>D<drones>c<capacity>, each >= 1")
    k, d, c = (int(g) for g in match.groups())
    return k, d, c


def _items(values: str | Sequence[Any], what: str) -> list[str]:
    items = [v.strip() for v in values.split(",")] if isinstance(values, str) else list(values)
    items = [str(v) for v in items if str(v)]
    if not items:
        raise InstanceError(f"{what}: give at least one")
    return items


def make_scenario(key: dict, settings: dict) -> Scenario:
    """Scenario ``key`` = (n, fleet, density, scenario) with its lower bound."""
    from taopt.fleet.bounds import chapter5_bound, fleet_lower

    k, d, c = parse_fleet(key["fleet"])
    seed = scenario_seed(settings["seed"], key["scenario"])
    problem = residential_fleet(
        int(key["n"]),
        trucks=k,
        drones=d,
        capacity=c,
        density=DENSITIES[key["density"]],
        seed=seed,
    )
    lower = max(fleet_lower(problem, "fast"), chapter5_bound(problem, "fast"))
    return Scenario(problem, columns={"K": k, "D": d, "c": c}, references={"lower": lower})


def method_seed(key: dict, settings: dict) -> int:
    """The scenario's own seed for every fleet and density (paired comparisons)."""
    return scenario_seed(settings["seed"], key["scenario"])


SPEC = StudySpec(
    name="fleet",
    problem_type=FleetProblem,
    key_columns=("n", "fleet", "density", "scenario"),
    make_scenario=make_scenario,
    scenario_columns=("K", "D", "c"),
    reference_columns=("lower",),
    info_columns=("stopped_by",),
    method_seed=method_seed,
)


def fleet_study(
    sizes: str | Sequence[Any] = SIZES,
    fleets: str | Sequence[str] = FLEETS,
    densities: str | Sequence[str] = tuple(DENSITIES),
    scenarios: int = 3,
    methods: str | Sequence[str] = METHODS,
    seed: int = 1,
    out_dir: str | os.PathLike[str] = "fleet-study",
    jobs: int = 1,
    time_limit: float | None = 60.0,
    exact_max_n: int = 10,
    progress: bool = True,
    dask: str | None = None,
) -> pd.DataFrame:
    """Run the study: sizes × fleets × densities × ``scenarios`` × methods.

    Parameters
    ----------
    sizes, fleets, densities : str (comma-separated) or list
        n values; ``K<k>D<d>c<c>`` names; ``"sparse"``/``"dense"``.
    scenarios : int
        Scenarios per (n, fleet, density).
    methods : str or list
        Registered FleetProblem methods. ``"exact"`` runs only where ``n <= exact_max_n``
        (beyond, the gap is measured to the lower bound alone).
    time_limit : float or None
        Seconds per method run (stops the exact method with a proven bound; the searches
        stop on their iteration budgets, :data:`SEARCH_OPTIONS`, well before).

    Returns
    -------
    pandas.DataFrame
        The rows plus ``optimum`` and ``exact_bound`` per scenario.

    Raises
    ------
    InstanceError
        A bad size, fleet, density, count or method (nothing is written).
    """
    ns = [check_integer("n", int(v), 1) for v in _items(sizes, "sizes")]
    fleets = _items(fleets, "fleets")
    for fleet in fleets:
        parse_fleet(fleet)
    densities = _items(densities, "densities")
    for density in densities:
        if density not in DENSITIES:
            raise InstanceError(f"density {density!r}: one of {sorted(DENSITIES)}")
    methods = _items(methods, "methods")
    scenarios = check_integer("scenarios", scenarios, 1)
    seed = check_integer("seed", seed, 0)
    options = {m: dict(o) for m, o in SEARCH_OPTIONS.items() if m in methods}
    frames = []
    for exact_here in (True, False):
        keys = [
            {"n": n, "fleet": fleet, "density": density, "scenario": s}
            for n in ns
            if (n <= exact_max_n) == exact_here
            for s in range(int(scenarios))
            for density in densities
            for fleet in fleets
        ]
        chosen = [m for m in methods if exact_here or m != "exact"]
        if keys and chosen:
            frames.append(
                run_study(
                    SPEC,
                    keys,
                    chosen,
                    {"seed": int(seed)},
                    Path(out_dir) / ("exact" if exact_here else "bound"),
                    jobs=jobs,
                    dask=dask,
                    time_limit=time_limit,
                    method_options=options,
                    progress=progress,
                )
            )
    df = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=SPEC.columns)
    return with_optimum(df, SPEC)


def _with_measures(df: pd.DataFrame) -> pd.DataFrame:
    if "optimum" not in df.columns:
        df = with_optimum(df, SPEC)
    bound = np.fmax(df["exact_bound"].to_numpy(float), df["lower"].to_numpy(float))
    return df.assign(
        gap_pct=100 * (df["objective"] / df["optimum"] - 1),
        gap_lb_pct=100 * (df["objective"] / bound - 1),
    )


def summarize(df: pd.DataFrame) -> pd.DataFrame:
    """Per (n, fleet, density, method): ``scenarios``, ``certified`` (scenarios with a
    certified optimum), ``gap_pct`` (mean true gap over those, %), ``gap_lb_pct`` (mean gap to
    the best proven lower bound, %, an upper bound on the true gap), ``f_mean`` (mean
    objective, s) and ``time_s`` (mean runtime)."""
    data = _with_measures(df)
    rows = []
    keys = ["n", "fleet", "density", "method"]
    for (n, fleet, density, method), group in data.groupby(keys, sort=False):
        certified = group.dropna(subset=["gap_pct"])
        rows.append(
            {
                "n": n,
                "fleet": fleet,
                "density": density,
                "method": method,
                "scenarios": group["scenario"].nunique(),
                "certified": len(certified),
                "gap_pct": float(certified["gap_pct"].mean()) if len(certified) else np.nan,
                "gap_lb_pct": float(group["gap_lb_pct"].mean()),
                "f_mean": float(group["objective"].mean()),
                "time_s": float(group["runtime"].mean()),
            }
        )
    return pd.DataFrame(rows)


def fleet_value(df: pd.DataFrame, reference: str = "K1D1c1") -> pd.DataFrame:
    """Per (n, density, fleet): the mean over scenarios of the best known makespan (the best
    answer of any method, the certified optimum where there is one) divided by the same
    scenario's under ``reference`` (``ratio``), and how many scenarios were certified for both.
    """
    best = df.groupby(["n", "density", "scenario", "fleet"])["objective"].min().rename("best")
    table = best.reset_index()
    ref = table[table["fleet"] == reference].set_index(["n", "density", "scenario"])["best"]
    index = pd.MultiIndex.from_frame(table[["n", "density", "scenario"]])
    table["ratio"] = table["best"].to_numpy() / ref.reindex(index).to_numpy()
    out = table.groupby(["n", "density", "fleet"], sort=False)["ratio"].agg(["mean", "count"])
    return out.reset_index().rename(columns={"mean": "ratio", "count": "scenarios"})


def plot_study(table: pd.DataFrame, path: str | None = None) -> Any:
    """Gap to the lower bound (%) and true gap (%) per fleet, one line per method, one row of
    panels per (n, density)."""
    from matplotlib.figure import Figure

    from taopt.plot import method_style

    groups = list(dict.fromkeys(zip(table["n"], table["density"], strict=True)))
    panels = (
        ("gap_pct", "true gap 100 (f / f_o − 1) (%)"),
        ("gap_lb_pct", "gap to the lower bound 100 (f / LB − 1) (%)"),
    )
    figure = Figure(figsize=(14, 3.8 * len(groups)))
    axes = figure.subplots(len(groups), len(panels), squeeze=False)
    for row, (n, density) in zip(axes, groups, strict=True):
        part = table[(table["n"] == n) & (table["density"] == density)]
        fleets = list(dict.fromkeys(part["fleet"]))
        x = np.arange(len(fleets))
        for method in dict.fromkeys(part["method"]):
            if method == "exact":
                continue
            line = part[part["method"] == method].set_index("fleet").reindex(fleets)
            for ax, (column, _) in zip(row, panels, strict=True):
                ax.plot(x, line[column], label=method, **method_style(method))
        for ax, (_, label) in zip(row, panels, strict=True):
            ax.set_xticks(x, fleets, rotation=45, fontsize=8)
            ax.set_xlabel("fleet: K trucks, D drones per truck, capacity c")
            ax.set_ylabel(label, fontsize=9)
            ax.set_title(f"n = {n}, {density} precedence", fontsize=10)
            ax.grid(alpha=0.3)
        row[0].legend(fontsize=8)
    figure.tight_layout()
    if path:
        figure.savefig(path, dpi=110, bbox_inches="tight")
    return figure


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's own flags (the CLI adds --out, --seed, --jobs, --plot, --time-limit,
    --dask)."""
    parser.add_argument("--sizes", default="10,20,40", help="comma-separated n values")
    parser.add_argument(
        "--fleets",
        default=",".join(FLEETS),
        metavar="LIST",
        help="comma-separated K<trucks>D<drones>c<capacity> (default: K 1-3, D 1-2, c 1-3)",
    )
    parser.add_argument(
        "--densities", default="sparse,dense", help="comma-separated: sparse, dense"
    )
    parser.add_argument("--scenarios", type=int, default=3, help="scenarios per cell")
    parser.add_argument(
        "--methods", default=",".join(METHODS), metavar="LIST", help="comma-separated methods"
    )
    parser.add_argument(
        "--exact-max-n", type=int, default=10, help="run the exact method only up to this n"
    )


def run(args: argparse.Namespace) -> int:
    """Body of ``taopt study fleet``: run, print and save the summaries, plot."""
    df = fleet_study(
        args.sizes,
        args.fleets,
        args.densities,
        args.scenarios,
        methods=args.methods,
        seed=getattr(args, "seed", 1),
        out_dir=args.out,
        jobs=getattr(args, "jobs", 1),
        time_limit=getattr(args, "time_limit", 60.0),
        exact_max_n=args.exact_max_n,
        progress=not getattr(args, "quiet", False),
        dask=getattr(args, "dask", None),
    )
    table = summarize(df)
    value = fleet_value(df)
    with pd.option_context("display.width", 160, "display.max_columns", 20):
        print(table.round(2).to_string(index=False))
        print()
        print(value.round(3).to_string(index=False))
    Path(args.out).mkdir(parents=True, exist_ok=True)
    table.to_csv(Path(args.out) / "summary.csv", index=False)
    value.to_csv(Path(args.out) / "fleet_value.csv", index=False)
    if getattr(args, "plot", None):
        plot_study(table, path=args.plot)
        print(f"plot written to {args.plot}")
    return 0
