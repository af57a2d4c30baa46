"""Timing of the chapter 5 core: the exact DP scheduler, t*, the bound, the subset DP.

Setup of §5.5: 11×11 stops over a 1000 m square (121 stops), unit truck speed,
v_d / v_t = 1.4, 120 customers with dial-a-ride pairs, random precedence-feasible
orders. Run: ``python benchmarks/bench_delivery_core.py [--repeats 20]``.
Target: schedule() median <= 100 ms for n = 120, s = 121.
"""

from __future__ import annotations

import argparse
import statistics
import time

import networkx as nx
import numpy as np

from taopt.delivery.bounds import arborescence_bound
from taopt.delivery.costs import drone_cost_matrix
from taopt.delivery.dags import paired_precedences
from taopt.delivery.instance import DeliveryInstance
from taopt.delivery.schedule import optimal_plan, schedule


def timed(func, repeats: int) -> list[float]:
    out = []
    for _ in range(repeats):
        start = time.perf_counter()
        func()
        out.append(time.perf_counter() - start)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=20)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    customers = rng.uniform(0, 1000, (120, 2))
    pairs = paired_precedences(120, seed=1)
    print(f"{'L/L0':>5} {'schedule median ms':>19} {'max ms':>7} {'t* ms':>6} {'bound ms':>9}")
    for ratio in (0.15, 0.30, 0.45, 0.60, 0.75, 0.90):
        inst = DeliveryInstance.grid(customers, 11, 1000.0, 1.4, 1.0, ratio * 1000.0, pairs)
        order = list(
            nx.lexicographical_topological_sort(inst.precedence_graph, key=lambda j: rng.random())
        )
        schedule(inst, order)  # warm-up
        runs = timed(lambda inst=inst, order=order: schedule(inst, order), args.repeats)
        cost = timed(lambda inst=inst: drone_cost_matrix(inst), 3)
        bound = timed(lambda inst=inst: arborescence_bound(inst), 3)
        print(
            f"{ratio:5.2f} {1e3 * statistics.median(runs):19.1f} {1e3 * max(runs):7.1f} "
            f"{1e3 * statistics.median(cost):6.1f} {1e3 * statistics.median(bound):9.1f}"
        )
    small = DeliveryInstance.grid(customers[:8], 11, 1000.0, 1.4, 1.0, 900.0, paired_precedences(8))
    runs = timed(lambda: optimal_plan(small), 3)
    print(f"optimal_plan (subset DP), n = 8, s = 121, L/L0 = 0.9: {statistics.median(runs):.3f} s")


if __name__ == "__main__":
    main()
