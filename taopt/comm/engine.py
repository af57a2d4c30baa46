"""The event-driven simulation of chapter 4: time, motion, links, knowledge and messages.

One engine, many policies (STYLE "An engine and its policies"): the engine owns time, the
vehicles' positions, the communication graph (4.3), what each vehicle knows (4.4) and the
message counter; an algorithm (CAA, DAA, HDA in :mod:`taopt.heuristics.comm`) is a
:class:`Policy` that reacts when a group of vehicles becomes newly connected, by exchanging
messages (:meth:`Group.send`, :meth:`Group.flood_or`, :meth:`Group.flood_min`) and setting
routes. Policies never advance time.

Motion and events
-----------------
Vehicles drive at unit speed on straight segments towards the first target of their route
``o_j`` and stop when their route is empty (they know all their targets are visited,
§4.2). Between events every vehicle moves on a straight line, so the next event is
computed exactly, with no time step:

* an **arrival**: vehicle j reaches the target q at the head of its route after
  ``|q - p_j|`` seconds; it visits q (``s_jq = 1``, (4.4)) and drops it from its route;
* a **link change**: two vehicles come within ``r`` of each other, or move apart beyond
  it: the roots of ``|Δp + Δv τ|² = r²`` on their current segments (4.3).

After each event the engine recomputes the connected components of the communication
graph. A component whose members were not all in one component just before is *newly
connected* (thesis §4.3.1: "no new members compared with R_i(t-1)" means no re-planning);
its policy runs its synchronous message rounds at that instant (the thesis assumes
communication is instantaneous). At ``t = 0`` every vehicle first plans its own route
(:meth:`Policy.initial_route`, CAA with ``R_i = {j}``, §4.3.2) and every component with two
or more vehicles is newly connected.

Knowledge is exchanged only in those message rounds: a vehicle learns that a target was
visited when it visits it itself or when a newly connected group merges its ``s`` (4.5).
The run ends when every target has been visited; (4.1) counts the distance driven up to
that moment (``d_j`` "when all the targets are visited"), so a vehicle still driving to a
target someone else already visited stops counting then.

Checks made at every event (``check=True``)
-------------------------------------------
* Lemma 4.3(i): every unvisited target is on the route of some vehicle able to visit it
  (violations are counted in ``info["invariant_violations"]``, and raise
  :class:`~taopt.errors.FeasibilityError` with ``strict=True``);
* Lemma 4.3(ii): a policy may only add to a vehicle's knowledge;
* a policy may only give a vehicle targets of its ability, each once.

Determinism: the only randomness is a policy's (CAA's leader choice), drawn from the
engine's ``numpy.random.Generator`` seeded with the run's seed; events at the same time are
handled in vehicle order. Same seed, same run, bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from taopt.comm.bytes import NUMBER_BYTES, message_numbers
from taopt.comm.problem import CommProblem
from taopt.comm.routes import distances_from, route_length
from taopt.comm.trajectories import Trajectories, evaluate_trajectories
from taopt.errors import ConvergenceError, FeasibilityError, SolverError

#: Events closer than this (seconds) are simultaneous.
TIME_TOLERANCE = 1e-9
_BIG = np.iinfo(np.int64).max
#: Guard against a run that never ends (a policy bug): events per (target + vehicle pair).
MAX_EVENTS_FACTOR = 200


def components(linked: np.ndarray) -> np.ndarray:
    """Connected components of the communication graph: each vehicle's smallest reachable index.

    Label propagation on the (m, m) boolean adjacency (a handful of numpy steps for the
    fleet sizes of chapter 4, where a sparse-graph call costs more than the work).
    """
    m = linked.shape[0]
    hear = linked | np.eye(m, dtype=bool)
    labels = np.arange(m)
    while True:
        spread = np.where(hear, labels[None, :], m).min(axis=1)
        if np.array_equal(spread, labels):
            return labels
        labels = spread


def initially_connected(problem: CommProblem) -> bool:
    """Whether the vehicles' communication graph (4.3) is connected at t = 0."""
    gap = problem.vehicles[:, None, :] - problem.vehicles[None, :, :]
    linked = np.hypot(gap[..., 0], gap[..., 1]) <= problem.comm_range
    return bool((components(linked) == 0).all())


class Policy(Protocol):
    """A chapter 4 algorithm, as the engine sees it."""

    name: str

    def initial_route(self, problem: CommProblem, vehicle: int) -> list[int]:
        """Vehicle ``vehicle``'s route at t = 0, planned alone (§4.3.2)."""
        ...

    def on_connect(self, group: Group) -> None:
        """React to a newly connected group: send messages, set routes and knowledge."""
        ...


@dataclass
class _Tally:
    messages: int = 0
    numbers: int = 0
    rounds: int = 0
    broadcast: int = 0  # numbers if each round's message were one broadcast per sender
    by_kind: dict[str, int] = field(default_factory=dict)

    def add(self, kind: str, messages: int, numbers: int, rounds: int, broadcast: int) -> None:
        self.messages += messages
        self.numbers += numbers
        self.rounds += rounds
        self.broadcast += broadcast
        self.by_kind[kind] = self.by_kind.get(kind, 0) + numbers


class Group:
    """A newly connected group of vehicles as its policy sees it.

    Attributes
    ----------
    time : float
    members : (k,) int array
        Vehicle indices, ascending; "member i" below means ``members[i]``.
    adjacency : (k, k) bool array
        ``adjacency[i, l]``: members i and l are within range (4.3); the diagonal is True
        (a vehicle hears itself, as ``R^d_j`` contains j in the thesis).
    problem : CommProblem
    rng : numpy.random.Generator
        The run's generator (CAA draws its leader from it).
    """

    def __init__(self, sim: Simulation, members: np.ndarray) -> None:
        self._sim = sim
        self.time = sim.time
        self.members = members
        self.problem = sim.problem
        self.rng = sim.rng
        k = len(members)
        self.adjacency = sim.linked[np.ix_(members, members)] | np.eye(k, dtype=bool)
        self._degree = self.adjacency.sum(axis=1) - 1
        self._tally = _Tally()
        self.notes: dict[str, Any] = {}
        # hop distances: r synchronous rounds of a neighbourhood OR / min reach exactly the
        # members at most r hops away, so a flood is computed on those balls in one step
        hops = np.full((k, k), k, dtype=np.int64)
        reach = np.eye(k, dtype=bool)
        hops[reach] = 0
        step = self.adjacency.astype(np.int64)
        for d in range(1, k):
            grown = (reach.astype(np.int64) @ step) > 0
            hops[grown & ~reach] = d
            if np.array_equal(grown, reach):
                break
            reach = grown
        self.hops = hops
        self._start: np.ndarray | None = None

    # -- what the members carry -------------------------------------------------------------
    @property
    def size(self) -> int:
        """|R_i(t)|."""
        return int(len(self.members))

    @property
    def positions(self) -> np.ndarray:
        """(k, 2) current positions p_j(t)."""
        return self._sim.pos[self.members].copy()

    @property
    def abilities(self) -> np.ndarray:
        """(k,) ability codes (indices into ``problem.attributes``)."""
        return self.problem.vehicle_code[self.members]

    @property
    def routes(self) -> list[list[int]]:
        """Current routes o_j(t) (copies)."""
        return [list(self._sim.routes[j]) for j in self.members]

    @property
    def knowledge(self) -> np.ndarray:
        """s_j(t) (4.4) of every member, a (k, n) bool array (a copy)."""
        return self._sim.knows[self.members].copy()

    @property
    def joint(self) -> np.ndarray:
        """(k, k) u_jk: time of the last adopted reassignment j and k took part in together.

        NaN when they never did. (The thesis's ``u_j(0) = 0`` cannot tell "never" from "at
        t = 0"; NaN can.)
        """
        return self._sim.joint[np.ix_(self.members, self.members)].copy()

    @property
    def last(self) -> np.ndarray:
        """(k,) ``max_k u_jk``: time of each member's last adopted joint reassignment (NaN: never)."""
        return self._sim.last[self.members].copy()

    @property
    def start_distances(self) -> np.ndarray:
        """Distance from each member's current position to every target, a (k, n) array."""
        if self._start is None:
            sim = self._sim
            self._start = np.array([distances_from(sim.pos[j], sim.targets) for j in self.members])
            self._start.setflags(write=False)
        return self._start

    @property
    def target_distances(self) -> np.ndarray:
        """(n, n) target–target distances."""
        return self._sim.dist

    def route_length(self, i: int, route: Sequence[int] | None = None) -> float:
        """Projected distance d(o) of member i driving ``route`` (default: its route)."""
        j = int(self.members[i])
        sim = self._sim
        return route_length(
            self.start_distances[i], sim.routes[j] if route is None else route, sim.dist
        )

    # -- messages ------------------------------------------------------------------------------
    def send(self, kind: str, rounds: int) -> None:
        """Count ``rounds`` synchronous rounds of messages of ``kind`` (see :mod:`.bytes`).

        In each round every member sends one message to each direct neighbour.
        """
        rounds = int(rounds)
        if rounds <= 0:
            return
        problem = self.problem
        per_sender = message_numbers(
            kind, problem.n, problem.m, self._sim.class_size[self.abilities]
        )
        numbers = int(np.sum(self._degree * per_sender)) * rounds
        speakers = np.broadcast_to(per_sender, self._degree.shape)[self._degree > 0]
        broadcast = int(np.sum(speakers)) * rounds
        self._tally.add(kind, int(self._degree.sum()) * rounds, numbers, rounds, broadcast)

    def flood_or(self, values: np.ndarray, rounds: int, kind: str) -> np.ndarray:
        """``rounds`` rounds in which every member ORs its neighbours' boolean rows into its own.

        ``values`` is (k, ...) bool, one row per member. After r rounds member i holds the OR
        of the rows of the members at most r hops away; that is what is returned. All the
        rounds are counted (:meth:`send`).
        """
        rows = np.asarray(values, dtype=bool).reshape(self.size, -1)
        ball = (self.hops <= int(rounds)).astype(np.int64)
        self.send(kind, rounds)
        return ((ball @ rows.astype(np.int64)) > 0).reshape(np.shape(values))

    def flood_min(
        self, costs: np.ndarray, ids: np.ndarray, rounds: int, kind: str
    ) -> tuple[np.ndarray, np.ndarray]:
        """``rounds`` rounds of (3.7) / Alg. 5 l. 19–23: keep the neighbours' smallest bid.

        ``costs`` (k, T) float and ``ids`` (k, T) int: member i's bid on each of T items and
        the vehicle it names. Each round, member i takes, per item, the lexicographically
        smallest (cost, id) over its neighbours and itself; after r rounds it holds the
        smallest over the members at most r hops away, which is what is returned (as
        (k, T) arrays, one row per member; read-only).
        """
        c = np.asarray(costs, dtype=float)
        b = np.asarray(ids, dtype=np.int64)
        if b.shape != c.shape:
            b = np.broadcast_to(b, c.shape)
        ball = self.hops <= int(rounds)
        big = _BIG
        self.send(kind, rounds)
        if ball.all():
            c_min = c.min(axis=0)
            b_min = np.where(c == c_min, b, big).min(axis=0)
            shape = c.shape
            return np.broadcast_to(c_min, shape), np.broadcast_to(b_min, shape)
        heard = np.where(ball[:, :, None], c[None, :, :], np.inf)
        c_min = heard.min(axis=1)
        tied = ball[:, :, None] & (c[None, :, :] == c_min[:, None, :])
        b_min = np.where(tied, b[None, :, :], big).min(axis=1)
        return c_min, b_min

    # -- what a policy may change ----------------------------------------------------------------
    def set_knowledge(self, knowledge: np.ndarray) -> None:
        """Set the members' s_j; only additions are allowed (Lemma 4.3(ii))."""
        sim = self._sim
        new = np.asarray(knowledge, dtype=bool)
        old = sim.knows[self.members]
        lost = old & ~new
        if lost.any():
            i, q = (int(v) for v in np.argwhere(lost)[0])
            raise FeasibilityError(
                f"vehicle {self.members[i]} would forget that target {q} was visited "
                "(Lemma 4.3(ii))"
            )
        sim.knows[self.members] = new

    def set_route(self, i: int, route: Sequence[int]) -> None:
        """Give member i the route ``route`` (targets of its ability, each once)."""
        sim = self._sim
        j = int(self.members[i])
        route = [int(q) for q in route]
        if len(set(route)) != len(route):
            raise FeasibilityError(f"route of vehicle {j} repeats a target: {route}")
        code = self.problem.vehicle_code[j]
        for q in route:
            if self.problem.target_code[q] != code:
                raise FeasibilityError(
                    f"vehicle {j} (ability {self.problem.vehicle_ability[j]!r}) cannot take "
                    f"target {q} (attribute {self.problem.target_attribute[q]!r})"
                )
        sim.routes[j] = route

    def record_joint(self, indices: Sequence[int]) -> None:
        """(4.15): members ``indices`` adopted a joint reassignment now (u_jk <- t)."""
        vehicles = self.members[np.asarray(list(indices), dtype=np.int64)]
        if len(vehicles) < 2:
            return
        sim = self._sim
        grid = np.ix_(vehicles, vehicles)
        sim.joint[grid] = self.time
        sim.last[vehicles] = self.time


@dataclass
class Run:
    """What a simulation produced: the trajectories, (4.1), and what happened on the way."""

    trajectories: Trajectories
    objective: float
    info: dict[str, Any]


class Simulation:
    """One run of a policy on a problem (use :func:`simulate`)."""

    def __init__(
        self,
        problem: CommProblem,
        policy: Policy,
        seed: int | None = 0,
        check: bool = True,
        strict: bool = False,
    ) -> None:
        self.problem = problem
        self.policy = policy
        #: a taopt.runtime.Deadline, or None: run() raises SimulationStopped when it expires
        self.deadline: Any = None
        self.rng = np.random.default_rng(seed)
        self.check = check
        self.strict = strict
        n, m = problem.n, problem.m
        self.targets = problem.targets
        self.dist = problem.distances[:n, :n]
        self.class_size = np.bincount(problem.target_code, minlength=len(problem.attributes))
        self.time = 0.0
        self.pos = np.array(problem.vehicles, dtype=float)
        self.vel = np.zeros((m, 2))
        self.heading: list[int | None] = [None] * m
        self.arrive_at = np.full(m, np.inf)
        self.driven = np.zeros(m)
        self.routes: list[list[int]] = [list(policy.initial_route(problem, j)) for j in range(m)]
        self.knows = np.zeros((m, n), dtype=bool)
        self.visited = np.zeros(n, dtype=bool)
        self.joint = np.full((m, m), np.nan)
        self.last = np.full(m, np.nan)
        self.paths: list[list[tuple[float, float, float]]] = [
            [(0.0, float(x), float(y))] for x, y in self.pos
        ]
        self.visits: list[list[tuple[int, int]]] = [[] for _ in range(m)]
        first, second = np.triu_indices(m, k=1)
        self.pair_first, self.pair_second = first, second
        gap = self.pos[second] - self.pos[first]
        self.pair_linked = np.hypot(gap[:, 0], gap[:, 1]) <= problem.comm_range
        self.change_at = np.full(first.size, np.inf)
        self.linked = np.zeros((m, m), dtype=bool)
        self.linked[first, second] = self.pair_linked
        self.linked[second, first] = self.pair_linked
        self.component = np.arange(m)
        self.events = 0
        self.arrivals = 0
        self.link_changes = 0
        self.tally = _Tally()
        self.group_log: list[dict[str, Any]] = []
        self.projected: list[float] = []
        self.violations = 0
        self.first_violation: str | None = None
        self.max_group_rounds = 0
        self.numbers_at_start = 0
        self.broadcast_at_start = 0

    # -- the loop ------------------------------------------------------------------------------
    def run(self) -> Run:
        problem = self.problem
        self._check_routes_initial()
        self.projected.append(self.projected_total())  # Σ_j d(o_j(0)) of Proposition 4.10
        self._regroup()
        self._steer(range(problem.m))
        self._schedule_links()
        self._after_event(updated=True)
        limit = MAX_EVENTS_FACTOR * (problem.n + problem.m * problem.m + 10)
        while not self.visited.all():
            arrive = float(self.arrive_at.min())
            change = float(self.change_at.min()) if self.change_at.size else math.inf
            when = min(arrive, change)
            if not math.isfinite(when):
                q = int(np.flatnonzero(~self.visited)[0])
                raise ConvergenceError(
                    f"{self.policy.name}: at t={self.time:.6g} no vehicle moves but target {q} "
                    "is unvisited (Proposition 4.4 fails)"
                )
            self.events += 1
            if self.deadline is not None and self.deadline.expired():
                raise SimulationStopped(
                    f"{self.policy.name}: time limit reached at t={self.time:.6g} after "
                    f"{self.events} events, {int(self.visited.sum())} of {problem.n} visited"
                )
            if self.events > limit:
                raise ConvergenceError(
                    f"{self.policy.name}: more than {limit} events by t={self.time:.6g}; the "
                    "run does not end"
                )
            self._advance(when)
            dirty: set[int] = set()
            if arrive <= when + TIME_TOLERANCE:
                for j in np.flatnonzero(self.arrive_at <= when + TIME_TOLERANCE):
                    self._arrive(int(j))
                    dirty.add(int(j))
            updated = False
            toggled = np.flatnonzero(self.change_at <= when + TIME_TOLERANCE)
            if toggled.size:
                self.link_changes += int(toggled.size)
                self.pair_linked[toggled] = ~self.pair_linked[toggled]
                first, second = self.pair_first[toggled], self.pair_second[toggled]
                self.linked[first, second] = self.pair_linked[toggled]
                self.linked[second, first] = self.pair_linked[toggled]
                touched = self._regroup()
                updated = bool(touched)
                dirty |= touched
            if self._steer(sorted(dirty)) or toggled.size or dirty:
                self._schedule_links()
            self._after_event(updated)
        return self._finish()

    # -- events --------------------------------------------------------------------------------
    def _schedule_links(self) -> None:
        """Absolute time of each pair's next link change (inf: never on current segments).

        With ``Δ = p_k - p_j`` and ``w = v_k - v_j``, the pair is at distance r when
        ``|w|² τ² + 2 (Δ·w) τ + |Δ|² - r² = 0`` (4.3): an unlinked pair links at the smaller
        root if it approaches, a linked pair unlinks at the larger root.
        """
        if self.pair_first.size == 0:
            return
        r = self.problem.comm_range
        i, k = self.pair_first, self.pair_second
        gap = self.pos[k] - self.pos[i]
        rel = self.vel[k] - self.vel[i]
        a = (rel * rel).sum(axis=1)
        b = 2.0 * (gap * rel).sum(axis=1)
        c = (gap * gap).sum(axis=1) - r * r
        disc = b * b - 4.0 * a * c
        with np.errstate(divide="ignore", invalid="ignore"):
            q = -0.5 * (b + np.copysign(np.sqrt(np.maximum(disc, 0.0)), b))
            one, two = q / a, c / q  # the roots, numerically stable
        linked = self.pair_linked
        moving = a > 0
        times = np.full(i.size, np.inf)
        enter = ~linked & moving & (b < 0) & (disc >= 0)
        times[enter] = np.maximum(np.minimum(one, two)[enter], 0.0)
        leave = linked & moving
        later = np.where(disc >= 0, np.maximum(one, two), 0.0)
        times[leave] = np.maximum(later[leave], 0.0)
        self.change_at = self.time + times

    def _advance(self, when: float) -> None:
        step = when - self.time
        if step > 0:
            moving = self.arrive_at < math.inf
            self.pos[moving] += self.vel[moving] * step
            self.driven[moving] += step
        self.time = when

    def _mark(self, j: int) -> int:
        x, y = self.pos[j]
        point = (float(self.time), float(x), float(y))
        if self.paths[j][-1] != point:
            self.paths[j].append(point)
        return len(self.paths[j]) - 1

    def _arrive(self, j: int) -> None:
        q = self.routes[j].pop(0)
        self.pos[j] = self.targets[q]
        self.heading[j] = None
        self.arrive_at[j] = math.inf
        self.vel[j] = 0.0
        self.knows[j, q] = True
        self.visited[q] = True
        self.arrivals += 1
        self.visits[j].append((q, self._mark(j)))

    def _steer(self, vehicles: Any) -> bool:
        """Point each of ``vehicles`` at the head of its route (or stop it); True if any turned."""
        turned = False
        for j in vehicles:
            route = self.routes[j]
            head = route[0] if route else None
            if head == self.heading[j]:
                continue
            self._mark(j)
            self.heading[j] = head
            turned = True
            if head is None:
                self.vel[j] = 0.0
                self.arrive_at[j] = math.inf
                continue
            gap = self.targets[head] - self.pos[j]
            length = math.hypot(gap[0], gap[1])
            self.vel[j] = gap / length if length > 0 else 0.0
            self.arrive_at[j] = self.time + length
        return turned

    def _regroup(self) -> set[int]:
        """Recompute components; run the policy on each newly connected one.

        Returns the vehicles of the groups that ran (their routes may have changed).
        """
        labels = components(self.linked)
        before = self.component
        self.component = labels
        touched: set[int] = set()
        for label in np.unique(labels):
            members = np.flatnonzero(labels == label)
            if members.size < 2 or np.unique(before[members]).size < 2:
                continue
            self._connect(members)
            touched.update(int(j) for j in members)
        return touched

    def _connect(self, members: np.ndarray) -> None:
        group = Group(self, members)
        before = [list(self.routes[j]) for j in members]
        self.policy.on_connect(group)
        tally = group._tally
        self.tally.messages += tally.messages
        self.tally.numbers += tally.numbers
        self.tally.rounds += tally.rounds
        self.tally.broadcast += tally.broadcast
        if self.time == 0.0:
            self.numbers_at_start += tally.numbers
            self.broadcast_at_start += tally.broadcast
        for kind, value in tally.by_kind.items():
            self.tally.by_kind[kind] = self.tally.by_kind.get(kind, 0) + value
        self.max_group_rounds = max(self.max_group_rounds, tally.rounds)
        first, second = np.nonzero(np.triu(group.adjacency, k=1))
        self.group_log.append(
            {
                "time": float(self.time),
                "members": [int(j) for j in members],
                "positions": self.pos[members].tolist(),
                "links": [
                    [int(members[a]), int(members[b])] for a, b in zip(first, second, strict=True)
                ],
                "rounds": tally.rounds,
                "messages": tally.messages,
                "numbers": tally.numbers,
                "routes_before": before,
                "routes_after": [list(self.routes[j]) for j in members],
                **group.notes,
            }
        )

    # -- checks and bookkeeping ----------------------------------------------------------------
    def _check_routes_initial(self) -> None:
        code = self.problem.vehicle_code
        for j, route in enumerate(self.routes):
            bad = [q for q in route if self.problem.target_code[q] != code[j]]
            if bad or len(set(route)) != len(route):
                raise FeasibilityError(
                    f"{self.policy.name}: initial route of vehicle {j} is invalid: {route}"
                )

    def projected_total(self) -> float:
        """Distance driven so far plus every vehicle's projected d(o_j): f of Lemma 4.7."""
        remaining = sum(
            route_length(distances_from(self.pos[j], self.targets), route, self.dist)
            for j, route in enumerate(self.routes)
            if route
        )
        return float(self.driven.sum() + remaining)

    def _after_event(self, updated: bool) -> None:
        if updated:
            self.projected.append(self.projected_total())
        if not self.check:
            return
        covered = np.zeros(self.problem.n, dtype=bool)
        for route in self.routes:
            covered[route] = True
        lost = ~self.visited & ~covered
        if lost.any():
            self.violations += 1
            q = int(np.flatnonzero(lost)[0])
            message = (
                f"{self.policy.name}: at t={self.time:.6g} target {q} is unvisited and on no "
                "vehicle's route (Lemma 4.3(i))"
            )
            if self.first_violation is None:
                self.first_violation = message
            if self.strict:
                raise FeasibilityError(message)

    def _finish(self) -> Run:
        for j in range(self.problem.m):
            self._mark(j)
        trajectories = Trajectories(
            [np.array(p) for p in self.paths], [list(v) for v in self.visits]
        )
        objective = evaluate_trajectories(self.problem, trajectories)
        projected = self.projected
        increases = [
            b - a
            for a, b in zip(projected[:-1], projected[1:], strict=True)
            if b > a + 1e-9 * max(1.0, abs(a))
        ]
        info = {
            "bytes": self.tally.numbers * NUMBER_BYTES,
            "numbers": self.tally.numbers,
            "messages": self.tally.messages,
            "rounds": self.tally.rounds,
            "max_group_rounds": self.max_group_rounds,
            "group_events": len(self.group_log),
            "replans": sum(1 for g in self.group_log if g.get("reassigned")),
            "events": self.events,
            "arrivals": self.arrivals,
            "link_changes": self.link_changes,
            "end_time": float(self.time),
            "projected": list(projected),
            "projected_increases": len(increases),
            "initial_total": projected[0],
            "invariant_violations": self.violations,
            "first_violation": self.first_violation,
            "numbers_by_kind": dict(self.tally.by_kind),
            # the same messages counted two other ways (for comparisons, not the model):
            # once per sender and round (a radio broadcast), and without the groups at t = 0
            "broadcast_bytes": self.tally.broadcast * NUMBER_BYTES,
            "bytes_after_start": (self.tally.numbers - self.numbers_at_start) * NUMBER_BYTES,
            "broadcast_bytes_after_start": (self.tally.broadcast - self.broadcast_at_start)
            * NUMBER_BYTES,
            "groups": self.group_log,
        }
        return Run(trajectories, objective, info)


class SimulationStopped(SolverError):
    """A run stopped by its :attr:`Simulation.deadline` before every target was visited."""


def simulate(
    problem: CommProblem,
    policy: Policy,
    seed: int | None = 0,
    *,
    check: bool = True,
    strict: bool = False,
) -> Run:
    """Run ``policy`` on ``problem`` from t = 0 until every target is visited.

    Parameters
    ----------
    problem : CommProblem
    policy : Policy
        E.g. ``taopt.heuristics.comm.DAA()``.
    seed : int
        Seeds the run's generator (CAA's leader choice).
    check : bool
        Check Lemma 4.3(i) after every event (counted in ``info["invariant_violations"]``).
    strict : bool
        Raise FeasibilityError at the first violation instead of counting.

    Returns
    -------
    Run
        ``trajectories`` (the payload), ``objective`` (4.1) from
        :func:`~taopt.comm.trajectories.evaluate_trajectories`, and ``info``: ``bytes``,
        ``numbers``, ``messages``, ``rounds`` (synchronous rounds, all groups),
        ``broadcast_bytes`` (each round's message counted once per sender, as one radio
        broadcast) and ``bytes_after_start`` (without the groups connected at t = 0) — the
        same messages counted differently, for comparisons —
        ``max_group_rounds`` (the most in one newly connected group, Theorem 4.5(ii)),
        ``group_events``, ``replans`` (groups that adopted a reassignment), ``events``,
        ``projected`` (Lemma 4.7's projected total after each update; the first is
        ``Σ_j d(o_j(0))`` of the routes planned alone, Proposition 4.10's bound),
        ``invariant_violations``, ``groups`` (a log of each newly connected group: time,
        members, positions, links, rounds, routes before and after).

    Raises
    ------
    ConvergenceError
        No vehicle moves while a target is unvisited (Proposition 4.4 fails), or the run
        exceeds its event budget.
    FeasibilityError
        A policy broke a rule (see the module notes), or ``strict`` and Lemma 4.3(i) fails.
    """
    return Simulation(problem, policy, seed=seed, check=check, strict=strict).run()


__all__ = [
    "Policy",
    "Group",
    "Run",
    "Simulation",
    "simulate",
    "SimulationStopped",
    "components",
    "initially_connected",
    "TIME_TOLERANCE",
]
