"""Chapter 4's studies (§4.4) on the one study runner: Tables 4.1–4.4, Figs. 4.5–4.8, gaps.

One :data:`SPEC` serves every experiment: a scenario is identified by ``(n, m, A, r,
scenario)``; its positions and labels depend on ``(n, m, A, scenario)`` and the study seed
only (:func:`scenario_seed`), so the seven ranges of a table see the same scenarios (common
random numbers) and a range's rows can be compared pairwise. Each row carries the Lemma 4.8
bound ``f_mst`` (the thesis's denominator, q = f / f_MST (4.21)) and the simulation's
``Solution.info`` counts (bytes, messages, rounds, re-plans, ...).

The certified optimum f_o does not depend on r: the exact model is run once per scenario
(at the largest range of a preset) and :func:`with_optimum` joins it to every range, giving
the true gap ``f / f_o`` the thesis could not report.

Presets (:data:`PRESETS`, the thesis's setups; 1000 m square, 500 scenarios each):

* ``table`` — Tables 4.1–4.2: m = 6, n = 30, |A| in 2..6, r in {1 m, r_c/6, ..., r_c},
  r_c = 600 m; DAA, HDA, CAA.
* ``table100`` — Tables 4.3–4.4 (withheld from our copy): m = 10, n = 100, |A| in
  {2, 4, 6, 8, 10}, r_c = 482 m.
* ``homogeneous15`` / ``homogeneous30`` — Figs. 4.5–4.6: |A| = 1, n15m4 (r_c = 712.8 m) and
  n30m6 (r_c = 600 m); DAA (the figures' RBA / STSTC / Greedy baselines of [5] are not
  defined in the thesis and are left out).
* ``scalability`` — Figs. 4.7–4.8: m = 10, n = 100..600, |A| in {2, 4, 6, 8, 10}, always
  connected (r = the square's diagonal + 1 m); DAA; its run time.

Example
-------
>>> import tempfile
>>> from taopt.orchestration.studies.comm import comm_study
>>> with tempfile.TemporaryDirectory() as tmp:
...     df = comm_study("homogeneous15", scenarios=1, out_dir=tmp, progress=False)
>>> len(df), df["method"].unique().tolist()  # one scenario at the preset's 7 ranges
(7, ['DAA'])
>>> bool((df["objective"] >= df["f_mst"] * (1 - 1e-9)).all())  # Lemma 4.8
True

``comm_study("table", scenarios=500)`` reproduces Tables 4.1-4.2 (hours).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from taopt.comm.bounds import mst_bound
from taopt.comm.engine import initially_connected
from taopt.comm.problem import THESIS_SIDE, CommProblem, random_problem
from taopt.defaults import TIME_LIMIT
from taopt.errors import InstanceError
from taopt.orchestration.cli import deprecated, folder, method_list, terminal_width
from taopt.orchestration.study import Scenario, StudySpec, check_integer, check_positive, run_study

ALGORITHMS = ("DAA", "HDA", "CAA")
INFO_COLUMNS = (
    "bytes",
    "numbers",
    "messages",
    "rounds",
    "max_group_rounds",
    "group_events",
    "replans",
    "events",
    "invariant_violations",
    "projected_increases",
    "initial_total",
)


# -- the command ``taopt study comm`` (found through the family's spec) ----------------------

#: One line for ``taopt study --help``.
HELP = "chapter 4 (§4.4, Tables 4.1-4.4, Figs. 4.5-4.8): CAA/DAA/HDA, q, bytes, true gap"
#: The file the study writes in ``--out``.
CSV = "comm.csv"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``taopt study comm`` (the CLI adds ``--out``, ``--seed``,
    ``--time-limit``, ``--jobs``, ``--dask`` and ``--plot``)."""
    parser.add_argument(
        "--preset",
        choices=["table", "table100", "homogeneous15", "homogeneous30", "scalability"],
        default="table",
        help="the experiment (table: Tables 4.1-4.2; table100: 4.3-4.4; homogeneous15/30: "
        "Figs. 4.5/4.6; scalability: Figs. 4.7-4.8)",
    )
    parser.add_argument(
        "--scenarios", type=int, default=500, help="scenarios per (n, m, |A|) (a count)"
    )
    parser.add_argument(
        "--methods",
        default=None,
        metavar="LIST",
        help="comma-separated: CAA,DAA,HDA and 'exact' (certifies f_o once per scenario, for "
        "the true gap) (default: none named: the preset's algorithms, no exact)",
    )
    deprecated(parser, "--exact", "exact_alias", "--methods ...,exact", nargs=0)
    parser.set_defaults(exact_alias=False)


def run(args: argparse.Namespace) -> int:
    """Body of ``taopt study comm``: run a §4.4 preset, print q, bytes and the true gap."""
    import pandas as pd

    from taopt.orchestration.studies.comm import (
        PRESETS,
        bytes_table,
        comm_study,
        plot_study,
        q_table,
    )
    from taopt.orchestration.studies.comm import summary as summarize

    preset = PRESETS[args.preset]
    from taopt.registry import get_method

    named = [get_method(CommProblem, m).name for m in method_list(args.methods) or preset.methods]
    exact = "exact" in named or args.exact_alias
    if not [m for m in named if m != "exact"]:
        raise InstanceError(
            "--methods: name an algorithm (CAA, DAA, HDA) beside 'exact': f_o is certified once "
            "per scenario for the true gap of the algorithms"
        )
    df = comm_study(
        args.preset,
        args.scenarios,
        args.out,
        methods=[m for m in named if m != "exact"],
        exact=exact,
        seed=args.seed,
        jobs=args.jobs,
        dask=args.dask,
        time_limit=args.time_limit,
        progress=not args.quiet,
    )
    table = summarize(df)
    table.to_csv(folder(args.out) / f"summary_{args.preset}.csv", index=False)
    with pd.option_context("display.width", 160, "display.max_columns", 20):
        print(preset.title)
        for n, m in preset.sizes:
            print(f"\nn = {n}, m = {m}: mean q = f / f_MST (4.21)")
            print(q_table(table, n, m).round(4).to_string(line_width=terminal_width()))
            if table["certified"].sum():
                print("\nmean true gap f / f_o (certified scenarios)")
                print(
                    q_table(table, n, m, value="gap")
                    .round(4)
                    .to_string(line_width=terminal_width())
                )
            print("\nmean bytes relayed (10^5 bytes)")
            print(bytes_table(table, n, m).round(4).to_string(line_width=terminal_width()))
    if args.plot:
        n, m = preset.sizes[0]
        plot_study(table, n, m, path=args.plot)
        print(f"plot written to {args.plot}")
    return 0


__all__ = [
    "SPEC",
    "PRESETS",
    "Preset",
    "ALGORITHMS",
    "scenario_seed",
    "make_scenario",
    "ranges",
    "preset_keys",
    "comm_study",
    "with_optimum",
    "summary",
    "q_table",
    "bytes_table",
    "plot_study",
    "THESIS_TABLE_4_1",
    "THESIS_TABLE_4_2",
    "compare_with_thesis",
    "report",
    "plot_homogeneous",
    "plot_scalability",
]

#: Table 4.1 as printed: mean q of HDA and DAA, n = 30, m = 6; rows r = k r_c / 6 (k = 0 is
#: r = 1 m), columns |A| = 2..6.
THESIS_TABLE_4_1 = {
    (0, "HDA"): (3.4717, 2.3407, 1.7132, 1.3638, 1.1351),
    (0, "DAA"): (3.4717, 2.3407, 1.7132, 1.3638, 1.1351),
    (1, "HDA"): (1.9504, 1.6221, 1.4022, 1.2495, 1.1351),
    (1, "DAA"): (1.9274, 1.6009, 1.3919, 1.2474, 1.1351),
    (2, "HDA"): (1.5582, 1.4016, 1.2855, 1.2048, 1.1351),
    (2, "DAA"): (1.5170, 1.3682, 1.2578, 1.1942, 1.1351),
    (3, "HDA"): (1.3126, 1.2393, 1.1990, 1.1658, 1.1351),
    (3, "DAA"): (1.2624, 1.2111, 1.1744, 1.1555, 1.1351),
    (4, "HDA"): (1.1878, 1.1727, 1.1565, 1.1453, 1.1351),
    (4, "DAA"): (1.1631, 1.1601, 1.1495, 1.1435, 1.1351),
    (5, "HDA"): (1.1507, 1.1529, 1.1442, 1.1406, 1.1351),
    (5, "DAA"): (1.1467, 1.1493, 1.1427, 1.1404, 1.1351),
    (6, "HDA"): (1.1453, 1.1492, 1.1417, 1.1398, 1.1351),
    (6, "DAA"): (1.1437, 1.1483, 1.1415, 1.1399, 1.1351),
}

#: Table 4.2 as printed: mean data relayed (10^5 bytes), n = 30, m = 6 (no r = 1 m row).
#: The row k = 5 is illegible in our copy ("Hyyyyy"); it is the one between 4 r_c/6 and r_c.
THESIS_TABLE_4_2 = {
    (1, "HDA"): (2.6525, 1.7352, 1.0261, 0.4747, 4.3152),
    (1, "DAA"): (4.7297, 4.8322, 4.5819, 4.4393, 4.3152),
    (1, "CAA"): (12.8744, 13.2027, 12.5462, 12.1706, 11.9303),
    (2, "HDA"): (2.8770, 1.9481, 1.1728, 0.5635, 6.4860),
    (2, "DAA"): (5.9341, 6.5702, 6.9101, 7.1652, 6.4860),
    (2, "CAA"): (16.0655, 17.8692, 18.8337, 19.5528, 17.9318),
    (3, "HDA"): (3.2648, 2.1329, 1.3397, 0.7086, 4.7002),
    (3, "DAA"): (6.1134, 6.5526, 6.5935, 6.7829, 4.7002),
    (3, "CAA"): (16.3616, 17.6188, 17.7728, 18.3142, 12.9946),
    (4, "HDA"): (3.4039, 2.2532, 1.5286, 1.0182, 2.3446),
    (4, "DAA"): (4.6646, 4.6149, 4.5518, 4.4915, 2.3446),
    (4, "CAA"): (12.2805, 12.1993, 12.0843, 11.9489, 6.4821),
    (5, "HDA"): (2.8228, 2.1607, 1.6917, 1.3769, 0.9829),
    (5, "DAA"): (3.0691, 3.0310, 2.9442, 2.9699, 0.9829),
    (5, "CAA"): (7.9659, 7.8915, 7.6851, 7.7764, 2.7174),
    (6, "HDA"): (2.2226, 1.9920, 1.8188, 1.7053, 0.2772),
    (6, "DAA"): (2.2593, 2.2576, 2.2699, 2.2590, 0.2772),
    (6, "CAA"): (5.8137, 5.8171, 5.8611, 5.8391, 0.7665),
}


def scenario_seed(seed: int, n: int, m: int, attributes: int, scenario: int) -> int:
    """Seed of a scenario's data: from the study seed and (n, m, |A|, scenario), not r."""
    values = [int(seed), int(n), int(m), int(attributes), int(scenario)]
    if min(values) < 0:
        raise InstanceError(f"seed and scenario numbers must be >= 0, got {values}")
    return int(np.random.SeedSequence(values[0], spawn_key=tuple(values[1:])).generate_state(1)[0])


def make_scenario(key: dict, settings: dict) -> Scenario:
    """The scenario of ``key`` (n, m, A, r, scenario) in a ``settings["side"]`` square."""
    n, m, attributes = int(key["n"]), int(key["m"]), int(key["A"])
    seed = scenario_seed(settings["seed"], n, m, attributes, int(key["scenario"]))
    problem = random_problem(
        n,
        m,
        attributes,
        float(key["r"]),
        seed=seed,
        side=float(settings.get("side", THESIS_SIDE)),
        name=f"n{n}m{m}A{attributes}s{key['scenario']}",
    )
    return Scenario(
        problem,
        columns={"connected": initially_connected(problem)},
        references={"f_mst": mst_bound(problem)},
    )


#: The study specification shared by every chapter 4 experiment.
SPEC = StudySpec(
    name="comm",
    problem_type=CommProblem,
    key_columns=("n", "m", "A", "r", "scenario"),
    make_scenario=make_scenario,
    scenario_columns=("connected",),
    reference_columns=("f_mst",),
    info_columns=INFO_COLUMNS,
)


@dataclass(frozen=True)
class Preset:
    """One experiment of §4.4: sizes, heterogeneities, ranges and methods."""

    title: str
    sizes: tuple[tuple[int, int], ...]  # (n, m)
    attributes: tuple[int, ...]
    ranges: tuple[float, ...]
    methods: tuple[str, ...]


def ranges(r_c: float, steps: int = 6) -> tuple[float, ...]:
    """The thesis's ranges: ``{1 m, r_c/6, 2 r_c/6, ..., r_c}`` (rounded to 1 mm)."""
    return (1.0, *(round(k * r_c / steps, 3) for k in range(1, steps + 1)))


DIAGONAL_PLUS = round(THESIS_SIDE * math.sqrt(2.0) + 1.0, 3)

#: The thesis's setups, by name (see the module docstring).
PRESETS = {
    "table": Preset(
        "Tables 4.1-4.2: m = 6, n = 30, r_c = 600 m",
        ((30, 6),),
        (2, 3, 4, 5, 6),
        ranges(600.0),
        ALGORITHMS,
    ),
    "table100": Preset(
        "Tables 4.3-4.4: m = 10, n = 100, r_c = 482 m",
        ((100, 10),),
        (2, 4, 6, 8, 10),
        ranges(482.0),
        ALGORITHMS,
    ),
    "homogeneous15": Preset(
        "Fig. 4.5: n = 15, m = 4, |A| = 1, r_c = 712.8 m",
        ((15, 4),),
        (1,),
        ranges(712.8),
        ("DAA",),
    ),
    "homogeneous30": Preset(
        "Fig. 4.6: n = 30, m = 6, |A| = 1, r_c = 600 m",
        ((30, 6),),
        (1,),
        ranges(600.0),
        ("DAA",),
    ),
    "scalability": Preset(
        "Figs. 4.7-4.8: m = 10, n = 100..600, always connected",
        tuple((n, 10) for n in range(100, 601, 100)),
        (2, 4, 6, 8, 10),
        (DIAGONAL_PLUS,),
        ("DAA",),
    ),
}


def preset_keys(preset: Preset, scenarios: int, first: int = 0) -> list[dict[str, Any]]:
    """Every (n, m, A, r, scenario) key of a preset, scenarios ``first .. first+scenarios-1``."""
    return [
        {"n": n, "m": m, "A": a, "r": r, "scenario": s}
        for n, m in preset.sizes
        for a in preset.attributes
        for r in preset.ranges
        for s in range(first, first + scenarios)
        if a <= m
    ]


def comm_study(
    preset: str | Preset,
    scenarios: int = 500,
    out_dir: str | Path = "comm-study",
    *,
    methods: Sequence[str] | None = None,
    exact: bool = False,
    seed: int = 0,
    jobs: int = 1,
    dask: str | None = None,
    time_limit: float | None = TIME_LIMIT,
    progress: bool = True,
) -> pd.DataFrame:
    """Run a preset of §4.4 (resumable; one CSV ``<out>/comm.csv`` for every preset).

    Parameters
    ----------
    preset : str or Preset
        A key of :data:`PRESETS`.
    scenarios : int
        Scenarios per (n, m, |A|) (the thesis: 500).
    methods : sequence of str, optional
        Default: the preset's.
    exact : bool
        Also certify f_o with the exact model, once per scenario (at the preset's largest
        range), with ``time_limit`` seconds each.
    seed : int
        Study seed (scenario data: :func:`scenario_seed`).
    jobs, dask :
        Worker processes or a Dask cluster (:func:`taopt.orchestration.study.run_study`).
    time_limit : float
        Seconds per exact solve (the simulations take none).

    Returns
    -------
    pandas.DataFrame
        The rows (every range, every method; the exact rows at the largest range), with
        ``optimum`` joined by :func:`with_optimum` and ``q = objective / f_mst``.
    """
    if isinstance(preset, str) and preset not in PRESETS:
        raise InstanceError(f"unknown preset {preset!r}; choose from {sorted(PRESETS)}")
    spec = PRESETS[preset] if isinstance(preset, str) else preset
    # every argument checked before anything is written (issue 15, item 7)
    scenarios = check_integer("scenarios", scenarios, 1)
    seed = check_integer("seed", seed, 0)
    time_limit = check_positive("time_limit", time_limit, allow_none=True)
    settings = {"seed": int(seed), "side": THESIS_SIDE}
    keys = preset_keys(spec, scenarios)
    chosen = list(methods) if methods is not None else list(spec.methods)
    from taopt.registry import get_method

    chosen = list(dict.fromkeys(get_method(CommProblem, m).name for m in chosen))  # "daa"->"DAA"
    frames = [
        run_study(
            SPEC,
            keys,
            chosen,
            settings,
            out_dir,
            jobs=jobs,
            dask=dask,
            time_limit=time_limit,
            progress=progress,
        )
    ]
    if exact:
        top = max(spec.ranges)
        exact_keys = [k for k in keys if k["r"] == top]
        frames.append(
            run_study(
                SPEC,
                exact_keys,
                ["exact"],
                settings,
                out_dir,
                jobs=jobs,
                dask=dask,
                time_limit=time_limit,
                progress=progress,
            )
        )
    return with_optimum(pd.concat(frames, ignore_index=True))


def with_optimum(df: pd.DataFrame) -> pd.DataFrame:
    """Join each scenario's certified f_o (from its exact row, at any range) to every row.

    Adds ``optimum`` (NaN where no exact row is "optimal"), ``q = objective / f_mst``
    (4.21), ``gap = objective / optimum`` and ``q_alone = initial_total / f_mst`` (every
    vehicle driving the whole route it planned alone at t = 0: Proposition 4.10's bound).
    """
    df = df.copy()
    scenario = ["n", "m", "A", "scenario"]
    exact = df[(df["method"] == "exact") & (df["status"] == "optimal")]
    best = exact.groupby(scenario)["objective"].min().rename("optimum")
    df = df.drop(columns=["optimum"], errors="ignore").join(best, on=scenario)
    df["q"] = df["objective"] / df["f_mst"]
    df["gap"] = df["objective"] / df["optimum"]
    df["q_alone"] = df["initial_total"] / df["f_mst"]
    return df


def summary(df: pd.DataFrame) -> pd.DataFrame:
    """Means per (n, m, A, r, method): q, q_alone, true gap, bytes, messages, rounds, re-plans.

    ``gap`` is averaged over the scenarios whose optimum is certified (``certified`` counts
    them); ``scenarios`` counts all.
    """
    if "q" not in df.columns:
        df = with_optimum(df)
    runs = df[df["method"] != "exact"]
    grouped = runs.groupby(["n", "m", "A", "r", "method"], sort=True)
    table = grouped.agg(
        scenarios=("objective", "size"),
        q=("q", "mean"),
        q_alone=("q_alone", "mean"),
        gap=("gap", "mean"),
        certified=("gap", "count"),
        f=("objective", "mean"),
        bytes=("bytes", "mean"),
        messages=("messages", "mean"),
        rounds=("rounds", "mean"),
        replans=("replans", "mean"),
        connected=("connected", "mean"),
        violations=("invariant_violations", "sum"),
        runtime=("runtime", "mean"),
    )
    return table.reset_index()


def _pivot(table: pd.DataFrame, value: str, n: int, m: int, methods: Sequence[str]) -> Any:
    part = table[(table["n"] == n) & (table["m"] == m) & table["method"].isin(methods)]
    pivot = part.pivot_table(index=["r", "method"], columns="A", values=value)
    order = {name: k for k, name in enumerate(methods)}
    pivot = pivot.reset_index()
    pivot["_order"] = pivot["method"].map(order)
    pivot = pivot.sort_values(["r", "_order"]).drop(columns="_order").set_index(["r", "method"])
    pivot.columns = [f"|A|={a}" for a in pivot.columns]
    return pivot


def q_table(table: pd.DataFrame, n: int = 30, m: int = 6, value: str = "q") -> pd.DataFrame:
    """Table 4.1's layout: mean ``value`` (q, or the true gap) by r and algorithm, per |A|."""
    return _pivot(table, value, n, m, ("HDA", "DAA"))


#: The unit of bytes in Table 4.2, in our tables and in the study's plot.
BYTES_UNIT = 1e5


def bytes_table(
    table: pd.DataFrame, n: int = 30, m: int = 6, scale: float = BYTES_UNIT
) -> pd.DataFrame:
    """Table 4.2's layout: mean bytes relayed / ``scale`` by r and algorithm, per |A|."""
    scaled = table.assign(bytes=table["bytes"] / scale)
    return _pivot(scaled, "bytes", n, m, ("HDA", "DAA", "CAA"))


def plot_study(
    table: pd.DataFrame,
    n: int = 30,
    m: int = 6,
    path: str | Path | None = None,
) -> Any:
    """q and bytes against r, one line per |A| and algorithm (the tables as curves)."""
    from matplotlib.figure import Figure

    from taopt.comm.plot import plot_range_curves

    part = table[(table["n"] == n) & (table["m"] == m)]
    fig = Figure(figsize=(13, 5.4))
    q_ax, bytes_ax = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    plot_range_curves(
        part, "q", ("DAA", "HDA"), ax=q_ax, ylabel="mean q = f / f_MST (4.21), ratio (1)"
    )
    q_ax.set_title("solution quality (Table 4.1)", fontsize=10)
    # in Table 4.2's unit (and bytes_table's): 10^5 bytes, not matplotlib's "1e7" offset
    plot_range_curves(
        part.assign(bytes=part["bytes"] / BYTES_UNIT),
        "bytes",
        ("DAA", "HDA", "CAA"),
        ax=bytes_ax,
        ylabel="mean bytes relayed (10^5 bytes)",
    )
    bytes_ax.set_title("communication load (Table 4.2)", fontsize=10)
    fig.suptitle(f"DAA, HDA and CAA against the range r: n = {n} targets, m = {m} vehicles")
    if path is not None:
        fig.tight_layout()
        fig.savefig(str(path), dpi=120, bbox_inches="tight")
    return fig


def compare_with_thesis(
    table: pd.DataFrame,
    value: str = "q",
    n: int = 30,
    m: int = 6,
    digits: int = 4,
) -> str:
    """A markdown table of ours beside the thesis's: "ours (thesis)" per r, algorithm, |A|.

    ``value`` is "q" (Table 4.1), "bytes" (Table 4.2, in 10^5 bytes) or "gap" (ours only).
    Rows are labelled by r as a multiple of r_c / 6 (the thesis's rows).
    """
    if value == "bytes":
        ours, thesis = bytes_table(table, n, m), THESIS_TABLE_4_2
    else:
        ours, thesis = q_table(table, n, m, value=value), THESIS_TABLE_4_1
    if (n, m) != (30, 6) or value == "gap":
        thesis = {}
    rs = sorted({r for r, _ in ours.index})
    names = [c.replace("|", "\\|") for c in ours.columns]  # a pipe would end the cell
    header = "| r | algorithm | " + " | ".join(names) + " |"
    lines = [header, "|" + "---|" * (2 + len(ours.columns))]
    for (r, method), row in ours.iterrows():
        k = rs.index(r)
        label = "1 m" if r == 1.0 else f"{k} r_c/6 = {r:g} m"
        printed = thesis.get((k, method))
        cells = []
        for c, v in enumerate(row):
            text = "–" if pd.isna(v) else f"{v:.{digits}f}"
            if printed is not None:
                text += f" ({printed[c]:.{digits}f})"
            cells.append(text)
        lines.append(f"| {label} | {method} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def report(csv: str | Path | pd.DataFrame, n: int = 30, m: int = 6) -> str:
    """The markdown tables of docs/reproduction/chapter4.md from a study's rows (CSV or frame)."""
    df = csv if isinstance(csv, pd.DataFrame) else pd.read_csv(csv)
    table = summary(with_optimum(df))
    part = table[(table["n"] == n) & (table["m"] == m)]
    counts = part.groupby("A")["scenarios"].max().to_dict()
    out = [f"scenarios per |A|: {counts}", ""]
    out += ["mean q = f / f_MST (thesis in brackets):", "", compare_with_thesis(part, "q", n, m)]
    if part["certified"].sum():
        out += ["", "mean true gap f / f_o:", "", compare_with_thesis(part, "gap", n, m)]
    out += ["", "mean bytes relayed, 10^5 bytes (thesis in brackets):", ""]
    out += [compare_with_thesis(part, "bytes", n, m, digits=3)]
    return "\n".join(out)


def plot_homogeneous(tables: Sequence[pd.DataFrame], path: str | Path | None = None) -> Any:
    """Figs. 4.5–4.6: DAA's mean q (and true gap, where certified) against r, |A| = 1."""
    from matplotlib.figure import Figure

    from taopt.plot import legend_outside

    fig = Figure(figsize=(6.5 * len(tables), 4.5))
    for k, table in enumerate(tables):
        ax = fig.add_subplot(1, len(tables), k + 1)
        rows = table[(table["A"] == 1) & (table["method"] == "DAA")].sort_values("r")
        n, m = int(rows["n"].iloc[0]), int(rows["m"].iloc[0])
        ax.plot(rows["r"], rows["q"], "o-", label="q = f / f_MST")
        if rows["certified"].sum():
            ax.plot(rows["r"], rows["gap"], "s--", label="f / f_o (certified)")
        ax.axhline(
            2.0,
            color="0.6",
            lw=0.8,
            ls=":",
            label="2: Theorem 4.9, f <= 2 f_o (initially connected)",
        )
        ax.set_xlabel("communication range r (m)")
        ax.set_ylabel("mean ratio (1)")
        ax.set_title(f"DAA, n = {n}, m = {m}, |A| = 1")
        ax.grid(alpha=0.3)
        legend_outside(ax, "below", ncol=2)
    if path is not None:
        fig.tight_layout()
        fig.savefig(str(path), dpi=120, bbox_inches="tight")
    return fig


def plot_scalability(table: pd.DataFrame, path: str | Path | None = None) -> Any:
    """Figs. 4.7–4.8: DAA's mean q and run time against n, one line per |A| (always connected)."""
    from matplotlib.figure import Figure

    from taopt.plot import LINESTYLES, MARKERS, legend_outside

    fig = Figure(figsize=(12, 4.8))
    q_ax, time_ax = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    rows = table[table["method"] == "DAA"]
    for k, (attributes, part) in enumerate(rows.groupby("A")):
        part = part.sort_values("n")
        style: dict[str, Any] = {
            "ls": LINESTYLES[k % len(LINESTYLES)],
            "marker": MARKERS[k % len(MARKERS)],
        }
        q_ax.plot(part["n"], part["q"], label=f"|A| = {attributes}", **style)
        time_ax.plot(part["n"], part["runtime"], label=f"|A| = {attributes}", **style)
    q_ax.set_ylabel("mean q = f / f_MST (4.21), ratio (1)")
    time_ax.set_ylabel("mean run time of a simulation (s)")
    q_ax.set_title("DAA: solution quality against n", fontsize=10)
    time_ax.set_title("DAA: run time against n", fontsize=10)
    for ax in (q_ax, time_ax):
        ax.set_xlabel("targets n (count; m = 10 vehicles)")
        ax.grid(alpha=0.3)
        legend_outside(ax, "below", ncol=4)
    if path is not None:
        fig.tight_layout()
        fig.savefig(str(path), dpi=120, bbox_inches="tight")
    return fig
