"""Timing of the exact chapter 2 model (2.2)–(2.5), DFJ cuts in a loop, HiGHS.

Run from the repository root::

    python benchmarks/bench_routing_exact.py            # everything
    python benchmarks/bench_routing_exact.py --skip-drift   # TSPLIB only
    python benchmarks/bench_routing_exact.py --sec flow --sizes 50x10

Targets (brief): median over 5 thesis-field scenarios (v = 1, 1000 m square,
``thesis_field()``, uniform random points) of the exact solve: n50m10 <= 5 s,
n120m20 <= 60 s; TSPLIB ftv38 <= 60 s (ftv35, p43 printed too).

Travel-time matrices come from ``taopt.navigation.travel_time_matrix`` and are
cached in ``benchmarks/.cache/routing`` (.npy + .json); only the solve is timed.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import taopt
from taopt.models import solve_routing
from taopt.routing.scenarios import drift_scenario, scenario_seed
from taopt.routing.tsplib import atsp_to_assignment, load_atsp

CACHE = Path(__file__).resolve().parent / ".cache" / "routing"
TARGETS = {(50, 10): 5.0, (120, 20): 60.0}


def bench_drift(n: int, m: int, count: int, sec: str, seed: int, jobs: int, limit: float) -> None:
    times = []
    for k in range(count):
        started = time.perf_counter()
        scenario = drift_scenario(n, m, scenario_seed(seed, k), cache_dir=CACHE, jobs=jobs)
        matrix_time = time.perf_counter() - started
        solution = solve_routing(scenario.problem, sec=sec, time_limit=limit)
        check = taopt.evaluate(scenario.problem, solution.routes)
        assert abs(check - solution.objective) <= 1e-6 * abs(check)
        times.append(solution.runtime)
        print(
            f"  n{n}m{m} scenario {k}: {solution.summary()} rounds={solution.info['rounds']} "
            f"cuts={solution.info['cuts']} (matrix {matrix_time:.1f}s)",
            flush=True,
        )
    target = TARGETS.get((n, m))
    median = statistics.median(times)
    verdict = ""
    if target is not None:
        verdict = f" (target <= {target:g} s: {'ok' if median <= target else 'MISSED'})"
    print(f"n{n}m{m} {sec}: median {median:.2f} s, max {max(times):.2f} s over {count}{verdict}")


def bench_tsplib(names: list[str], sec: str, limit: float) -> None:
    for name in names:
        atsp = load_atsp(name)
        solution = solve_routing(atsp_to_assignment(atsp), sec=sec, time_limit=limit)
        ok = solution.status == "optimal" and abs(solution.objective - atsp.optimum) < 1e-6
        print(
            f"{name:6s} {sec}: {solution.runtime:7.2f} s  objective {solution.objective:g} "
            f"(optimum {atsp.optimum}) status {solution.status} rounds={solution.info['rounds']} "
            f"cuts={solution.info['cuts']} {'ok' if ok else 'NOT CERTIFIED'}",
            flush=True,
        )


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--sec", default="dfj", choices=("dfj", "mtz", "flow"))
    parser.add_argument("--sizes", default="50x10,120x20", help="comma list of NxM")
    parser.add_argument("--scenarios", type=int, default=5)
    parser.add_argument("--seed", type=int, default=2024)
    parser.add_argument("--jobs", type=int, default=1, help="processes for travel-time matrices")
    parser.add_argument("--time-limit", type=float, default=300.0)
    parser.add_argument("--tsplib", default="br17,ftv33,ftv35,ftv38,p43")
    parser.add_argument("--skip-drift", action="store_true")
    parser.add_argument("--skip-tsplib", action="store_true")
    args = parser.parse_args()
    if not args.skip_tsplib:
        bench_tsplib(args.tsplib.split(","), args.sec, args.time_limit)
    if not args.skip_drift:
        for size in args.sizes.split(","):
            n, m = (int(x) for x in size.lower().split("x"))
            bench_drift(n, m, args.scenarios, args.sec, args.seed, args.jobs, args.time_limit)


if __name__ == "__main__":
    main()
