"""A part's label search in doubling time slices, restarted at each slice or resumed from its
memo (:func:`taopt.fleet.search.label_search`, ``memo``; issue 32).

Solves fleet8's K2D3c1 (``residential_fleet(8, 2, 3, 1, seed=0)``) once with the split search,
recording each part's label-search call; for the ``--parts`` longest, solves that part again
(no incumbent, cut off at ``--cutoff``, the best value the 10-s run holds) three ways: in one
run; in slices of ``--slice`` s doubled at each retry, each restarting from scratch (the split
search before the memo); and in the same slices resumed from the memo. Prints seconds,
slices and the value of each. Run:
``python benchmarks/bench_fleet_resume.py [--parts 3] [--slice 0.5] [--cutoff 168.0477]``.
"""

from __future__ import annotations

import argparse
import os
import time
from typing import Any

import taopt
import taopt.fleet.search as search
from taopt.fleet.instances import residential_fleet


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--parts", type=int, default=3)
    parser.add_argument("--slice", type=float, default=0.5)
    parser.add_argument("--cutoff", type=float, default=168.04767624770662)
    parser.add_argument("--limit", type=float, default=60.0)
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    calls: list[tuple[float, Any, dict[str, Any]]] = []
    original = search.label_search

    def recorded(sub: Any, **options: Any) -> dict[str, Any]:
        started = time.perf_counter()
        found = original(sub, **options)
        calls.append((time.perf_counter() - started, sub, options))
        return found

    search.label_search = recorded  # the split search imports it at call time
    try:
        solution = taopt.solve(
            residential_fleet(8, 2, 3, 1, seed=0), "exact", time_limit=args.limit
        )
    finally:
        search.label_search = original
    print(f"split search: {solution.status} {solution.objective:.2f} [{solution.bound:.2f}]")
    calls.sort(key=lambda call: -call[0])
    for _, sub, options in calls[: args.parts]:
        options = {k: v for k, v in options.items() if k not in ("memo", "time_limit", "incumbent")}
        options["cutoff"] = args.cutoff
        load = os.getloadavg()[0]
        started = time.perf_counter()
        whole = original(sub, **options)
        row = [f"n={sub.n}", f"whole {time.perf_counter() - started:.2f} s {whole['value']:.3f}"]
        for mode in ("restart", "resume"):
            memo: dict[str, Any] | None = {} if mode == "resume" else None
            started = time.perf_counter()
            slices = 0
            while True:
                found = original(sub, time_limit=args.slice * 2**slices, memo=memo, **options)
                slices += 1
                if found["stopped_by"] != "time_limit":
                    break
            seconds = time.perf_counter() - started
            row.append(f"{mode} {seconds:.2f} s in {slices} slices {found['value']:.3f}")
        print(", ".join(row), f"(load {load:.1f} -> {os.getloadavg()[0]:.1f})")


if __name__ == "__main__":
    main()
