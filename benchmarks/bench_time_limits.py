"""Wall-clock time limits: for each family, T, the elapsed wall time and the overrun.

The contract (docs/architecture.md, invariant 4, issue 15 item 2): ``taopt.solve(problem, method,
time_limit=T)`` returns within T + 0.5 s of being called, everything included (warm start,
model building, separation, decoding), with status "time_limit" (or "optimal" if it proved
the optimum in time), a proven bound and no exception.

Imports are paid once before the clock (a first ``taopt.solve`` on a tiny problem), as a CLI
or a study pays them once. Each row prints the family, the instance, T, the elapsed seconds,
the overrun (elapsed - T), the status, objective and bound, and the warm start's seconds (the
part of the pipeline before the method).

Run: ``python benchmarks/bench_time_limits.py [--quick]`` (``--quick``: T = 0.2 and smaller
instances, as the tests use).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import taopt

# the public TSPLIB files beside the checkout (../shared/benchmarks/tsplib)
BENCHMARKS = Path(__file__).resolve().parents[2] / "shared" / "benchmarks" / "tsplib"


def assignment(n: int, m: int = 3, seed: int = 0) -> taopt.AssignmentProblem:
    """Random Euclidean points in the unit square: n targets, m vehicles."""
    points = np.random.default_rng(seed).random((n + m, 2))
    cost = np.linalg.norm(points[:, None] - points[None], axis=-1)
    return taopt.AssignmentProblem(cost, n, name=f"euclid-{n}x{m}")


def sop(name: str):
    """A TSPLIB SOP instance: shipped, or from the shared benchmark folder."""
    from taopt.sop.problem import SopProblem, shipped_sop

    if name in shipped_sop():
        return SopProblem.load(name)
    return SopProblem.load(BENCHMARKS / f"{name}.sop")


def delivery(n: int, seed: int = 7):
    """The residential example's generator with n customers."""
    from taopt.delivery import build_example_instance

    return build_example_instance(seed=seed, n=n)


def capability(n: int, m: int = 10, classes: int = 3, seed: int = 0):
    """A §3.7 scenario (grid navigation around the thesis's obstacles)."""
    from taopt.capability.instances import thesis_scenario

    return thesis_scenario(n, m, classes, seed).problem


def comm(n: int, m: int = 10, seed: int = 0):
    """A §4.4 random scenario."""
    from taopt.comm.problem import random_problem

    return random_problem(n, m, 3, 200.0, seed=seed)


def cases(quick: bool) -> list[tuple[str, str, callable, float]]:
    """(family, method, instance builder, T)."""
    if quick:
        return [
            ("assignment", "exact", lambda: assignment(300), 0.2),
            ("sop", "exact", lambda: sop("ESC25"), 0.2),
            ("delivery", "exact", lambda: delivery(20), 0.2),
            ("delivery", "DP", lambda: delivery(14), 0.2),
            ("capability", "exact", lambda: capability(50), 0.2),
            ("capability", "joint", lambda: capability(50), 0.2),
            ("comm", "exact", lambda: comm(300), 0.2),
        ]
    return [
        ("assignment", "exact", lambda: assignment(1000), 1.0),
        ("assignment", "exact", lambda: assignment(500), 1.0),
        ("sop", "exact", lambda: sop("ESC47"), 1.0),
        ("sop", "exact", lambda: sop("ESC25"), 1.0),
        ("sop", "exact", lambda: sop("ry48p.4"), 5.0),
        ("delivery", "exact", lambda: delivery(20), 1.0),
        ("delivery", "DP", lambda: delivery(14), 1.0),
        ("capability", "exact", lambda: capability(90), 1.0),
        ("capability", "joint", lambda: capability(90), 1.0),
        ("comm", "exact", lambda: comm(1000), 1.0),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="T = 0.2 on smaller instances")
    parser.add_argument("--only", default="", help="comma-separated families to run")
    args = parser.parse_args()
    taopt.solve(assignment(3, 1), "exact", time_limit=5)  # imports paid before the clock
    only = {f for f in args.only.split(",") if f}
    print(
        f"{'family':<11}{'method':<7}{'instance':<22}{'T':>5}{'elapsed':>9}{'overrun':>9}  "
        f"{'status':<11}{'objective':>12}{'bound':>12}{'warm':>7}"
    )
    for family, method, build, limit in cases(args.quick):
        if only and family not in only:
            continue
        problem = build()
        began = time.perf_counter()
        try:
            result = taopt.solve(problem, method, time_limit=limit)
        except Exception as exc:  # the benchmark reports, it does not stop
            elapsed = time.perf_counter() - began
            print(
                f"{family:<11}{method:<7}{getattr(problem, 'name', '')[:21]:<22}{limit:>5g}"
                f"{elapsed:>9.2f}{elapsed - limit:>9.2f}  {type(exc).__name__}: {exc}"
            )
            continue
        elapsed = time.perf_counter() - began
        warm = result.info.get("warm_start", {}).get("runtime", 0.0)
        bound = "-" if result.bound is None else f"{result.bound:.6g}"
        print(
            f"{family:<11}{method:<7}{getattr(problem, 'name', '')[:21]:<22}{limit:>5g}"
            f"{elapsed:>9.2f}{elapsed - limit:>9.2f}  {result.status.value:<11}"
            f"{result.objective:>12.6g}{bound:>12}{warm:>7.2f}",
            flush=True,
        )


if __name__ == "__main__":
    main()
