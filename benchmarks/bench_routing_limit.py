"""Wall-clock time limits of the exact routing model (issue 15 item 2, routing part).

The contract: a method called with ``time_limit=T`` returns within ``T + 0.5`` s of being
called, everything included, with status ``time_limit``, the best routes found and a proven
bound. This script measures, for random Euclidean instances (n targets and m vehicles
uniform in a 1000 m square, seed 0), the build stages one by one and then whole calls::

    python benchmarks/bench_routing_limit.py                        # n = 1000, m = 10, T = 1
    python benchmarks/bench_routing_limit.py --sizes 300x10,1000x10 --limits 0.2,1,5
    python benchmarks/bench_routing_limit.py --cvxpy                # also cvxpy's compilation

Stages (the matrix itself is not timed): the greedy start, :func:`assignment_bound`,
:class:`DfjModel` (arrays and HiGHS's ``passModel``), optionally cvxpy's build and
compilation of the same rows (what DfjModel did before), and the root LP's first run
without a limit (how long HiGHS takes before it can stop). Calls: ``solve_routing(problem,
time_limit=T)`` and ``taopt.solve(problem, "exact", time_limit=T)`` (the pipeline, with its
warm start). Each line prints the wall time, how far past T it returned, the status and the
bound. Figures on a shared machine are noisy: compare lines of one run.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import taopt
from taopt import AssignmentProblem
from taopt.models.highs import HighsModel
from taopt.models.routing import DfjModel, assignment_bound, build, greedy_routes, solve_routing


def instance(n: int, m: int, seed: int = 0) -> AssignmentProblem:
    """n targets and m vehicle starts uniform in a 1000 m square; Euclidean times."""
    points = np.random.default_rng(seed).uniform(0, 1000, size=(n + m, 2))
    cost = np.linalg.norm(points[:, None] - points[None, :], axis=2)
    return AssignmentProblem(cost, n, name=f"n{n}m{m}")


def timed(function, *args, **kwargs):
    began = time.perf_counter()
    result = function(*args, **kwargs)
    return result, time.perf_counter() - began


def stages(problem: AssignmentProblem, cvxpy: bool, lp: bool) -> None:
    arcs = (problem.n + problem.m) * problem.n - problem.n
    print(f"{problem.name}: {arcs} arcs")
    _, seconds = timed(greedy_routes, problem)
    print(f"  greedy start           {seconds:7.3f} s")
    bound, seconds = timed(assignment_bound, problem)
    print(f"  assignment_bound       {seconds:7.3f} s   ({bound:.1f})")
    model, seconds = timed(DfjModel, problem)
    print(f"  DfjModel (passModel)   {seconds:7.3f} s   ({seconds / arcs * 1e6:.2f} µs/arc)")
    if lp:
        model.model.relax(True)
        run, seconds = timed(model.model.solve)
        print(f"  root LP, no limit      {seconds:7.3f} s   ({run.solver_status})")
    if cvxpy:
        formulation, seconds = timed(build, problem, "dfj")
        print(f"  cvxpy build            {seconds:7.3f} s")
        _, seconds = timed(HighsModel, formulation.problem)
        print(f"  cvxpy compile + pass   {seconds:7.3f} s")


def calls(problem: AssignmentProblem, limits: list[float]) -> None:
    for limit in limits:
        for label, function in (
            ("solve_routing", lambda t=limit: solve_routing(problem, time_limit=t)),
            ("taopt.solve  ", lambda t=limit: taopt.solve(problem, "exact", time_limit=t)),
        ):
            solution, seconds = timed(function)
            print(
                f"  {label} T={limit:<5g} {seconds:7.3f} s  ({seconds - limit:+.3f})  "
                f"{solution.status}  objective {solution.objective:.1f}  "
                f"bound {solution.bound:.1f}  stage {solution.info.get('stage', '-')}"
            )


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--sizes", default="1000x10", help="comma list of NxM")
    parser.add_argument("--limits", default="1", help="comma list of seconds")
    parser.add_argument("--cvxpy", action="store_true", help="time cvxpy's compilation too")
    parser.add_argument("--lp", action="store_true", help="time the full root LP (slow)")
    args = parser.parse_args()
    limits = [float(v) for v in args.limits.split(",")]
    for size in args.sizes.split(","):
        n, m = (int(v) for v in size.split("x"))
        problem = instance(n, m)
        stages(problem, args.cvxpy, args.lp)
        calls(problem, limits)


if __name__ == "__main__":
    main()
