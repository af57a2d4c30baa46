"""Timing of the fleet family's exact method (issue 32's speed targets).

* ``tspd``: every shipped TSP-D instance (5–13 nodes), solved to optimality and compared with
  the published optimum; per size the median and max seconds. Target: each <= 5 s.
* ``fleet8``: residential instances (:func:`taopt.fleet.instances.residential_fleet`), n = 8,
  every K, D, c in {1, 2, 3}. Target: each <= 10 s.
* ``fleet10``: n = 10, K = 2, D = 2, c = 2, layered DAG. Target: median <= 60 s, max <= 10 min.

Each solve has a wall-clock limit (``--time-limit``); a solve that stops there counts as that
long and is reported with its status and gap. Run: ``python benchmarks/bench_fleet.py [--sets
tspd,fleet8,fleet10] [--time-limit 60] [--seeds 3] [--no-milp]``; the exact rows end with
the algorithm and, where computed, the root sortie-walk bound; the teaching MILP
(``"milp"``) is solved beside the exact method on every fleet instance, same limit. The machine's load average is printed
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


def _solve(
    problem: FleetProblem, limit: float, method: str = "exact"
) -> tuple[float, taopt.Solution]:
    start = time.perf_counter()
    solution = taopt.solve(problem, method, time_limit=limit)
    return time.perf_counter() - start, solution


def _root(solution: taopt.Solution) -> str:
    """The root sortie-walk bound (``taopt.fleet.cover``) when the exact method computed one."""
    root = solution.info.get("root_cover_bound")
    return "" if root is None else f"root {root:.2f}"


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


def fleet(n: int, grid: list[tuple[int, int, int]], seeds: int, limit: float, milp: bool) -> None:
    print(
        f"{'n':>3} {'K':>2} {'D':>2} {'c':>2} {'seed':>4} {'method':>6} {'status':>10} {'value':>8} "
        f"{'bound':>8} {'gap':>7} {'s':>7} algorithm"
    )
    times: dict[str, list[float]] = {}
    certified: dict[str, int] = {}
    for (K, D, c), seed in itertools.product(grid, range(seeds)):
        problem = residential_fleet(n, K, D, c, seed=seed)
        for method in ("exact", "milp") if milp else ("exact",):
            seconds, solution = _solve(problem, limit, method)
            times.setdefault(method, []).append(seconds)
            certified[method] = certified.get(method, 0) + (solution.status == "optimal")
            gap = solution.gap if solution.gap is not None else float("nan")
            bound = solution.bound if solution.bound is not None else float("nan")
            print(
                f"{n:>3} {K:>2} {D:>2} {c:>2} {seed:>4} {method:>6} {solution.status!s:>10} "
                f"{solution.objective:>8.2f} {bound:>8.2f} {gap:>7.3f} {seconds:>7.2f} "
                f"{solution.info.get('algorithm', '')} {_root(solution)}",
                flush=True,
            )
    for method, values in times.items():
        print(
            f"n = {n} {method}: certified {certified[method]} of {len(values)}, median "
            f"{statistics.median(values):.2f} s, max {max(values):.2f} s"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sets", default="tspd,fleet8,fleet10")
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--no-milp", action="store_true", help="leave the teaching MILP out")
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    sets = args.sets.split(",")
    if "tspd" in sets:
        tspd(args.time_limit)
    if "fleet8" in sets:
        grid = list(itertools.product((1, 2, 3), repeat=3))
        fleet(8, grid, 1, min(args.time_limit, 10.0), not args.no_milp)
    if "fleet10" in sets:
        fleet(10, [(2, 2, 2)], args.seeds, args.time_limit, not args.no_milp)


if __name__ == "__main__":
    main()
