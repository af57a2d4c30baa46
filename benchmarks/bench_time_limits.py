"""Wall-clock time limits under load: every registered method of every family, wall time / T.

The contract (docs/architecture.md, "the runtime contract"; issue 30 item 4):
``taopt.solve(problem, method, time_limit=T)`` returns within ``T + max(1 s, 5 % of T)`` of being called, everything
included (a peer's worker start-up and import, model building, warm starts, decoding), on a
loaded machine too, with a status and no exception.

The script makes the load itself: ``--load K`` busy-loop processes (default 4), each one
bounded in time (``--load-seconds``, default 900 s, and stopped when the script ends). It then
runs every method :func:`taopt.available_methods` lists for one mid-size problem of each
family (``--families``) at each limit of ``--limits`` and prints, per run, the elapsed wall
time, elapsed / T, the overrun (elapsed - T) against the allowance max(1 s, 5 % T), the
status, the objective and the 1-minute load average when the run ended. Imports of taopt's
own modules are paid once before any clock runs (as a CLI or a study pays them); the peers'
worker processes are *not* started beforehand: their first call counts the start-up.

Mid-size problems (``--large``: the larger instances of the exact-method table in
``docs/benchmarks.md``):

* assignment: Euclidean n = 200, m = 10 (the report's instance);
* budgeted: Euclidean n = 100, m = 10, capacity 12 and a route-time limit of 1.5;
* capability: the §3.7 scenario n = 90, m = 10, |A| = 3;
* comm: a §4.4 random scenario n = 300, m = 10, |A| = 3;
* delivery: the residential example with 20 customers;
* sop: ESC47 (TSPLIB);
* fleet: a residential fleet instance (:func:`taopt.fleet.instances.residential_fleet`),
  n = 10, K = 2, D = 2, c = 2 (the teaching MILP: 253k rows; ``--large`` n = 20).

Run: ``python benchmarks/bench_time_limits.py [--limits 0.5,1,5] [--load 4]
[--families assignment,sop] [--methods GA,cpsat] [--repeat 1]``. ``--load 0`` measures on the
machine as it is.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

import taopt
from taopt.runtime import overrun_allowance

# the public TSPLIB files beside the checkout (../shared/benchmarks/tsplib)
BENCHMARKS = Path(__file__).resolve().parents[2] / "shared" / "benchmarks" / "tsplib"

#: A busy loop that ends by itself after its argument's seconds (the load is bounded).
BUSY_LOOP = (
    "import sys, time\nend = time.time() + float(sys.argv[1])\nwhile time.time() < end: pass\n"
)


def euclidean(n: int, m: int, seed: int = 0) -> np.ndarray:
    """Travel times between random points of the unit square: n targets then m starts."""
    points = np.random.default_rng(seed).random((n + m, 2))
    return np.linalg.norm(points[:, None] - points[None], axis=-1)


def assignment(n: int = 200, m: int = 10) -> taopt.AssignmentProblem:
    return taopt.AssignmentProblem(euclidean(n, m), n, name=f"euclid-{n}x{m}")


def budgeted(n: int = 100, m: int = 10):
    from taopt.budgeted import BudgetedProblem

    capacity = [int(np.ceil(1.2 * n / m))] * m
    return BudgetedProblem(
        euclidean(n, m), n, capacity=capacity, max_time=[1.5] * m, name=f"budgeted-{n}x{m}"
    )


def capability(n: int = 90, m: int = 10, classes: int = 3, seed: int = 0):
    from taopt.capability.instances import thesis_scenario

    return thesis_scenario(n, m, classes, seed).problem


def comm(n: int = 300, m: int = 10, seed: int = 0):
    from taopt.comm.problem import random_problem

    return random_problem(n, m, 3, 200.0, seed=seed, name=f"comm-{n}x{m}")


def delivery(n: int = 20, seed: int = 7):
    from taopt.delivery import build_example_instance

    return build_example_instance(seed=seed, n=n)


def sop(name: str = "ESC47"):
    from taopt.sop.problem import SopProblem, shipped_sop

    if name in shipped_sop():
        return SopProblem.load(name)
    return SopProblem.load(BENCHMARKS / f"{name}.sop")


def fleet(n: int = 10, seed: int = 0):
    from taopt.fleet.instances import residential_fleet

    return residential_fleet(n, 2, 2, 2, seed=seed)


#: family -> (mid-size builder, large builder)
FAMILIES: dict[str, tuple[Callable[[], object], Callable[[], object]]] = {
    "assignment": (assignment, lambda: assignment(1000, 3)),
    "budgeted": (budgeted, lambda: budgeted(200, 10)),
    "capability": (capability, capability),
    "comm": (comm, lambda: comm(1000)),
    "delivery": (delivery, delivery),
    "sop": (sop, lambda: sop("ry48p.4")),
    "fleet": (fleet, lambda: fleet(20)),
}


class Load:
    """``count`` busy-loop processes, each ending by itself after ``seconds``; stopped on exit."""

    def __init__(self, count: int, seconds: float) -> None:
        self.processes = [
            subprocess.Popen([sys.executable, "-c", BUSY_LOOP, str(seconds)]) for _ in range(count)
        ]

    def __enter__(self) -> Load:
        return self

    def __exit__(self, *exc: object) -> None:
        for process in self.processes:  # only the processes this script started
            process.kill()
        for process in self.processes:
            process.wait()


def name_of(problem: object) -> str:
    return str(getattr(problem, "name", "") or type(problem).__name__)[:18]


def run(problem: object, family: str, method: str, limit: float) -> tuple[float, bool]:
    """One timed run, printed; (elapsed / limit, within the allowance)."""
    began = time.perf_counter()
    try:
        result = taopt.solve(problem, method, time_limit=limit, seed=0)
        elapsed = time.perf_counter() - began
        status, objective = result.status.value, f"{result.objective:.6g}"
        startup = result.info.get("startup")
    except Exception as exc:  # the benchmark reports, it does not stop
        elapsed = time.perf_counter() - began
        status, objective, startup = type(exc).__name__, str(exc).splitlines()[0][:40], None
    overrun = elapsed - limit
    ok = overrun <= overrun_allowance(limit)
    extra = "" if not startup else f"  start-up {startup:.2f} s"
    print(
        f"{family:<11}{method:<16}{name_of(problem):<19}{limit:>5g}{elapsed:>8.2f}"
        f"{elapsed / limit:>7.2f}{overrun:>+8.2f} {'ok' if ok else 'OVER':<5}{status:<12}"
        f"{objective:>12} {os.getloadavg()[0]:>5.1f}{extra}",
        flush=True,
    )
    return elapsed / limit, ok


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--limits", default="1", help="comma-separated T in seconds (default 1)")
    parser.add_argument("--load", type=int, default=4, help="busy-loop processes (default 4)")
    parser.add_argument(
        "--load-seconds", type=float, default=900.0, help="each busy loop ends after this"
    )
    parser.add_argument("--families", default=",".join(FAMILIES), help="comma-separated")
    parser.add_argument("--methods", default="", help="comma-separated (default: every one)")
    parser.add_argument("--repeat", type=int, default=1, help="runs per method and limit")
    parser.add_argument("--large", action="store_true", help="the larger instances")
    parser.add_argument(
        "--settle", type=float, default=20.0, help="seconds of load before the first run"
    )
    args = parser.parse_args()
    limits = [float(t) for t in args.limits.split(",") if t]
    only = {m.lower() for m in args.methods.split(",") if m}
    taopt.solve(assignment(3, 1), "exact", time_limit=5)  # taopt's imports, before any clock
    problems = {}
    for family in args.families.split(","):
        problems[family] = FAMILIES[family][1 if args.large else 0]()
    print(f"load: {args.load} busy loops (<= {args.load_seconds:g} s each) + the machine's own")
    ratios, over = [], []
    with Load(args.load, args.load_seconds):
        time.sleep(args.settle if args.load else 0.0)
        print(
            f"{'family':<11}{'method':<16}{'instance':<19}{'T':>5}{'elapsed':>8}{'/T':>7}"
            f"{'overrun':>8} {'':<5}{'status':<12}{'objective':>12} {'load':>5}"
        )
        for family, problem in problems.items():
            for method in taopt.available_methods(problem):
                if only and method.lower() not in only:
                    continue
                for limit in limits:
                    for _ in range(args.repeat):
                        ratio, ok = run(problem, family, method, limit)
                        ratios.append(ratio)
                        if not ok:
                            over.append(f"{family}/{method}@{limit:g}")
    print(
        f"{len(ratios)} runs; largest elapsed / T {max(ratios):.2f}; over the allowance: "
        + (", ".join(over) if over else "none")
    )


if __name__ == "__main__":
    main()
