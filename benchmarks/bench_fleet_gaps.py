"""True gaps of the fleet heuristics where the sortie DP certifies the optimum (one truck
carrying one multi-parcel drone), on the scenarios of ``taopt study fleet``.

For n in ``--sizes``, fleets K1D1c2 and K1D1c3, densities sparse and dense, ``--scenarios``
scenarios each: the exact optimum (its seconds) and 100 (f / f_o - 1) for NIA, MMA, SMMA, 3P
(3 descent passes) and ILS (10 iterations), then mean / max per (n, fleet, method). Run:
``python benchmarks/bench_fleet_gaps.py [--sizes 8,10] [--scenarios 3]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import taopt
from taopt.defaults import SEED
from taopt.orchestration.studies.fleet import SEARCH_OPTIONS, make_scenario

HEURISTICS = ("NIA", "MMA", "SMMA", "3P", "ILS")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", default="8,10")
    parser.add_argument("--scenarios", type=int, default=3)
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    gaps: dict[tuple[int, str, str], list[float]] = {}
    for n in (int(x) for x in args.sizes.split(",")):
        for fleet in ("K1D1c2", "K1D1c3"):
            for density in ("sparse", "dense"):
                for scenario in range(args.scenarios):
                    key = {"n": n, "fleet": fleet, "density": density, "scenario": scenario}
                    problem = make_scenario(key, {"seed": SEED}).problem
                    start = time.perf_counter()
                    exact = taopt.solve(problem, "exact", time_limit=600)
                    seconds = time.perf_counter() - start
                    if exact.status != "optimal":
                        print(f"{key}: not certified ({exact.status})")
                        continue
                    row = [f"{n} {fleet} {density} {scenario} {exact.objective:.1f} {seconds:.2f}"]
                    for method in HEURISTICS:
                        found = taopt.solve(
                            problem, method, seed=SEED, **SEARCH_OPTIONS.get(method, {})
                        )
                        gap = 100 * (found.objective / exact.objective - 1)
                        gaps.setdefault((n, fleet, method), []).append(gap)
                        row.append(f"{gap:.1f}")
                    print(" ".join(row), flush=True)
    for (n, fleet, method), values in gaps.items():
        print(f"n = {n} {fleet} {method}: mean {statistics.mean(values):.1f} max {max(values):.1f}")


if __name__ == "__main__":
    main()
