"""Time of the limit-aware heuristics (MC, EVM, GA) at each tightness level vs no limit.

Run from the repository root::

    python benchmarks/bench_budgeted_heuristics.py                       # n50m10, n120m10
    python benchmarks/bench_budgeted_heuristics.py --sizes n50m10 --scenarios 5
    python benchmarks/bench_budgeted_heuristics.py --json before.json    # keep every run

Issue 17's target: every heuristic within 2x of its unlimited time. Instances are the
chapter-6 study's (:func:`taopt.orchestration.studies.budgeted.make_scenario`: the thesis-field drift
scenarios of §2.5, study seed 1, scenario k seeded ``scenario_seed(1, k)``, every level on
the same matrix; ``T*`` from the unlimited certified optimum, cached in
``benchmarks/.cache/budgeted``), and each method runs with the study's seed
(:func:`taopt.orchestration.studies.budgeted.method_seed`) and its default options. Scenario-major: the
levels of one scenario run one after the other, so a change of machine load hits every
level alike. Printed per (size, level, method): the median wall time over the scenarios,
the median of the per-scenario ratio to the same scenario's ``none`` time, and the median
objective (every answer re-scored by the one scorer; ``inf`` when the method gave none).
The machine may be shared: quote ratios, measured in the same run.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time
from pathlib import Path

from taopt.budgeted import evaluate_budgeted
from taopt.heuristics import budgeted
from taopt.orchestration.studies.budgeted import make_scenario, method_seed

CACHE = Path(__file__).resolve().parent / ".cache" / "budgeted"
LEVELS = "none,Q2,Q1.5,Q1.2,Q1,T1,T0.8,T0.6"
METHODS = {"MC": budgeted.mc, "EVM": budgeted.evm, "GA": budgeted.genetic_algorithm}


def run_one(size: str, level: str, scenario: int, method: str) -> dict:
    """One run: wall time, objective (re-scored), status."""
    key = {"size": size, "level": level, "scenario": scenario}
    settings = {"seed": 1, "field": "thesis", "context": {"cache_dir": str(CACHE)}}
    problem = make_scenario(key, settings).problem
    seed = method_seed(key, settings)
    began = time.perf_counter()
    solution = METHODS[method](problem, seed=seed)
    seconds = time.perf_counter() - began
    objective = math.inf
    if solution.routes is not None:
        objective = evaluate_budgeted(problem, solution.routes)
        assert abs(objective - solution.objective) <= 1e-9 * max(1.0, objective)
    return {**key, "method": method, "seconds": seconds, "objective": objective}


def table(rows: list[dict], size: str, levels: list[str], methods: list[str]) -> str:
    """Markdown table: median time (s), median ratio to none, median objective."""
    lines = [
        "| method | " + " | ".join(levels) + " |",
        "|:--" + "|--:" * len(levels) + "|",
    ]
    for method in methods:
        mine = [r for r in rows if r["size"] == size and r["method"] == method]
        none = {r["scenario"]: r["seconds"] for r in mine if r["level"] == "none"}
        cells_time, cells_ratio, cells_f = [], [], []
        for level in levels:
            runs = [r for r in mine if r["level"] == level]
            cells_time.append(f"{statistics.median(r['seconds'] for r in runs):.3f}")
            ratios = [r["seconds"] / none[r["scenario"]] for r in runs if r["scenario"] in none]
            cells_ratio.append(f"{statistics.median(ratios):.2f}" if ratios else "")
            cells_f.append(f"{statistics.median(r['objective'] for r in runs):.1f}")
        lines.append(f"| {method} time s | " + " | ".join(cells_time) + " |")
        lines.append(f"| {method} / none | " + " | ".join(cells_ratio) + " |")
        lines.append(f"| {method} median f | " + " | ".join(cells_f) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="n50m10,n120m10")
    parser.add_argument("--levels", default=LEVELS)
    parser.add_argument("--methods", default=",".join(METHODS))
    parser.add_argument("--scenarios", type=int, default=3)
    parser.add_argument("--json", help="write every run to this file")
    args = parser.parse_args()
    sizes, levels = args.sizes.split(","), args.levels.split(",")
    methods = args.methods.split(",")
    rows = []
    for size in sizes:
        for k in range(args.scenarios):
            for level in levels:
                for method in methods:
                    row = run_one(size, level, k, method)
                    rows.append(row)
                    print(
                        f"{size} s{k} {level:5s} {method:4s} {row['seconds']:8.3f} s "
                        f"f = {row['objective']:10.2f}",
                        flush=True,
                    )
        print(f"\n{size}, {args.scenarios} scenarios:\n" + table(rows, size, levels, methods))
        print(flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
