"""Timing of the fleet family's exact method (issue 32's speed targets).

* ``tspd``: every shipped TSP-D instance (5–13 nodes), solved to optimality and compared with
  the published optimum, and our generated 14–17 node instances (``taopt/data/tspd/generated``);
  per size the median and max seconds. Targets: each shipped <= 5 s, 14–17 nodes <= 60 s.
  ``--before`` also runs the full operations DP (``fast=False``, same limit) in the same run
  and checks both optima agree.
* ``fleet8``: residential instances (:func:`taopt.fleet.instances.residential_fleet`), n = 8,
  every K, D, c in {1, 2, 3}. Target: each <= 10 s.
* ``fleet10``: n = 10, K = 2, D = 2, c = 2, layered DAG. Target: median <= 60 s, max <= 10 min.

Each solve has a wall-clock limit (``--time-limit``); a solve that stops there counts as that
long and is reported with its status and gap. Run: ``python benchmarks/bench_fleet.py [--sets
tspd,fleet8,fleet10] [--time-limit 60] [--seeds 3] [--no-milp] [--before]``; the exact rows end with
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
from taopt.errors import InstanceError
from taopt.fleet import FleetProblem
from taopt.fleet.instances import residential_fleet
from taopt.fleet.operations import operations_dp
from taopt.fleet.tspd import generated_instances, published_optimum, tspd_instances


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


def _before(problem: FleetProblem, limit: float) -> tuple[float, dict[str, object]]:
    """The full operations DP (the method before the sparse TSP-D DP), same limit."""
    start = time.perf_counter()
    result = operations_dp(problem, time_limit=limit, fast=False)
    return time.perf_counter() - start, result


def tspd(limit: float, before: bool) -> None:
    """Shipped 5-13 nodes (published optima) and our generated 14-17 (no published optimum):
    the exact method (sparse DP) and, with ``before``, the full operations DP in the same run."""
    rows: dict[int, dict[str, list[float]]] = {}
    wrong = 0
    _solve(FleetProblem.from_tspd(tspd_instances()[0]), limit)  # warm-up: imports
    for path in tspd_instances() + generated_instances():
        problem = FleetProblem.from_tspd(path)
        seconds, solution = _solve(problem, limit)
        row = rows.setdefault(problem.s, {"after": [], "before": [], "unsolved": []})
        row["after"].append(seconds)
        try:
            opt = published_optimum(path)
        except InstanceError:
            opt = solution.objective  # ours: checked against the full DP below when it finishes
        if before:
            old_seconds, old = _before(problem, limit)
            row["before"].append(old_seconds)
            if old["stopped_by"] != "optimal":
                row["unsolved"].append(1.0)
            elif abs(float(old["value"]) - solution.objective) > 1e-9 * opt:  # type: ignore[arg-type]
                wrong += 1
                print(f"  {path.stem}: sparse {solution.objective:.9f} vs full {old['value']}")
        if solution.status != "optimal" or abs(solution.objective - opt) > 1e-6 * opt:
            wrong += 1
            print(f"  {path.stem}: {solution.status} {solution.objective:.6f} vs {opt:.6f}")
        print(
            f"  {path.stem}: {solution.objective:.6f} {seconds:.2f} s"
            + (f" (full DP {old_seconds:.2f} s, {old['stopped_by']})" if before else ""),
            flush=True,
        )
    print(
        f"{'nodes':>5} {'count':>5} {'median s':>9} {'max s':>7}"
        + (f" {'before median':>13} {'before max':>10} {'unfinished':>10}" if before else "")
    )
    for size, row in sorted(rows.items()):
        after = row["after"]
        line = f"{size:>5} {len(after):>5} {statistics.median(after):>9.2f} {max(after):>7.2f}"
        if before:
            old_times = row["before"]
            line += (
                f" {statistics.median(old_times):>13.2f} {max(old_times):>10.2f}"
                f" {len(row['unsolved']):>10}"
            )
        print(line)
    print(f"optimum missed (published, or the full DP's) on {wrong} instances")


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
    parser.add_argument(
        "--before", action="store_true", help="TSP-D: also time the full operations DP"
    )
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    sets = args.sets.split(",")
    if "tspd" in sets:
        tspd(args.time_limit, args.before)
    if "fleet8" in sets:
        grid = list(itertools.product((1, 2, 3), repeat=3))
        fleet(8, grid, 1, min(args.time_limit, 10.0), not args.no_milp)
    if "fleet10" in sets:
        fleet(10, [(2, 2, 2)], args.seeds, args.time_limit, not args.no_milp)


if __name__ == "__main__":
    main()
