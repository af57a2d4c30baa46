"""Timing of the exact chapter 2 model (2.2)–(2.5), DFJ, against a naive reference loop.

Run from the repository root::

    python benchmarks/bench_routing_exact.py                      # everything
    python benchmarks/bench_routing_exact.py --parts harness --sizes 120x20
    python benchmarks/bench_routing_exact.py --parts tsplib --tsplib ftv70,p43 --no-reference
    python benchmarks/bench_routing_exact.py --parts drift --sec mtz

Per instance it prints our wall time (``taopt.models.solve_routing(sec="dfj")`` given
the MC heuristic's routes as incumbent, MC's own time included) and its CPU time (a
steadier figure on a shared machine), the wall time of a naive reference (below),
their ratio, and checks that both certify the same optimum.

Instances:

* ``harness`` — m vehicles at uniform random starts and n targets in a 1000 m square,
  uniform current (0.3, 0.1) m/s, v = 1, seeds 0–4; travel times in closed form
  (:func:`taopt.navigation.uniform_travel_times`). Sizes n50m10, n120m20, n120m10, n120m5.
* ``drift`` — the thesis-field scenarios of §2.5 (:func:`taopt.routing.scenarios.drift_scenario`,
  seed 2024, scenarios 0–4); matrices cached in ``benchmarks/.cache/routing`` (copy an
  existing cache there to avoid recomputing them).
* ``tsplib`` — ATSP instances through the one-vehicle reduction
  (:func:`taopt.routing.tsplib.atsp_to_assignment`): the shipped files, and ftv47…ftv70
  from ``--tsplib-dir`` when that folder holds them.

The naive reference (:func:`reference_dfj`) is the textbook loop, written here from
scratch on cvxpy + HiGHS: build the whole model, solve, add a (2.5) row for every
cycle among targets, rebuild and solve again, until no cycle is left; no root cuts,
no MIP start, no reduced-cost core. Only the solve is timed, never the matrices.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import cvxpy as cp
import numpy as np

import taopt
import taopt.heuristics
from taopt import AssignmentProblem
from taopt.models import solve_routing
from taopt.navigation import uniform_travel_times
from taopt.registry import improver
from taopt.routing.scenarios import drift_scenario, scenario_seed
from taopt.routing.tsplib import KNOWN_OPTIMA, atsp_to_assignment, load_atsp

CACHE = Path(__file__).resolve().parent / ".cache" / "routing"
SHARED_TSPLIB = Path("/work/shared/benchmarks/tsplib")
#: Optima of the larger TSPLIB95 ATSP files (DOC.PS, Table 2), not shipped in taopt/data.
MORE_OPTIMA = {
    "ftv47": 1776,
    "ftv55": 1608,
    "ftv64": 1839,
    "ftv70": 1950,
    "rbg403": 2465,
    "rbg443": 2720,
}
TSPLIB = "ftv33,ftv35,ftv38,p43,ftv44,ftv47,ry48p,ft53,ftv55,ftv64,ftv70"
#: Bars of the brief (seconds, on 2 idle cores): median of our time.
BARS = {
    "n120m20": 1.0,
    "n120m5": 10.0,
    "ftv70": 3.0,
    "ry48p": 5.0,
    "p43": 10.0,
    "rbg403": 10.0,  # issue 33
    "rbg443": 10.0,
}
RELATIVE = 1e-6


# --------------------------------------------------------------------------- instances
def harness(n: int, m: int, seed: int) -> AssignmentProblem:
    """n targets and m vehicle starts uniform in a 1000 m square, current (0.3, 0.1) m/s, v = 1."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(0.0, 1000.0, size=(n + m, 2))
    cost = uniform_travel_times([0.3, 0.1], points[:, None, :], points[None, :, :], speed=1.0)
    return AssignmentProblem(cost, n, name=f"harness n{n}m{m} seed {seed}")


def tsplib_problem(name: str, folder: Path) -> tuple[AssignmentProblem, float] | None:
    """The reduction of a TSPLIB ATSP and its optimum (None if the file is not at hand)."""
    if name in KNOWN_OPTIMA:
        atsp = load_atsp(name)
        return atsp_to_assignment(atsp), float(atsp.optimum)
    path = folder / f"{name}.atsp"
    if not path.exists() or name not in MORE_OPTIMA:
        return None
    return atsp_to_assignment(load_atsp(path)), float(MORE_OPTIMA[name])


# --------------------------------------------------------------------- naive reference
def reference_dfj(problem: AssignmentProblem, time_limit: float | None = None) -> dict:
    """The textbook DFJ loop: rebuild the cvxpy model every round, no root cuts, no start.

    Returns ``{"objective", "rounds", "time", "certified"}``; ``certified`` is False if the
    time limit struck first.
    """
    began = time.perf_counter()
    n, m, cost = problem.n, problem.m, problem.cost
    size = n + m
    allowed = np.ones((size, n))
    allowed[np.arange(n), np.arange(n)] = 0.0
    subsets: list[list[int]] = []
    rounds = 0
    while True:
        rounds += 1
        left = None if time_limit is None else time_limit - (time.perf_counter() - began)
        if left is not None and left <= 0:
            return {"objective": np.nan, "rounds": rounds, "time": left, "certified": False}
        x = cp.Variable((size, n), boolean=True)
        constraints = [
            cp.sum(x, axis=0) == 1,  # (2.3)
            cp.sum(x, axis=1) <= 1,  # (2.4)
            cp.multiply(1.0 - allowed, x) == 0,  # no self loops
        ]
        constraints += [cp.sum(x[s][:, s]) <= len(s) - 1 for s in subsets]  # (2.5)
        model = cp.Problem(cp.Minimize(cp.sum(cp.multiply(cost[:, :n], x))), constraints)
        options = {"mip_rel_gap": 1e-7}
        if left is not None:
            options["time_limit"] = max(left, 1e-3)
        model.solve(solver=cp.HIGHS, **options)
        if model.status != "optimal":
            return {"objective": np.nan, "rounds": rounds, "time": 0.0, "certified": False}
        successor = {int(i): int(j) for i, j in zip(*np.nonzero(x.value > 0.5), strict=True)}
        reached = set()
        for vehicle in range(m):
            point = n + vehicle
            while point in successor:
                point = successor[point]
                reached.add(point)
        cycles = []
        for target in range(n):
            cycle = []
            while target not in reached:
                reached.add(target)
                cycle.append(target)
                target = successor[target]
            if cycle:
                cycles.append(cycle)
        if not cycles:
            return {
                "objective": float(model.value),
                "rounds": rounds,
                "time": time.perf_counter() - began,
                "certified": True,
            }
        subsets.extend(cycles)


# ------------------------------------------------------------------------------- ours
def ours(
    problem: AssignmentProblem, sec: str, time_limit: float | None
) -> tuple[taopt.Solution, float, float]:
    """MC's routes as incumbent, then the exact model with the registered improver (as
    :func:`taopt.solve` runs it); wall and CPU seconds include MC."""
    began, cpu = time.perf_counter(), time.process_time()
    incumbent = taopt.heuristics.run("MC", problem).routes
    solution = solve_routing(
        problem, sec=sec, time_limit=time_limit, incumbent=incumbent, improve=improver(problem)
    )
    return solution, time.perf_counter() - began, time.process_time() - cpu


def measure(label, problem, args, optimum=None) -> tuple[float, float | None]:
    """One instance: our time, the reference's, the check; returns both times."""
    solution, ours_time, cpu_time = ours(problem, args.sec, args.time_limit)
    check = taopt.evaluate(problem, solution.routes)
    assert abs(check - solution.objective) <= RELATIVE * abs(check), label
    assert solution.bound <= solution.objective * (1 + 1e-12), label
    if optimum is not None and solution.status == "optimal":
        assert abs(solution.objective - optimum) <= RELATIVE * optimum, (label, optimum)
    line = (
        f"{label:<26} ours {ours_time:7.2f} s (cpu {cpu_time:6.2f}) "
        f"{solution.status:<10} "
        f"objective {solution.objective:<12.6g} rounds {solution.info['rounds']:>2} "
        f"cuts {solution.info['cuts']:>3}"
    )
    reference_time = None
    if args.reference:
        reference = reference_dfj(problem, args.reference_limit)
        if reference["certified"]:
            reference_time = reference["time"]
            if solution.status == "optimal":
                agree = abs(reference["objective"] - solution.objective)
                assert agree <= RELATIVE * abs(reference["objective"]), (label, reference)
            line += (
                f" | reference {reference_time:7.2f} s ({reference['rounds']} rounds), "
                f"ratio {ours_time / reference_time:5.2f}, optimum agrees"
            )
        else:
            line += f" | reference not certified within {args.reference_limit:g} s"
    print(line, flush=True)
    return ours_time, reference_time


def summary(name: str, times: list[float], references: list[float | None]) -> None:
    line = f"== {name}: ours median {statistics.median(times):.2f} s (max {max(times):.2f} s)"
    paired = [(t, r) for t, r in zip(times, references, strict=True) if r is not None]
    if paired:
        ratio = statistics.median(t / r for t, r in paired)
        reference_median = statistics.median(r for _, r in paired)
        line += f", reference median {reference_median:.2f} s, median ratio {ratio:.2f}"
    bar = BARS.get(name.split()[0])
    if bar is not None:
        verdict = "ok" if statistics.median(times) <= bar else "MISSED"
        line += f"  [bar <= {bar:g} s: {verdict}]"
    print(line, flush=True)


# --------------------------------------------------------------------------------- main
def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--parts", default="harness,drift,tsplib", help="comma list")
    parser.add_argument("--sec", default="dfj", choices=("dfj", "mtz", "flow"))
    parser.add_argument("--sizes", default="50x10,120x20,120x10,120x5", help="harness NxM")
    parser.add_argument("--seeds", default="0,1,2,3,4", help="harness seeds")
    parser.add_argument("--drift-sizes", default="50x10,120x20,120x10", help="thesis-field NxM")
    parser.add_argument("--scenarios", type=int, default=5)
    parser.add_argument("--tsplib", default=TSPLIB)
    parser.add_argument("--tsplib-dir", type=Path, default=SHARED_TSPLIB)
    parser.add_argument("--time-limit", type=float, default=None, help="ours, seconds")
    parser.add_argument("--no-reference", dest="reference", action="store_false")
    parser.add_argument("--reference-limit", type=float, default=300.0)
    parser.add_argument("--jobs", type=int, default=1, help="processes for new drift matrices")
    args = parser.parse_args()
    parts = args.parts.split(",")
    seeds = [int(s) for s in args.seeds.split(",")]

    def sizes(text: str) -> list[tuple[int, int]]:
        return [tuple(int(v) for v in size.lower().split("x")) for size in text.split(",")]

    if "harness" in parts:
        for n, m in sizes(args.sizes):
            pairs = [measure(f"n{n}m{m} seed {s}", harness(n, m, s), args) for s in seeds]
            summary(f"n{n}m{m} harness", *map(list, zip(*pairs, strict=True)))
    if "drift" in parts:
        for n, m in sizes(args.drift_sizes):
            pairs = []
            for k in range(args.scenarios):
                seed = scenario_seed(2024, k)
                problem = drift_scenario(n, m, seed, cache_dir=CACHE, jobs=args.jobs).problem
                pairs.append(measure(f"n{n}m{m} thesis field {k}", problem, args))
            summary(f"n{n}m{m} thesis field", *map(list, zip(*pairs, strict=True)))
    if "tsplib" in parts:
        for name in args.tsplib.split(","):
            loaded = tsplib_problem(name, args.tsplib_dir)
            if loaded is None:
                print(f"{name:<26} skipped (no file in {args.tsplib_dir})")
                continue
            problem, optimum = loaded
            ours_time, reference_time = measure(f"{name} (opt {optimum:g})", problem, args, optimum)
            summary(name, [ours_time], [reference_time])


if __name__ == "__main__":
    main()
