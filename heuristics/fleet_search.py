"""Search heuristics for the fleet: Bai et al.'s three phases ("3P") and an iterated local
search ("ILS").

Both search over an *encoding* of a plan: a priority order of the customers (a topological
order of G^p) and, per customer, the truck whose vehicles serve it. The decoder
(:func:`taopt.heuristics.fleet.decode`) places the customers in that order, each by the option
of least marginal makespan among its truck's options (the truck itself, a new sortie of one of
its drones, or merging into a drone's open sortie when c > 1), checking the range and the
capacity as it goes: every decoded plan is feasible, and its kept times are the earliest
schedule (re-scored by :func:`taopt.evaluate` at the end).

3P (Bai et al., IEEE T-RO 2025, from the published description; no code is public)
    1. precedence-feasible truck routes by an extended min-marginal-cost rule: every customer
       is visited by a truck at its *anchor* stop (its own stop when a truck may serve it,
       else the nearest stop a drone reaches it from), customers taken viable-first (the
       topological-sorting technique) and each appended to the truck and position of least
       marginal makespan of the trucks-only schedule, waiting for predecessors;
    2. a split of each truck route into drone sorties with the endurance check: the route's
       customers decoded in order on their truck (truck service, a new sortie, or merging
       into the open sortie while it stays within the range and c);
    3. variable neighbourhood descent over the encoding: N1 move one customer to another
       truck, N2 shift one customer within its precedence window, N3 exchange the trucks of
       two customers; first improvement, back to N1 after each improvement, each
       neighbourhood sampled (``sample`` moves).

ILS
    Starts from the better of MMA's and SMMA's plans (their order and trucks), runs the same
    descent, then perturbs (``strength`` random truck moves and shifts) and descends again,
    accepting a plan no more than ``accept_worse`` (relative) worse than the current one; the
    best plan found is returned.

Both are seeded (a ``numpy`` generator), stop after ``iterations`` (tests) or at
``time_limit`` seconds (wall-clock, checked between decodes).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from taopt.errors import InstanceError
from taopt.fleet.problem import FleetProblem
from taopt.heuristics.fleet import (
    FleetBuilder,
    _check_servable,
    construct,
    decode,
    infeasible_solution,
    servers,
)
from taopt.registry import register_improver, register_method
from taopt.result import FEASIBLE, Solution, make_solution
from taopt.runtime import Deadline

#: Customers between two snapshots of the current decode (:class:`_Search`).
SNAPSHOT_EVERY = 8


class _Search:
    """The encoding (order, trucks), its decoded value, and the descent's neighbourhoods."""

    def __init__(self, problem: FleetProblem, rng: np.random.Generator, deadline: Deadline):
        self.problem = problem
        self.rng = rng
        self.deadline = deadline
        self.servers = [servers(problem, j) for j in range(problem.n)]
        self.preds: list[list[int]] = [[] for _ in range(problem.n)]
        self.succs: list[list[int]] = [[] for _ in range(problem.n)]
        for r, j in problem.precedences:
            self.preds[j].append(int(r))
            self.succs[r].append(int(j))
        self.decodes = 0
        self.builder = FleetBuilder(problem)
        self.blank = self.builder.snapshot()
        # the current encoding and snapshots of its decode every SNAPSHOT_EVERY customers
        self.current: tuple[list[int], np.ndarray] | None = None
        self.snapshots: list[tuple[Any, ...]] = []

    def set_current(self, order: list[int], trucks: np.ndarray) -> float:
        """Decode ``order`` from scratch, keeping snapshots: later values re-decode only from
        the first customer where a candidate differs."""
        self.decodes += 1
        builder = self.builder
        builder.restore(self.blank)
        self.snapshots = []
        for i, j in enumerate(order):
            if i % SNAPSHOT_EVERY == 0:
                self.snapshots.append(builder.snapshot())
            builder.place(j, int(trucks[j]))
        self.current = (list(order), trucks.copy())
        return builder.objective()

    def value(self, order: list[int], trucks: np.ndarray) -> float:
        """The decoded objective of an encoding (= ``decode(...).objective()``), re-decoding
        from the snapshot before the first customer where it differs from the current one."""
        if self.current is None:
            return self.set_current(order, trucks)
        self.decodes += 1
        old_order, old_trucks = self.current
        first = 0
        while (
            first < len(order)
            and order[first] == old_order[first]
            and trucks[order[first]] == old_trucks[order[first]]
        ):
            first += 1
        block = min(first // SNAPSHOT_EVERY, len(self.snapshots) - 1)
        builder = self.builder
        builder.restore(self.snapshots[block])
        for j in order[block * SNAPSHOT_EVERY :]:
            builder.place(j, int(trucks[j]))
        return builder.objective()

    def out_of_time(self) -> bool:
        return self.deadline.expired()

    # -- moves ------------------------------------------------------------------------------
    def reassign(self, trucks: np.ndarray) -> np.ndarray | None:
        """N1: one customer to another truck that can serve it."""
        movable = [j for j in range(self.problem.n) if len(self.servers[j]) > 1]
        if not movable:
            return None
        j = movable[int(self.rng.integers(len(movable)))]
        choices = [k for k in self.servers[j] if k != trucks[j]]
        out = trucks.copy()
        out[j] = choices[int(self.rng.integers(len(choices)))]
        return out

    def shift(self, order: list[int]) -> list[int] | None:
        """N2: one customer to another place in the order, within its precedence window."""
        n = len(order)
        if n < 2:
            return None
        j = order[int(self.rng.integers(n))]
        rest = [x for x in order if x != j]
        position = {x: i for i, x in enumerate(rest)}
        lo = max((position[r] + 1 for r in self.preds[j]), default=0)
        hi = min((position[v] for v in self.succs[j]), default=n - 1)
        if hi <= lo:
            return None
        q = int(self.rng.integers(lo, hi + 1))
        out = rest[:q] + [j] + rest[q:]
        return None if out == order else out

    def exchange(self, trucks: np.ndarray) -> np.ndarray | None:
        """N3: two customers on different trucks exchange trucks (when both can)."""
        n = self.problem.n
        if self.problem.K < 2 or n < 2:
            return None
        i, j = (int(x) for x in self.rng.choice(n, 2, replace=False))
        if trucks[i] == trucks[j]:
            return None
        if trucks[j] not in self.servers[i] or trucks[i] not in self.servers[j]:
            return None
        out = trucks.copy()
        out[i], out[j] = trucks[j], trucks[i]
        return out

    def descend(
        self, order: list[int], trucks: np.ndarray, value: float, sample: int
    ) -> tuple[list[int], np.ndarray, float]:
        """Variable neighbourhood descent (N1, N2, N3; first improvement; back to N1)."""
        self.set_current(order, trucks)
        level = 0
        while level < 3 and not self.out_of_time():
            improved = False
            for _ in range(sample):
                if self.out_of_time():
                    break
                new_order, new_trucks = order, trucks
                if level == 0:
                    moved = self.reassign(trucks)
                    if moved is None:
                        break
                    new_trucks = moved
                elif level == 1:
                    shifted = self.shift(order)
                    if shifted is None:
                        continue
                    new_order = shifted
                else:
                    swapped = self.exchange(trucks)
                    if swapped is None:
                        continue
                    new_trucks = swapped
                candidate = self.value(new_order, new_trucks)
                if candidate < value - 1e-9 * max(1.0, abs(value)):
                    order, trucks, value = new_order, new_trucks, candidate
                    self.set_current(order, trucks)
                    improved = True
                    break
            level = 0 if improved else level + 1
        return order, trucks, value

    def perturb(
        self, order: list[int], trucks: np.ndarray, strength: int
    ) -> tuple[list[int], np.ndarray]:
        for _ in range(strength):
            moved = self.reassign(trucks)
            if moved is not None:
                trucks = moved
            shifted = self.shift(order)
            if shifted is not None:
                order = shifted
        return order, trucks


def _encoding(builder: FleetBuilder) -> tuple[list[int], np.ndarray]:
    return list(builder.order), builder.truck_of.copy()


def truck_routes(problem: FleetProblem) -> tuple[list[int], np.ndarray]:
    """3P's phase 1: the order and trucks of the trucks-only min-marginal-makespan routes.

    Each customer is visited at its anchor stop (its own stop, or the stop nearest to it that a
    drone reaches it from and back within the range); a viable customer (all predecessors
    placed) goes to the truck whose arrival there, waiting for the predecessors, raises the
    trucks' makespan least (ties: the earliest arrival, then the lowest customer index). Only
    trucks that can serve the customer (a drone-only customer needs a truck with a drone) are
    tried.
    """
    n, K = problem.n, problem.K
    tt = problem.truck_time
    anchor = np.empty(n, dtype=np.int64)
    for j in range(n):
        if problem.truck_servable(j):
            anchor[j] = problem.truck_stop(j)
        else:
            reach = np.where(
                2.0 * problem.flight_stop[j] <= problem.flight_limit, problem.flight_stop[j], np.inf
            )
            anchor[j] = int(np.argmin(reach))
    at = [problem.depot] * K
    clock = [0.0] * K
    served = np.full(n, np.nan)
    waiting = np.zeros(n, dtype=np.int64)
    successors: list[list[int]] = [[] for _ in range(n)]
    preds: list[list[int]] = [[] for _ in range(n)]
    for r, j in problem.precedences:
        waiting[j] += 1
        successors[r].append(int(j))
        preds[j].append(int(r))
    open_ = [j for j in range(n) if waiting[j] == 0]
    can = [servers(problem, j) for j in range(n)]
    order: list[int] = []
    trucks = np.full(n, -1, dtype=np.int64)
    makespan = 0.0
    while open_:
        best: tuple[Any, ...] | None = None
        for j in open_:
            ready = max((served[r] for r in preds[j]), default=0.0)
            for k in can[j]:
                arrive = max(clock[k] + float(tt[at[k], anchor[j]]), ready)
                key = (max(makespan, arrive) - makespan, arrive, j, k)
                if best is None or key < best:
                    best = key
        assert best is not None
        _, arrive, j, k = best
        at[k], clock[k], served[j] = int(anchor[j]), arrive, arrive
        makespan = max(makespan, arrive)
        order.append(j)
        trucks[j] = k
        open_.remove(j)
        for v in successors[j]:
            waiting[v] -= 1
            if waiting[v] == 0:
                open_.append(v)
    return order, trucks


def _check(iterations: int, sample: int, strength: int, accept_worse: float) -> None:
    for name, value in (("iterations", iterations), ("sample", sample), ("strength", strength)):
        if int(value) != value or value < 0:
            raise InstanceError(f"{name} must be an integer >= 0, got {value!r}")
    if not accept_worse >= 0:
        raise InstanceError(f"accept_worse must be >= 0, got {accept_worse!r}")


def _finish(
    problem: FleetProblem,
    name: str,
    order: list[int],
    trucks: np.ndarray,
    began: float,
    seed: int,
    info: dict[str, Any],
) -> Solution:
    builder = decode(problem, order, trucks)
    return make_solution(
        problem,
        builder.plan(),
        method=name,
        status=FEASIBLE,
        runtime=time.perf_counter() - began,
        seed=seed,
        info={"order": list(order), "trucks": [int(k) for k in trucks], **info},
    )


@register_method(FleetProblem, "3P", style=(":", "v"))
def three_phase(
    problem: FleetProblem,
    seed: int = 0,
    time_limit: float | None = None,
    iterations: int = 20,
    sample: int | None = None,
) -> Solution:
    """Bai et al. (2025)'s three phases: truck routes, a split into sorties, VND.

    Phase 1 :func:`truck_routes`, phase 2 the decoder on those trucks, phase 3 the variable
    neighbourhood descent (N1 truck move, N2 shift, N3 truck exchange; ``sample`` random moves
    per neighbourhood, default ``2 n``), repeated from the best plan at most ``iterations``
    times (each pass with fresh samples) or until ``time_limit`` seconds. ``info``:
    ``phase1``, ``phase2`` (the objectives after each phase), ``decodes``, ``stopped_by``.

    References
    ----------
    Bai, X. et al., IEEE T-RO 2025 (several trucks with drones under precedence; a three-phase
    heuristic, from its published description); thesis §5.4, §6.2.
    """
    began = time.perf_counter()
    why = _check_servable(problem)
    if why:
        return infeasible_solution(problem, "3P", why, began)
    sample = 2 * problem.n if sample is None else sample
    _check(iterations, sample, 0, 0.0)
    search = _Search(problem, np.random.default_rng(seed), Deadline(time_limit))
    order, trucks = truck_routes(problem)
    value = search.value(order, trucks)
    phase2 = value
    stopped_by = "iterations"
    for _ in range(int(iterations)):
        if search.out_of_time():
            stopped_by = "time_limit"
            break
        new_order, new_trucks, new_value = search.descend(order, trucks, value, int(sample))
        if new_value < value:
            order, trucks, value = new_order, new_trucks, new_value
    else:
        stopped_by = "iterations"
    if search.out_of_time():
        stopped_by = "time_limit"
    info = {"phase2": phase2, "decodes": search.decodes, "stopped_by": stopped_by}
    return _finish(problem, "3P", order, trucks, began, seed, info)


@register_method(
    FleetProblem,
    "ILS",
    default=False,
    not_default="ILS runs only when named (--methods ILS): a search with a budget",
    style=(":", "P"),
)
def ils_fleet(
    problem: FleetProblem,
    seed: int = 0,
    time_limit: float | None = None,
    iterations: int = 30,
    sample: int | None = None,
    strength: int = 3,
    accept_worse: float = 0.01,
) -> Solution:
    """Iterated local search over the whole fleet (order and trucks, decoded greedily).

    Starts from the better of MMA's and SMMA's plans, descends (the VND of "3P", ``sample``
    random moves per neighbourhood, default ``2 n``), then ``iterations`` times perturbs the
    current encoding (``strength`` truck moves and shifts), descends, and accepts the result
    when it is at most ``accept_worse`` (relative) worse than the current one. Never worse
    than its start. ``info``: ``start_objective``, ``iterations`` (done), ``decodes``,
    ``stopped_by``.
    """
    began = time.perf_counter()
    why = _check_servable(problem)
    if why:
        return infeasible_solution(problem, "ILS", why, began)
    sample = 2 * problem.n if sample is None else sample
    _check(iterations, sample, strength, accept_worse)
    search = _Search(problem, np.random.default_rng(seed), Deadline(time_limit))
    starts = [_encoding(construct(problem, rule)) for rule in ("MMA", "SMMA")]
    scored = [(search.value(o, t), i) for i, (o, t) in enumerate(starts)]
    start_value, index = min(scored)
    order, trucks = starts[index]
    value = start_value
    order, trucks, value = search.descend(order, trucks, value, int(sample))
    best = (value, order, trucks)
    done = 0
    stopped_by = "iterations"
    for _ in range(int(iterations)):
        if search.out_of_time():
            stopped_by = "time_limit"
            break
        new_order, new_trucks = search.perturb(order, trucks, int(strength))
        new_value = search.value(new_order, new_trucks)
        new_order, new_trucks, new_value = search.descend(
            new_order, new_trucks, new_value, int(sample)
        )
        done += 1
        if new_value <= value * (1.0 + accept_worse):
            order, trucks, value = new_order, new_trucks, new_value
        if new_value < best[0]:
            best = (new_value, new_order, new_trucks)
    if search.out_of_time():
        stopped_by = "time_limit"
    info = {
        "start_objective": start_value,
        "iterations": done,
        "decodes": search.decodes,
        "stopped_by": stopped_by,
    }
    if not math.isfinite(best[0]):
        raise InstanceError("ILS found no plan")  # cannot happen: the starts are feasible
    return _finish(problem, "ILS", best[1], best[2], began, seed, info)


@register_improver(FleetProblem)
def improve_fleet(
    problem: FleetProblem, plan: Any, time_limit: float | None = None, seed: int = 0
) -> Any:
    """The better of ``plan`` and :func:`ils_fleet`'s (within ``time_limit``): never worse.

    The improver of the fleet's label search (:func:`taopt.models.fleet.solve_fleet` takes it
    as ``improve`` and calls it before searching, so pruning starts at a good plan;
    :func:`taopt.solve` passes it, the model imports no heuristic).
    """
    from taopt.errors import FeasibilityError
    from taopt.fleet.evaluate import as_plan, evaluate_fleet

    found = ils_fleet(problem, seed=seed, time_limit=time_limit)
    if plan is None:
        return found.solution
    try:
        value = evaluate_fleet(problem, as_plan(plan))
    except FeasibilityError:
        return found.solution
    return found.solution if found.objective < value else plan


__all__ = ["ils_fleet", "improve_fleet", "three_phase", "truck_routes"]
