"""Timing of the budgeted family's exact model against chapter 2's exact loop, same run.

Run from the repository root::

    python benchmarks/bench_budgeted.py                                   # n50m10, mid
    python benchmarks/bench_budgeted.py --sizes 20x4,30x5,50x10 --tightness loose,mid,tight
    python benchmarks/bench_budgeted.py --form arc-vehicle --time-limit 20
    python benchmarks/bench_budgeted.py --options '{"capacity_cuts": false}'   # one idea off
    python benchmarks/bench_budgeted.py --options '{"improve": null}'   # no improver

Instances: the thesis-field drift scenarios of §2.5 (:func:`taopt.routing.scenarios.drift_scenario`,
study seed 2024, scenarios 0..``--scenarios``-1), the travel times of the drift study. For
each scenario the unlimited optimum ``f0`` is solved first by chapter 2's exact DFJ loop
(:func:`taopt.models.routing.solve_routing`, the reference time), then limits are set for
each tightness level, the same for every vehicle:

=========  ========================  ======================
level      capacity Q_k              max_time T_k
=========  ========================  ======================
loose      ceil(2.5 n / m)           4 f0 / m
mid        ceil(1.5 n / m)           2 f0 / m
tight      ceil(1.2 n / m)           1.5 f0 / m
cap        ceil(1.5 n / m)           none
time       none                      2 f0 / m
=========  ========================  ======================

and :func:`taopt.models.budgeted.solve_budgeted` is timed (wall clock, its own time limit
``--time-limit``), with the family's registered improver as :func:`taopt.solve` passes it. Printed per run: status, objective, bound, the ratio to the reference
time; per level the median. Every answer is re-scored by the one scorer. The machine may
be shared: quote ratios, measured in the same run.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time
from pathlib import Path

import taopt.heuristics  # noqa: F401  (registers the family's improver, as taopt.solve sees it)
from taopt.budgeted import BudgetedProblem, evaluate_budgeted
from taopt.budgeted.bounds import lower
from taopt.models.budgeted import FORMS, solve_budgeted
from taopt.models.routing import solve_routing
from taopt.registry import improver
from taopt.routing.scenarios import drift_scenario, scenario_seed

CACHE = Path(__file__).resolve().parent / ".cache" / "routing"

LEVELS = {
    "loose": (2.5, 4.0),
    "mid": (1.5, 2.0),
    "tight": (1.2, 1.5),
    "cap": (1.5, None),
    "time": (None, 2.0),
}


def limits(n: int, m: int, f0: float, level: str) -> tuple[list | None, list | None]:
    """Capacity and max_time lists of ``level`` (see the module docstring)."""
    share, budget = LEVELS[level]
    capacity = None if share is None else [math.ceil(share * n / m)] * m
    max_time = None if budget is None else [budget * f0 / m] * m
    return capacity, max_time


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="50x10", help="n x m, comma separated")
    parser.add_argument("--scenarios", type=int, default=5)
    parser.add_argument("--tightness", default="mid", help=f"comma separated of {list(LEVELS)}")
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--form", default="resource", choices=FORMS)
    parser.add_argument("--options", default="{}", help="JSON of further solve_budgeted keywords")
    args = parser.parse_args()
    options = json.loads(args.options)
    for size in args.sizes.split(","):
        n, m = (int(v) for v in size.split("x"))
        rows: dict[str, list[tuple[float, float, str]]] = {}
        for k in range(args.scenarios):
            problem = drift_scenario(n, m, scenario_seed(2024, k), cache_dir=CACHE).problem
            began = time.perf_counter()
            free = solve_routing(problem)
            reference = time.perf_counter() - began
            for level in args.tightness.split(","):
                capacity, max_time = limits(n, m, free.objective, level)
                budgeted = BudgetedProblem.from_routing(problem, capacity, max_time)
                began = time.perf_counter()
                result = solve_budgeted(
                    budgeted,
                    time_limit=args.time_limit,
                    form=args.form,
                    **{"improve": improver(budgeted), **options},  # as taopt.solve passes it
                )
                seconds = time.perf_counter() - began
                if result.routes is not None:
                    assert abs(evaluate_budgeted(budgeted, result.routes) - result.objective) <= (
                        1e-6 * result.objective
                    )
                assert result.bound is None or result.bound <= result.objective + 1e-6
                rows.setdefault(level, []).append((seconds, reference, result.status.value))
                print(
                    f"n{n}m{m} scenario {k} {level:5s}: {result.status.value:10s} "
                    f"{seconds:7.2f} s (reference {reference:5.2f} s, x{seconds / reference:6.1f}) "
                    f"f = {result.objective:9.1f}  bound = {result.bound or math.nan:9.1f}  "
                    f"f0 = {free.objective:9.1f}  lower(auto) = {lower(budgeted):9.1f}",
                    flush=True,
                )
        for level, values in rows.items():
            seconds = statistics.median(v[0] for v in values)
            ratio = statistics.median(v[0] / v[1] for v in values)
            solved = sum(v[2] == "optimal" for v in values)
            print(
                f"n{n}m{m} {level}: median {seconds:.2f} s, median ratio x{ratio:.1f} to chapter 2, "
                f"{solved}/{len(values)} optimal within {args.time_limit:g} s ({args.form})"
            )


if __name__ == "__main__":
    main()
