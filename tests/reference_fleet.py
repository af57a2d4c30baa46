"""Reference problems of the fleet family (:class:`taopt.FleetProblem`), optima by hand.

Found by ``tests/reference.py`` (every ``tests/reference_<family>.py`` adds its ``REFERENCES``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import networkx as nx
from reference import BruteForce, Reference

import taopt
from taopt.fleet.search import _bound, _children, _complete


def _two_houses(objective: str) -> taopt.FleetProblem:
    g = nx.Graph()
    g.add_edge(0, 1, length=100.0)
    return taopt.FleetProblem(
        [[100, 50], [0, 50]],
        [[0, 0], [100, 0]],
        g,
        depot=0,
        drones=[2],
        capacity=1,
        flight_range=500,
        v_truck=10,
        v_drone=10,
        precedences=[(0, 1)],
        objective=objective,
        name=f"two houses, two drones ({objective})",
    )


def fleet_two_houses() -> Reference:
    """Both drones leave the depot at once: house 0 is served after sqrt(100² + 50²) / 10 s,
    house 1 after 5 s (waiting for house 0 by the precedence); no launch elsewhere is faster
    (the truck needs 10 s to reach stop 1, then 5 s of flight)."""
    return Reference(
        "fleet_two_houses",
        _two_houses("last_service"),
        math.hypot(100, 50) / 10,
        "by hand (docstring)",
    )


def fleet_two_houses_return() -> Reference:
    """Objective "return": drone 0 out to house 0 and back to the depot, 2 sqrt(100² + 50²) /
    10 s; recovering it at stop 1 instead costs 10 + 5 + 5 + 10 s or more; drone 1's round
    trip is 10 s and the truck never moves."""
    return Reference(
        "fleet_two_houses_return",
        _two_houses("return"),
        2 * math.hypot(100, 50) / 10,
        "by hand (docstring)",
    )


REFERENCES: list[Callable[[], Reference]] = [fleet_two_houses, fleet_two_houses_return]


def _fleet_cases(seeds: range) -> list[tuple[taopt.FleetProblem, float]]:
    """Tiny fleets (n = 2-3, K, D, c in {1, 2}, with and without precedence, both objectives)
    with their optima by :func:`taopt.fleet.brute.brute_force` (every plan of a complete set)."""
    from taopt.fleet.brute import brute_force, tiny_instance

    cases = []
    for seed in seeds:
        trucks, drones, capacity = 1 + seed % 2, 1 + (seed // 2) % 2, 1 + (seed // 4) % 2
        problem = tiny_instance(
            seed,
            n=2 + seed % 2,
            trucks=trucks,
            drones=drones,
            capacity=capacity,
            precedence=bool(seed % 3),
            objective=("last_service", "return")[(seed // 3) % 2],
            stops=2 + seed % 2,
        )
        cases.append((problem, brute_force(problem)[0]))
    return cases


BRUTE_FORCE = [BruteForce("fleet", "exact", _fleet_cases, fast=6, slow=60)]


def root_label(problem: taopt.FleetProblem) -> tuple:
    """The label search's root label of ``problem`` (every truck at the depot at time 0, every
    drone aboard and ready, nothing served): the layout of :mod:`taopt.fleet.search`."""
    trucks = tuple(
        (problem.depot, 0.0, 0.0, True, False, 0.0, tuple((0, 0.0) for _ in range(d)))
        for d in problem.drones
    )
    return (0, 0.0, (-1.0,) * problem.n, trucks)


def best_completion(tab: Any, label: tuple, memo: dict, seen: list | None = None) -> float:
    """The least objective over every completion of ``label`` in the label search's tables
    ``tab`` (all children, no dominance: tiny instances only). Every label below it is memoised
    in ``memo`` with its best completion; when ``seen`` is given, ``(bound, best)`` is appended
    for each label visited (the label bound :func:`taopt.fleet.search._bound`)."""
    got = memo.get(label)
    if got is not None:
        return got
    if _complete(tab, label):
        best = max(tr[5] for tr in label[3]) if tab.ret else label[1]
    else:
        best = math.inf
        for child, _ in _children(tab, label):
            best = min(best, best_completion(tab, child, memo, seen))
    memo[label] = best
    if seen is not None:
        seen.append((_bound(tab, label), best))
    return best
