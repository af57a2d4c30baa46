"""Timing of the fleet heuristics at the issue's size: n = 120, K = 3, D = 2, c = 2.

Instances: :func:`taopt.fleet.instances.residential_fleet` (chapter 5's residential network,
a layered DAG). Targets (issue 32): NIA, MMA, SMMA <= 1 s each; ILS <= 30 s (``time_limit``).
Also prints 3P under the same limit and the lower bound's time. State the machine's load
(printed) with the figures.

Run: ``PYTHONPATH=$PWD python benchmarks/bench_fleet_heuristics.py [--seeds 3]``.
"""

from __future__ import annotations

import argparse
import os
import statistics

import taopt
from taopt.fleet.bounds import fleet_lower
from taopt.fleet.instances import residential_fleet


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=120)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--limit", type=float, default=30.0, help="ILS / 3P time_limit (s)")
    args = parser.parse_args()
    print(f"load average {os.getloadavg()}, {os.cpu_count()} cores")
    times: dict[str, list[float]] = {}
    for seed in range(args.seeds):
        p = residential_fleet(args.n, trucks=3, drones=2, capacity=2, seed=seed)
        lb = fleet_lower(p, "fast")
        row = [f"seed {seed}: lower {lb:.1f}"]
        for method in ("NIA", "MMA", "SMMA", "3P", "ILS"):
            options = {"time_limit": args.limit} if method in ("3P", "ILS") else {}
            s = taopt.solve(p, method, **options)
            times.setdefault(method, []).append(s.runtime)
            row.append(f"{method} {s.objective:.1f} ({s.runtime:.2f} s)")
        print(", ".join(row))
    for method, values in times.items():
        print(f"{method}: median {statistics.median(values):.3f} s, max {max(values):.3f} s")


if __name__ == "__main__":
    main()
