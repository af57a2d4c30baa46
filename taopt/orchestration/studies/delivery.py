"""The chapter 5 study (§5.5): heuristics versus the bound (and the optimum when small).

Setups (all: 1000 m square, 121 stops on an 11×11 street grid with 100 m blocks,
depot at (0, 0), unit truck speed, τ = 0, customers uniform in the square, the same
customers for every flight range L = ratio · L0 with L0 = 1000 m):

* ``dag40`` — 40 customers under a layered precedence DAG
  (:func:`taopt.delivery.dags.layered_dag`, 8 layers, density 0.1; Fig. 5.5 is not
  printed), v_d / v_t = 1: Tables 5.1–5.2. The exact DP over order ideals
  (:func:`taopt.delivery.ideal_dp.ideal_dp`, method ``"exact"``) certifies every instance.
* ``pairs120`` — 120 customers in dial-a-ride pairs
  (:func:`taopt.delivery.dags.paired_precedences`), v_d / v_t = 1.4: Tables 5.5–5.7
  (``vd_ratio=1.0`` gives the setting of the withheld Tables 5.3–5.4).
* ``small`` — 7 customers, layered DAG of 3 layers, v_d / v_t = 1: small enough for
  the exact optimum in every run, so the true gaps of the heuristics and of the bound can
  be measured.

Measures per (instance, ratio, method): the makespan f (5.1) scored by
:func:`taopt.evaluate`; f_a the valid arborescence bound (Proposition 5.3, rule
"precede") and q = f / f_a (5.19); ``strong_bound`` the stronger valid bound
:func:`taopt.bounds.lower` and ``q_strong`` = f / strong_bound; ``bound_thesis_rule`` the arborescence on E^d built
from the sets S_r as printed (not a proven bound); the run time; and the optimum f_o and
the gap f / f_o − 1. The reference ``optimum`` is computed per scenario by the ideal DP
when n <= ``exact_max_n``; beyond, :func:`with_measures` takes it from the rows of method
``"exact"`` with status "optimal" of the same (instance, ratio) (e.g. a separate
``--methods exact`` run into the same folder, or a CSV of them joined with
:func:`with_optimum`).

Rows go through the one study runner (:func:`taopt.orchestration.study.run_study`) into
``out_dir/delivery_<setup>.csv`` (settings in ``delivery_<setup>.config.json``): resumable,
one writer, any executor (process pool or Dask). A re-run computes only the missing
(instance, ratio, method) rows.

Example
-------
>>> import tempfile
>>> from taopt.orchestration.studies.delivery import delivery_study, summarize
>>> with tempfile.TemporaryDirectory() as tmp:
...     df = delivery_study("small", instances=1, ratios=(0.6,), methods=("NIA", "exact"),
...                         out_dir=tmp, progress=False)
>>> table = summarize(df)["makespan"]
>>> len(df), bool(table["NIA"].iloc[0] >= table["exact"].iloc[0] * (1 - 1e-9))
(2, True)
"""

from __future__ import annotations

import argparse
import dataclasses
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from taopt.bounds import lower
from taopt.defaults import SEED
from taopt.delivery.bounds import arborescence_bound
from taopt.delivery.dags import layered_dag, paired_precedences
from taopt.delivery.ideal_dp import ideal_dp
from taopt.delivery.instance import DeliveryInstance
from taopt.errors import InstanceError
from taopt.orchestration.cli import deprecated, folder, method_list, parse_numbers, terminal_width
from taopt.orchestration.study import (
    Scenario,
    StudySpec,
    canonical_methods,
    check_integer,
    check_positive,
    run_study,
)

L0 = 1000.0
GRID_K = 11
SETUPS: dict[str, dict[str, Any]] = {
    "dag40": {"n": 40, "precedences": "layered", "layers": 8, "density": 0.1, "vd_ratio": 1.0},
    "pairs120": {"n": 120, "precedences": "pairs", "vd_ratio": 1.4},
    "small": {"n": 7, "precedences": "layered", "layers": 3, "density": 0.2, "vd_ratio": 1.0},
}
DEFAULT_RATIOS = (0.15, 0.30, 0.45, 0.60, 0.75, 0.90)
DEFAULT_METHODS = ("NIA", "MMA", "SMMA", "GA")
#: MILP seconds per solve in a study unless ``time_limit`` says otherwise.
EXACT_TIME_LIMIT = 60.0


def study_instance(
    setup: str, index: int, seed: int = 1, ratio: float = 0.3, vd_ratio: float | None = None
) -> DeliveryInstance:
    """Instance ``index`` of a §5.5 setup at flight range L = ratio · 1000 m.

    The customers and precedences depend on (seed, index) only, so the ratios of one
    instance share them, as in the thesis.
    """
    if setup not in SETUPS:
        raise InstanceError(f"unknown setup {setup!r}; choose from {sorted(SETUPS)}")
    spec = SETUPS[setup]
    rng = np.random.default_rng([int(seed), int(index)])
    n = spec["n"]
    customers = rng.uniform(0.0, L0, size=(n, 2))
    if spec["precedences"] == "pairs":
        pairs = paired_precedences(n, seed=rng)
    else:
        pairs = layered_dag(n, layers=spec["layers"], density=spec["density"], seed=rng)
    v_ratio = spec["vd_ratio"] if vd_ratio is None else float(vd_ratio)
    return DeliveryInstance.grid(
        customers,
        GRID_K,
        L0,
        v_drone=v_ratio,
        v_truck=1.0,
        flight_range=float(ratio) * L0,
        precedences=pairs,
        name=f"{setup}-{index}-L{ratio:g}",
    )


def _method_seed(key: dict, settings: dict) -> int:
    """Randomised methods of instance i get seed·10007 + i (the same at every ratio)."""
    return int(settings["seed"]) * 10_007 + int(key["instance"])


def make_scenario(key: dict, settings: dict) -> Scenario:
    """Instance ``key["instance"]`` at ``key["ratio"]`` with its bounds (and optimum if small)."""
    inst = study_instance(
        settings["setup"], key["instance"], settings["seed"], key["ratio"], settings["vd_ratio"]
    )
    try:
        thesis_bound = arborescence_bound(inst, rule="thesis")
    except Exception:  # the printed E^d may have no arborescence
        thesis_bound = math.nan
    optimum = ideal_dp(inst).objective if inst.n <= settings["exact_max_n"] else math.nan
    return Scenario(
        inst,
        columns={
            "setup": settings["setup"],
            "L": inst.flight_range,
            "vd_ratio": inst.v_drone / inst.v_truck,
            "n": inst.n,
        },
        references={
            "valid_bound": arborescence_bound(inst),
            "strong_bound": lower(inst),  # issue 16: never below valid_bound
            "bound_thesis_rule": thesis_bound,
            "optimum": optimum,
        },
    )


SPEC = StudySpec(
    name="delivery",
    problem_type=DeliveryInstance,
    key_columns=("instance", "ratio"),
    make_scenario=make_scenario,
    scenario_columns=("setup", "L", "vd_ratio", "n"),
    reference_columns=("valid_bound", "strong_bound", "bound_thesis_rule", "optimum"),
    info_columns=("tstar_cost",),
    method_seed=_method_seed,
)


def delivery_study(
    setup: str = "dag40",
    instances: int = 10,
    ratios: Sequence[float] = DEFAULT_RATIOS,
    methods: Sequence[str] = DEFAULT_METHODS,
    seed: int = SEED,
    out_dir: str | Path = "delivery-study",
    jobs: int = 1,
    progress: bool = True,
    exact_max_n: int = 8,
    vd_ratio: float | None = None,
    method_options: dict[str, dict[str, Any]] | None = None,
    time_limit: float | None = None,
    dask: str | None = None,
) -> pd.DataFrame:
    """Run the §5.5 experiment and return one row per (instance, ratio, method).

    Parameters
    ----------
    setup : {"dag40", "pairs120", "small"}
        See the module docstring.
    instances : int
        Number of random instances (10 in the thesis).
    ratios : sequence of float
        L / L0 values (Tables 5.1–5.6: 0.15 ... 0.90).
    methods : sequence of str
        Registered methods of DeliveryInstance: "NIA", "MMA", "SMMA", "GA", "exact" (the DP
        over order ideals, :func:`taopt.delivery.ideal_dp.ideal_dp`), "subset-dp" (n <= 14)
        or "milp" (the MILP (5.1)–(5.7)). An exact method is stopped after ``time_limit``
        (default :data:`EXACT_TIME_LIMIT` s when "exact" or "milp" is asked for); a stopped
        run is recorded with status "time_limit" and its proven gap.
    seed : int
        Instances depend on (seed, index); randomised methods get seed·10007 + index.
    out_dir : path
        Folder of the resumable ``delivery_<setup>.csv``.
    jobs : int
        Worker processes (or Dask workers with ``dask="local"``).
    progress : bool
        tqdm progress bar.
    exact_max_n : int
        Compute the optimum (ideal DP) per scenario when n <= this (beyond, the optimum
        comes from the "exact" rows, see :func:`with_measures`).
    vd_ratio : float, optional
        Override the setup's v_d / v_t (e.g. 1.0 for Tables 5.3–5.4's setting).
    method_options : dict, optional
        Per-method keyword options, e.g. ``{"GA": {"generations": 200}}``.
    time_limit : float, optional
        Wall-clock seconds per exact solve ("exact", "milp"; warm start included).
    dask : str, optional
        "local" or a scheduler address.

    Returns
    -------
    pandas.DataFrame
        The runner's columns plus ``makespan`` (= objective), ``q`` = f / valid bound
        (5.19) and ``gap_to_optimum`` = f / f_o − 1.

    Raises
    ------
    InstanceError
        Unknown setup, bad arguments (nothing is written), or ``out_dir`` holds results of
        this setup computed with other settings (the message names the keys).
    """
    if setup not in SETUPS:
        raise InstanceError(f"unknown setup {setup!r}; choose from {sorted(SETUPS)}")
    # every argument checked before anything is written (issue 15, item 7)
    instances = check_integer("instances", instances, 1)
    seed = check_integer("seed", seed, 0)
    vd_ratio = check_positive("vd_ratio", vd_ratio, allow_none=True)
    exact_max_n = check_integer("exact_max_n", exact_max_n, 0)
    try:
        ratios = [float(r) for r in ratios]
    except (TypeError, ValueError):
        raise InstanceError(f"ratios must be numbers, got {ratios!r}") from None
    if not ratios or not all(0 < r < math.inf for r in ratios):
        shown = ", ".join(f"{r:g}" for r in ratios)
        raise InstanceError(f"ratios must be positive and finite, got [{shown}]")
    methods = canonical_methods(DeliveryInstance, methods)  # "smma" -> "SMMA"
    if time_limit is None and {"exact", "milp"} & set(methods):
        time_limit = EXACT_TIME_LIMIT
    settings = {
        "setup": setup,
        "seed": int(seed),
        "vd_ratio": float(SETUPS[setup]["vd_ratio"] if vd_ratio is None else vd_ratio),
        "exact_max_n": int(exact_max_n),
    }
    keys = [{"instance": i, "ratio": r} for i in range(int(instances)) for r in ratios]
    df = run_study(
        dataclasses.replace(SPEC, name=f"delivery_{setup}"),
        keys,
        list(methods),
        settings,
        out_dir,
        jobs=jobs,
        dask=dask,
        time_limit=time_limit,
        method_options=method_options,
        progress=progress,
    )
    return with_measures(df)


def with_optimum(df: pd.DataFrame, exact: pd.DataFrame | None = None) -> pd.DataFrame:
    """Fill the ``optimum`` column where it is missing from certified "exact" rows.

    Parameters
    ----------
    df : DataFrame
        Study rows.
    exact : DataFrame, optional
        Rows of method "exact" (e.g. another run's CSV, same setup and seed); default the
        "exact" rows of ``df`` itself. Only rows with status "optimal" are used.

    Returns
    -------
    DataFrame
        ``df`` with ``optimum`` filled by (instance, ratio) where it was NaN.
    """
    source = df if exact is None else exact
    if df.empty or "method" not in source or "optimum" not in df:
        return df
    done = source[(source["method"] == "exact") & (source["status"] == "optimal")]
    if done.empty:
        return df
    best = done.groupby(["instance", "ratio"])["objective"].min()
    keys = pd.MultiIndex.from_frame(df[["instance", "ratio"]])
    found = pd.Series(best.reindex(keys).to_numpy(), index=df.index)
    return df.assign(optimum=df["optimum"].fillna(found))


def with_measures(df: pd.DataFrame) -> pd.DataFrame:
    """Add ``makespan`` (f), ``q`` = f / f_a (5.19, the valid bound), ``q_strong`` = f /
    :func:`taopt.bounds.lower` (NaN for rows written without it) and ``gap_to_optimum``
    (the ``optimum`` filled from certified "exact" rows first, :func:`with_optimum`)."""
    df = with_optimum(df)
    strong = df["strong_bound"] if "strong_bound" in df else math.nan
    return df.assign(
        makespan=df["objective"],
        q=df["objective"] / df["valid_bound"],
        q_strong=df["objective"] / strong,
        gap_to_optimum=df["objective"] / df["optimum"] - 1.0,
    )


def summarize(df: pd.DataFrame) -> pd.DataFrame:
    """Averages per (method, ratio), the thesis's way of reporting (Tables 5.1–5.7).

    Returns
    -------
    DataFrame indexed by (method, ratio) with the mean makespan, mean q (5.19), mean
    run time, the number of instances, and when optima are known the mean and max gap
    to the optimum and the mean bound / optimum ratio.
    """
    if df.empty:
        return pd.DataFrame()
    grouped = df.groupby(["method", "ratio"])
    out = pd.DataFrame(
        {
            "makespan": grouped["makespan"].mean(),
            "q": grouped["q"].mean(),
            "runtime": grouped["runtime"].mean(),
            "instances": grouped["instance"].nunique(),
        }
    )
    if df["optimum"].notna().any():
        out["gap_mean"] = grouped["gap_to_optimum"].mean()
        out["gap_max"] = grouped["gap_to_optimum"].max()
        out["bound_over_optimum"] = (
            (df["valid_bound"] / df["optimum"]).groupby([df["method"], df["ratio"]]).mean()
        )
    return out


def thesis_table(df: pd.DataFrame, value: str = "makespan") -> pd.DataFrame:
    """Method × L/L0 table of the mean ``value`` ("makespan", "q", "runtime", ...)."""
    return df.pivot_table(index="method", columns="ratio", values=value, aggfunc="mean")


def _counted(df: pd.DataFrame) -> str:
    """What a study plot averages over: "3 instances x 6 L/L0 values" (as plotted)."""

    def plural(count: int, word: str) -> str:
        return f"{count} {word}{'' if count == 1 else 's'}"

    column = "instance" if "instance" in df else "scenario" if "scenario" in df else None
    count = int(df[column].nunique()) if column else len(df)
    ratios = int(df["ratio"].nunique()) if "ratio" in df else 0
    text = plural(count, "instance" if column == "instance" else "scenario")
    return f"{text} x {plural(ratios, 'L/L0 value')}" if ratios else text


def plot_study(df: pd.DataFrame, value: str = "q", ax: Any = None, path: str | None = None) -> Any:
    """Mean ``value`` ("q", "makespan", "gap_to_optimum", ...) per method against L/L0.

    The picture of Tables 5.1–5.6: one line per method. Saves a PNG when ``path`` is given.

    Returns
    -------
    matplotlib Axes
    """
    from matplotlib.figure import Figure

    from taopt.plot import dodge, legend_outside, method_style

    if ax is None:
        ax = Figure(figsize=(7, 4)).add_subplot()
    table = thesis_table(df, value)
    ratios = table.columns.astype(float)
    span = float(ratios.max() - ratios.min()) if len(ratios) > 1 else 1.0
    for k, (method, row) in enumerate(table.iterrows()):
        # methods with equal means (two at the optimum) would hide each other's markers
        shift = dodge(k, len(table), span, share=0.012)
        ax.plot(
            row.index.astype(float) + shift,
            row.to_numpy(dtype=float),
            label=str(method),
            ms=6,
            mfc="white" if k % 2 else None,
            **method_style(str(method), k),
        )
    ax.set_xlabel("flight range L / L0, ratio (1); methods shifted sideways a little")
    ax.set_ylabel(
        {
            "q": "mean q = f / f_a (5.19), ratio (1)",
            "makespan": "mean makespan (5.1) (s)",
            "runtime": "mean run time (s)",
            "seconds": "mean run time (s)",
            "gap_to_optimum": "mean f / f_o - 1, ratio (1)",
        }.get(value, value)
    )
    ax.set_title(
        f"mean {value} per method against L / L0 ({_counted(df)})",
        fontsize=10,
    )
    legend_outside(ax)
    ax.grid(alpha=0.3)
    if path is not None:
        ax.figure.tight_layout()
        ax.figure.savefig(path, dpi=120, bbox_inches="tight")
    return ax


# -- the command ``taopt study delivery`` (found through the family's spec) ----------------------

#: One line for ``taopt study --help``.
HELP = "chapter 5 (§5.5, Tables 5.1-5.7): truck-drone heuristics vs the bound"
#: The file the study writes in ``--out``.
CSV = "delivery_<setup>.csv"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``taopt study delivery`` (the CLI adds ``--out``, ``--seed``,
    ``--time-limit``, ``--jobs``, ``--dask`` and ``--plot``)."""
    parser.add_argument(
        "--setup", choices=["dag40", "pairs120", "small"], default="dag40", help="§5.5 setup"
    )
    parser.add_argument(
        "--scenarios", type=int, default=10, help="random instances per setup (a count)"
    )
    deprecated(parser, "--instances", "scenarios", "--scenarios N (a count)", type=int)
    parser.add_argument(
        "--methods",
        default="NIA,MMA,SMMA,GA",
        metavar="LIST",
        help="comma-separated: NIA,MMA,SMMA,GA,exact (DP over order ideals),subset-dp,milp",
    )
    parser.add_argument(
        "--ratios", default="0.15,0.3,0.45,0.6,0.75,0.9", help="comma-separated L/L0 values"
    )
    parser.add_argument(
        "--vd-ratio",
        type=float,
        default=None,
        help="override v_d / v_t (default: none: the setup's)",
    )
    parser.add_argument(
        "--exact-max-n",
        type=int,
        default=8,
        help="compute optima (ideal DP) per scenario when n <= this; beyond, from 'exact' rows",
    )
    parser.add_argument(
        "--ga-generations",
        type=int,
        default=None,
        help="GA generations (default: none: the GA's own)",
    )


def run(args: argparse.Namespace) -> int:
    """Body of ``taopt study delivery``: run, print Tables 5.1-5.7's averages, plot."""
    import pandas as pd

    from taopt.orchestration.studies.delivery import delivery_study, plot_study, thesis_table

    ratios = tuple(parse_numbers(args.ratios, len(args.ratios.split(",")), "--ratios"))
    options = (
        {"GA": {"generations": args.ga_generations}} if args.ga_generations is not None else None
    )
    df = delivery_study(
        setup=args.setup,
        instances=args.scenarios,
        ratios=ratios,
        methods=method_list(args.methods) or (),
        seed=args.seed,
        out_dir=args.out,
        jobs=args.jobs,
        dask=args.dask,
        progress=not args.quiet,
        exact_max_n=args.exact_max_n,
        vd_ratio=args.vd_ratio,
        method_options=options,
        time_limit=args.time_limit,
    )
    with pd.option_context("display.width", 160, "display.max_columns", 20):
        print("average makespan f (5.1):")
        print(thesis_table(df, "makespan").round(1).to_string(line_width=terminal_width()))
        print("\naverage q = f / f_a (5.19):")
        print(thesis_table(df, "q").round(4).to_string(line_width=terminal_width()))
        print("\naverage run time (s):")
        print(thesis_table(df, "runtime").round(3).to_string(line_width=terminal_width()))
        if df["optimum"].notna().any():
            print("\naverage gap to the optimum f / f_o - 1:")
            print(
                thesis_table(df, "gap_to_optimum").round(4).to_string(line_width=terminal_width())
            )
    print(f"\nrows: {folder(args.out) / f'delivery_{args.setup}.csv'}")
    if args.plot:
        plot_study(df, "q", path=args.plot)
        print(f"plot written to {args.plot}")
    return 0


__all__ = [
    "SPEC",
    "SETUPS",
    "delivery_study",
    "make_scenario",
    "summarize",
    "thesis_table",
    "study_instance",
    "plot_study",
    "with_measures",
    "with_optimum",
]
