"""Timing and quality of NIA, MMA, SMMA, GA and ILS on the §5.5 120-customer pairs setup.

Setup (thesis §5.5, Tables 5.5–5.7): 120 random customers in a 1000 m square, 11×11 stops
on a street grid, v_d / v_t = 1.4 (v_t = 1), L = 0.45 · 1000 m, and "every customer has
only one precedence constraint requiring it to be served either before or after another
customer" (Remark 5.2, a dial-a-ride structure): the customers are paired at random,
60 pairs (pickup, delivery).

For each method the script prints: time to build t* (5.11), ordering time, scheduling
time (:func:`taopt.schedule`), total, the makespan (5.1), the t* path cost and
q = f / f_a (5.19) with f_a the arborescence bound of Proposition 5.3.

Thesis Table 5.7 (Matlab, i5-4590): GA 128.8 s, NIA 0.31 s, MMA 0.85 s, SMMA 37.6 s.

ILS (:mod:`taopt.heuristics.ils_delivery`, not in the thesis) searches orders scored by the
exact schedule DP itself; its "order s" column includes those DP evaluations (and the SMMA
and MMA orders it starts from).

Usage::

    python benchmarks/bench_delivery_heuristics.py [--instances 1] [--seed 0]
        [--range 0.45] [--customers 120] [--generations 2000] [--ils-iterations 200]
"""

from __future__ import annotations

import argparse
import time
from functools import partial

import numpy as np

import taopt
import taopt.bounds
from taopt.delivery.costs import drone_cost_matrix
from taopt.delivery.dags import paired_precedences
from taopt.heuristics.ga_delivery import ga_order
from taopt.heuristics.ils_delivery import ils_delivery
from taopt.heuristics.sequencing import (
    delivery_cost_matrix,
    mma_order,
    nia_order,
    path_cost,
    schedule_order,
    smma_order,
)


def pairs_instance(seed: int, n: int = 120, range_ratio: float = 0.45) -> taopt.DeliveryInstance:
    """The §5.5 pairs instance: n customers, a random perfect matching as precedences."""
    rng = np.random.default_rng(seed)
    customers = rng.random((n, 2)) * 1000.0
    return taopt.DeliveryInstance.grid(
        customers,
        k=11,
        side=1000.0,
        v_drone=1.4,
        v_truck=1.0,
        flight_range=range_ratio * 1000.0,
        precedences=paired_precedences(n, seed=rng),
        name=f"pairs-{n}-seed{seed}",
    )


def ils_path(instance: taopt.DeliveryInstance, seed: int, iterations: int) -> list[int]:
    """ILS's order as a node path (depot first), as the other rules return it."""
    order = ils_delivery(instance, seed=seed, iterations=iterations).plan.order
    return [instance.n, *order]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--instances", type=int, default=1)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--range", type=float, default=0.45, help="L / L0")
    parser.add_argument("--customers", type=int, default=120)
    parser.add_argument("--generations", type=int, default=2000)
    parser.add_argument("--ils-iterations", type=int, default=200)
    args = parser.parse_args()

    rows = []
    for k in range(args.instances):
        instance = pairs_instance(args.seed + k, args.customers, args.range)
        began = time.perf_counter()
        drone_cost_matrix(instance)
        tstar_time = time.perf_counter() - began
        cost, start, pairs, customer_of = delivery_cost_matrix(instance)
        bound = taopt.bounds.arborescence(instance)
        seed = args.seed + k
        methods = {
            "NIA": partial(nia_order, cost, pairs, start),
            "MMA": partial(mma_order, cost, pairs, start),
            "SMMA": partial(smma_order, cost, pairs, start),
            "SMMA-updated": partial(smma_order, cost, pairs, start, lookahead="updated"),
            "GA": partial(ga_order, cost, pairs, start, seed=seed, generations=args.generations),
            "ILS": partial(ils_path, instance, seed, args.ils_iterations),
        }
        print(
            f"{instance!r}\n  t* matrix: {tstar_time:.3f} s; arborescence bound f_a = {bound:.1f}"
        )
        print(
            f"  {'method':13s} {'order s':>8s} {'sched s':>8s} {'total s':>8s} "
            f"{'makespan':>10s} {'t* cost':>10s} {'q=f/f_a':>8s}"
        )
        for name, build in methods.items():
            began = time.perf_counter()
            path = build()
            ordering = time.perf_counter() - began
            began = time.perf_counter()
            solution = schedule_order(instance, path, customer_of)
            scheduling = time.perf_counter() - began
            makespan = taopt.evaluate(instance, solution.plan)
            assert abs(makespan - solution.objective) <= 1e-9 * makespan
            value = path_cost(cost, path)
            rows.append((name, ordering, scheduling, makespan, makespan / bound))
            print(
                f"  {name:13s} {ordering:8.3f} {scheduling:8.3f} "
                f"{tstar_time + ordering + scheduling:8.3f} {makespan:10.1f} {value:10.1f} "
                f"{makespan / bound:8.4f}"
            )
    if args.instances > 1:
        print("mean over instances:")
        for name in dict.fromkeys(r[0] for r in rows):
            sel = [r for r in rows if r[0] == name]
            order_s, makespan, q = (np.mean([r[i] for r in sel]) for i in (1, 3, 4))
            print(f"  {name:13s} order {order_s:7.3f} s  makespan {makespan:10.1f}  q {q:.4f}")


if __name__ == "__main__":
    main()
