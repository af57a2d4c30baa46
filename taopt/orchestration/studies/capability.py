"""The chapter 3 study (§3.7, Figs. 3.4–3.6, Tables 3.1–3.2) on the one study runner.

Scenarios: n50m10, n70m10 and n90m10 (10 vehicles; 50, 70 or 90 targets) × |A| in
{1, 3, 5, 7, 10}, 50 scenarios each in the thesis, drawn by
:func:`taopt.capability.instances.thesis_scenario` (the 1000 m square, the thesis field, the
three obstacles, travel times by the grid planner with 10 m cells and 16 moves; demands
uniform over the non-empty subsets of A). Scenario ``(n, m, A, k)`` has the seed
:func:`~taopt.capability.instances.scenario_seed` of ``(study seed, n, m, A, k)``, so it does
not depend on which other scenarios run or in which order.

Methods: "DTAA" (§3.5), "GA" (§3.7's GA per class), "exact" (the certified corrected model),
optionally "MC" (chapter 2's MC per class) and "joint". Chapter 2's peers (PyVRP, OR-Tools)
are registered for :class:`~taopt.AssignmentProblem` only, so they do not run here.

Each row carries per-scenario reference values: ``f_a`` (Theorem 3.4's Algorithm 1 value, the
denominator of the thesis's q (3.15); not a valid bound on these asymmetric matrices),
``valid_bound`` (Edmonds per class), ``f_da`` (Lemma 3.6), ``demands`` (Σ_j |demands_j|), and
DTAA's ``rounds``, ``messages`` and ``bytes``.

:func:`summarize` gives per (instance, |A|, method) the mean and the variance of
``q_thesis = f / f^a`` (Fig. 3.4–3.6, Table 3.1), the mean ``q_valid = f / valid bound``, the
mean true ratio ``q_exact = f / f^o`` where the optimum is certified, and the mean runtime
(Table 3.2); :func:`thesis_table` lays one measure out as the thesis's tables;
:func:`plot_figures` draws Figs. 3.4–3.6.

Example
-------
>>> import tempfile
>>> from taopt.orchestration.studies.capability import capability_study, thesis_table
>>> with tempfile.TemporaryDirectory() as tmp:
...     df = capability_study(instances=("n6m2",), capabilities=(1, 2), scenarios=1,
...                           methods=["DTAA", "exact"], out_dir=tmp, progress=False)
>>> thesis_table(df, "q_thesis").shape  # (instance, method) x |A|
(2, 2)
>>> f = df.pivot_table(index="A", columns="method", values="objective")
>>> bool((f["DTAA"] >= f["exact"] * (1 - 1e-9)).all())
True
"""

from __future__ import annotations

import argparse
import os
import re
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from taopt.bounds import arborescence, doubled_arborescence, thesis_mcga
from taopt.capability.instances import (
    STUDY_CELL,
    STUDY_NEIGHBOURS,
    scenario_seed,
    thesis_scenario,
)
from taopt.capability.problem import CapabilityProblem
from taopt.defaults import SEED
from taopt.errors import InstanceError
from taopt.navigation.grid import NEIGHBOURHOODS
from taopt.orchestration.cli import deprecated, folder, terminal_width
from taopt.orchestration.study import (
    Scenario,
    StudySpec,
    canonical_methods,
    check_integer,
    check_positive,
    parse_integers,
    run_study,
    with_optimum,
)

INSTANCES = ("n50m10", "n70m10", "n90m10")
CAPABILITIES = (1, 3, 5, 7, 10)
METHODS = ("DTAA", "GA", "exact")

#: Table 3.1 of the thesis: average variance of q over 50 scenarios (GA, DTAA) per |A|.
#: The thesis prints five values per row under a header of four (|A| = 10 is missing from
#: the header); the columns are read here as |A| = 1, 3, 5, 7, 10, as in Table 3.2.
THESIS_TABLE_3_1 = {
    ("n50m10", "GA"): (0.4975, 0.0210, 0.0036, 0.0025, 0.0015),
    ("n50m10", "DTAA"): (0.0035, 0.0030, 0.0024, 0.0024, 0.0014),
    ("n70m10", "GA"): (0.0515, 0.1015, 0.0453, 0.0257, 0.0018),
    ("n70m10", "DTAA"): (0.0026, 0.0017, 0.0012, 0.0013, 0.0009),
    ("n90m10", "GA"): (0.0297, 0.1086, 0.0700, 0.0570, 0.0262),
    ("n90m10", "DTAA"): (0.0025, 0.0013, 0.0011, 0.0009, 0.0013),
}
#: Table 3.2 of the thesis: average computation time (s), Matlab on an Intel i5-4590.
THESIS_TABLE_3_2 = {
    ("n50m10", "GA"): (37.04, 41.12, 49.66, 58.27, 72.74),
    ("n50m10", "DTAA"): (0.19, 0.32, 0.46, 0.60, 0.82),
    ("n70m10", "GA"): (65.06, 81.63, 105.94, 128.53, 156.09),
    ("n70m10", "DTAA"): (0.29, 0.48, 0.71, 0.93, 1.25),
    ("n90m10", "GA"): (104.55, 134.19, 172.45, 213.34, 273.92),
    ("n90m10", "DTAA"): (0.38, 1.19, 2.29, 3.20, 4.40),
}


# -- the command ``taopt study capability`` (found through the family's spec) ----------------------

#: One line for ``taopt study --help``.
HELP = (
    "chapter 3 (§3.7, Figs. 3.4-3.6, Tables 3.1-3.2): DTAA and GA vs f^a, a valid bound "
    "and the certified optimum"
)
#: The file the study writes in ``--out``.
CSV = "capability.csv"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``taopt study capability`` (the CLI adds ``--out``, ``--seed``,
    ``--time-limit``, ``--jobs``, ``--dask`` and ``--plot``)."""
    parser.add_argument(
        "--sizes", default="n50m10,n70m10,n90m10", help="comma-separated nNmM sizes"
    )
    deprecated(parser, "--instances", "sizes", "--sizes (a list of nNmM sizes)")
    parser.add_argument("--capabilities", default="1,3,5,7,10", help="comma-separated |A|")
    parser.add_argument(
        "--scenarios", type=int, default=50, help="scenarios per (size, |A|) (a count)"
    )
    parser.add_argument("--first-scenario", type=int, default=0, help="index of the first scenario")
    parser.add_argument(
        "--methods",
        default="DTAA,GA,exact",
        metavar="LIST",
        help="comma-separated: DTAA,GA,exact,MC,joint",
    )
    parser.add_argument("--cell", type=float, default=10.0, help="grid cell side (m)")
    parser.add_argument("--neighbours", type=int, choices=[8, 16], default=16, help="grid moves")
    parser.add_argument(
        "--ga-generations",
        type=int,
        default=None,
        help="GA generations (default: none: the GA's own, 350)",
    )
    parser.add_argument(
        "--ga-operators",
        default="ox-inversion",
        help="chapter 2 GA operator set: 'ox-inversion' (the thesis's plain GA, as in "
        "docs/reproduction/chapter3.md), 'memetic', or 'default' (the GA's own default)",
    )


def run(args: argparse.Namespace) -> int:
    """Body of ``taopt study capability``: run, print Tables 3.1-3.2 beside taopt's, plot."""
    import pandas as pd

    from taopt.orchestration.studies.capability import (
        capability_study,
        plot_figures,
        summarize,
        thesis_comparison,
    )

    ga = {"operators": args.ga_operators} if args.ga_operators != "default" else {}
    if args.ga_generations is not None:
        ga["generations"] = args.ga_generations
    options = {"GA": ga} if ga else None
    df = capability_study(
        instances=[i.strip() for i in args.sizes.split(",") if i.strip()],
        capabilities=args.capabilities,  # parsed and checked by capability_study
        scenarios=args.scenarios,
        methods=args.methods,
        seed=args.seed,
        out_dir=args.out,
        jobs=args.jobs,
        dask=args.dask,
        time_limit=args.time_limit,
        method_options=options,
        cell=args.cell,
        neighbours=args.neighbours,
        first_scenario=args.first_scenario,
        progress=not args.quiet,
    )
    table = summarize(df)
    shown = ["scenarios", "q_thesis", "var_q_thesis", "q_valid", "q_exact", "time_s"]
    with pd.option_context("display.width", 160, "display.max_columns", 20):
        print(table[shown].round(4).to_string(line_width=terminal_width()))
        for name in ("3.1", "3.2"):
            print(f"\nTable {name}, thesis beside taopt:")
            print(thesis_comparison(df, name).round(4).to_string(line_width=terminal_width()))
    table.to_csv(folder(args.out) / "summary.csv")
    if args.plot:
        plot_figures(df, path=args.plot)
        print(f"plot written to {args.plot}")
    return 0


__all__ = [
    "INSTANCES",
    "CAPABILITIES",
    "METHODS",
    "SPEC",
    "THESIS_TABLE_3_1",
    "THESIS_TABLE_3_2",
    "parse_instance",
    "make_scenario",
    "capability_study",
    "summarize",
    "thesis_table",
    "thesis_comparison",
    "plot_figures",
    "markdown_report",
]


def parse_instance(name: str) -> tuple[int, int]:
    """``"n50m10"`` -> ``(50, 10)``."""
    match = re.fullmatch(r"n(\d+)m(\d+)", str(name).strip())
    if not match:
        raise InstanceError(f"an instance is written nNmM (e.g. n50m10), got {name!r}")
    n, m = int(match[1]), int(match[2])
    if n < 1 or m < 1:
        raise InstanceError(f"instance {name!r} needs n >= 1 and m >= 1")
    return n, m


def _seed(key: dict, settings: dict) -> int:
    return scenario_seed(settings["seed"], key["n"], key["m"], key["A"], key["scenario"])


def make_scenario(key: dict, settings: dict) -> Scenario:
    """Scenario ``(n, m, A, scenario)`` of the §3.7 study (module notes)."""
    seed = _seed(key, settings)
    problem = thesis_scenario(
        key["n"], key["m"], key["A"], seed, settings["cell"], settings["neighbours"]
    ).problem
    return Scenario(
        problem,
        columns={"scenario_seed": seed, "demands": problem.demand_pairs()},
        references={
            "f_a": thesis_mcga(problem),
            "valid_bound": arborescence(problem),
            "f_da": doubled_arborescence(problem),
        },
    )


def method_seed(key: dict, settings: dict) -> int:
    """Randomised methods of a scenario get the scenario's own seed."""
    return _seed(key, settings)


SPEC = StudySpec(
    name="capability",
    problem_type=CapabilityProblem,
    key_columns=("n", "m", "A", "scenario"),
    make_scenario=make_scenario,
    scenario_columns=("scenario_seed", "demands"),
    reference_columns=("f_a", "valid_bound", "f_da"),
    info_columns=("rounds", "messages", "bytes"),
    method_seed=method_seed,
)


def capability_study(
    instances: Sequence[str] = INSTANCES,
    capabilities: Sequence[int] = CAPABILITIES,
    scenarios: int = 50,
    methods: str | Sequence[str] = METHODS,
    seed: int = SEED,
    out_dir: str | os.PathLike = "capability-study",
    jobs: int = 1,
    dask: str | None = None,
    time_limit: float | None = None,
    method_options: dict[str, dict] | None = None,
    cell: float = STUDY_CELL,
    neighbours: int = STUDY_NEIGHBOURS,
    first_scenario: int = 0,
    progress: bool = True,
) -> pd.DataFrame:
    """Run the §3.7 study: instances × |A| × scenarios × methods, resumable.

    Parameters
    ----------
    instances : sequence of str
        "nNmM" names (the thesis: n50m10, n70m10, n90m10).
    capabilities : sequence of int, or str
        |A| values, each at most m (the thesis: 1, 3, 5, 7, 10); "1,3,5" is accepted.
    scenarios : int
        Scenarios per (instance, |A|) (the thesis: 50).
    methods : str or sequence of str
        Registered methods of CapabilityProblem ("DTAA", "GA", "exact", "MC", "joint").
    seed : int
        Study seed.
    out_dir : path
        Folder of ``capability.csv`` and its settings.
    jobs, dask : see :func:`taopt.orchestration.study.run_study`
    time_limit : float, optional
        Seconds per exact solve; a stopped solve leaves ``optimum`` NaN for its scenario.
    method_options : dict, optional
        ``{"GA": {"generations": 100}}`` etc.
    cell, neighbours : float, int
        Grid planner settings of the travel times.
    first_scenario : int
        Index of the first scenario (run scenarios ``first_scenario ..`` in chunks).

    Returns
    -------
    pandas.DataFrame
        The runner's rows plus ``instance``, ``optimum`` and ``exact_bound``.
    """
    methods = canonical_methods(CapabilityProblem, methods)  # "dtaa" -> "DTAA"
    # every argument checked before anything is written (issue 15, item 7)
    scenarios = check_integer("scenarios", scenarios, 1)
    first_scenario = check_integer("first_scenario", first_scenario, 0)
    seed = check_integer("seed", seed, 0)
    cell = check_positive("cell", cell)
    if check_integer("neighbours", neighbours, 1) not in NEIGHBOURHOODS:
        raise InstanceError(f"neighbours must be one of {sorted(NEIGHBOURHOODS)}, got {neighbours}")
    capabilities = parse_integers("capabilities", capabilities, 1)
    if isinstance(instances, str):
        instances = [part.strip() for part in instances.split(",") if part.strip()]
    if not instances:
        raise InstanceError("instances: no instance given (expected e.g. n50m10)")
    keys = []
    for name in instances:
        n, m = parse_instance(name)
        for k in capabilities:
            if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 1 <= k <= m:
                raise InstanceError(f"|A| must be an integer in 1..m = {m} for {name}, got {k!r}")
            keys += [
                {"n": n, "m": m, "A": int(k), "scenario": s}
                for s in range(first_scenario, first_scenario + scenarios)
            ]
    settings = {"seed": int(seed), "cell": float(cell), "neighbours": int(neighbours)}
    df = run_study(
        SPEC,
        keys,
        methods,
        settings,
        out_dir,
        jobs=jobs,
        dask=dask,
        time_limit=time_limit,
        method_options=method_options,
        progress=progress,
    )
    return _with_ratios(with_optimum(df, SPEC))


def _with_ratios(df: pd.DataFrame) -> pd.DataFrame:
    if "optimum" not in df.columns or "exact_bound" not in df.columns:
        df = with_optimum(df.drop(columns=["optimum", "exact_bound"], errors="ignore"), SPEC)
    keys = list(SPEC.key_columns)
    incumbent = df[df["method"] == "exact"].groupby(keys)["objective"].min()
    index = pd.MultiIndex.from_frame(df[keys])
    best_known = incumbent.reindex(index).to_numpy(dtype=float)
    return df.assign(
        instance=[f"n{n}m{m}" for n, m in zip(df["n"], df["m"], strict=True)],
        q_thesis=df["objective"] / df["f_a"],
        q_valid=df["objective"] / df["valid_bound"],
        q_exact=df["objective"] / df["optimum"],
        # every scenario, certified or not: f / (exact incumbent) <= f / f^o <= f / bound
        q_exact_low=df["objective"] / best_known,
        q_exact_high=df["objective"] / df["exact_bound"],
    )


def summarize(df: pd.DataFrame) -> pd.DataFrame:
    """Per (instance, |A|, method): the measures of Figs. 3.4–3.6 and Tables 3.1–3.2.

    Columns: ``scenarios``; ``q_thesis`` and ``var_q_thesis`` (mean and variance, ddof 1, of
    f / f^a: the thesis's q (3.15) and Table 3.1); ``q_valid`` (mean f / valid bound);
    ``q_exact`` (mean f / f^o over scenarios with a certified optimum) and ``var_q_exact``;
    ``worst_q_exact``; ``q_exact_low`` and ``q_exact_high`` (means over every scenario of f
    / exact incumbent and f / proven bound, which bracket f / f^o where the exact solve
    stopped at its time limit); ``optimum_over_f_a`` (mean f^o / f^a: where the optimum lies on the
    thesis's scale); ``time_s`` (mean runtime, Table 3.2); ``optimal`` (runs proven
    optimal); ``rounds``, ``messages``, ``bytes`` (mean, DTAA).
    """
    data = _with_ratios(df)
    data = data.assign(optimum_over_f_a=data["optimum"] / data["f_a"])
    keys = ["instance", "A", "method"]
    grouped = data.groupby(keys, sort=False)
    table = pd.DataFrame(
        {
            "scenarios": grouped["scenario"].nunique(),
            "q_thesis": grouped["q_thesis"].mean(),
            "var_q_thesis": grouped["q_thesis"].var(ddof=1),
            "q_valid": grouped["q_valid"].mean(),
            "q_exact": grouped["q_exact"].mean(),
            "var_q_exact": grouped["q_exact"].var(ddof=1),
            "worst_q_exact": grouped["q_exact"].max(),
            "q_exact_low": grouped["q_exact_low"].mean(),
            "q_exact_high": grouped["q_exact_high"].mean(),
            "optimum_over_f_a": grouped["optimum_over_f_a"].mean(),
            "time_s": grouped["runtime"].mean(),
            "optimal": grouped["status"].apply(lambda s: int((s == "optimal").sum())),
            "rounds": grouped["rounds"].mean(),
            "messages": grouped["messages"].mean(),
            "bytes": grouped["bytes"].mean(),
        }
    )
    order = {name: k for k, name in enumerate(METHODS)}
    table = table.reset_index()
    table["_order"] = table["method"].map(lambda m: order.get(m, len(order)))
    table = table.sort_values(["instance", "_order", "A"]).drop(columns="_order")
    return table.set_index(keys)


def thesis_table(df: pd.DataFrame, column: str = "q_thesis", how: str = "mean") -> pd.DataFrame:
    """One measure laid out as the thesis's tables: rows (instance, method), columns |A|.

    ``how`` is "mean" (Fig. 3.4–3.6's q, Table 3.2's time with ``column="runtime"``) or
    "var" (Table 3.1's variance of q).
    """
    data = _with_ratios(df)
    if how not in ("mean", "var"):
        raise InstanceError(f"how must be 'mean' or 'var', got {how!r}")
    grouped = data.groupby(["instance", "method", "A"])[column]
    values = grouped.mean() if how == "mean" else grouped.var(ddof=1)
    return values.unstack("A")


def thesis_comparison(df: pd.DataFrame, table: str = "3.1") -> pd.DataFrame:
    """Our Table 3.1 (variance of q) or 3.2 (mean time) beside the thesis's, per |A|.

    Returns rows (instance, method, source) with source "thesis" or "taopt".
    """
    if table == "3.1":
        ours, printed = thesis_table(df, "q_thesis", "var"), THESIS_TABLE_3_1
    elif table == "3.2":
        ours, printed = thesis_table(df, "runtime", "mean"), THESIS_TABLE_3_2
    else:
        raise InstanceError(f"table must be '3.1' or '3.2', got {table!r}")
    rows: list[dict[Any, Any]] = []  # keys: column names and the capability counts |A|
    for (instance, method), values in printed.items():
        thesis_row = dict(zip(CAPABILITIES, values, strict=True))
        rows.append({"instance": instance, "method": method, "source": "thesis", **thesis_row})
        if (instance, method) in ours.index:
            mine = ours.loc[(instance, method)]
            rows.append(
                {
                    "instance": instance,
                    "method": method,
                    "source": "taopt",
                    **{k: mine.get(k, np.nan) for k in CAPABILITIES},
                }
            )
    return pd.DataFrame(rows).set_index(["instance", "method", "source"])


def plot_figures(df: pd.DataFrame, column: str = "q_thesis", path: str | None = None) -> Any:
    """Figs. 3.4–3.6: mean ``column`` against |A|, one panel per instance.

    The exact method's line on the ``q_thesis`` scale is ``f^o / f^a``: the thesis's q of
    the optimum itself, the floor no method can go below.

    Returns
    -------
    matplotlib Figure
    """
    from matplotlib.figure import Figure

    from taopt.capability.plot import plot_quality

    table = summarize(df).reset_index()
    names = [i for i in INSTANCES if i in set(table["instance"])] or sorted(set(table["instance"]))
    figure = Figure(figsize=(4.5 * len(names), 4.0))
    axes = np.atleast_1d(figure.subplots(1, len(names)))
    for ax, name in zip(axes, names, strict=True):
        plot_quality(table, column, instance=name, ax=ax)
    if path:
        figure.tight_layout()
        figure.savefig(path, dpi=120)
    return figure


def _markdown(frame: pd.DataFrame, digits: int = 4) -> str:
    """A small pipe table (no extra dependency)."""
    header = "| " + " | ".join(str(c) for c in frame.columns) + " |"
    rule = "|" + "---|" * len(frame.columns)
    rows = []
    for values in frame.itertuples(index=False):
        cells = []
        for v in values:
            if isinstance(v, (float, np.floating)):
                cells.append("–" if not np.isfinite(v) else f"{v:.{digits}f}")
            else:
                cells.append(str(v))
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join([header, rule, *rows])


def markdown_report(df: pd.DataFrame) -> str:
    """The tables of ``docs/reproduction/chapter3.md`` from a study's rows.

    Mean q = f / f^a (Figs. 3.4–3.6), the true ratio f / f^o over certified scenarios with
    its worst case, f^o / f^a, Tables 3.1 (variance of q) and 3.2 (mean time) beside the
    thesis's, certification counts and DTAA's communication.
    """
    data = _with_ratios(df)
    table = summarize(data).reset_index()
    parts = []

    def wide(column: str, methods: Sequence[str]) -> pd.DataFrame:
        rows = table[table["method"].isin(methods)]
        out = rows.pivot_table(index=["instance", "method"], columns="A", values=column)
        out = out.reindex(sorted(out.index, key=lambda im: (im[0], list(methods).index(im[1]))))
        out.columns = [f"A={k}" for k in out.columns]
        return out.reset_index()

    known = ("DTAA", "GA", "GA-memetic", "MC", "exact")
    methods = [m for m in known if m in set(table["method"])]
    counts = table.pivot_table(index="instance", columns="A", values="scenarios", aggfunc="max")
    counts.columns = [f"A={k}" for k in counts.columns]
    parts.append("#### Scenarios per cell\n\n" + _markdown(counts.reset_index(), 0))
    parts.append(
        "#### Mean q = f / f^a (3.15), Figs. 3.4–3.6 (the exact row is f^o / f^a)\n\n"
        + _markdown(wide("q_thesis", methods))
    )
    heuristics = [m for m in methods if m != "exact"]
    parts.append(
        "#### Mean true ratio f / f^o over certified scenarios\n\n"
        + _markdown(wide("q_exact", heuristics))
    )
    parts.append(
        "#### Worst f / f^o over certified scenarios\n\n"
        + _markdown(wide("worst_q_exact", heuristics))
    )
    low, high = wide("q_exact_low", methods), wide("q_exact_high", methods)
    bracket = low.copy()
    for column in [c for c in low.columns if str(c).startswith("A=")]:
        bracket[column] = [
            f"{a:.4f}–{b:.4f}" for a, b in zip(low[column], high[column], strict=True)
        ]
    parts.append(
        "#### Mean f / f^o over every scenario, bracketed by the exact incumbent and its proven "
        "bound (the exact row: incumbent / bound)\n\n" + _markdown(bracket)
    )
    parts.append(
        "#### Mean f / valid bound (Edmonds per class); the exact row is f^o / bound\n\n"
        + _markdown(wide("q_valid", methods))
    )
    exact = table[table["method"] == "exact"]
    if len(exact):
        certified = exact.pivot_table(index="instance", columns="A", values="optimal")
        certified.columns = [f"A={k}" for k in certified.columns]
        parts.append(
            "#### Scenarios certified optimal (exact)\n\n" + _markdown(certified.reset_index(), 0)
        )
    for name, how in (("3.1", "variance of q"), ("3.2", "mean time (s)")):
        comparison = thesis_comparison(data, name).reset_index()
        comparison.columns = [
            f"A={c}" if isinstance(c, (int, np.integer)) else c for c in comparison.columns
        ]
        parts.append(f"#### Table {name}: {how}, thesis beside taopt\n\n" + _markdown(comparison))
    times = wide("time_s", methods)
    parts.append("#### Mean run time (s), every method\n\n" + _markdown(times))
    dtaa = table[table["method"] == "DTAA"]
    if len(dtaa):
        comm = dtaa[["instance", "A", "rounds", "messages", "bytes"]].copy()
        comm["MB"] = comm.pop("bytes") / 1e6
        parts.append("#### DTAA communication (complete graph; means)\n\n" + _markdown(comm, 1))
    return "\n\n".join(parts) + "\n"


if __name__ == "__main__":  # pragma: no cover
    import sys

    frames = [pd.read_csv(path) for path in sys.argv[1:]]
    print(markdown_report(pd.concat(frames, ignore_index=True)))
