"""The fleet heuristics: timing at the issue's size, and their gaps on the TSP-D instances.

Default: n = 120, K = 3, D = 2, c = 2 (:func:`taopt.fleet.instances.residential_fleet`,
chapter 5's residential network, a layered DAG, objective ``"last_service"``). Targets (issue
32): NIA, MMA, SMMA <= 1 s each; ILS <= 30 s (``time_limit``). Also prints 3P under the same
limit and the lower bound's time.

``--tspd``: every shipped TSP-D instance (``taopt/data/tspd``, or ``--folder``), objective
``"return"``: each heuristic's objective over the published optimum (Bouman, Agatz & Schmidt
2018), mean and max per instance size and overall, each method with its default options
(3P 20 descent passes, ILS 30 iterations; no time limit, so the figures do not depend on the
load). A ratio below 1 is a bug (every plan is re-scored by :func:`taopt.evaluate`): it is
flagged and the exit status is 1.

State the machine's load (printed) with the figures. Run:
``PYTHONPATH=$PWD python benchmarks/bench_fleet_heuristics.py [--seeds 3]`` or
``... --tspd [--folder DIR]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import taopt
from taopt.fleet.bounds import fleet_lower
from taopt.fleet.instances import residential_fleet

HEURISTICS = ("NIA", "MMA", "SMMA", "3P", "ILS")


def timing(args: argparse.Namespace) -> None:
    """The n = 120, K = 3, D = 2, c = 2 timing table."""
    times: dict[str, list[float]] = {}
    for seed in range(args.seeds):
        p = residential_fleet(args.n, trucks=3, drones=2, capacity=2, seed=seed)
        lb = fleet_lower(p, "fast")
        row = [f"seed {seed}: lower {lb:.1f}"]
        for method in HEURISTICS:
            options = {"time_limit": args.limit} if method in ("3P", "ILS") else {}
            s = taopt.solve(p, method, **options)
            times.setdefault(method, []).append(s.runtime)
            row.append(f"{method} {s.objective:.1f} ({s.runtime:.2f} s)")
        print(", ".join(row))
    for method, values in times.items():
        print(f"{method}: median {statistics.median(values):.3f} s, max {max(values):.3f} s")


def tspd(args: argparse.Namespace) -> int:
    """The TSP-D table: objective / published optimum per heuristic and size."""
    import re

    from taopt.fleet.problem import FleetProblem
    from taopt.fleet.tspd import TSPD_FOLDER, published_optimum

    folder = Path(args.folder) if args.folder else TSPD_FOLDER

    def key(path: Path) -> tuple[int, int]:
        m = re.fullmatch(r"uniform-(\d+)-n(\d+)", path.stem)
        return (int(m.group(2)), int(m.group(1))) if m else (0, 0)

    paths = sorted(folder.glob("uniform-*.txt"), key=key)
    ratios: dict[tuple[str, int], list[float]] = {}
    seconds: dict[str, list[float]] = {}
    below = 0
    for path in paths:
        problem = FleetProblem.from_tspd(path)
        optimum = published_optimum(path)
        size = key(path)[0]
        row = [path.stem]
        for method in HEURISTICS:
            start = time.perf_counter()
            found = taopt.solve(problem, method, seed=args.seed)
            seconds.setdefault(method, []).append(time.perf_counter() - start)
            ratio = found.objective / optimum
            if ratio < 1.0 - 1e-6:
                below += 1
                row.append(f"{method} {ratio:.3f} BELOW THE OPTIMUM")
            else:
                row.append(f"{method} {ratio:.3f}")
            for group in (size, 0):
                ratios.setdefault((method, group), []).append(ratio)
        print(" ".join(row), flush=True)
    sizes = sorted({size for _, size in ratios if size})
    print("objective / published optimum, mean (max), per number of nodes:")
    print("method | " + " | ".join(f"{s}" for s in sizes) + " | all | max s")
    for method in HEURISTICS:
        cells = [
            f"{statistics.mean(ratios[(method, s)]):.3f} ({max(ratios[(method, s)]):.3f})"
            for s in [*sizes, 0]
        ]
        print(f"{method} | " + " | ".join(cells) + f" | {max(seconds[method]):.2f}")
    if below:
        print(f"{below} plans below a published optimum", file=sys.stderr)
    return 1 if below else 0


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--n", type=int, default=120)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--limit", type=float, default=30.0, help="ILS / 3P time_limit (s)")
    parser.add_argument("--tspd", action="store_true", help="the TSP-D gap table instead")
    parser.add_argument("--folder", default=None, help="TSP-D instances (default: shipped)")
    parser.add_argument("--seed", type=int, default=0, help="the heuristics' seed (--tspd)")
    args = parser.parse_args()
    print(f"load average {os.getloadavg()}, {os.cpu_count()} cores")
    if args.tspd:
        sys.exit(tspd(args))
    timing(args)


if __name__ == "__main__":
    main()
