"""The chapter 2 gap study (§2.5, Tables 2.1–2.2) on the one study runner.

For each random scenario (§2.5 setup, :mod:`taopt.routing.scenarios`) every requested
method is run through :func:`taopt.solve` and one row per method is appended to
``<out>/drift.csv`` by :func:`taopt.orchestration.study.run_study` (resumable, any executor). Each row
carries the scenario's reference values:

* ``f_a`` — the thesis's Algorithm 1 value ("MCGA", ``taopt.bounds.thesis_mcga``), the
  denominator of the thesis's quality ratio ``q = f / f_a`` (2.26). On an asymmetric matrix
  it is *not* a valid lower bound, so q can dip below 1.
* ``valid_bound`` — the minimum-cost arborescence (Edmonds), a valid bound.

:func:`summarize` adds the per-scenario ``optimum`` (the exact row's objective where proven
optimal) and gives, per method, the mean of ``q_thesis = f / f_a`` (Table 2.1's measure),
``q_valid = f / valid_bound``, the true gap ``q_exact = f / optimum`` and the mean runtime
(Table 2.2); :func:`wilcoxon_pairs` the pairwise two-tailed Wilcoxon signed-rank tests at
5 % (§2.5).

Example
-------
>>> import tempfile
>>> from taopt.orchestration.studies.drift import drift_study, summarize
>>> with tempfile.TemporaryDirectory() as tmp:
...     df = drift_study(4, 2, 2, methods=["MC", "exact"], seed=1, out_dir=tmp, progress=False)
>>> len(df), sorted(df["method"].unique())
(4, ['MC', 'exact'])
>>> table = summarize(df)
>>> int(table.loc["exact", "optimal"]), bool(table.loc["MC", "q_exact"] >= 1 - 1e-9)
(2, True)
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Sequence
from itertools import combinations
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from taopt.bounds import arborescence, thesis_mcga
from taopt.defaults import SEED
from taopt.errors import InstanceError
from taopt.orchestration.cli import FIELD_HELP, deprecated, folder, parse_field, terminal_width
from taopt.orchestration.study import (
    Scenario,
    StudySpec,
    canonical_methods,
    check_integer,
    run_study,
    with_optimum,
)
from taopt.routing.problem import AssignmentProblem
from taopt.routing.scenarios import drift_scenario, scenario_seed

METHODS = ("VN", "VM", "EVN", "EVM", "MC", "GA", "exact")


# -- the command ``taopt study drift`` (found through the family's spec) ----------------------

#: One line for ``taopt study --help``.
HELP = "chapter 2 (§2.5, Tables 2.1-2.2): heuristics vs f_a, a valid bound and the optimum"
#: The file the study writes in ``--out``.
CSV = "drift.csv"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``taopt study drift`` (the CLI adds ``--out``, ``--seed``,
    ``--time-limit``, ``--jobs``, ``--dask`` and ``--plot``)."""
    parser.add_argument(
        "--sizes",
        default=None,
        metavar="LIST",
        help="comma-separated nNmM sizes (n targets, m vehicles), e.g. n10m3 or n50m10,n120m10; "
        "several sizes go to OUT/<size>/ (default: none: required)",
    )
    deprecated(parser, "--n", "n_alias", "--sizes nNmM", type=int)
    deprecated(parser, "--m", "m_alias", "--sizes nNmM", type=int)
    parser.set_defaults(n_alias=None, m_alias=None)
    parser.add_argument("--scenarios", type=int, default=400, help="random scenarios (a count)")
    parser.add_argument(
        "--methods",
        default="VN,VM,EVN,EVM,MC,GA,exact",
        metavar="LIST",
        help="comma-separated registered methods, case-insensitive (also pyvrp, ortools with "
        "taopt[peers])",
    )
    parser.add_argument("--field", default="thesis", metavar="SPEC", help=FIELD_HELP)
    parser.add_argument(
        "--ga-generations",
        type=int,
        default=None,
        help="GA generations (default: none: the GA's own, the thesis's 350)",
    )


def run(args: argparse.Namespace) -> int:
    """Body of ``taopt study drift``: run, print the summary and the tests, plot."""
    import pandas as pd

    from taopt.orchestration.studies.budgeted import parse_size
    from taopt.orchestration.studies.drift import drift_study, plot_gaps, summarize, wilcoxon_pairs

    sizes = _cli_sizes(args)
    pairs = [parse_size(size) for size in sizes]  # every size checked before anything runs
    options = (
        {"GA": {"generations": args.ga_generations}} if args.ga_generations is not None else None
    )
    field = "thesis" if args.field == "thesis" else parse_field(args.field)
    for size, (n, m) in zip(sizes, pairs, strict=True):
        out = folder(args.out) if len(sizes) == 1 else folder(args.out) / size
        plot = args.plot
        if plot and len(sizes) > 1:
            plot = str(folder(plot).with_name(f"{folder(plot).stem}_{size}.png"))
        if len(sizes) > 1:
            print(f"== {size} ({out})")
        df = drift_study(
            n,
            m,
            args.scenarios,
            methods=args.methods,
            seed=args.seed,
            out_dir=out,
            jobs=args.jobs,
            dask=args.dask,
            progress=not args.quiet,
            time_limit=args.time_limit,
            method_options=options,
            field=field,
        )
        table = summarize(df)
        with pd.option_context("display.width", 160, "display.max_columns", 20):
            print(table.round(4).to_string(line_width=terminal_width()))
            print()
            print(wilcoxon_pairs(df).round(4).to_string(index=False, line_width=terminal_width()))
        table.to_csv(out / "summary.csv")
        if plot:
            plot_gaps(df, path=plot)
            print(f"plot written to {plot}")
    return 0


def _cli_sizes(args: argparse.Namespace) -> list[str]:
    """``--sizes`` as a list, or the deprecated ``--n N --m M`` as one size."""
    n, m = getattr(args, "n_alias", None), getattr(args, "m_alias", None)
    if n is not None or m is not None:
        if n is None or m is None or args.sizes:
            raise InstanceError("give --sizes nNmM (the deprecated --n and --m go together)")
        return [f"n{n}m{m}"]
    if not args.sizes:
        raise InstanceError("--sizes is required: comma-separated nNmM sizes, e.g. n10m3")
    sizes = list(dict.fromkeys(s.strip() for s in args.sizes.split(",") if s.strip()))
    if not sizes:
        raise InstanceError(f"--sizes: no sizes in {args.sizes!r}")
    return sizes


__all__ = [
    "METHODS",
    "SPEC",
    "drift_study",
    "make_scenario",
    "summarize",
    "wilcoxon_pairs",
    "plot_gaps",
]


def make_scenario(key: dict, settings: dict) -> Scenario:
    """Scenario ``key["scenario"]`` of a study with ``settings`` (n, m, seed, field)."""
    seed = scenario_seed(settings["seed"], key["scenario"])
    cache = settings.get("context", {}).get("cache_dir")
    scenario = drift_scenario(
        settings["n"], settings["m"], seed, field=settings["field"], cache_dir=cache, jobs=1
    )
    problem = scenario.problem
    return Scenario(
        problem,
        columns={"n": settings["n"], "m": settings["m"]},
        references={"f_a": thesis_mcga(problem), "valid_bound": arborescence(problem)},
    )


def method_seed(key: dict, settings: dict) -> int:
    """Heuristics of scenario k get the scenario's own seed (as the thesis's study)."""
    return scenario_seed(settings["seed"], key["scenario"])


SPEC = StudySpec(
    name="drift",
    problem_type=AssignmentProblem,
    key_columns=("scenario",),
    make_scenario=make_scenario,
    scenario_columns=("n", "m"),
    reference_columns=("f_a", "valid_bound"),
    method_seed=method_seed,
)


def drift_study(
    n: int,
    m: int,
    scenarios: int,
    methods: str | Sequence[str] = METHODS,
    seed: int = SEED,
    out_dir: str | os.PathLike = "drift-study",
    jobs: int = 1,
    progress: bool = True,
    time_limit: float | None = None,
    method_options: dict[str, dict] | None = None,
    field: Any = "thesis",
    dask: str | None = None,
) -> pd.DataFrame:
    """Run the §2.5 study: ``scenarios`` random scenarios × ``methods``.

    Parameters
    ----------
    n, m : int
        Targets and vehicles (the thesis's "n50m10" is n=50, m=10).
    scenarios : int
        Number of scenarios (the thesis: 400); scenario k has seed ``scenario_seed(seed, k)``.
    methods : str or list of str
        Registered methods of AssignmentProblem ("VN", ..., "GA", "exact", "pyvrp", ...;
        a comma-separated string is allowed).
    seed : int
        Study seed.
    out_dir : path
        Folder for ``drift.csv``, its settings and the cached matrices.
    jobs : int
        Worker processes (or Dask workers with ``dask="local"``).
    progress : bool
        A tqdm progress bar over scenarios.
    time_limit : float, optional
        Seconds per exact (or peer) solve; a limit leaves ``optimum`` NaN for that scenario.
    method_options : dict, optional
        Keyword options per method, e.g. ``{"GA": {"generations": 50}}``.
    field : Field, None or "thesis"
        The drift (default: the thesis's §2.5 field).
    dask : str, optional
        "local" or a scheduler address (see :func:`taopt.orchestration.study.run_study`).

    Returns
    -------
    pandas.DataFrame
        One row per (scenario, method): the runner's columns plus ``optimum`` and
        ``exact_bound`` (from the scenario's exact row, when there is one).

    Raises
    ------
    InstanceError
        Bad sizes or methods (nothing is written), or ``out_dir`` holds a study with other
        settings (the message names the differing keys).
    """
    methods = parse_methods(methods)
    # every argument checked before anything is written (issue 15, item 7)
    n, m = check_integer("n", n, 1), check_integer("m", m, 1)
    scenarios = check_integer("scenarios", scenarios, 1)
    seed = check_integer("seed", seed, 0)
    field_description = field if isinstance(field, str) or field is None else field.to_dict()
    settings = {"n": int(n), "m": int(m), "seed": int(seed), "field": field_description}
    df = run_study(
        SPEC,
        [{"scenario": k} for k in range(int(scenarios))],
        methods,
        settings,
        out_dir,
        jobs=jobs,
        dask=dask,
        time_limit=time_limit,
        method_options=method_options,
        context={"cache_dir": str(Path(out_dir) / "matrices")},
        progress=progress,
    )
    return with_optimum(df, SPEC)


def parse_methods(methods: str | Sequence[str]) -> list[str]:
    """A comma-separated string or a list of method names, deduplicated, non-empty."""
    if isinstance(methods, str):
        methods = [m.strip() for m in methods.split(",") if m.strip()]
    methods = list(dict.fromkeys(methods))
    if not methods:
        raise InstanceError("no methods given")
    return canonical_methods(AssignmentProblem, methods)  # "mc" -> "MC"


def _with_ratios(df: pd.DataFrame) -> pd.DataFrame:
    if "optimum" not in df.columns:
        df = with_optimum(df, SPEC)
    return df.assign(
        q_thesis=df["objective"] / df["f_a"],
        q_valid=df["objective"] / df["valid_bound"],
        q_exact=df["objective"] / df["optimum"],
    )


def _method_order(names: Any) -> list[str]:
    present = list(dict.fromkeys(names))
    return [m for m in METHODS if m in present] + [m for m in present if m not in METHODS]


def summarize(df: pd.DataFrame) -> pd.DataFrame:
    """Per method: mean ratios and runtime (Tables 2.1 and 2.2, plus the true gap).

    Columns: ``scenarios``, ``q_thesis`` (mean f / f_a, Table 2.1's q), ``q_valid`` (mean
    f / arborescence bound), ``q_exact`` (mean f / optimum over scenarios with a proven
    optimum), ``gap_exact_pct`` (mean ``100 (f − f_o) / f_o``), ``below_f_a`` (scenarios where
    f < f_a, i.e. the thesis's bound is exceeded by a real solution), ``time_s`` (mean
    runtime), ``optimal`` (how many runs were proven optimal).
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
    return table.loc[_method_order(table.index)]


def wilcoxon_pairs(df: pd.DataFrame, column: str = "q_thesis", alpha: float = 0.05) -> pd.DataFrame:
    """Pairwise two-tailed Wilcoxon signed-rank tests on paired scenarios (§2.5).

    Returns one row per pair (a, b): the p-value, whether the difference is significant at
    ``alpha``, and which method is better (lower mean) when it is (``"same"`` otherwise).
    """
    from scipy.stats import wilcoxon

    data = _with_ratios(df)
    wide = data.pivot(index="scenario", columns="method", values=column)
    methods = _method_order(wide.columns)
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


def plot_gaps(df: Any, column: str = "gap_pct", ax: Any = None, path: str | None = None) -> Any:
    """Boxplot per method of the true gap to the certified optimum (or another ratio).

    Parameters
    ----------
    df : pandas.DataFrame
        Rows of :func:`drift_study`.
    column : {"gap_pct", "q_thesis", "q_valid", "q_exact"}
        ``gap_pct`` (default): the true gap ``100 (f / f_o - 1)`` to the scenario's proven
        optimum f_o (an "exact" row with status optimal; scenarios without one are left
        out, and the exact method itself, 0 by definition, is not drawn). Without any
        certified optimum it falls back to ``q_valid`` and says so in the axis label.
        ``q_thesis`` is ``f / f_a`` (Table 2.1's q, not a gap: f_a is no valid bound),
        ``q_valid`` ``f / valid bound`` and ``q_exact`` ``f / f_o``.
    ax : matplotlib Axes, optional
    path : str, optional
        Save the figure as PNG there.

    Returns
    -------
    matplotlib Axes
    """
    from matplotlib.figure import Figure

    data = _with_ratios(df)
    data = data.assign(gap_pct=100.0 * (data["q_exact"] - 1.0))
    certified = int(data.loc[data["optimum"].notna(), "scenario"].nunique())
    if column in ("gap_pct", "q_exact"):
        if certified == 0:
            column = "q_valid"
        else:
            data = data[(data["method"] != "exact") & data["optimum"].notna()]
    methods = _method_order(data["method"])
    sizes = list(dict.fromkeys(zip(data["n"].astype(int), data["m"].astype(int), strict=True)))
    boxes, names = [], []
    for n_m in sizes:
        part = data[(data["n"] == n_m[0]) & (data["m"] == n_m[1])]
        for method in methods:
            boxes.append(part.loc[part["method"] == method, column].dropna().to_numpy())
            names.append(method if len(sizes) == 1 else f"{method}\nn{n_m[0]}m{n_m[1]}")
    if ax is None:
        ax = Figure(figsize=(max(7.0, 0.8 * len(boxes) + 1.5), 4)).add_subplot()
    ax.boxplot(boxes, tick_labels=names)
    reference = 0.0 if column == "gap_pct" else 1.0
    ax.axhline(reference, color="0.5", lw=0.8, ls="--")
    labels = {
        "gap_pct": "true gap to the certified optimum\n100 (f / f_o - 1) (%)",
        "q_thesis": "q = f / f_a (2.26), ratio (1)",
        "q_valid": "f / arborescence bound (valid, no optimum certified), ratio (1)",
        "q_exact": "true ratio f / f_o (certified optimum), ratio (1)",
    }
    ax.set_xlabel("method (box: quartiles, whiskers: 1.5 IQR, circles: outliers)")
    ax.set_ylabel(labels.get(column, column))
    size_text = (
        f"n = {sizes[0][0]} targets, m = {sizes[0][1]} vehicles"
        if len(sizes) == 1
        else "sizes " + ", ".join(f"n{n}m{m}" for n, m in sizes)
    )
    scenarios = int(df["scenario"].nunique()) if len(df) else 0
    what = {
        "gap_pct": f"true gap to the optimum, certified in {certified} of {scenarios} scenarios",
        "q_exact": f"f / f_o, optimum certified in {certified} of {scenarios} scenarios",
    }.get(column, f"{column} over {scenarios} scenarios")
    ax.set_title(f"{what}\n{size_text} (dashed: {reference:g})", fontsize=10)
    if path:
        ax.figure.savefig(path, dpi=120, bbox_inches="tight")
    return ax
