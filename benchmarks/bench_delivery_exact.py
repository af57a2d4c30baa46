"""Exact truck–drone delivery: the MILP, the subset DP and the DP over order ideals.

Run::

    python benchmarks/bench_delivery_exact.py                 # 3 instances, L = 600 m (MILP)
    python benchmarks/bench_delivery_exact.py --seeds 5 --range 900 --customer-legs
    python benchmarks/bench_delivery_exact.py --compare 8,10,12   # ideal DP, subset DP, MILP
    python benchmarks/bench_delivery_exact.py --dag40 10          # ideal DP on Tables 5.1-5.2

``--compare``: on the same instances (n customers, the grid below) the ideal DP
(:func:`taopt.delivery.ideal_dp.ideal_dp`), the subset DP and the MILP (``--time-limit``)
side by side: ideals, states kept / pruned, peak traced memory (tracemalloc) and time.
``--dag40 N``: the ideal DP on dag40 instances 0..N-1 at every L/L0 (seed 1, as
``taopt study delivery --setup dag40``), with SMMA's plan as incumbent (as ``taopt.solve``
passes it; ``--memory`` traces each run's peak allocation, about 5x slower), and without the beam pass and pruning on instance 1 at 0.15 and 0.3 (the plain DP over
ideals with dominance).

Instances: 8 customers uniform in a 1000 m square, 16 stops on a 4×4 grid (333 m
blocks), depot (0, 0), v_d = v_t = 1, τ = 0, a layered precedence DAG (3 layers,
density 0.2, as the §5.5 "small" setup). For each: model size, LP bound, the
MILP's status, objective, bound and time (limit 60 s), and the subset-DP optimum
(:func:`taopt.delivery.schedule.optimal_plan`) as an independent check.
"""

from __future__ import annotations

import argparse
import resource
import time
import tracemalloc

import cvxpy as cp
import numpy as np

import taopt
from taopt.delivery.dags import layered_dag
from taopt.delivery.ideal_dp import count_ideals, ideal_dp
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


def measured(func, *args, trace: bool = True, **kwargs):
    """(result, seconds, peak traced MB or nan) of one call; tracing numpy's allocations
    slows the ideal DP about 5x, so the time is then only indicative."""
    if trace:
        tracemalloc.start()
    began = time.perf_counter()
    result = func(*args, **kwargs)
    seconds = time.perf_counter() - began
    peak = float("nan")
    if trace:
        peak = tracemalloc.get_traced_memory()[1] / 1e6
        tracemalloc.stop()
    return result, seconds, peak


def peak_rss_gb() -> float:
    """The process's peak resident memory so far (GB, Linux's kB units)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6


def describe(sol, seconds: float, peak: float) -> str:
    info = sol.info
    return (
        f"{sol.status.value:<10} {sol.objective:11.4f}  {seconds:7.2f}s  {peak:7.1f} MB  "
        f"ideals {info.get('ideals', '-')} expanded {info.get('ideals_expanded', '-')} "
        f"kept {info.get('states_kept', '-')} pruned {info.get('states_pruned', '-')} "
        f"dominated {info.get('states_dominated', '-')} peak/layer "
        f"{info.get('peak_layer_states', '-')}"
    )


def compare(sizes: list[int], seeds: int, grid: int, flight_range: float, limit: float) -> None:
    """The ideal DP, the subset DP and the MILP on the same instances."""
    for n in sizes:
        for seed in range(seeds):
            inst = instance(seed, n, grid, flight_range)
            print(f"n={n} seed={seed} s={inst.s} ideals={count_ideals(inst)}")
            ideal, t_ideal, m_ideal = measured(ideal_dp, inst)
            print(f"    ideal DP   {describe(ideal, t_ideal, m_ideal)}")
            subset, t_subset, m_subset = measured(optimal_plan, inst)
            print(
                f"    subset DP  {subset.status.value:<10} {subset.objective:11.4f}  "
                f"{t_subset:7.2f}s  {m_subset:7.1f} MB  (2^n = {2**n} sets)"
            )
            milp, t_milp = None, time.perf_counter()
            milp = solve_delivery(inst, time_limit=limit)
            t_milp = time.perf_counter() - t_milp
            print(
                f"    MILP       {milp.status.value:<10} {milp.objective:11.4f}  "
                f"{t_milp:7.2f}s  bound {milp.bound:.4f}"
            )
            assert abs(ideal.objective - subset.objective) <= 1e-9 * subset.objective


def dag40(count: int, ratios: tuple[float, ...], trace: bool) -> None:
    """The ideal DP on the dag40 instances (Tables 5.1-5.2), SMMA's plan as incumbent."""
    from taopt.orchestration.studies.delivery import study_instance

    rows = []
    for i in range(count):
        for ratio in ratios:
            inst = study_instance("dag40", i, seed=1, ratio=ratio)
            smma = taopt.solve(inst, "SMMA")
            sol, seconds, peak = measured(ideal_dp, inst, incumbent=smma, trace=trace)
            rows.append(seconds)
            print(
                f"dag40-{i} L/L0={ratio:<4g} SMMA {smma.objective:10.2f}  {describe(sol, seconds, peak)}"
            )
    rows.sort()
    print(
        f"median {rows[len(rows) // 2]:.2f}s, max {rows[-1]:.2f}s over {len(rows)} runs; "
        f"process peak RSS {peak_rss_gb():.2f} GB"
    )
    if count > 1:
        for ratio in (0.15, 0.3):  # 0.9 takes minutes without pruning
            inst = study_instance("dag40", 1, seed=1, ratio=ratio)
            plain, seconds, peak = measured(ideal_dp, inst, beam=0, prune=False, trace=trace)
            print(
                f"dag40-1 L/L0={ratio:<4g} plain DP (no beam, no pruning): {describe(plain, seconds, peak)}"
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--customers", type=int, default=8)
    parser.add_argument("--grid", type=int, default=4)
    parser.add_argument("--range", type=float, default=600.0, dest="flight_range")
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--customer-legs", action="store_true", help="also with the pair cuts")
    parser.add_argument("--compare", default="", help="n values: ideal DP vs subset DP vs MILP")
    parser.add_argument("--dag40", type=int, default=0, help="ideal DP on dag40 instances 0..N-1")
    parser.add_argument("--ratios", default="0.15,0.3,0.45,0.6,0.75,0.9")
    parser.add_argument("--memory", action="store_true", help="dag40: trace memory (slower)")
    args = parser.parse_args()
    if args.compare or args.dag40:
        if args.compare:
            sizes = [int(x) for x in args.compare.split(",")]
            compare(sizes, args.seeds, args.grid, args.flight_range, args.time_limit)
        if args.dag40:
            ratios = tuple(float(r) for r in args.ratios.split(","))
            dag40(args.dag40, ratios, args.memory)
        return
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
