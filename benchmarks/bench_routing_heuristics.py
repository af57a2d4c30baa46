"""Runtime and quality of the chapter 2 heuristics on thesis-field scenarios (Table 2.2).

Scenario (§2.5): v = 1, a 1000 m square, the field
``1e-3 [0.3x + 0.2y, -0.2x + 0.3y]``, random targets and vehicle starts; the
travel-time matrix comes from ``taopt.navigation.travel_time_matrix``
(its default, vectorised Pontryagin shooting, about 0.3 s at n120m20; cached on
disk as .npy, so a cache written earlier by collocation, equal within 2e-10, is reused). Each heuristic is timed on each scenario (best of ``--repeat`` for
the fast ones) and the median over scenarios is printed, with the median
quality q = f / f_a (2.26, f_a = Algorithm 1) and f / arborescence (valid bound).

The thesis's Matlab timings (n120m10): MC 0.25 s, EVM 0.43 s, GA 163 s; for
n120m20 the brief quotes MC 0.30 s and GA 227 s.

Usage::

    python benchmarks/bench_routing_heuristics.py                 # n120m20, 5 scenarios
    python benchmarks/bench_routing_heuristics.py --costs uniform # no navigation (fast)
    python benchmarks/bench_routing_heuristics.py --n 50 --m 10 --scenarios 3 --no-ga
    python benchmarks/bench_routing_heuristics.py --ga-operators ox-inversion  # first GA
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

import taopt
import taopt.heuristics
from taopt.fields import UniformField, thesis_field
from taopt.instance import Instance
from taopt.routing.bounds import arborescence_bound, thesis_mcga

FAST = ["VN", "VM", "EVN", "EVM", "MC"]


def scenario(n: int, m: int, seed: int, costs: str, cache: Path, jobs: int | None):
    """The travel-time matrix of one random scenario (cached as .npy)."""
    field = thesis_field(1e-3)
    instance = Instance.random(n, m, side=1000.0, field=field, seed=seed)
    path = cache / f"routing-{costs}-n{n}m{m}-seed{seed}.npy"
    if path.exists():
        matrix = np.load(path)
    else:
        from taopt.navigation import travel_time_matrix

        if costs == "uniform":  # the field's value at the centre, closed form (3.4)
            vx, vy = field.velocity(np.array([[500.0, 500.0]]))[0]
            matrix = travel_time_matrix(UniformField(vx, vy), instance.points)
        else:
            start = time.perf_counter()
            matrix = travel_time_matrix(field, instance.points, jobs=jobs, progress=True)
            print(f"  navigation matrix for seed {seed}: {time.perf_counter() - start:.1f} s")
        np.save(path, matrix)
    return taopt.AssignmentProblem(matrix, n, name=f"n{n}m{m}-seed{seed}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=120)
    parser.add_argument("--m", type=int, default=20)
    parser.add_argument("--scenarios", type=int, default=5)
    parser.add_argument("--repeat", type=int, default=5, help="timing repeats (fast methods)")
    parser.add_argument("--costs", choices=("navigation", "uniform"), default="navigation")
    parser.add_argument("--cache", type=Path, default=Path(tempfile.gettempdir()) / "taopt-bench")
    parser.add_argument("--jobs", type=int, default=None, help="navigation worker processes")
    parser.add_argument("--no-ga", action="store_true")
    parser.add_argument("--generations", type=int, default=350)
    parser.add_argument("--population", type=int, default=120)
    parser.add_argument(
        "--ga-operators", default="memetic", help='GA operator set ("memetic", "ox-inversion")'
    )
    args = parser.parse_args()
    args.cache.mkdir(parents=True, exist_ok=True)

    methods = FAST + ([] if args.no_ga else ["GA"])
    times = {name: [] for name in methods}
    quality = {name: [] for name in methods}
    valid_ratio = {name: [] for name in methods}
    for seed in range(args.scenarios):
        problem = scenario(args.n, args.m, seed, args.costs, args.cache, args.jobs)
        f_a = thesis_mcga(problem)
        lower = arborescence_bound(problem)
        for name in methods:
            options = (
                {
                    "generations": args.generations,
                    "population": args.population,
                    "operators": args.ga_operators,
                }
                if name == "GA"
                else {}
            )
            best = np.inf
            for _ in range(1 if name == "GA" else args.repeat):
                start = time.perf_counter()
                solution = taopt.heuristics.run(name, problem, seed=seed, **options)
                best = min(best, time.perf_counter() - start)
            times[name].append(best)
            quality[name].append(solution.objective / f_a)
            valid_ratio[name].append(solution.objective / lower)
        print(f"scenario {seed}: f_a = {f_a:.1f}, arborescence = {lower:.1f}")

    print(f"\nn{args.n}m{args.m}, {args.scenarios} scenarios, costs: {args.costs}")
    print(f"{'method':<6} {'median time (s)':>16} {'median f/f_a':>13} {'median f/arb':>13}")
    for name in methods:
        print(
            f"{name:<6} {np.median(times[name]):>16.4f} {np.median(quality[name]):>13.4f}"
            f" {np.median(valid_ratio[name]):>13.4f}"
        )


if __name__ == "__main__":
    main()
