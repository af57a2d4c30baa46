"""The chapter 2 exact loop past the thesis's sizes: n200m20 and n400m50 (issue 18 item 3).

Run from the repository root::

    python benchmarks/bench_routing_scale.py --sizes 200x20,400x50 --scenarios 3 --time-limit 600

Scenarios are §2.5's drift-field scenarios (:func:`taopt.routing.scenarios.drift_scenario`,
travel times by the vectorised PMP, seeds ``scenario_seed(1, k)``) at the given sizes. Each
exact solve runs in its own spawned process (so its peak memory is its own): the incumbent is
the best of MC and the GA (``taopt.solve``'s warm start), the wall-clock limit counts
everything. Printed per run: status, objective, proven bound, gap, seconds, DFJ rounds, cuts
and the process's peak resident memory; then the median time per size.
"""

from __future__ import annotations

import argparse
import multiprocessing
import resource
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any


def _solve(cost: Any, n: int, time_limit: float, queue: Any) -> None:
    import taopt

    problem = taopt.AssignmentProblem(cost, n_targets=n)
    began = time.perf_counter()
    result = taopt.solve(problem, "exact", time_limit=time_limit)
    info = result.info
    queue.put(
        {
            "status": result.status.value,
            "objective": result.objective,
            "bound": result.bound,
            "gap": result.gap,
            "seconds": time.perf_counter() - began,
            "rounds": info.get("rounds"),
            "cuts": info.get("cuts"),
            "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        }
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="200x20,400x50", help="comma-separated NxM")
    parser.add_argument("--scenarios", type=int, default=3)
    parser.add_argument("--time-limit", type=float, default=600.0)
    parser.add_argument("--cache", type=Path, default=Path(tempfile.gettempdir()) / "taopt-bench")
    args = parser.parse_args()

    from taopt.routing.scenarios import drift_scenario, scenario_seed

    context = multiprocessing.get_context("spawn")
    for size in args.sizes.split(","):
        n, m = (int(x) for x in size.lower().split("x"))
        times = []
        for k in range(args.scenarios):
            tic = time.perf_counter()
            scenario = drift_scenario(n, m, scenario_seed(1, k), cache_dir=args.cache, jobs=None)
            matrix_s = time.perf_counter() - tic
            queue = context.Queue()
            worker = context.Process(
                target=_solve, args=(scenario.problem.cost, n, args.time_limit, queue)
            )
            worker.start()
            row = queue.get()
            worker.join()
            times.append(row["seconds"])
            gap = "-" if row["gap"] is None else f"{100 * row['gap']:.3f} %"
            print(
                f"n{n}m{m} scenario {k}: matrix {matrix_s:.1f} s; {row['status']}, "
                f"f = {row['objective']:.1f}, bound {row['bound']:.1f}, gap {gap}, "
                f"{row['seconds']:.1f} s, rounds {row['rounds']}, cuts {row['cuts']}, "
                f"peak {row['peak_mb']:.0f} MB",
                flush=True,
            )
        print(f"n{n}m{m}: median {statistics.median(times):.1f} s over {len(times)} scenarios")


if __name__ == "__main__":
    main()
