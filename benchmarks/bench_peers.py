"""PyVRP, OR-Tools and CP-SAT beside the thesis's MC heuristic and the certified optimum (chapter 2).

Harness ("uniform current"): n targets then m vehicle starts uniform in a
1000 m square (``numpy.random.default_rng(seed)``), a uniform current
(0.3, 0.1) m/s, vehicle speed v = 1, closed-form travel times
(:func:`taopt.navigation.uniform_travel_times`, (3.4)). For every instance the
script prints the exact optimum (``taopt.models.solve_routing``, DFJ + HiGHS),
MC (``taopt.heuristics.run("MC", p)``) and each peer at each time limit, with
its gap ``(f - f*) / f*`` in percent; then the mean and worst gap per method
and size. The peers run in their worker processes (started once, before the
timed calls) and search up to each limit (``no_improvement=None``: their default stop
on no improvement is off here); every objective is re-scored by ``taopt.evaluate``. CP-SAT (the
circuit model of ``"cpsat"``, 2 workers) may find no solution in a short limit: its
objective is then inf. Peers stopped
by time are not deterministic, so the figures move a little between runs.

Usage::

    python benchmarks/bench_peers.py                       # n50m10 and n120m20, seeds 0-4, 1 s and 5 s
    python benchmarks/bench_peers.py --sizes 50x10 --seeds 0,1 --limits 1
"""

from __future__ import annotations

import argparse
import statistics

import numpy as np

import taopt
import taopt.heuristics
from taopt.heuristics.peers import cpsat_routing, ortools_solve, pyvrp_solve, shutdown
from taopt.models import solve_routing
from taopt.navigation import uniform_travel_times

PEERS = {"pyvrp": pyvrp_solve, "ortools": ortools_solve, "cpsat": cpsat_routing}


def uniform_current_problem(n: int, m: int, seed: int) -> taopt.AssignmentProblem:
    """n targets then m vehicles uniform in a 1000 m square, current (0.3, 0.1) m/s, v = 1."""
    rng = np.random.default_rng(seed)
    points = np.vstack([rng.uniform(0, 1000, (n, 2)), rng.uniform(0, 1000, (m, 2))])
    times = uniform_travel_times((0.3, 0.1), points[:, None], points[None, :], speed=1.0)
    return taopt.AssignmentProblem(times, n, name=f"n{n}m{m}-seed{seed}")


def gap(value: float, reference: float) -> float:
    """Relative gap in percent."""
    return 100.0 * (value - reference) / reference


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--sizes", default="50x10,120x20", help="comma list of NxM")
    parser.add_argument("--seeds", default="0,1,2,3,4", help="comma list of harness seeds")
    parser.add_argument("--limits", default="1,5", help="comma list of peer time limits (s)")
    parser.add_argument("--peer-seed", type=int, default=0, help="seed passed to the peers")
    parser.add_argument("--exact-time-limit", type=float, default=900.0)
    args = parser.parse_args()
    limits = [float(x) for x in args.limits.split(",")]
    seeds = [int(x) for x in args.seeds.split(",")]
    columns = ["MC"] + [f"{peer}@{limit:g}s" for peer in PEERS for limit in limits]

    warm = uniform_current_problem(5, 2, 0)  # start the workers outside the timed calls
    for solve in PEERS.values():
        solve(warm, time_limit=None)  # no limit: waits for the start-up, then a tiny search

    for size in args.sizes.split(","):
        n, m = (int(x) for x in size.lower().split("x"))
        gaps: dict[str, list[float]] = {name: [] for name in columns}
        print(f"\nn{n}m{m}: objective (gap % to the optimum)", flush=True)
        print(
            f"{'seed':>4} {'optimum':>10} {'exact s':>8} " + " ".join(f"{c:>19}" for c in columns)
        )
        for seed in seeds:
            problem = uniform_current_problem(n, m, seed)
            exact = solve_routing(problem, time_limit=args.exact_time_limit)
            certified = exact.status == "optimal"
            reference = exact.objective if certified else exact.bound  # else: gaps are upper bounds
            results = {"MC": taopt.heuristics.run("MC", problem).objective}
            for peer, solve in PEERS.items():
                for limit in limits:
                    # the heuristic peers search up to the limit (no no-improvement stop)
                    stop = {} if peer == "cpsat" else {"no_improvement": None}
                    solution = solve(problem, time_limit=limit, seed=args.peer_seed, **stop)
                    assert solution.objective >= exact.bound * (1 - 1e-9)
                    results[f"{peer}@{limit:g}s"] = solution.objective
            cells = []
            for name in columns:
                gaps[name].append(gap(results[name], reference))
                cells.append(f"{results[name]:>10.2f} ({gaps[name][-1]:5.2f})")
            mark = "" if certified else f"  [exact {exact.status}: gaps vs bound {exact.bound:.2f}]"
            print(
                f"{seed:>4} {exact.objective:>10.2f} {exact.runtime:>8.2f} "
                + " ".join(cells)
                + mark,
                flush=True,
            )
        print(
            f"{'mean gap %':>24} " + " ".join(f"{statistics.mean(gaps[c]):>19.3f}" for c in columns)
        )
        print(f"{'worst gap %':>24} " + " ".join(f"{max(gaps[c]):>19.3f}" for c in columns))
    shutdown()


if __name__ == "__main__":
    main()
