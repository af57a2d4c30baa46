"""Navigation timings: one collocation solve, the 60- and 140-point travel-time matrices.

Run from the repository root::

    python benchmarks/bench_navigation.py             # everything
    python benchmarks/bench_navigation.py --part single m60
    python benchmarks/bench_navigation.py --part m60 --no-reference

Setup (thesis §2.5): the field 1e-3 [0.3x + 0.2y, -0.2x + 0.3y], v = 1, points
uniform in a 1000 m square (seeded). The 60-point matrix is checked entry by
entry against a fresh per-pair solve on a 4x finer grid (and reports the
largest relative difference). Bars from the brief: single solve median
<= 10 ms; 60 points <= 10 s with every entry within 1e-6; 140 points <= 60 s.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from taopt.fields import thesis_field
from taopt.navigation import travel_time_matrix
from taopt.navigation.checks import matrix_report
from taopt.navigation.collocation import DEFAULT_INTERVALS, CollocationSolver, get_solver


def points(n_targets: int, n_vehicles: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.vstack([rng.uniform(0, 1000, (n_targets, 2)), rng.uniform(0, 1000, (n_vehicles, 2))])


def bench_single(field, pairs: int, seed: int) -> None:
    solver = get_solver(field)
    rng = np.random.default_rng(seed)
    times, iterations = [], []
    for _ in range(pairs):
        a, b = rng.uniform(0, 1000, (2, 2))
        tic = time.perf_counter()
        path = solver.solve(a, b)
        times.append(time.perf_counter() - tic)
        iterations.append(path.iterations)
        assert path.success, path.status
    print(
        f"single collocation solve ({pairs} pairs, K={solver.intervals}, d={solver.degree}): "
        f"median {1e3 * np.median(times):.2f} ms, p90 {1e3 * np.percentile(times, 90):.2f} ms, "
        f"median IPOPT iterations {np.median(iterations):.0f}"
    )


def bench_matrix(
    field, n_targets: int, n_vehicles: int, seed: int, jobs: int | None, reference: bool
) -> None:
    pts = points(n_targets, n_vehicles, seed)
    n = len(pts)
    tic = time.perf_counter()
    T, info = travel_time_matrix(field, pts, jobs=jobs, return_info=True)
    wall = time.perf_counter() - tic
    report = matrix_report(T)
    print(
        f"{n}-point matrix ({n_targets} targets + {n_vehicles} vehicles, {n * (n - 1)} pairs, "
        f"jobs={jobs or os.cpu_count()}): {wall:.2f} s wall; iterations {info['iterations']}; "
        f"retried {len(info['retried'])}"
    )
    print("   ", report.summary())
    if reference:
        fine = CollocationSolver(field, intervals=4 * DEFAULT_INTERVALS)
        worst, where = 0.0, None
        tic = time.perf_counter()
        for i in range(n):
            for j in range(n):
                if i == j:
                    continue
                ref = fine.solve(pts[i], pts[j])
                assert ref.success, ref.status
                rel = abs(T[i, j] - ref.time) / ref.time
                if rel > worst:
                    worst, where = rel, (i, j)
        print(
            f"    max relative error vs fresh per-pair solves on {4 * DEFAULT_INTERVALS} "
            "intervals: "
            f"{worst:.2e} at {where} (reference took {time.perf_counter() - tic:.1f} s)"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--part", nargs="+", choices=["single", "m60", "m140"], default=["single", "m60", "m140"]
    )
    parser.add_argument("--pairs", type=int, default=50)
    parser.add_argument("--jobs", type=int, default=None)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--no-reference", action="store_true", help="skip the per-pair reference check"
    )
    args = parser.parse_args()
    field = thesis_field(1e-3)
    print(f"cpus: {os.cpu_count()}, load average: {os.getloadavg()[0]:.2f}")
    if "single" in args.part:
        bench_single(field, args.pairs, args.seed)
    if "m60" in args.part:
        bench_matrix(field, 50, 10, args.seed, args.jobs, not args.no_reference)
    if "m140" in args.part:
        bench_matrix(field, 120, 20, args.seed, args.jobs, False)


if __name__ == "__main__":
    main()
