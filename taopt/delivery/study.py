"""The chapter 5 study (§5.5): heuristics versus the bound (and the optimum when small).

Setups (all: 1000 m square, 121 stops on an 11×11 street grid with 100 m blocks,
depot at (0, 0), unit truck speed, τ = 0, customers uniform in the square, the same
customers for every flight range L = ratio · L0 with L0 = 1000 m):

* ``dag40`` — 40 customers under a layered precedence DAG
  (:func:`taopt.delivery.dags.layered_dag`, 8 layers, density 0.1; Fig. 5.5 is not
  printed), v_d / v_t = 1: Tables 5.1–5.2.
* ``pairs120`` — 120 customers in dial-a-ride pairs
  (:func:`taopt.delivery.dags.paired_precedences`), v_d / v_t = 1.4: Tables 5.5–5.7
  (``vd_ratio=1.0`` gives the setting of the withheld Tables 5.3–5.4).
* ``small`` — 7 customers, layered DAG of 3 layers, v_d / v_t = 1: small enough for
  the exact optimum (:func:`taopt.delivery.schedule.optimal_plan`), so the true gaps of
  the heuristics and of the bound can be measured.

Measures per (instance, ratio, method): the makespan f (5.1) scored by
:func:`taopt.evaluate`; f_a the valid arborescence bound (Proposition 5.3, rule
"precede") and q = f / f_a (5.19); ``bound_thesis_rule`` the arborescence on E^d built
from the sets S_r as printed (not a proven bound); the run time; and for n <=
``exact_max_n`` the optimum f_o and the gap f / f_o − 1.

Rows are appended to ``out_dir/delivery_<setup>.csv`` as the tasks finish (in
finishing order, one task's rows in one fsync'd write, each ending with ``complete``
= 1) through :class:`taopt.studyio.ResultsStore`. The settings that change the numbers
(setup, seed, v_d / v_t, exact_max_n, the MILP time limit, method_options) are kept in
``out_dir/delivery_<setup>.config.json``; a re-run with other settings is refused with
an error naming them. A re-run computes only the (instance, ratio, method) rows that
are missing; rows of other methods, ratios or instances stay in the file; torn lines
left by a crash are dropped and recomputed.
"""

from __future__ import annotations

import argparse
import itertools
import math
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from taopt.delivery.bounds import arborescence_bound
from taopt.delivery.dags import layered_dag, paired_precedences
from taopt.delivery.instance import DeliveryInstance
from taopt.errors import InstanceError
from taopt.studyio import ResultsStore, normalize_key

L0 = 1000.0
GRID_K = 11
SETUPS: dict[str, dict[str, Any]] = {
    "dag40": {"n": 40, "precedences": "layered", "layers": 8, "density": 0.1, "vd_ratio": 1.0},
    "pairs120": {"n": 120, "precedences": "pairs", "vd_ratio": 1.4},
    "small": {"n": 7, "precedences": "layered", "layers": 3, "density": 0.2, "vd_ratio": 1.0},
}
DEFAULT_RATIOS = (0.15, 0.30, 0.45, 0.60, 0.75, 0.90)
DEFAULT_METHODS = ("NIA", "MMA", "SMMA", "GA")
COLUMNS = [
    "setup",
    "instance",
    "ratio",
    "L",
    "vd_ratio",
    "n",
    "method",
    "seed",
    "status",
    "makespan",
    "bound",
    "q",
    "bound_thesis_rule",
    "optimum",
    "gap_to_optimum",
    "runtime",
    "tstar_cost",
]
KEY = ["instance", "ratio", "method"]  # a row's identity in the resumable CSV


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


EXACT_TIME_LIMIT = 60.0  # seconds per MILP solve in a study, unless --time-limit says otherwise


def _method_seed(seed: int, index: int) -> int:
    return int(seed) * 10_007 + int(index)


def _run_method(name: str, inst: DeliveryInstance, seed: int, options: dict) -> Any:
    import taopt
    from taopt.delivery.schedule import optimal_plan

    if name == "exact":
        from taopt.models import solve_delivery

        # The MILP is certified but grows with |stops|^2 per sortie: on the 121-stop setups
        # it is stopped at EXACT_TIME_LIMIT and reported with its proven gap (status
        # "time_limit"); the subset DP ("DP") is the exact method that scales there.
        sol = solve_delivery(inst, **{"time_limit": EXACT_TIME_LIMIT, **options.get("exact", {})})
    elif name == "DP":
        sol = optimal_plan(inst)
    else:
        import taopt.heuristics

        sol = taopt.heuristics.run(name, inst, seed=seed, **options.get(name, {}))
    # the one scorer: never trust a method's own objective
    makespan = taopt.evaluate(inst, sol)
    if not math.isclose(makespan, sol.objective, rel_tol=1e-6, abs_tol=1e-9):
        raise RuntimeError(
            f"{name}: reported objective {sol.objective} != evaluated makespan {makespan}"
        )
    return sol, makespan


def _task(args: tuple) -> list[dict[str, Any]]:
    """Every pending method on one (instance, ratio); returns the rows."""
    setup, index, ratio, seed, vd_ratio, methods, exact_max_n, options = args
    inst = study_instance(setup, index, seed, ratio, vd_ratio)
    bound = arborescence_bound(inst)
    try:
        thesis_bound = arborescence_bound(inst, rule="thesis")
    except Exception:  # the printed E^d may have no arborescence
        thesis_bound = float("nan")
    optimum = float("nan")
    if inst.n <= exact_max_n:
        from taopt.delivery.schedule import optimal_plan

        optimum = optimal_plan(inst).objective
    rows = []
    method_seed = _method_seed(seed, index)
    for name in methods:
        began = time.perf_counter()
        sol, makespan = _run_method(name, inst, method_seed, options)
        runtime = sol.runtime if sol.runtime else time.perf_counter() - began
        rows.append(
            {
                "setup": setup,
                "instance": index,
                "ratio": ratio,
                "L": inst.flight_range,
                "vd_ratio": inst.v_drone / inst.v_truck,
                "n": inst.n,
                "method": name,
                "seed": method_seed,
                "status": sol.status,
                "makespan": makespan,
                "bound": bound,
                "q": makespan / bound,
                "bound_thesis_rule": thesis_bound,
                "optimum": optimum,
                "gap_to_optimum": makespan / optimum - 1.0 if optimum == optimum else float("nan"),
                "runtime": runtime,
                "tstar_cost": sol.info.get("tstar_cost", float("nan")),
            }
        )
    return rows


def delivery_study(
    setup: str = "dag40",
    instances: int = 10,
    ratios: Sequence[float] = DEFAULT_RATIOS,
    methods: Sequence[str] = DEFAULT_METHODS,
    seed: int = 1,
    out_dir: str | Path | None = None,
    jobs: int = 1,
    progress: bool = True,
    exact_max_n: int = 8,
    vd_ratio: float | None = None,
    method_options: dict[str, dict[str, Any]] | None = None,
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
        Heuristics registered in :func:`taopt.heuristics.run` ("NIA", "MMA", "SMMA",
        "GA"), "DP" (exact subset DP, n <= 14) or "exact" (``taopt.models.solve_delivery``,
        stopped after :data:`EXACT_TIME_LIMIT` s unless ``method_options["exact"]`` says
        otherwise; a stopped run is recorded with status "time_limit" and its proven gap).
    seed : int
        Instances depend on (seed, index); randomised methods get seed·10007 + index.
    out_dir : path, optional
        Folder of the resumable CSV ``delivery_<setup>.csv`` and its settings
        ``delivery_<setup>.config.json``; None keeps results in memory.
    jobs : int
        Worker processes (one task = one instance at one ratio).
    progress : bool
        tqdm progress bar.
    exact_max_n : int
        Compute the optimum (subset DP) and the true gaps when n <= this.
    vd_ratio : float, optional
        Override the setup's v_d / v_t (e.g. 1.0 for Tables 5.3–5.4's setting).
    method_options : dict, optional
        Per-method keyword options, e.g. ``{"GA": {"generations": 200}}``.

    Returns
    -------
    pandas.DataFrame with columns :data:`COLUMNS`: the rows of the requested instances,
    ratios and methods (those finished by earlier runs included), sorted by instance,
    ratio, method.

    Raises
    ------
    InstanceError
        Unknown setup, no methods, or ``out_dir`` holds results of this setup computed
        with other settings (the message names the keys).
    """
    if setup not in SETUPS:
        raise InstanceError(f"unknown setup {setup!r}; choose from {sorted(SETUPS)}")
    methods = list(dict.fromkeys(methods))
    if not methods:
        raise InstanceError("no methods given")
    ratios = [float(r) for r in ratios]
    instances = int(instances)
    if instances < 0 or int(jobs) < 1:
        raise InstanceError(f"need instances >= 0 and jobs >= 1; got {instances}, {jobs}")
    options = dict(method_options or {})
    # everything that changes a row; instances, ratios and methods are the rows' key instead
    settings = {
        "setup": setup,
        "seed": int(seed),
        "vd_ratio": float(SETUPS[setup]["vd_ratio"] if vd_ratio is None else vd_ratio),
        "exact_max_n": int(exact_max_n),
        "exact_time_limit": EXACT_TIME_LIMIT,
        "method_options": options,
    }
    store = None
    done: set[tuple[Any, ...]] = set()
    if out_dir is not None:
        store = ResultsStore(
            out_dir,
            f"delivery_{setup}.csv",
            COLUMNS,
            KEY,
            settings,
            config=f"delivery_{setup}.config.json",
        )
        done = store.done_keys()
    tasks = []
    for index in range(instances):
        for ratio in ratios:
            pending = [m for m in methods if normalize_key((index, ratio, m)) not in done]
            if pending:
                tasks.append((setup, index, ratio, seed, vd_ratio, pending, exact_max_n, options))
    new_rows: list[dict[str, Any]] = []

    def record(rows: list[dict[str, Any]]) -> None:
        new_rows.extend(rows)
        if store is not None:
            store.append(rows)  # one task's rows in one write, as soon as it finishes

    from tqdm.auto import tqdm

    bar = tqdm(total=len(tasks), disable=not progress, desc=f"delivery {setup}", unit="task")
    try:
        if int(jobs) == 1 or len(tasks) <= 1:
            for task in tasks:
                record(_task(task))
                bar.update()
        else:
            with ProcessPoolExecutor(max_workers=int(jobs)) as pool:
                futures = [pool.submit(_task, task) for task in tasks]
                for future in as_completed(futures):  # write in finishing order
                    record(future.result())
                    bar.update()
    finally:
        bar.close()
    result = store.read() if store is not None else pd.DataFrame(new_rows, columns=COLUMNS)
    wanted = {normalize_key(k) for k in itertools.product(range(instances), ratios, methods)}
    keys = zip(result["instance"], result["ratio"], result["method"], strict=True)
    result = result.loc[np.array([normalize_key(k) in wanted for k in keys], dtype=bool)]
    return result.sort_values(["instance", "ratio", "method"], ignore_index=True)


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
            (df["bound"] / df["optimum"]).groupby([df["method"], df["ratio"]]).mean()
        )
    return out


def thesis_table(df: pd.DataFrame, value: str = "makespan") -> pd.DataFrame:
    """Method × L/L0 table of the mean ``value`` ("makespan", "q", "runtime", ...)."""
    return df.pivot_table(index="method", columns="ratio", values=value, aggfunc="mean")


def plot_study(df: pd.DataFrame, value: str = "q", ax: Any = None, path: str | None = None) -> Any:
    """Mean ``value`` ("q", "makespan", "gap_to_optimum", ...) per method against L/L0.

    The picture of Tables 5.1–5.6: one line per method. Saves a PNG when ``path`` is given.

    Returns
    -------
    matplotlib Axes
    """
    from matplotlib.figure import Figure

    if ax is None:
        ax = Figure(figsize=(6, 4)).add_subplot()
    table = thesis_table(df, value)
    for method, row in table.iterrows():
        ax.plot(row.index.astype(float), row.to_numpy(dtype=float), marker="o", label=str(method))
    ax.set_xlabel("L / L0")
    ax.set_ylabel(
        {"q": "mean q = f / f_a (5.19)", "makespan": "mean makespan (s)"}.get(value, value)
    )
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    if path is not None:
        ax.figure.tight_layout()
        ax.figure.savefig(path, dpi=120)
    return ax


# -- command line ----------------------------------------------------------------------------


def _cmd_study_delivery(args: argparse.Namespace) -> int:
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    ratios = tuple(float(r) for r in args.ratios.split(","))
    options: dict[str, dict[str, Any]] = {}
    if args.ga_generations is not None:
        options["GA"] = {"generations": args.ga_generations}
    if args.time_limit is not None:
        options["exact"] = {"time_limit": args.time_limit}
    df = delivery_study(
        setup=args.setup,
        instances=args.instances,
        ratios=ratios,
        methods=methods,
        seed=args.seed,
        out_dir=args.out,
        jobs=args.jobs,
        progress=not args.quiet,
        exact_max_n=args.exact_max_n,
        vd_ratio=args.vd_ratio,
        method_options=options,
    )
    with pd.option_context("display.width", 160, "display.max_columns", 20):
        print("average makespan f (5.1):")
        print(thesis_table(df, "makespan").round(1).to_string())
        print("\naverage q = f / f_a (5.19):")
        print(thesis_table(df, "q").round(4).to_string())
        print("\naverage run time (s):")
        print(thesis_table(df, "runtime").round(3).to_string())
        if df["optimum"].notna().any():
            print("\naverage gap to the optimum f / f_o - 1:")
            print(thesis_table(df, "gap_to_optimum").round(4).to_string())
    if args.out:
        print(f"\nrows: {Path(args.out) / f'delivery_{args.setup}.csv'}")
    if args.plot:
        plot_study(df, "q", path=args.plot)
        print(f"plot written to {args.plot}")
    return 0


def _study_subparsers(subparsers: Any) -> Any:
    """The sub-command group under ``taopt study`` (created on first use, shared)."""
    study = subparsers.choices.get("study")
    if study is None:
        study = subparsers.add_parser(
            "study", help="run a thesis study (chapter 2 or 5)", description="Run a thesis study."
        )
    for action in study._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action
    group = study.add_subparsers(dest="study", metavar="STUDY")
    group.required = True
    return group


def register_cli(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``taopt study delivery`` to the ``taopt`` command's subparsers.

    ``taopt study delivery --setup dag40|pairs120|small --instances 10
    --methods NIA,MMA,SMMA,GA[,DP,exact] --seed 1 --out DIR [--jobs 2] [--vd-ratio 1.4]``
    """
    group = _study_subparsers(subparsers)
    parser = group.add_parser(
        "delivery",
        help="chapter 5: truck-drone heuristics vs the bound (§5.5, Tables 5.1-5.7)",
        description=__doc__.split("\n\n")[0],
    )
    parser.add_argument("--setup", choices=sorted(SETUPS), default="dag40")
    parser.add_argument("--instances", type=int, default=10)
    parser.add_argument(
        "--methods",
        default=",".join(DEFAULT_METHODS),
        help="comma-separated: NIA,MMA,SMMA,GA,DP,exact",
    )
    parser.add_argument(
        "--ratios",
        default=",".join(f"{r:g}" for r in DEFAULT_RATIOS),
        help="comma-separated L/L0 values",
    )
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", default=None, help="folder of the resumable CSV")
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--vd-ratio", type=float, default=None, help="override v_d / v_t")
    parser.add_argument(
        "--exact-max-n", type=int, default=8, help="compute optima (subset DP) when n <= this"
    )
    parser.add_argument("--ga-generations", type=int, default=None)
    parser.add_argument("--time-limit", type=float, default=None, help="for --methods exact")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.add_argument("--plot", default=None, metavar="PNG", help="draw mean q against L/L0")
    parser.set_defaults(handler=_cmd_study_delivery)
    return parser


__all__ = [
    "delivery_study",
    "summarize",
    "thesis_table",
    "study_instance",
    "register_cli",
    "SETUPS",
]
