"""Navigation timings: the 60- and 140-point travel-time matrices, PMP against collocation.

Run from the repository root::

    python benchmarks/bench_navigation.py                 # everything
    python benchmarks/bench_navigation.py --part m140     # one matrix
    python benchmarks/bench_navigation.py --samples 0     # skip the refined-grid reference
    python benchmarks/bench_navigation.py --part single   # one collocation solve

Setup (thesis §2.5): the field 1e-3 [0.3x + 0.2y, -0.2x + 0.3y], v = 1, points
uniform in a 1000 m square (seeded). For each matrix the default method
("auto" = vectorised Pontryagin shooting, :mod:`taopt.navigation.pmp`) is timed
(median of ``--repeats`` runs, wall and CPU), then batched collocation (the
reference method) in the same run; printed: both times, their ratio, the
largest relative difference between the two matrices, and, on ``--samples``
sampled pairs, the largest relative difference of each to a per-pair
collocation solve on a 4x finer grid and (on 100 of them) to CVODES shooting.
Bars (issue 8, item 1): 140 points
<= 1 s wall on 2 cores, 60 points <= 0.3 s, every entry within 1e-8 of the
refined collocation.
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
from taopt.navigation.shooting import shooting_path


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


def relative_difference(A: np.ndarray, B: np.ndarray) -> tuple[float, tuple[int, int]]:
    off = ~np.eye(len(A), dtype=bool)
    rel = np.where(off, np.abs(A - B) / np.where(off, B, 1.0), 0.0)
    where = np.unravel_index(int(np.argmax(rel)), rel.shape)
    return float(rel[where]), (int(where[0]), int(where[1]))


def bench_matrix(
    field, n_targets: int, n_vehicles: int, seed: int, jobs: int | None, repeats: int, samples: int
) -> None:
    pts = points(n_targets, n_vehicles, seed)
    n = len(pts)
    cpus = jobs or os.cpu_count()
    walls, cpu = [], []
    for _ in range(repeats):
        tic, tic_cpu = time.perf_counter(), time.process_time()
        T, info = travel_time_matrix(field, pts, jobs=jobs, return_info=True)
        walls.append(time.perf_counter() - tic)
        cpu.append(time.process_time() - tic_cpu)
    wall = float(np.median(walls))
    tic = time.perf_counter()
    C, cinfo = travel_time_matrix(field, pts, method="collocation", jobs=jobs, return_info=True)
    colloc = time.perf_counter() - tic
    worst, where = relative_difference(T, C)
    print(
        f"{n}-point matrix ({n_targets} targets + {n_vehicles} vehicles, {n * (n - 1)} pairs, "
        f"jobs={cpus}):\n"
        f"    {info['method']}: {wall:.3f} s wall (median of {repeats}; min {min(walls):.3f}, "
        f"first {walls[0]:.3f}), {np.median(cpu):.3f} s CPU; Newton iterations "
        f"{info['iterations']}; fallback {len(info['fallback'])}, restarted "
        f"{len(info['restarted'])}, suspect {len(info['suspect'])}\n"
        f"    collocation: {colloc:.2f} s wall, {len(cinfo['retried'])} retried; "
        f"ratio {colloc / wall:.0f}x\n"
        f"    max relative difference pmp vs collocation: {worst:.2e} at {where}"
    )
    print("   ", matrix_report(T).summary())
    if samples:
        fine = CollocationSolver(field, intervals=4 * DEFAULT_INTERVALS)
        rows, cols = np.nonzero(~np.eye(n, dtype=bool))
        pick = np.random.default_rng(seed + 1).choice(rows.size, min(samples, rows.size), False)
        worst_pmp = worst_colloc = 0.0
        tic = time.perf_counter()
        for r in pick:
            i, j = rows[r], cols[r]
            ref = fine.solve(pts[i], pts[j])
            assert ref.success, ref.status
            worst_pmp = max(worst_pmp, abs(T[i, j] - ref.time) / ref.time)
            worst_colloc = max(worst_colloc, abs(C[i, j] - ref.time) / ref.time)
        print(
            f"    vs per-pair collocation on {4 * DEFAULT_INTERVALS} intervals, {pick.size} "
            f"sampled pairs: pmp max {worst_pmp:.2e}, default collocation max "
            f"{worst_colloc:.2e} (reference took {time.perf_counter() - tic:.1f} s)"
        )
        # CVODES shooting (rtol = atol = 1e-12) on the first 100 of those pairs
        worst_pmp = worst_colloc = 0.0
        for r in pick[:100]:
            i, j = rows[r], cols[r]
            ref = shooting_path(field, pts[i], pts[j]).time
            worst_pmp = max(worst_pmp, abs(T[i, j] - ref) / ref)
            worst_colloc = max(worst_colloc, abs(C[i, j] - ref) / ref)
        print(
            f"    vs CVODES shooting (tolerances 1e-12), {min(100, pick.size)} of those pairs: "
            f"pmp max {worst_pmp:.2e}, default collocation max {worst_colloc:.2e}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--part", nargs="+", choices=["single", "m60", "m140"], default=["m60", "m140"]
    )
    parser.add_argument("--pairs", type=int, default=50, help="pairs of the single-solve part")
    parser.add_argument("--jobs", type=int, default=None)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeats", type=int, default=5, help="timed runs of the default method")
    parser.add_argument(
        "--samples", type=int, default=500, help="pairs checked on the refined grid (0: skip)"
    )
    args = parser.parse_args()
    field = thesis_field(1e-3)
    print(f"cpus: {os.cpu_count()}, load average: {os.getloadavg()[0]:.2f}")
    if "single" in args.part:
        bench_single(field, args.pairs, args.seed)
    if "m60" in args.part:
        bench_matrix(field, 50, 10, args.seed, args.jobs, args.repeats, args.samples)
    if "m140" in args.part:
        bench_matrix(field, 120, 20, args.seed, args.jobs, args.repeats, args.samples)
    print(f"load average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
