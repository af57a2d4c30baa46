"""Exact truck–drone MILP (models/delivery.py) on 8 customers and a 4×4 street grid.

Run::

    python benchmarks/bench_delivery_exact.py                 # 3 instances, L = 600 m
    python benchmarks/bench_delivery_exact.py --seeds 5 --range 900 --customer-legs

Instances: 8 customers uniform in a 1000 m square, 16 stops on a 4×4 grid (333 m
blocks), depot (0, 0), v_d = v_t = 1, τ = 0, a layered precedence DAG (3 layers,
density 0.2, as the §5.5 "small" setup). For each: model size, LP bound, the
MILP's status, objective, bound and time (limit 60 s), and the subset-DP optimum
(:func:`taopt.delivery.schedule.optimal_plan`) as an independent check.
"""

from __future__ import annotations

import argparse
import time

import cvxpy as cp
import numpy as np

import taopt
from taopt.delivery.dags import layered_dag
from taopt.delivery.instance import DeliveryInstance
from taopt.delivery.schedule import optimal_plan
from taopt.models import solve_delivery
from taopt.models.delivery import build


def instance(seed: int, n: int, k: int, flight_range: float) -> DeliveryInstance:
    rng = np.random.default_rng([2024, seed])
    customers = rng.uniform(0.0, 1000.0, size=(n, 2))
    precedences = layered_dag(n, layers=3, density=0.2, seed=rng)
    return DeliveryInstance.grid(
        customers,
        k,
        1000.0,
        v_drone=1.0,
        v_truck=1.0,
        flight_range=flight_range,
        precedences=precedences,
        name=f"bench-{seed}",
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--customers", type=int, default=8)
    parser.add_argument("--grid", type=int, default=4)
    parser.add_argument("--range", type=float, default=600.0, dest="flight_range")
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--customer-legs", action="store_true", help="also with the pair cuts")
    args = parser.parse_args()
    variants = [False, True] if args.customer_legs else [False]
    for seed in range(args.seeds):
        inst = instance(seed, args.customers, args.grid, args.flight_range)
        began = time.perf_counter()
        reference = optimal_plan(inst)
        dp_time = time.perf_counter() - began
        print(
            f"{inst.name}: n={inst.n}, s={inst.s}, L={inst.flight_range:g}, "
            f"{len(inst.precedences)} precedences; subset-DP optimum "
            f"{reference.objective:.4f} ({dp_time:.2f}s)"
        )
        for legs in variants:
            relaxed = build(inst, relax=True, customer_legs=legs)
            relaxed.problem.solve(solver=cp.HIGHS)
            sol = solve_delivery(inst, time_limit=args.time_limit, customer_legs=legs)
            scored = taopt.evaluate(inst, sol.plan)
            match = abs(sol.objective - reference.objective) <= 1e-6 * reference.objective
            print(
                f"    customer_legs={legs!s:<5} y={sol.info['binaries']} w={sol.info['legs']} "
                f"LP={relaxed.problem.value:.1f}  {sol.summary()}  nodes={sol.info['nodes']}  "
                f"evaluate={scored:.4f}  equals DP: {match}"
            )


if __name__ == "__main__":
    main()
