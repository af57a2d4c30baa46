"""Sweep of the chapter 2 GA's operator sets and tournament sizes (docs/ga-operators.md).

Every candidate runs with the thesis's budget (population 120, 350
generations, crossover 0.9, mutation 0.1) on the same seeded instances:

* "uniform": n targets and m vehicle starts uniform in a 1000 m square, a
  uniform current (0.3, 0.1) m/s, v = 1; closed-form travel times
  (:func:`taopt.navigation.uniform.uniform_travel_times`), so no navigation;
* "drift": the thesis's field scenarios (:func:`taopt.routing.scenarios.drift_scenario`,
  study seed 2024), travel times by collocation, read from
  ``benchmarks/.cache/routing`` (computed and cached if missing: slow).

For each size and family it reports the mean q = f / f_a (2.26, f_a the
thesis's Algorithm 1, :func:`taopt.routing.bounds.thesis_mcga`), the mean
f / f_MC, the mean f / f_o with the exact optimum (:func:`taopt.models.solve_routing`,
certified; at n50m10 and n120m20 by default), each candidate's mean ratio to
the reference candidate with the Wilcoxon signed-rank p-value of the paired
difference, and the mean wall and CPU time of one GA run (CPU time is the fairer
figure on a shared machine). MC and the exact optimum are computed once per
instance.

Usage (from the repository root)::

    python benchmarks/ga_sweep.py --csv sweep.csv   # the table in docs/ga-operators.md
    python benchmarks/ga_sweep.py --table-from sweep.csv
    python benchmarks/ga_sweep.py --uniform 3 --drift 1 --candidates memetic-t2,ox-inversion-t4
    python benchmarks/ga_sweep.py --sizes 90x10 --drift 0 --exact-sizes "" --candidates memetic-t2
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import numpy as np

import taopt
import taopt.heuristics
from taopt.heuristics.ga_routing import OPERATOR_SETS, OperatorSet, genetic_algorithm
from taopt.navigation.uniform import uniform_travel_times
from taopt.routing.bounds import thesis_mcga
from taopt.routing.scenarios import drift_scenario, scenario_seed

CACHE = Path(__file__).resolve().parent / ".cache" / "routing"
CURRENT = (0.3, 0.1)

MEMETIC = OPERATOR_SETS["memetic"]
OPERATORS: dict[str, OperatorSet] = {
    "ox-inversion": OPERATOR_SETS["ox-inversion"],
    # the memetic set without local search: what the new encoding and mutations do alone
    "ox-mix": OperatorSet(polish=0),
    "memetic": MEMETIC,
    "memetic-obx": OperatorSet(crossover="obx"),
    "memetic-distinct": OperatorSet(distinct=True),
    # local search with reversal and relocation only (no 2-opt*, no exchange)
    "memetic-rr": OperatorSet(neighbourhood=("reverse", "relocate")),
    "memetic-p1": OperatorSet(polish=1),
    "memetic-p4": OperatorSet(polish=4),
}
DEFAULT_CANDIDATES = (
    "ox-inversion-t4,ox-mix-t2,ox-mix-t4,memetic-t2,memetic-t3,memetic-t4,memetic-t8,"
    "memetic-obx-t2,memetic-distinct-t2,memetic-rr-t2,memetic-p1-t2,memetic-p4-t2"
)


def uniform_problem(n: int, m: int, seed: int) -> taopt.AssignmentProblem:
    """n targets and m starts uniform in a 1000 m square; current (0.3, 0.1) m/s, v = 1."""
    points = np.random.default_rng(seed).uniform(0.0, 1000.0, size=(n + m, 2))
    cost = uniform_travel_times(CURRENT, points[:, None, :], points[None, :, :], 1.0)
    return taopt.AssignmentProblem(cost, n, name=f"uniform-n{n}m{m}-seed{seed}")


def candidate(label: str) -> tuple[OperatorSet, int]:
    """``"<operator set>-t<size>"`` -> (operator set, tournament size)."""
    name, _, size = label.rpartition("-t")
    if name not in OPERATORS or not size.isdigit():
        raise SystemExit(f"unknown candidate {label!r}; operator sets: {sorted(OPERATORS)}")
    return OPERATORS[name], int(size)


def instances(n: int, m: int, uniform: int, drift: int, jobs: int):
    """(family, problem) pairs: ``uniform`` closed-form ones, ``drift`` thesis-field ones."""
    for seed in range(uniform):
        yield "uniform", uniform_problem(n, m, seed)
    for k in range(drift):
        yield (
            "drift",
            drift_scenario(n, m, scenario_seed(2024, k), cache_dir=CACHE, jobs=jobs).problem,
        )


FIELDS = [
    "size",
    "family",
    "instance",
    "candidate",
    "f",
    "q",
    "f_mc",
    "f_o",
    "time",
    "cpu",
    "moves",
]


def run_sweep(args: argparse.Namespace, labels: list[str]) -> list[dict]:
    """Run every candidate on every instance; rows also appended to ``args.csv``."""
    from taopt.models import solve_routing

    exact_sizes = set(args.exact_sizes.split(",")) if args.exact_sizes else set()
    writer = None
    if args.csv:
        handle = open(args.csv, "w", newline="")  # noqa: SIM115 - kept open for the run
        writer = csv.DictWriter(handle, fieldnames=FIELDS)
        writer.writeheader()
    rows = []
    for size in args.sizes.split(","):
        n, m = (int(part) for part in size.lower().split("x"))
        for family, problem in instances(n, m, args.uniform, args.drift, args.jobs):
            f_a = thesis_mcga(problem)
            mc = taopt.heuristics.run("MC", problem)
            f_o = None
            if size in exact_sizes:
                exact = solve_routing(problem, time_limit=args.exact_limit)
                f_o = exact.objective if exact.status == "optimal" else None
            found = [("MC", mc, mc.runtime, mc.runtime)]
            for label in labels:
                ops, tournament = candidate(label)
                wall, cpu = time.perf_counter(), time.process_time()
                solution = genetic_algorithm(
                    problem,
                    seed=args.seed,
                    population=args.population,
                    generations=args.generations,
                    tournament=tournament,
                    operators=ops,
                )
                found.append(
                    (label, solution, time.perf_counter() - wall, time.process_time() - cpu)
                )
            for label, solution, wall, cpu in found:
                row = {
                    "size": f"n{n}m{m}",
                    "family": family,
                    "instance": problem.name,
                    "candidate": label,
                    "f": solution.objective,
                    "q": solution.objective / f_a,
                    "f_mc": solution.objective / mc.objective,
                    "f_o": None if f_o is None else solution.objective / f_o,
                    "time": wall,
                    "cpu": cpu,
                    "moves": solution.info.get("moves", 0),
                }
                rows.append(row)
                if writer:
                    writer.writerow(row)
            if writer:
                handle.flush()
            print(f"  {problem.name}: done", flush=True)
    if writer:
        handle.close()
    return rows


def read_rows(path: Path) -> list[dict]:
    """Rows of a CSV written by :func:`run_sweep`."""
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    for row in rows:
        for key in ("f", "q", "f_mc", "time", "cpu"):
            row[key] = float(row[key])
        row["f_o"] = float(row["f_o"]) if row["f_o"] else None
    return rows


def print_table(rows: list[dict], reference: str) -> None:
    """Markdown table of means per size, family and candidate, paired against ``reference``."""
    from scipy.stats import wilcoxon

    print(
        f"\n| size | instances | candidate | q = f/f_a | f/f_MC | f/f_o | f/f_{reference} "
        "(Wilcoxon p) | wall s (max) | CPU s |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    groups = sorted(
        {(r["size"], r["family"]) for r in rows}, key=lambda g: (int(g[0][1:].split("m")[0]), g[1])
    )
    labels = list(dict.fromkeys(r["candidate"] for r in rows))
    for size, family in groups:
        group = [r for r in rows if (r["size"], r["family"]) == (size, family)]
        base = {r["instance"]: r["f"] for r in group if r["candidate"] == reference}
        for label in labels:
            chosen = sorted(
                (r for r in group if r["candidate"] == label), key=lambda r: r["instance"]
            )
            if not chosen:
                continue
            optimum = [r["f_o"] for r in chosen if r["f_o"] is not None]
            gap = f"{np.mean(optimum):.4f}" if len(optimum) == len(chosen) else "-"
            paired = "-"
            if base and label != reference:
                mine = np.array([r["f"] for r in chosen])
                theirs = np.array([base[r["instance"]] for r in chosen])
                differ = not np.allclose(mine, theirs, rtol=1e-12)
                p = wilcoxon(mine, theirs).pvalue if differ else 1.0
                paired = f"{np.mean(mine / theirs):.4f} ({p:.2g})"
            print(
                f"| {size} | {family} ×{len(chosen)} | {label} "
                f"| {np.mean([r['q'] for r in chosen]):.4f} "
                f"| {np.mean([r['f_mc'] for r in chosen]):.4f} | {gap} | {paired} "
                f"| {np.mean([r['time'] for r in chosen]):.2f} ({max(r['time'] for r in chosen):.2f}) "
                f"| {np.mean([r['cpu'] for r in chosen]):.2f} |"
            )


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--sizes", default="50x10,120x20", help="comma list of NxM")
    parser.add_argument("--uniform", type=int, default=10, help="uniform-current instances")
    parser.add_argument("--drift", type=int, default=5, help="thesis-field instances (cached)")
    parser.add_argument("--candidates", default=DEFAULT_CANDIDATES)
    parser.add_argument(
        "--reference", default="memetic-t2", help="candidate others are paired with"
    )
    parser.add_argument("--seed", type=int, default=0, help="GA seed")
    parser.add_argument("--generations", type=int, default=350)
    parser.add_argument("--population", type=int, default=120)
    parser.add_argument(
        "--exact-sizes", default="50x10,120x20", help="sizes with f / f_o ('' for none)"
    )
    parser.add_argument("--exact-limit", type=float, default=300.0, help="seconds per MILP")
    parser.add_argument("--jobs", type=int, default=1, help="processes for missing matrices")
    parser.add_argument("--csv", type=Path, default=None, help="write every run here")
    parser.add_argument("--table-from", type=Path, default=None, help="only print a saved CSV")
    args = parser.parse_args()
    if args.table_from:
        print_table(read_rows(args.table_from), args.reference)
        return
    labels = args.candidates.split(",")
    for label in labels:
        candidate(label)  # fail early on a typo
    print_table(run_sweep(args, labels), args.reference)


if __name__ == "__main__":
    main()
