"""What the registry and the one Solution cost: a method called directly vs through taopt.solve.

Run from the repository root::

    python benchmarks/bench_registry_overhead.py

For MC on n120m20 (uniform current, closed-form travel times) and SMMA on the 120-customer
delivery setup, the median time of the method's own function and of ``taopt.solve`` (look-up,
option check, re-scoring by ``taopt.evaluate``, the frozen Solution) are measured alternately
in the same run, and their ratio printed.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

import taopt
from taopt.fields import UniformField
from taopt.heuristics.clustering import mc
from taopt.heuristics.sequencing import smma_delivery
from taopt.navigation import travel_time_matrix
from taopt.orchestration.studies.delivery import study_instance


def timed(call, repeat: int) -> list[float]:
    out = []
    for _ in range(repeat):
        tic = time.perf_counter()
        call()
        out.append(time.perf_counter() - tic)
    return out


def compare(label: str, direct, through, rounds: int = 15, repeat: int = 3) -> None:
    a, b = [], []
    for _ in range(rounds):  # alternate, so load changes hit both alike
        a += timed(direct, repeat)
        b += timed(through, repeat)
    da, db = statistics.median(a), statistics.median(b)
    print(f"{label}: direct {1e3 * da:.2f} ms, taopt.solve {1e3 * db:.2f} ms, ratio {db / da:.3f}")


def main() -> None:
    rng = np.random.default_rng(0)
    points = rng.uniform(0, 1000, size=(140, 2))
    cost = travel_time_matrix(UniformField(0.3, 0.1), points, 1.0)
    problem = taopt.AssignmentProblem(cost, n_targets=120)
    compare("MC n120m20", lambda: mc(problem), lambda: taopt.solve(problem, "MC"))
    inst = study_instance("pairs120", 0, seed=1, ratio=0.45)
    compare(
        "SMMA 120 customers",
        lambda: smma_delivery(inst),
        lambda: taopt.solve(inst, "SMMA"),
        rounds=8,
    )


if __name__ == "__main__":
    main()
