"""Timing of the fleet family's exact method (issue 32's speed targets).

* ``tspd``: every shipped TSP-D instance (5–13 nodes), solved to optimality and compared with
  the published optimum; per size the median and max seconds. Target: each <= 5 s.
* ``fleet8``: residential instances (:func:`taopt.fleet.instances.residential_fleet`), n = 8,
  every K, D, c in {1, 2, 3}. Target: each <= 10 s.
* ``fleet10``: n = 10, K = 2, D = 2, c = 2, layered DAG. Target: median <= 60 s, max <= 10 min.

Each solve has a wall-clock limit (``--time-limit``); a solve that stops there counts as that
long and is reported with its status and gap. Run: ``python benchmarks/bench_fleet.py [--sets
tspd,fleet8,fleet10] [--time-limit 60] [--seeds 3]``. The machine's load average is printed
(timings on shared cores scale with it).
"""

from __future__ import annotations

import argparse
import itertools
import os
import statistics
import time

import taopt
from taopt.fleet import FleetProblem
from taopt.fleet.instances import residential_fleet
from taopt.fleet.tspd import published_optimum, tspd_instances


def _solve(problem: FleetProblem, limit: float) -> tuple[float, taopt.Solution]:
    start = time.perf_counter()
    solution = taopt.solve(problem, "exact", time_limit=limit)
    return time.perf_counter() - start, solution


def tspd(limit: float) -> None:
    by_size: dict[int, list[float]] = {}
    wrong = 0
    _solve(FleetProblem.from_tspd(tspd_instances()[0]), limit)  # warm-up: imports
    for path in tspd_instances():
        problem = FleetProblem.from_tspd(path)
        seconds, solution = _solve(problem, limit)
        opt = published_optimum(path)
        if solution.status != "optimal" or abs(solution.objective - opt) > 1e-6 * opt:
            wrong += 1
            print(f"  {path.stem}: {solution.status} {solution.objective:.6f} vs {opt:.6f}")
        by_size.setdefault(problem.s, []).append(seconds)
    print(f"{'nodes':>5} {'count':>5} {'median s':>9} {'max s':>7}")
    for size, times in sorted(by_size.items()):
        print(f"{size:>5} {len(times):>5} {statistics.median(times):>9.2f} {max(times):>7.2f}")
    print(f"published optimum missed on {wrong} of {sum(map(len, by_size.values()))}")


def fleet(n: int, grid: list[tuple[int, int, int]], seeds: int, limit: float) -> None:
    print(
        f"{'n':>3} {'K':>2} {'D':>2} {'c':>2} {'seed':>4} {'status':>10} {'gap':>7} {'s':>7} algorithm"
    )
    times = []
    for (K, D, c), seed in itertools.product(grid, range(seeds)):
        problem = residential_fleet(n, K, D, c, seed=seed)
        seconds, solution = _solve(problem, limit)
        times.append(seconds)
        gap = solution.gap if solution.gap is not None else float("nan")
        print(
            f"{n:>3} {K:>2} {D:>2} {c:>2} {seed:>4} {solution.status!s:>10} {gap:>7.3f} "
            f"{seconds:>7.2f} {solution.info.get('algorithm', '')}",
            flush=True,
        )
    print(f"n = {n}: median {statistics.median(times):.2f} s, max {max(times):.2f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sets", default="tspd,fleet8,fleet10")
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--seeds", type=int, default=3)
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    sets = args.sets.split(",")
    if "tspd" in sets:
        tspd(args.time_limit)
    if "fleet8" in sets:
        grid = list(itertools.product((1, 2, 3), repeat=3))
        fleet(8, grid, 1, min(args.time_limit, 10.0))
    if "fleet10" in sets:
        fleet(10, [(2, 2, 2)], args.seeds, args.time_limit)


if __name__ == "__main__":
    main()
