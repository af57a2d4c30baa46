"""Chapter 4 speed: one simulation at n30m6 and n100m10, one at n600m10, the table study.

Run from the repository root::

    python benchmarks/bench_comm.py                 # single runs (about a minute)
    python benchmarks/bench_comm.py --study 50      # + the Tables 4.1-4.2 study, 50 scenarios

Wall and CPU time are both shown: on a machine shared with other work the wall time of a
single-threaded run is inflated by the contention, its CPU time much less.

Issue 10's bars (two cores): one DAA run at n30m6 <= 20 ms median and at n100m10 <= 0.3 s
(random scenarios of Table 4.1's setup over the seven ranges and every |A|); one CAA, DAA
or HDA run at n600m10, initially connected, <= 5 s; the whole Table 4.1-4.2 study
(7 ranges x 5 |A| x 500 scenarios x 3 algorithms) <= 30 min — ``--study K`` runs K
scenarios with ``--jobs`` workers and extrapolates linearly to 500.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time

from taopt.comm import random_problem
from taopt.comm.engine import simulate
from taopt.heuristics.comm import POLICIES
from taopt.orchestration.studies.comm import PRESETS, comm_study


def timed_runs(n: int, m: int, r_c: float, attributes: list[int], count: int, algorithm: str):
    """Seconds of ``count`` runs over every |A| and the seven ranges {1, r_c/6, ..., r_c}."""
    ranges = [1.0, *(k * r_c / 6 for k in range(1, 7))]
    policy = POLICIES[algorithm]
    walls, cpus = [], []
    for k in range(count):
        a = attributes[k % len(attributes)]
        r = ranges[(k // len(attributes)) % len(ranges)]
        problem = random_problem(n, m, a, r, seed=k)
        began, cpu = time.perf_counter(), time.process_time()
        simulate(problem, policy(), seed=k)
        walls.append(time.perf_counter() - began)
        cpus.append(time.process_time() - cpu)
    return walls, cpus


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=105, help="runs per size (n30m6)")
    parser.add_argument("--study", type=int, default=0, help="scenarios of the table study")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()

    timed_runs(30, 6, 600.0, [2], 1, "DAA")  # imports and caches
    for algorithm in ("DAA", "HDA", "CAA"):
        wall, cpu = timed_runs(30, 6, 600.0, [2, 3, 4, 5, 6], args.runs, algorithm)
        print(
            f"{algorithm} n30m6  : median {1000 * statistics.median(wall):7.2f} ms wall, "
            f"{1000 * statistics.median(cpu):7.2f} ms CPU over {len(wall)} runs"
        )
    for algorithm in ("DAA", "HDA", "CAA"):
        wall, cpu = timed_runs(100, 10, 482.0, [2, 4, 6, 8, 10], max(35, args.runs // 3), algorithm)
        print(
            f"{algorithm} n100m10: median {statistics.median(wall):7.3f} s wall, "
            f"{statistics.median(cpu):7.3f} s CPU, max {max(wall):6.3f} s wall"
        )
    connected = PRESETS["scalability"].ranges[0]
    for algorithm in ("DAA", "CAA", "HDA"):
        for attributes in (1, 2, 10):
            problem = random_problem(600, 10, attributes, connected, seed=attributes)
            began, cpu = time.perf_counter(), time.process_time()
            simulate(problem, POLICIES[algorithm]())
            print(
                f"{algorithm} n600m10 |A|={attributes:2d}, always connected: "
                f"{time.perf_counter() - began:6.2f} s wall, {time.process_time() - cpu:6.2f} s CPU"
            )
    if args.study:
        with tempfile.TemporaryDirectory() as tmp:
            began = time.perf_counter()
            df = comm_study("table", args.study, tmp, jobs=args.jobs, progress=False)
            spent = time.perf_counter() - began
        rows = len(df)
        print(
            f"table study: {args.study} scenarios, {rows} runs in {spent:.1f} s with "
            f"--jobs {args.jobs}; 500 scenarios: about {spent * 500 / args.study / 60:.1f} min"
        )


if __name__ == "__main__":
    main()
