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
f / f_MC, at n50m10 the mean f / f_o with the exact optimum
(:func:`taopt.models.solve_routing`, certified), and the mean GA time. MC and
the exact optimum are computed once per instance.

Usage (from the repository root)::

    python benchmarks/ga_sweep.py                          # the table in docs/ga-operators.md
    python benchmarks/ga_sweep.py --uniform 3 --drift 1 --candidates memetic-t2,ox-inversion-t4
    python benchmarks/ga_sweep.py --sizes 90x10 --drift 0 --no-exact --candidates memetic-t2
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
    "memetic-obx": OperatorSet(crossover="obx", polish=MEMETIC.polish),
    "memetic-clones": OperatorSet(distinct=False, polish=MEMETIC.polish),
    "memetic-p1": OperatorSet(polish=1),
    "memetic-p4": OperatorSet(polish=4),
}
DEFAULT_CANDIDATES = (
    "ox-inversion-t4,ox-mix-t2,ox-mix-t4,memetic-t2,memetic-t3,memetic-t4,memetic-t8,"
    "memetic-obx-t2,memetic-clones-t2,memetic-p1-t2,memetic-p4-t2"
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


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--sizes", default="50x10,120x20", help="comma list of NxM")
    parser.add_argument("--uniform", type=int, default=10, help="uniform-current instances")
    parser.add_argument("--drift", type=int, default=5, help="thesis-field instances (cached)")
    parser.add_argument("--candidates", default=DEFAULT_CANDIDATES)
    parser.add_argument("--seed", type=int, default=0, help="GA seed")
    parser.add_argument("--generations", type=int, default=350)
    parser.add_argument("--population", type=int, default=120)
    parser.add_argument("--no-exact", action="store_true", help="skip f / f_o at n50m10")
    parser.add_argument("--jobs", type=int, default=1, help="processes for missing matrices")
    parser.add_argument("--csv", type=Path, default=None, help="also write every run here")
    args = parser.parse_args()
    labels = args.candidates.split(",")
    for label in labels:
        candidate(label)  # fail early on a typo

    rows = []
    for size in args.sizes.split(","):
        n, m = (int(part) for part in size.lower().split("x"))
        for family, problem in instances(n, m, args.uniform, args.drift, args.jobs):
            f_a = thesis_mcga(problem)
            mc = taopt.heuristics.run("MC", problem)
            f_mc = mc.objective
            f_o = None
            if (n, m) == (50, 10) and not args.no_exact:
                from taopt.models import solve_routing

                exact = solve_routing(problem)
                f_o = exact.objective if exact.status == "optimal" else None
            rows.append(
                {
                    "size": f"n{n}m{m}",
                    "family": family,
                    "instance": problem.name,
                    "candidate": "MC",
                    "f": f_mc,
                    "q": f_mc / f_a,
                    "f_mc": 1.0,
                    "f_o": None if f_o is None else f_mc / f_o,
                    "time": mc.runtime,
                    "moves": 0,
                }
            )
            for label in labels:
                ops, tournament = candidate(label)
                started = time.perf_counter()
                solution = genetic_algorithm(
                    problem,
                    seed=args.seed,
                    population=args.population,
                    generations=args.generations,
                    tournament=tournament,
                    operators=ops,
                )
                seconds = time.perf_counter() - started
                rows.append(
                    {
                        "size": f"n{n}m{m}",
                        "family": family,
                        "instance": problem.name,
                        "candidate": label,
                        "f": solution.objective,
                        "q": solution.objective / f_a,
                        "f_mc": solution.objective / f_mc,
                        "f_o": None if f_o is None else solution.objective / f_o,
                        "time": seconds,
                        "moves": solution.info["moves"],
                    }
                )
            print(f"  {problem.name}: done", flush=True)
    if args.csv:
        with open(args.csv, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)

    print(
        "\n| size | instances | candidate | mean q = f/f_a | mean f/f_MC | mean f/f_o "
        "| mean time (s) | max time (s) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    groups = sorted(
        {(r["size"], r["family"]) for r in rows}, key=lambda g: (int(g[0][1:].split("m")[0]), g[1])
    )
    for size, family in groups:
        for label in ["MC", *labels]:
            chosen = [
                r for r in rows if (r["size"], r["family"], r["candidate"]) == (size, family, label)
            ]
            optimum = [r["f_o"] for r in chosen if r["f_o"] is not None]
            gap = f"{np.mean(optimum):.4f}" if optimum and len(optimum) == len(chosen) else "-"
            print(
                f"| {size} | {family} ×{len(chosen)} | {label} | {np.mean([r['q'] for r in chosen]):.4f} "
                f"| {np.mean([r['f_mc'] for r in chosen]):.4f} | {gap} "
                f"| {np.mean([r['time'] for r in chosen]):.2f} | {max(r['time'] for r in chosen):.2f} |"
            )


if __name__ == "__main__":
    main()
