"""Interleaved sorties for trucks carrying several drones: a beam decoder and a local search
over sortie lists (issue 32's incumbent).

The iterated local search of :mod:`taopt.heuristics.fleet_search` places one customer at a
time by least marginal makespan; it cannot build the plans in which the drones of one truck
*interleave* around a truck that drives ahead (launch drone 1 at stop a, drive to b, launch
drone 2, recover drone 1 at c and relaunch it, ...), and :mod:`taopt.fleet.synced` covers only
plans where every drone is recovered together. At n = 5, one truck with two or three drones,
both stayed 10-40 % above the certified optimum.

Encoding (one truck k)
    A *sortie list*: the truck's sorties in launch order, each ``(drone, customers)`` with
    1..c customers in flying order. A list is *valid* when every precedence predecessor of a
    customer on the same truck is served earlier on its own sortie, on a sortie launched
    before, or on a later sortie of another drone: the drone then waits at the customer, its
    sortie's times stay pending until the predecessor is served, and the truck cannot
    recover it before (a list whose waits close a cycle decodes to ``inf``).

Decoder (``_Decoder.decode``, a beam over the truck's stop sequence)
    The sorties are launched in list order. Before launching a sortie of drone d, the truck
    recovers, in any order, a set of airborne drones that holds d when d is airborne: each at
    the stop where its recovery is earliest, d's own (when it comes last) at one of the
    :data:`NEAR_STOPS` stops of earliest recovery, the truck's stop or the stops nearest the
    sortie's first customer. It then drives to one of the :data:`NEAR_STOPS` stops from which
    the drone reaches the first customer earliest (or stays) and launches; a variant also
    recovers there every other airborne drone in range. A label holds the truck's stop and
    time, each airborne drone's last customer, time there and distance flown, and every service
    time so far; each launch expands every label into these
    children and keeps the ``width`` best by ``_key``. After the last launch the airborne
    drones are recovered greedily (least recovery time) and, under ``"return"``, the truck
    drives home. Times follow :mod:`taopt.fleet.evaluate`'s rules (a drone waits at a customer
    for a predecessor or a release; a recovery is ``max(truck there, drone there) + τ``), so
    the decoded value is at least the plan's earliest-schedule value: every plan returned is
    re-scored by :func:`taopt.evaluate`. Every plan decoded is feasible by construction (range
    checked per sortie, each drone's sorties in order, every precedence satisfied by the times).

Search (:func:`interleave_plan`)
    Starts from the best decoded of the given plan's sorties (per truck, in launch order of its
    earliest schedule), the same reordered so that predecessors' sorties launch first, and one
    sortie per customer; then repeats random moves (relocate a customer to another sortie or
    to a new one, swap two customers, give a sortie to another drone, move a sortie in the
    launch order), keeping a move when the decoded value does not grow; after :data:`STALL` moves without improvement
    it restarts from the best list with ``strength`` random moves. Seeded (``numpy``
    generator), stopped by ``iterations`` (tests) or ``time_limit`` (wall-clock). With several
    trucks each truck's sortie list is searched in turn, the other trucks' plans fixed and the
    service times of its customers' cross-truck predecessors (in the whole plan's earliest
    schedule) taken as releases; a truck's new plan is kept only when the whole plan's value
    under :func:`taopt.evaluate` drops.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np

from taopt.errors import FeasibilityError
from taopt.fleet.evaluate import as_plan, evaluate_fleet, schedule
from taopt.fleet.problem import FleetPlan, FleetProblem, Sortie
from taopt.runtime import Deadline

#: Candidate stops per customer: the launch (recovery) stop of a sortie is one of the stops
#: nearest its first (last) customer, or the stop where the truck stands.
NEAR_STOPS = 4

#: Beam width of the decoder during the search (the best list is decoded once more with
#: :data:`FINAL_WIDTH`).
SEARCH_WIDTH = 3

#: Beam width of the final decode of the best sortie list.
FINAL_WIDTH = 12

#: Moves without improvement before the search restarts from the best list, perturbed.
STALL = 60

#: A move is kept when its decoded value is at most this much (relative) above the current.
ACCEPT_WORSE = 0.0

INF = math.inf

#: A sortie list: per sortie ``(drone, customers)`` in launch order.
SortieList = list[tuple[int, tuple[int, ...]]]


def _key(label: tuple[Any, ...]) -> float:
    """Beam order of a label: the mean of its truck's and airborne drones' clocks plus half
    the latest (on the n = 5 optima's sortie lists this kept the decoded value nearest the
    optimum among five such keys)."""
    T, drones = label[1], label[2]
    clocks = [T] + [x[4] if x[1] is None else x[1] for x in drones if x is not None]
    return sum(clocks) / len(clocks) + 0.5 * max(clocks)


class _Decoder:
    """One truck's beam decoder (module docstring)."""

    def __init__(
        self,
        problem: FleetProblem,
        k: int,
        release: np.ndarray | None = None,
        near: int = NEAR_STOPS,
    ) -> None:
        p = problem
        self.problem = p
        self.k = k
        self.D = p.drones[k]
        self.c = p.capacity
        self.tt = np.asarray(p.truck_time, dtype=float)
        self.fs = np.asarray(p.flight_stop, dtype=float)
        self.fc = np.asarray(p.flight_customer, dtype=float)
        self.vd = float(p.v_drone)
        self.tau = float(p.service_time)
        self.limit = float(p.flight_limit)
        self.depot = int(p.depot)
        self.returns = p.objective == "return"
        self.near = [
            [int(w) for w in np.argsort(self.fs[j], kind="stable")[:near]] for j in range(p.n)
        ]
        self.near_count = max(int(near), 1)
        self.preds: list[list[int]] = [[] for _ in range(p.n)]
        for r, j in p.precedences:
            self.preds[int(j)].append(int(r))
        self.release = np.zeros(p.n) if release is None else np.asarray(release, dtype=float)
        self.mine: set[int] = set()

    def valid(self, sorties: SortieList) -> bool:
        """Sizes 1..c, drones in range, and every same-truck predecessor of a customer served
        earlier on its sortie, on an earlier sortie, or on a later sortie of another drone
        (the drone then waits at the customer; the decoder finds any deadlock)."""
        where = {j: (i, d) for i, (d, cs) in enumerate(sorties) for j in cs}
        seen: set[int] = set()
        for i, (d, cs) in enumerate(sorties):
            if not 1 <= len(cs) <= self.c or not 0 <= d < self.D:
                return False
            for j in cs:
                for r in self.preds[j]:
                    if r in seen or r not in where:
                        continue
                    if where[r][0] <= i or where[r][1] == d:
                        return False
                seen.add(j)
        return True

    def decode(
        self, sorties: SortieList, width: int, start: float = 0.0
    ) -> tuple[float, list[tuple[Any, ...]] | None]:
        """The best value of the sortie list over the beam and its events (None when no
        label survives: a sortie out of range from every candidate stop).

        A label is ``(parent, T, drones, w, last, times, events)``: the truck at stop w ready
        at T, per drone None (aboard) or (last customer, time there, distance flown), the last
        service so far, the service times (dict), the events added by its transition."""
        fs, fc, tt, vd, tau, limit = self.fs, self.fc, self.tt, self.vd, self.tau, self.limit
        self.mine = {j for _, cs in sorties for j in cs}
        root: tuple[Any, ...] = (None, start, (None,) * self.D, self.depot, 0.0, {}, ())
        beam: list[tuple[Any, ...]] = [root]
        for d, cs in sorties:
            first, lastc = cs[0], cs[-1]
            inner = sum(float(fc[a, b]) for a, b in zip(cs[:-1], cs[1:], strict=False))
            back = inner + float(fs[lastc, self.near[lastc][0]])
            children: dict[tuple[Any, ...], tuple[float, tuple[Any, ...]]] = {}
            for label in beam:
                options: list[tuple[int, float, tuple[Any, ...], list[tuple[Any, ...]]]] = []
                for w, T, drones, before, own in self._early(label, d):
                    air = drones[d]
                    if air is None or not own:
                        options.append((w, T, drones, before))
                        continue
                    ac, aF, aused = air
                    for b in self._recoveries(w, T, ac, aF, aused, first):
                        R = max(T + tt[w, b], aF + fs[ac, b] / vd) + tau
                        state = list(drones)
                        state[d] = None
                        options.append((b, R, tuple(state), [*before, ("rec", d, b)]))
                last, times = label[4], label[5]
                for b, T1, drones, events in options:
                    for a in self._launches(b, T1, first, back):
                        L = T1 + tt[b, a]
                        new_times = dict(times)
                        used = float(fs[first, a]) + inner
                        new_drones: list[Any] = list(drones)
                        t = self._chain(a, L, cs, new_times)
                        if t is None:  # a predecessor on a later sortie: times pending
                            new_drones[d] = (lastc, None, used, a, L, cs)
                            t = last
                        else:
                            new_drones[d] = (lastc, t, used)
                        t = max(t, self._resolve(new_drones, new_times))
                        variants: list[tuple[float, tuple[Any, ...], tuple[Any, ...]]] = [
                            (L, tuple(new_drones), ())
                        ]
                        # the variant that also recovers the other airborne drones here
                        T2, more = L, list(new_drones)
                        extra: list[tuple[Any, ...]] = []
                        for e, x in enumerate(new_drones):
                            if e == d or x is None or x[1] is None:
                                continue
                            if x[2] + fs[x[0], a] > limit + 1e-9:
                                continue
                            T2 = max(T2, x[1] + fs[x[0], a] / vd) + tau
                            more[e] = None
                            extra.append(("rec", e, a))
                        if extra:
                            variants.append((T2, tuple(more), tuple(extra)))
                        for T3, held_drones, tail in variants:
                            child = (
                                label,
                                T3,
                                held_drones,
                                a,
                                max(last, t),
                                new_times,
                                (*events, ("launch", d, a, cs), *tail),
                            )
                            sig = (a, tuple(None if x is None else x[0] for x in held_drones))
                            score = _key(child)
                            held = children.get(sig)
                            if held is None or score < held[0]:
                                children[sig] = (score, child)
            if not children:
                return INF, None
            ranked = sorted(children.values(), key=lambda item: item[0])
            beam = [child for _, child in ranked[:width]]
        best_value, best_events = INF, None
        for label in beam:
            value, closing = self._close(label)
            if value < best_value:
                best_value, best_events = value, self._trace(label) + closing
        return best_value, best_events

    def _chain(
        self, a: int, L: float, cs: tuple[int, ...], times: dict[int, float]
    ) -> float | None:
        """Service times of a sortie launched from stop a at L (written into ``times``; a
        drone waits at a customer for its predecessors and its release): the last one, or
        None (``times`` untouched) when a predecessor on this truck is not served yet."""
        fs, fc, vd, tau = self.fs, self.fc, self.vd, self.tau
        t = L
        prev = -1
        found: list[tuple[int, float]] = []
        for j in cs:
            t += (fs[j, a] if prev < 0 else fc[prev, j]) / vd + tau
            ready = self.release[j]
            for r in self.preds[j]:
                tr = times.get(r)
                if tr is None:
                    tr = next((x for y, x in found if y == r), None)
                if tr is None:
                    if r in self.mine:
                        return None
                    continue
                if tr > ready:
                    ready = tr
            if ready > t:
                t = ready
            found.append((j, t))
            prev = j
        times.update(found)
        return t

    def _resolve(self, drones: list[Any], times: dict[int, float]) -> float:
        """Settle the pending sorties whose predecessors are now served (in place); the
        latest service time settled (0 when none)."""
        latest = 0.0
        changed = True
        while changed:
            changed = False
            for e, x in enumerate(drones):
                if x is None or x[1] is not None:
                    continue
                t = self._chain(x[3], x[4], x[5], times)
                if t is not None:
                    drones[e] = (x[0], t, x[2])
                    latest = max(latest, t)
                    changed = True
        return latest

    def _close(self, label: tuple[Any, ...]) -> tuple[float, list[tuple[Any, ...]]]:
        """Recover every airborne drone (earliest first, each at its least-recovery stop) and
        the objective: the last service, or the truck's return home."""
        fs, tt, vd, tau = self.fs, self.tt, self.vd, self.tau
        _, T, drones, w, last, _, _ = label
        if any(x is not None and x[1] is None for x in drones):
            return INF, []  # a sortie still waits for a predecessor: a deadlock
        events: list[tuple[Any, ...]] = []
        airborne = sorted((x[1], d, x) for d, x in enumerate(drones) if x is not None)
        for _, d, (ac, aF, aused) in airborne:
            best: tuple[float, int] | None = None
            for b in {w, *self.near[ac]}:
                if aused + fs[ac, b] > self.limit + 1e-9:
                    continue
                R = max(T + tt[w, b], aF + fs[ac, b] / vd) + tau
                if best is None or R < best[0]:
                    best = (R, b)
            if best is None:  # cannot happen: the nearest stop was checked at launch
                return INF, []
            T, w = best
            events.append(("rec", d, w))
        if self.returns:
            return T + tt[w, self.depot], events
        return last, events

    def _early(
        self, label: tuple[Any, ...], d: int
    ) -> list[tuple[int, float, tuple[Any, ...], list[tuple[Any, ...]], bool]]:
        """The truck's states before it launches drone d's next sortie: every order of
        recoveries of a set of airborne drones that holds d when d is airborne, each at the
        stop where its recovery is earliest, but d's own recovery left to the caller
        (``own`` True, its candidate stops) when it comes last: ``(stop, time, drones,
        events, own)``."""
        _, T, drones, w, _, _, _ = label
        if drones[d] is not None and drones[d][1] is None:
            return []  # drone d waits for a predecessor not launched yet: no recovery
        others = [e for e, x in enumerate(drones) if x is not None and x[1] is not None and e != d]
        need = drones[d] is not None
        out: list[tuple[int, float, tuple[Any, ...], list[tuple[Any, ...]], bool]] = []
        fs, tt, vd, tau = self.fs, self.tt, self.vd, self.tau
        for size in range(len(others) + 1):
            for group in itertools.combinations(others, size):
                chosen = (*group, d) if need else group
                for seq in itertools.permutations(chosen):
                    own = need and seq[-1] == d
                    steps = seq[:-1] if own else seq
                    w1, T1, state, events = w, T, list(drones), []
                    for e in steps:
                        ac, aF, aused = state[e]
                        reach = aused + fs[ac] <= self.limit + 1e-9
                        when = np.where(reach, np.maximum(T1 + tt[w1], aF + fs[ac] / vd), INF)
                        b = int(np.argmin(when))
                        T1, w1 = float(when[b]) + tau, b
                        state[e] = None
                        events.append(("rec", e, b))
                    out.append((w1, T1, tuple(state), events, own))
        return out

    def _recoveries(
        self, w: int, T: float, ac: int, aF: float, aused: float, first: int
    ) -> list[int]:
        """Candidate recovery stops of a drone whose last customer is ``ac`` (reached at
        ``aF`` after flying ``aused``), the truck at w ready at T: the :data:`NEAR_STOPS`
        earliest recoveries in range, the truck's own stop and, in range, the stops nearest the
        next sortie's first customer."""
        reach = aused + self.fs[ac] <= self.limit + 1e-9
        when = np.maximum(T + self.tt[w], aF + self.fs[ac] / self.vd)
        when = np.where(reach, when, INF)
        m = self.near_count
        top = np.argpartition(when, m - 1)[:m] if len(when) > m else np.arange(len(when))
        out = {int(b) for b in top if math.isfinite(when[b])}
        out.update(b for b in (w, *self.near[first][:2]) if reach[b])
        return sorted(out)

    def _launches(self, b: int, T1: float, first: int, back: float) -> list[int]:
        """Candidate launch stops of a sortie whose first customer is ``first`` (its flight
        past the first leg at least ``back``), the truck at b ready at T1: the
        :data:`NEAR_STOPS` stops where the drone reaches ``first`` earliest (drive there,
        launch, fly) in range, and b itself when in range."""
        reach = self.fs[first] + back <= self.limit + 1e-9
        when = np.where(reach, T1 + self.tt[b] + self.fs[first] / self.vd, INF)
        m = self.near_count
        top = np.argpartition(when, m - 1)[:m] if len(when) > m else np.arange(len(when))
        out = {int(a) for a in top if math.isfinite(when[a])}
        if reach[b]:
            out.add(b)
        return sorted(out)

    @staticmethod
    def _trace(label: tuple[Any, ...]) -> list[tuple[Any, ...]]:
        chain = []
        while label is not None:
            chain.append(label[6])
            label = label[0]
        return [event for events in reversed(chain) for event in events]

    def route(self, events: list[tuple[Any, ...]]) -> tuple[list[int], list[list[Sortie]]]:
        """Truck k's stop sequence and its drones' sorties from decoded events (consecutive
        events at one stop share a position)."""
        route = [self.depot]
        flights: list[list[Sortie]] = [[] for _ in range(self.D)]
        pending: dict[int, tuple[int, tuple[int, ...]]] = {}
        for event in events:
            stop = event[2]
            if stop != route[-1]:
                route.append(stop)
            p = len(route) - 1
            if event[0] == "launch":
                pending[event[1]] = (p, event[3])
            else:
                launch, cs = pending.pop(event[1])
                flights[event[1]].append(Sortie(launch, cs, p))
        return route, flights


def sortie_list(problem: FleetProblem, plan: FleetPlan, k: int) -> SortieList:
    """Truck k's sorties in launch order of the plan's earliest schedule (ties: position)."""
    sched = schedule(problem, plan)
    launch_time = {(kk, d, i): t for kk, d, i, t, _, _ in sched.sorties}
    rows = []
    for d, flights in enumerate(plan.sorties[k]):
        for i, f in enumerate(flights):
            rows.append((launch_time[(k, d, i)], f.launch, d, i, f.customers))
    rows.sort()
    return [(d, tuple(cs)) for _, _, d, _, cs in rows]


def _reorder(sorties: SortieList, decoder: _Decoder) -> SortieList:
    """The sorties in a launch order where each comes after the sorties serving its
    customers' predecessors (the least original index first among the ready ones), so that
    no drone waits at a customer for a later launch (one more start for the search).
    Unchanged when the sorties' precedences form a cycle."""
    where = {j: i for i, (_, cs) in enumerate(sorties) for j in cs}
    needs = [
        {where[r] for j in cs for r in decoder.preds[j] if r in where and where[r] != i}
        for i, (_, cs) in enumerate(sorties)
    ]
    out: list[int] = []
    done: set[int] = set()
    while len(out) < len(sorties):
        ready = [i for i in range(len(sorties)) if i not in done and needs[i] <= done]
        if not ready:
            return sorties
        out.append(ready[0])
        done.add(ready[0])
    return [sorties[i] for i in out]


def _singletons(problem: FleetProblem, plan: FleetPlan, k: int) -> SortieList:
    """Truck k's customers one per sortie, in order of their service times in the plan's
    earliest schedule (ties: a topological order), each on the drone that serves it: a valid
    sortie list (a predecessor is served no later, so it comes first)."""
    import networkx as nx

    times = schedule(problem, plan).service
    rank = {j: i for i, j in enumerate(nx.topological_sort(problem.precedence_graph))}
    rows = [
        (float(times[j]), rank.get(j, -1), d, j)
        for d, flights in enumerate(plan.sorties[k])
        for f in flights
        for j in f.customers
    ]
    rows.sort()
    return [(d, (j,)) for _, _, d, j in rows]


def _move(sorties: SortieList, D: int, c: int, rng: np.random.Generator) -> SortieList | None:
    """One random move of a sortie list (module docstring); None when it does not apply."""
    out = [(d, list(cs)) for d, cs in sorties]
    kind = int(rng.integers(5))
    m = len(out)
    if kind <= 1:  # relocate one customer (kind 1: to a new sortie)
        i = int(rng.integers(m))
        j = out[i][1].pop(int(rng.integers(len(out[i][1]))))
        if kind == 1 or c == 1:
            q = int(rng.integers(m + 1))
            out.insert(q, (int(rng.integers(D)), [j]))
        else:
            room = [x for x in range(m) if len(out[x][1]) < c and x != i] + [i]
            x = room[int(rng.integers(len(room)))]
            out[x][1].insert(int(rng.integers(len(out[x][1]) + 1)), j)
    elif kind == 2:  # swap two customers
        cells = [(x, y) for x in range(m) for y in range(len(out[x][1]))]
        if len(cells) < 2:
            return None
        a, b = rng.choice(len(cells), 2, replace=False)
        (x1, y1), (x2, y2) = cells[int(a)], cells[int(b)]
        out[x1][1][y1], out[x2][1][y2] = out[x2][1][y2], out[x1][1][y1]
    elif kind == 3:  # another drone
        if D < 2:
            return None
        i = int(rng.integers(m))
        d = int(rng.integers(D - 1))
        out[i] = (d if d < out[i][0] else d + 1, out[i][1])
    else:  # move a sortie in the launch order
        if m < 2:
            return None
        i = int(rng.integers(m))
        item = out.pop(i)
        q = int(rng.integers(m))
        if q >= i:
            q += 1
        out.insert(min(q, m - 1), item)
    return [(d, tuple(cs)) for d, cs in out if cs]


def search_truck(
    decoder: _Decoder,
    start: SortieList,
    rng: np.random.Generator,
    deadline: Deadline,
    iterations: int | None,
    strength: int = 3,
) -> tuple[float, SortieList]:
    """The local search of one truck's sortie list (module docstring): the best list found
    and its decoded value at :data:`SEARCH_WIDTH`."""
    best_value, _ = decoder.decode(start, SEARCH_WIDTH)
    best = current = start
    value = best_value
    stall = done = 0
    while (iterations is None or done < iterations) and not deadline.expired():
        done += 1
        moved = _move(current, decoder.D, decoder.c, rng)
        if moved is None or not decoder.valid(moved):
            continue
        found, _ = decoder.decode(moved, SEARCH_WIDTH)
        if found <= value * (1.0 + ACCEPT_WORSE):
            stall = 0 if found < value - 1e-9 else stall + 1
            current, value = moved, found
            if found < best_value - 1e-9:
                best, best_value = moved, found
        else:
            stall += 1
        if stall >= STALL:
            stall = 0
            current = best
            for _ in range(strength):
                shaken = _move(current, decoder.D, decoder.c, rng)
                if shaken is not None and decoder.valid(shaken):
                    current = shaken
            value, _ = decoder.decode(current, SEARCH_WIDTH)
    return best_value, best


def _score(problem: FleetProblem, plan: FleetPlan | None) -> float:
    if plan is None:
        return INF
    try:
        return evaluate_fleet(problem, plan)
    except FeasibilityError:
        return INF


def _with_truck(
    plan: FleetPlan, k: int, route: list[int], flights: list[list[Sortie]]
) -> FleetPlan:
    routes = [list(r) for r in plan.routes]
    service = [list(s) for s in plan.truck_service]
    sorties = [list(map(list, s)) for s in plan.sorties]
    routes[k], service[k], sorties[k] = route, [], [list(f) for f in flights]
    return FleetPlan(routes, service, sorties)


def interleave_applies(problem: FleetProblem) -> bool:
    """Some truck carries a drone and every customer may be served by a drone."""
    return problem.D >= 1 and all(problem.drone_servable(j) for j in range(problem.n))


def interleave_plan(
    problem: FleetProblem,
    plan: Any = None,
    seed: int = 0,
    time_limit: float | None = None,
    iterations: int | None = None,
    rounds: int = 2,
) -> FleetPlan | None:
    """The best plan of the interleaved-sortie search from ``plan`` (module docstring); never
    worse than ``plan`` under :func:`taopt.evaluate` (returned unchanged when the search
    does not apply or finds nothing better).

    Parameters
    ----------
    problem : FleetProblem
    plan : FleetPlan or Solution, optional
        The start: its trucks' customers and sorties. Without one, :func:`interleave_plan`
        starts from the best of :func:`taopt.heuristics.fleet.construct`'s MMA and SMMA.
    seed : int
        Seeds the moves.
    time_limit : float, optional
        Wall-clock seconds (shared by the trucks in turn).
    iterations : int, optional
        Moves per truck and round (tests); unlimited (the time limit) by default.
    rounds : int
        Passes over the trucks (one truck: one pass).

    Returns
    -------
    FleetPlan or None
        None only when ``plan`` is None and the problem has no drone-servable plan.
    """
    deadline = Deadline(time_limit)
    if plan is None:
        from taopt.heuristics.fleet import construct

        built = [construct(problem, rule) for rule in ("MMA", "SMMA")]
        plan = min((b.plan() for b in built), key=lambda x: _score(problem, x))
    best = as_plan(plan)
    best_value = _score(problem, best)
    if not interleave_applies(problem) or not math.isfinite(best_value):
        return best
    rng = np.random.default_rng(seed)
    trucks = [k for k in range(problem.K) if problem.drones[k] >= 1]
    passes = 1 if problem.K == 1 else max(int(rounds), 1)
    for round_ in range(passes):
        improved = False
        for index, k in enumerate(trucks):
            if deadline.expired():
                return best
            mine = {j for d in best.sorties[k] for f in d for j in f.customers}
            if best.truck_service[k] or not mine:
                continue
            release = np.zeros(problem.n)
            if problem.K > 1:
                times = schedule(problem, best).service
                for r, j in problem.precedences:
                    if j in mine and r not in mine:
                        release[j] = max(release[j], float(times[r]))
            decoder = _Decoder(problem, k, release)
            listed = sortie_list(problem, best, k)
            starts = [x for x in (listed, _reorder(listed, decoder)) if decoder.valid(x)]
            starts.append(_singletons(problem, best, k))
            start = min(starts, key=lambda x: decoder.decode(x, SEARCH_WIDTH)[0])
            left = deadline.remaining()
            turns = len(trucks) - index + (passes - round_ - 1) * len(trucks)
            share = None if left is None else left / turns
            _, found = search_truck(decoder, start, rng, Deadline(share), iterations)
            value, events = decoder.decode(found, FINAL_WIDTH)
            if events is None:
                continue
            route, flights = decoder.route(events)
            candidate = _with_truck(best, k, route, flights)
            score = _score(problem, candidate)
            if score < best_value - 1e-9:
                best, best_value, improved = candidate, score, True
        if not improved:
            break
    return best


__all__ = [
    "ACCEPT_WORSE",
    "FINAL_WIDTH",
    "NEAR_STOPS",
    "SEARCH_WIDTH",
    "STALL",
    "interleave_applies",
    "interleave_plan",
    "search_truck",
    "sortie_list",
]
