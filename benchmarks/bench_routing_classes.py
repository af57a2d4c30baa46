"""Chapter 3's exact classes one by one: the DFJ loop with and without its lifted root rows.

Run from the repository root::

    python benchmarks/bench_routing_classes.py                    # n90m10, |A| = 1 3 5 7 10
    python benchmarks/bench_routing_classes.py --sizes 1,10 --min-targets 40

Each class of the capability split (§3.6) of the study's n90m10 scenarios is a chapter 2
model; this solves every class with ``solve_routing`` (DTAA's routes restricted to the
class as incumbent) twice in the same run, alternating: with the root's lifted rows
(:data:`taopt.models.routing.dfj.LIFTED_ROUNDS` as shipped) and without them
(``LIFTED_ROUNDS = 0``, the DFJ root as before the rows were added). It prints wall and
CPU time (the CPU time is the steadier figure on a shared machine), MIP rounds, root gap
to the optimum and the lifted rows kept, checks that both runs certify the same optimum,
and sums the CPU times.
"""

from __future__ import annotations

import argparse
import time

import taopt
import taopt.models.routing.dfj as dfj
from taopt.capability.instances import STUDY_CELL
from taopt.models.capability import class_incumbents
from taopt.models.routing import solve_routing
from taopt.orchestration.studies.capability import make_scenario

SETTINGS = {"seed": 1, "cell": STUDY_CELL, "neighbours": 16}


def timed(problem, incumbent, lifted_rounds: int):
    """``solve_routing`` with ``LIFTED_ROUNDS`` set; the solution, wall and CPU seconds."""
    shipped = dfj.LIFTED_ROUNDS
    dfj.LIFTED_ROUNDS = lifted_rounds
    try:
        wall, cpu = time.perf_counter(), time.process_time()
        solution = solve_routing(problem, incumbent=incumbent)
        return solution, time.perf_counter() - wall, time.process_time() - cpu
    finally:
        dfj.LIFTED_ROUNDS = shipped


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="1,3,5,7,10", help="comma list of |A|")
    parser.add_argument("--scenarios", type=int, default=1, help="scenarios per |A|")
    parser.add_argument("--min-targets", type=int, default=40, help="skip smaller classes")
    args = parser.parse_args()
    totals = {"with": 0.0, "without": 0.0}
    for k in (int(v) for v in args.sizes.split(",")):
        for index in range(args.scenarios):
            capability = make_scenario({"n": 90, "m": 10, "A": k, "scenario": index}, SETTINGS)
            problem = capability.problem
            given = class_incumbents(problem, taopt.solve(problem, "DTAA"))
            for cls in problem.classes:
                if cls.problem is None or cls.problem.n < args.min_targets:
                    continue
                line = f"|A|={k:2d} s{index} class {cls.capability!s:>4} n={cls.problem.n:3d} "
                line += f"m={cls.problem.m:2d}"
                objectives = set()
                for label, rounds in (("with", dfj.LIFTED_ROUNDS), ("without", 0)):
                    solution, wall, cpu = timed(cls.problem, given[cls.capability], rounds)
                    assert solution.status == "optimal", solution.summary()
                    objectives.add(round(solution.objective, 6))
                    totals[label] += cpu
                    gap = 100 * (solution.objective - solution.info["lp_bound"])
                    gap /= solution.objective
                    line += (
                        f" | {label} {wall:6.2f} s cpu {cpu:6.2f} rounds "
                        f"{solution.info['rounds']:2d} root gap {gap:.2f} % lifted "
                        f"{solution.info['lifted_cuts']:2d}"
                    )
                assert len(objectives) == 1, objectives
                print(line, flush=True)
    ratio = totals["without"] / max(totals["with"], 1e-9)
    print(
        f"CPU seconds, every class: with lifted rows {totals['with']:.2f}, without "
        f"{totals['without']:.2f} (ratio {ratio:.2f})",
        flush=True,
    )


if __name__ == "__main__":
    main()
