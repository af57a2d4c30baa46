"""Ground truth for tiny fleet instances: enumerate every plan of a finite complete set.

Kept obviously correct rather than fast (n <= 6 with few stops). Every plan is scored by the
family's one scorer :func:`taopt.fleet.evaluate.evaluate_fleet`; infeasible ones (range,
deadlock) are skipped.

Why the enumerated set contains an optimal plan. Take any feasible plan and its earliest
schedule (module :mod:`taopt.fleet.evaluate`). (i) Deleting a truck position where nothing
happens (no truck service, launch or recovery) other than position 0 keeps every constraint
and lowers no time bound... precisely: the old times satisfy the new inequalities (the street
metric obeys the triangle inequality, ``tt[a, c] <= tt[a, b] + tt[b, c]``), so the new earliest
times are no later. (ii) Merging two consecutive positions at the same stop likewise: the old
times with ``A' = A[p]`` and ``Dep' = Dep[p + 1]`` satisfy the merged inequalities. Repeating
both, every truck's sequence has an event at each position p >= 1 and no two consecutive equal
stops, hence at most ``1 + (truck customers) + 2 (sorties)`` positions. The enumeration below
lists, for every choice of server per customer, every order of every drone's customers cut into
sorties of 1..c, and every such sequence of positions with every placement of the events that
respects each drone's order (launch <= recovery <= next launch), all such plans.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence
from typing import Any

from taopt.errors import FeasibilityError
from taopt.fleet.evaluate import evaluate_fleet
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie


def _sortie_splits(
    customers: tuple[int, ...], c: int, precedences: tuple[tuple[int, int], ...]
) -> Iterator[list[tuple[int, ...]]]:
    """Every ordered list of sorties (each 1..c customers in order) covering ``customers``,
    skipping orders that serve j before r for a precedence (r, j): one drone serves its
    customers one after the other, so such a plan deadlocks (the scorer refuses it)."""
    if not customers:
        yield []
        return
    for order in itertools.permutations(customers):
        where = {j: i for i, j in enumerate(order)}
        if any(r in where and j in where and where[r] > where[j] for r, j in precedences):
            continue
        yield from _cuts(order, c)


def _cuts(order: tuple[int, ...], c: int) -> Iterator[list[tuple[int, ...]]]:
    if not order:
        yield []
        return
    for size in range(1, min(c, len(order)) + 1):
        for rest in _cuts(order[size:], c):
            yield [order[:size], *rest]


def _truck_layouts(
    problem: FleetProblem, truck_customers: tuple[int, ...], chains: list[int]
) -> Iterator[tuple[list[int], list[tuple[int, int]], list[list[tuple[int, int]]]]]:
    """Every (route, truck service, per drone [(launch, recovery) per sortie]) of one truck.

    ``chains[d]`` is the number of sorties of drone d; its events are the chain
    L_0, R_0, L_1, R_1, ... placed at non-decreasing positions. Position 0 is the depot (any
    events, or none); every later position holds at least one event and differs in stop from
    the previous one.
    """
    s = problem.s
    at = problem.customer_stop

    def rec(
        route: list[int],
        served: list[tuple[int, int]],
        left: frozenset[int],
        pointers: list[int],
        places: list[list[int]],
    ) -> Iterator[Any]:
        p = len(route) - 1
        w = route[-1]
        # events at position p: for each drone a contiguous run of its chain, and a subset of
        # the remaining truck customers whose stop is w
        here = [j for j in left if at[j] == w]
        runs = [range(0, 2 * chains[d] - pointers[d] + 1) for d in range(len(chains))]
        for subset_size in range(len(here) + 1):
            for subset in itertools.combinations(sorted(here), subset_size):
                for take in itertools.product(*runs):
                    if p > 0 and subset_size == 0 and not any(take):
                        continue
                    new_pointers = [a + b for a, b in zip(pointers, take, strict=True)]
                    new_places = [places[d] + [p] * take[d] for d in range(len(chains))]
                    new_served = served + [(p, j) for j in subset]
                    new_left = left - set(subset)
                    if not new_left and all(
                        new_pointers[d] == 2 * chains[d] for d in range(len(chains))
                    ):
                        sorties = [
                            [(pl[2 * i], pl[2 * i + 1]) for i in range(chains[d])]
                            for d, pl in enumerate(new_places)
                        ]
                        yield list(route), new_served, sorties
                    # continue to a next position
                    if new_left or any(new_pointers[d] < 2 * chains[d] for d in range(len(chains))):
                        for nxt in range(s):
                            if nxt == w:
                                continue
                            yield from rec(
                                route + [nxt], new_served, new_left, new_pointers, new_places
                            )

    yield from rec(
        [problem.depot], [], frozenset(truck_customers), [0] * len(chains), [[]] * len(chains)
    )


def _canonical(
    problem: FleetProblem, choice: tuple[tuple[Any, ...], ...], trucks: bool = True
) -> bool:
    """Symmetry: the drones of one truck are interchangeable, and so are trucks carrying as
    many drones (all start at the depot; not with ``trucks=False``); relabelling them maps
    plans to plans of the same value. Keep only the labelling where, among interchangeable
    ones, the smallest customer served increases with the label (unused ones last)."""
    first: dict[tuple[Any, ...], int] = {}
    for j, who in enumerate(choice):
        first.setdefault(who, j)
        if who[0] == "drone":
            first.setdefault(("truck", who[1]), j)
    big = problem.n

    def smallest(key: tuple[Any, ...]) -> int:
        return first.get(key, big)

    for k in range(problem.K):
        for d in range(problem.drones[k] - 1):
            if smallest(("drone", k, d)) > smallest(("drone", k, d + 1)):
                return False
    for k in range(problem.K - 1 if trucks else 0):
        if problem.drones[k] == problem.drones[k + 1]:
            if smallest(("truck", k)) > smallest(("truck", k + 1)):
                return False
    return True


def brute_force(
    problem: FleetProblem, limit: int = 5_000_000, truck_of: Sequence[int] | None = None
) -> tuple[float, FleetPlan | None, int]:
    """The optimum of a tiny instance by enumeration (with ``truck_of``: over the plans where
    customer j is served by truck ``truck_of[j]`` or its drones only).

    Returns
    -------
    (value, plan, count)
        The least objective over all feasible plans of the complete set (module docstring),
        ``inf`` and None when none is feasible; ``count`` the plans scored.

    Raises
    ------
    FeasibilityError
        More than ``limit`` plans would be scored (the instance is not tiny).
    """
    n = problem.n
    options: list[list[tuple[Any, ...]]] = []
    for j in range(n):
        opts: list[tuple[Any, ...]] = []
        if problem.truck_servable(j):
            opts += [("truck", k) for k in range(problem.K)]
        if problem.drone_servable(j):
            opts += [("drone", k, d) for k, d in problem.drone_ids()]
        if truck_of is not None:
            opts = [o for o in opts if o[1] == truck_of[j]]
        options.append(opts)
    best, best_plan, count = float("inf"), None, 0
    for choice in itertools.product(*options):
        if not _canonical(problem, choice, trucks=truck_of is None):
            continue
        truck_sets = [
            tuple(j for j in range(n) if choice[j] == ("truck", k)) for k in range(problem.K)
        ]
        drone_sets = {
            (k, d): tuple(j for j in range(n) if choice[j] == ("drone", k, d))
            for k, d in problem.drone_ids()
        }
        # every truck's options: for each split of its drones' customers, every layout
        per_truck: list[list[tuple[list[int], list[tuple[int, int]], list[list[Sortie]]]]] = []
        for k in range(problem.K):
            found = []
            splits = [
                list(_sortie_splits(drone_sets[(k, d)], problem.capacity, problem.precedences))
                for d in range(problem.drones[k])
            ]
            for split in itertools.product(*splits):
                chains = [len(sp) for sp in split]
                for route, served, places in _truck_layouts(problem, truck_sets[k], chains):
                    flights = [
                        [Sortie(a, cs, b) for (a, b), cs in zip(places[d], split[d], strict=True)]
                        for d in range(len(split))
                    ]
                    found.append((route, served, flights))
            per_truck.append(found)
        for combo in itertools.product(*per_truck):
            count += 1
            if count > limit:
                raise FeasibilityError(f"brute force: more than {limit} plans; not a tiny instance")
            plan = FleetPlan([c[0] for c in combo], [c[1] for c in combo], [c[2] for c in combo])
            try:
                value = evaluate_fleet(problem, plan)
            except FeasibilityError:
                continue
            if value < best:
                best, best_plan = value, plan
    return best, best_plan, count


__all__ = ["brute_force"]


def tiny_instance(
    seed: int,
    n: int = 3,
    trucks: int = 1,
    drones: int = 1,
    capacity: int = 1,
    precedence: bool = False,
    objective: str = "last_service",
    stops: int = 3,
) -> FleetProblem:
    """A random tiny instance for the brute-force checks: ``stops`` stops in a 100 m square on
    a complete street graph (lengths 1.0–1.3 times the straight line), customers anywhere in
    it, each served by drone, truck or both (truck at its nearest stop), τ ∈ {0, 2}, a range
    that sometimes binds, and, with ``precedence``, a random DAG (pairs i < j, probability 0.4).
    """
    import networkx as nx
    import numpy as np

    rng = np.random.default_rng(seed)
    pts = rng.uniform(0, 100, (stops, 2))
    g = nx.Graph()
    for a in range(stops):
        for b in range(a + 1, stops):
            g.add_edge(a, b, length=float(np.hypot(*(pts[a] - pts[b])) * rng.uniform(1.0, 1.3)))
    cust = rng.uniform(0, 100, (n, 2))
    near = [int(np.argmin(np.hypot(*(pts - c).T))) for c in cust]
    modes = [str(m) for m in rng.choice(["drone", "both", "truck"], size=n, p=[0.5, 0.35, 0.15])]
    if drones == 0:
        modes = ["truck" if m == "drone" else m for m in modes]
    stop_of = [None if m == "drone" else near[j] for j, m in enumerate(modes)]
    reach = max(2.0 * float(np.min(np.hypot(*(pts - c).T))) for c in cust)
    flight_range = None if rng.random() < 0.4 else float(max(reach * 1.05, rng.uniform(60, 200)))
    pairs = (
        [(i, j) for i in range(n) for j in range(i + 1, n) if rng.random() < 0.4]
        if precedence
        else []
    )
    perm = rng.permutation(n)
    pairs = [(int(perm[i]), int(perm[j])) for i, j in pairs]
    return FleetProblem(
        customers=cust,
        stops=pts,
        graph=g,
        depot=0,
        drones=[drones] * trucks,
        capacity=capacity,
        flight_range=flight_range,
        v_truck=1.0,
        v_drone=float(rng.choice([1.0, 1.5, 2.0])),
        service=modes,
        customer_stop=stop_of,
        precedences=pairs,
        service_time=float(rng.choice([0.0, 2.0])),
        objective=objective,
        name=f"tiny-{seed}",
    )


__all__ += ["tiny_instance"]
